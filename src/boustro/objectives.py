"""Named objectives of a transect layout: what the optimisers maximise or minimise (layer 3).

An objective is a small frozen object with a ``name``, a ``maximise`` flag and a ``__call__``
that maps a model's output to one value per layout, batched over leading dimensions, in the frame
of the half-planes (the normalised frame for the library). Objectives stay separate from the
optimisers that use them (STYLE.md): any optimiser takes any objective, and an optimiser that
maximises negates the value of an objective whose ``maximise`` is False.

* :class:`~boustro.fitness.SmithFitness` - Eq. 1 of the paper, ``a * mean + b * (1 - std)`` of
  the lengths; **maximised**. Input: :class:`~boustro.models.TransectLengths`.
* :class:`FewestTransects` - the number of transects that cross the polygon (= turns + 1);
  **minimised**. Input: :class:`~boustro.models.TransectLengths` (the soft count for soft models).
* :class:`ShortestPath` - total length of the boustrophedon path: every transect plus the
  straight connecting move between consecutive transects; **minimised**. Input:
  :class:`~boustro.models.Chords` (it needs the transects' ends, which only the exact chords
  have): ``needs_chords`` is True.

Coverage. None of these objectives sees the polygon itself, so none can tell whether the
layout's swaths cover it: with a free offset, the first and last transects may sit up to one
spacing inside the polygon's extremes, leaving a strip of up to half a spacing unswept. The exact
optimisers :func:`boustro.global_opt.fewest_transects_optimum` and
:func:`boustro.global_opt.shortest_path_optimum` enforce full coverage (every point within half a
spacing of a transect) by default.

Exact optima: :func:`boustro.global_opt.global_optimum` (Eq. 1, certified by branch and
bound), :func:`~boustro.global_opt.fewest_transects_optimum` (closed form: the minimum-width
direction) and :func:`~boustro.global_opt.shortest_path_optimum` (certified by branch and bound).
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal, Protocol, runtime_checkable

import torch

from .errors import InvalidParameterError
from .fitness import SmithFitness
from .models import Chords, TransectLengths

__all__ = [
    "OBJECTIVES",
    "FewestTransects",
    "LengthObjective",
    "Objective",
    "PlanObjective",
    "PreferredAngle",
    "ShortestPath",
    "SmithFitness",
    "as_plan_objective",
    "coverage_count",
    "get_objective",
    "objective_sense",
    "objective_sign",
    "path_length",
]

#: Chords at most this long (relative to the frame's radius 1) are a transect grazing a vertex,
#: not a transect: the same rule as :class:`~boustro.models.ExactModel`.
GRAZE = 1e-12


# Attributes that say an objective's direction, and the sense each means when True.
_DIRECTION_FLAGS = {"maximise": "max", "maximize": "max", "minimise": "min", "minimize": "min"}


def objective_sense(objective: object) -> Literal["max", "min"]:
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


@runtime_checkable
class Objective(Protocol):
    """Anything with a name, a direction and a value per layout."""

    name: str
    maximise: bool

    def __call__(self, x: TransectLengths | Chords, /) -> torch.Tensor: ...


@dataclass(frozen=True)
class FewestTransects:
    """The number of transects that cross the polygon (turns + 1); **minimised**.

    On exact lengths it is the count of transects longer than zero; on a soft model's lengths it
    is the sum of the "shown" weights (Eq. 7), a differentiable surrogate.

    The count with full coverage at angle ``theta`` is ``ceil(width(theta) / spacing)``
    (:func:`coverage_count`), minimised by the polygon's minimum-width direction, which is
    parallel to one of its edges (rotating calipers); see
    :func:`boustro.global_opt.fewest_transects_optimum`.
    """

    name: str = "fewest_transects"
    maximise: bool = False
    needs_chords: bool = False

    def __call__(self, tl: TransectLengths | Chords) -> torch.Tensor:
        if isinstance(tl, Chords):
            return (tl.lengths > GRAZE).to(tl.lengths.dtype).sum(dim=-1)
        return tl.weights.sum(dim=-1)


def coverage_count(width: float, spacing: float) -> int:
    """Fewest transects whose swaths (half a spacing each side) cover a strip of ``width``.

    ``ceil(width / spacing)``, with a width that is a whole number of spacings up to rounding
    (relative 1e-12) counted as that number: the transects then sit half a spacing from each
    side.
    """
    ratio = width / spacing
    k = math.floor(ratio)
    return int(k) if ratio - k <= 1e-12 * max(1.0, ratio) else int(k) + 1


def path_length(
    chords: Chords, *, start: Literal["best", "upper", "lower"] = "best"
) -> torch.Tensor:
    """Total boustrophedon path ``(*)`` over exact chords ``(*, K)``: see :class:`ShortestPath`.

    The transects that cross the polygon are driven in order of position; consecutive ones are
    joined by a straight move between their ends on the same side, the side alternating. With
    ``start="upper"`` the first move joins the ends at the transects' ``upper`` coordinate (the
    first transect is driven along its direction), with ``"lower"`` the other way round, and
    ``"best"`` takes the shorter. Layouts without any transect have length 0.
    """
    if start not in ("best", "upper", "lower"):
        raise InvalidParameterError(f"start must be 'best', 'upper' or 'lower', got {start!r}")
    length = chords.lengths
    shown = length > GRAZE
    zero = torch.zeros_like(length)
    lower = torch.where(shown, chords.lower, zero)
    upper = torch.where(shown, chords.upper, zero)
    total = torch.where(shown, length, zero).sum(dim=-1)
    pair = shown[..., 1:] & shown[..., :-1]
    gap = chords.positions[..., 1:] - chords.positions[..., :-1]
    # index of each move among the moves of its layout: 0, 1, 2, ...
    index = torch.cumsum(pair.to(torch.int64), dim=-1) - 1
    even = (index % 2) == 0
    d_up = upper[..., 1:] - upper[..., :-1]
    d_lo = lower[..., 1:] - lower[..., :-1]
    move_up = torch.sqrt(gap * gap + d_up * d_up)
    move_lo = torch.sqrt(gap * gap + d_lo * d_lo)
    pz = torch.zeros_like(move_up)
    first_up = torch.where(pair, torch.where(even, move_up, move_lo), pz).sum(dim=-1)
    first_lo = torch.where(pair, torch.where(even, move_lo, move_up), pz).sum(dim=-1)
    if start == "upper":
        return total + first_up
    if start == "lower":
        return total + first_lo
    return total + torch.minimum(first_up, first_lo)


@dataclass(frozen=True)
class ShortestPath:
    """Total path length: transects plus straight connecting moves; **minimised**.

    Needs exact :class:`~boustro.models.Chords` (the ends of the transects), hence
    ``needs_chords = True``: an optimiser evaluates it on
    :func:`~boustro.models.exact_chords` rather than on a model's lengths. Lengths are in the
    chords' frame (normalised for the library: multiply by the polygon's diameter for its units).

    Attributes:
        start: which side the first connecting move is on (``"best"``: the shorter path).
    """

    start: Literal["best", "upper", "lower"] = "best"
    name: str = "shortest_path"
    maximise: bool = False
    needs_chords: bool = True

    def __post_init__(self) -> None:
        if self.start not in ("best", "upper", "lower"):
            raise InvalidParameterError(
                f"start must be 'best', 'upper' or 'lower', got {self.start!r}"
            )

    def __call__(self, chords: TransectLengths | Chords) -> torch.Tensor:
        if not isinstance(chords, Chords):
            raise InvalidParameterError(
                "ShortestPath needs exact chords (boustro.models.exact_chords), got "
                f"{type(chords).__name__}: transect lengths alone do not say where the ends are"
            )
        return path_length(chords, start=self.start)


#: The objectives by name, as the command line and the optimisers' ``objective=`` accept them.
OBJECTIVES: dict[str, type] = {
    "smith": SmithFitness,
    "fewest_transects": FewestTransects,
    "shortest_path": ShortestPath,
}


def get_objective(name: str | Objective, **settings: object) -> Objective:
    """An objective by name (``"smith"``, ``"fewest_transects"``, ``"shortest_path"``) with
    its settings (e.g. ``a``, ``b`` for ``"smith"``), or the object itself."""
    if not isinstance(name, str):
        return name
    if name not in OBJECTIVES:
        raise InvalidParameterError(
            f"unknown objective {name!r}; expected one of {', '.join(sorted(OBJECTIVES))}"
        )
    return OBJECTIVES[name](**settings)


# -- plan-aware objectives: of the lengths AND the layout (angle, offset, spacing) ------------


@runtime_checkable
class PlanObjective(Protocol):
    """A differentiable objective of the soft lengths AND the plan parameters, maximised.

    ``objective(tl, theta, offset, spacing) -> values``, everything in the normalised frame
    (polygon diameter 1):

    * ``tl``: :class:`~boustro.models.TransectLengths` ``(*, K)`` (soft or exact lengths and
      weights, transect positions);
    * ``theta``: ``(*)`` transect directions, radians (period pi with the offset's sign flip);
    * ``offset``: ``(*)`` grid offsets (period ``spacing``);
    * ``spacing``: ``(*)`` or broadcastable, the spacing of each layout;

    and returns ``(*)`` values, MAXIMISED. Any torch function of these works (it must be
    differentiable for training and gradient refinement; exact scoring only evaluates it). An
    attribute ``maximise = False`` turns it into a cost (minimised). Objectives of the lengths
    alone (:class:`~boustro.fitness.SmithFitness`, anything ``f(tl)``) are wrapped by
    :func:`as_plan_objective`.
    """

    def __call__(
        self,
        tl: TransectLengths,
        theta: torch.Tensor,
        offset: torch.Tensor,
        spacing: torch.Tensor,
    ) -> torch.Tensor: ...


@dataclass(frozen=True)
class LengthObjective:
    """A :class:`PlanObjective` from an objective of the lengths alone, ``f(tl) -> (*)``.

    Honours ``maximise = False`` on the wrapped objective by negating it, so the result is
    always maximised.
    """

    objective: Callable[[TransectLengths], torch.Tensor]

    @property
    def name(self) -> str:
        return str(getattr(self.objective, "name", type(self.objective).__name__))

    def __call__(
        self,
        tl: TransectLengths,
        theta: torch.Tensor,
        offset: torch.Tensor,
        spacing: torch.Tensor,
    ) -> torch.Tensor:
        value = self.objective(tl)
        return value if objective_sign(self.objective) > 0 else -value


@dataclass(frozen=True)
class _Negated:
    objective: Callable[..., torch.Tensor]

    def __call__(
        self,
        tl: TransectLengths,
        theta: torch.Tensor,
        offset: torch.Tensor,
        spacing: torch.Tensor,
    ) -> torch.Tensor:
        return -self.objective(tl, theta, offset, spacing)


@dataclass(frozen=True)
class PreferredAngle:
    """Example plan objective: ``base`` minus ``weight * sin^2(theta - angle)``.

    Rewards transects near a preferred direction (crop rows, wind, the long side of a field),
    period pi like the layouts. ``base`` is any objective :func:`as_plan_objective` accepts
    (default: Eq. 1).
    """

    angle: float
    weight: float = 0.05
    base: Any = None

    def __call__(
        self,
        tl: TransectLengths,
        theta: torch.Tensor,
        offset: torch.Tensor,
        spacing: torch.Tensor,
    ) -> torch.Tensor:
        base = as_plan_objective(self.base)(tl, theta, offset, spacing)
        return base - self.weight * torch.sin(theta - self.angle) ** 2


def as_plan_objective(objective: Any = None) -> PlanObjective:
    """The :class:`PlanObjective` (maximised) for ``objective``.

    * ``None``: Eq. 1 (:class:`~boustro.fitness.SmithFitness`, ``a = b = 0.5``);
    * a callable taking ``(tl, theta, offset, spacing)``: used as it is (negated if it has
      ``maximise = False``);
    * a callable taking ``(tl)`` only (``SmithFitness``, optimize's objectives): wrapped by
      :class:`LengthObjective`.

    Raises:
        InvalidParameterError: not callable, or with another signature.
    """
    if objective is None:
        return LengthObjective(SmithFitness())
    if isinstance(objective, (LengthObjective, _Negated)):
        return objective
    if not callable(objective):
        raise InvalidParameterError(
            f"an objective must be callable as f(tl) or f(tl, theta, offset, spacing), "
            f"got {objective!r}"
        )
    if getattr(objective, "needs_chords", False):
        raise InvalidParameterError(
            f"the {getattr(objective, 'name', type(objective).__name__)} objective needs the "
            "exact chords' ends, which the learned planner's soft lengths do not have; use an "
            "objective of the transect lengths"
        )
    try:
        sig = inspect.signature(objective)
    except (TypeError, ValueError):  # builtins without a signature: assume lengths only
        return LengthObjective(objective)
    for args, kind in ((4, "plan"), (1, "lengths")):
        try:
            sig.bind(*range(args))
        except TypeError:
            continue
        if kind == "lengths":
            return LengthObjective(objective)
        if objective_sign(objective) > 0:
            return objective
        return _Negated(objective)
    raise InvalidParameterError(
        f"an objective must be callable as f(tl) or f(tl, theta, offset, spacing); "
        f"{getattr(objective, '__name__', objective)!r} has signature {sig}"
    )
