"""Plan-aware objectives: of the lengths AND the layout (angle, offset, spacing), maximised."""

from __future__ import annotations

import inspect
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

from .._torch import torch
from ..errors import InvalidParameterError
from ..models import TransectLengths
from .base import PlanObjective, objective_sign
from .smith import SmithFitness

__all__ = ["LengthObjective", "PlanObjective", "PreferredAngle", "as_plan_objective"]


@dataclass(frozen=True)
class LengthObjective:
    """A :class:`PlanObjective` from an objective of the lengths alone, ``f(tl) -> (*)``.

    Honours ``maximise = False`` on the wrapped objective by negating it, so the result is
    always maximised.
    """

    objective: Callable[[TransectLengths], torch.Tensor]

    plan_aware: ClassVar[bool] = True
    sense: ClassVar[str] = "max"

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
    """A minimised plan objective turned into a maximised one."""

    objective: Callable[..., torch.Tensor]

    plan_aware: ClassVar[bool] = True
    sense: ClassVar[str] = "max"

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

    plan_aware: ClassVar[bool] = True
    sense: ClassVar[str] = "max"

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
    * a plan objective, declared by ``plan_aware = True`` or recognised by its signature
      ``(tl, theta, offset, spacing)``: used as it is (negated if it is minimised);
    * a callable taking ``(tl)`` only (``SmithFitness``, optimize's objectives): wrapped by
      :class:`LengthObjective`.

    Raises:
        InvalidParameterError: not callable, or with another signature.
    """
    if objective is None:
        return LengthObjective(SmithFitness())
    if getattr(objective, "plan_aware", False) is True:  # declared: no signature sniffing
        return objective if objective_sign(objective) > 0 else _Negated(objective)
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
    if getattr(objective, "plan_aware", None) is False:  # declared objective of the lengths
        return LengthObjective(objective)
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
