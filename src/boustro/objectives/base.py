"""The objective protocol: a name, a sense ("max" or "min"), what it reads, and its value."""

from __future__ import annotations

from typing import Any, Literal, Protocol, runtime_checkable

from .._torch import torch
from ..errors import InvalidParameterError
from ..models import TransectLengths

__all__ = [
    "BaseObjective",
    "Objective",
    "PlanObjective",
    "Sense",
    "objective_sense",
    "objective_sign",
]

#: The direction of an objective: maximised or minimised.
Sense = Literal["max", "min"]

# Attributes that say an objective's direction, and the sense each means when True.
_DIRECTION_FLAGS = {"maximise": "max", "maximize": "max", "minimise": "min", "minimize": "min"}


@runtime_checkable
class Objective(Protocol):
    """Anything with a name, a direction and a value per layout, ``(*, K) -> (*)``.

    ``sense`` is ``"max"`` or ``"min"`` (or, for compatibility, a bool ``maximise`` flag in
    either spelling: see :func:`objective_sense`); ``needs_chords`` says that it reads exact
    :class:`~boustro.models.Chords` (the transects' ends) rather than
    :class:`~boustro.models.TransectLengths`.
    """

    def __call__(self, x: Any, /) -> torch.Tensor: ...


@runtime_checkable
class PlanObjective(Protocol):
    """The plan-aware variant of :class:`Objective`: a value of the lengths AND the layout.

    ``objective(tl, theta, offset, spacing) -> values``, everything in the normalised frame
    (polygon diameter 1): ``tl`` :class:`~boustro.models.TransectLengths` ``(*, K)``, ``theta``
    ``(*)`` transect directions (radians), ``offset`` ``(*)`` grid offsets, ``spacing`` ``(*)``
    or broadcastable; returns ``(*)`` values, MAXIMISED unless its sense says ``"min"``. It
    declares itself with ``plan_aware = True`` (undeclared callables are recognised by their
    signature, see :func:`~boustro.objectives.as_plan_objective`). It must be differentiable
    for training and gradient refinement; exact scoring only evaluates it.
    """

    def __call__(
        self,
        tl: TransectLengths,
        theta: torch.Tensor,
        offset: torch.Tensor,
        spacing: torch.Tensor,
    ) -> torch.Tensor: ...


class BaseObjective:
    """Base of the built-in objectives: ``sense`` from their public ``maximise`` field.

    Subclasses are frozen dataclasses with the fields ``name`` and ``maximise``; they read
    :class:`~boustro.models.TransectLengths` unless they set ``needs_chords = True``.
    """

    name: str
    maximise: bool
    needs_chords: bool = False
    plan_aware: bool = False

    @property
    def sense(self) -> Sense:
        """``"max"`` or ``"min"``, from ``maximise``."""
        return "max" if self.maximise else "min"


def objective_sense(objective: object) -> Sense:
    """Whether ``objective`` is maximised (``"max"``) or minimised (``"min"``).

    Read from its ``sense`` attribute (``"max"`` or ``"min"``) or from a boolean flag spelt
    ``maximise``, ``maximize``, ``minimise`` or ``minimize``; a plain function with none of
    these is maximised. Flags that disagree, a ``sense`` other than ``"max"``/``"min"`` and a
    flag that is not a bool are errors: an objective is never optimised in the wrong direction.

    >>> from boustro.objectives import FewestTransects, objective_sense
    >>> objective_sense(FewestTransects()), objective_sense(lambda lengths: lengths.sum())
    ('min', 'max')
    """
    senses: dict[str, str] = {}
    sense = getattr(objective, "sense", None)
    if sense is not None:
        if sense not in ("max", "min"):
            raise InvalidParameterError(
                f"an objective's sense must be 'max' or 'min', got {sense!r}"
            )
        senses["sense"] = sense
    for flag, when_true in _DIRECTION_FLAGS.items():
        value = getattr(objective, flag, None)
        if value is None:
            continue
        if not isinstance(value, bool):
            raise InvalidParameterError(
                f"an objective's {flag!r} must be True or False, got {value!r}"
            )
        senses[flag] = when_true if value else ("min" if when_true == "max" else "max")
    if len(set(senses.values())) > 1:
        said = ", ".join(f"{k} -> {v}" for k, v in senses.items())
        raise InvalidParameterError(f"the objective's direction flags disagree ({said})")
    return "min" if "min" in senses.values() else "max"


def objective_sign(objective: object) -> float:
    """``+1.0`` for a maximised objective, ``-1.0`` for a minimised one.

    See :func:`objective_sense`.
    """
    return 1.0 if objective_sense(objective) == "max" else -1.0
