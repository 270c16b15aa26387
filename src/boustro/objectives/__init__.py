"""Named objectives of a transect layout, and the one registry of their names."""

from __future__ import annotations

from collections.abc import Callable

from ..errors import InvalidParameterError
from .base import _DIRECTION_FLAGS as _DIRECTION_FLAGS  # re-exported (private)
from .base import (
    BaseObjective,
    Objective,
    PlanObjective,
    Sense,
    objective_sense,
    objective_sign,
)
from .path import ShortestPath, path_length
from .plan_objective import LengthObjective, PreferredAngle, as_plan_objective
from .plan_objective import _Negated as _Negated  # re-exported (private)
from .smith import SmithFitness, smith_fitness
from .turns import GRAZE, FewestTransects, coverage_count

__all__ = [
    "GRAZE",
    "OBJECTIVES",
    "BaseObjective",
    "FewestTransects",
    "LengthObjective",
    "Objective",
    "PlanObjective",
    "PreferredAngle",
    "Sense",
    "ShortestPath",
    "SmithFitness",
    "as_plan_objective",
    "coverage_count",
    "get_objective",
    "objective_key",
    "objective_sense",
    "objective_sign",
    "path_length",
    "register_objective",
    "smith_fitness",
]

#: The objectives by name (snake case), as the command line (in kebab case) and the optimisers'
#: ``objective=`` accept them; :func:`register_objective` adds one.
OBJECTIVES: dict[str, Callable[..., Objective]] = {
    "smith": SmithFitness,
    "fewest_transects": FewestTransects,
    "shortest_path": ShortestPath,
}


def objective_key(name: str) -> str:
    """The registry's spelling of an objective name: ``"fewest-transects"`` ->
    ``"fewest_transects"``."""
    return name.replace("-", "_")


def register_objective(
    name: str, factory: Callable[..., Objective], *, replace: bool = False
) -> None:
    """Register an objective: ``get_objective(name, **settings)`` will call
    ``factory(**settings)`` (a class or a function returning an objective)."""
    if not isinstance(name, str) or not name:
        raise InvalidParameterError(f"an objective name must be a non-empty string, got {name!r}")
    key = objective_key(name)
    if key in OBJECTIVES and not replace:
        raise InvalidParameterError(f"objective {name!r} is already registered")
    if not callable(factory):
        raise InvalidParameterError(f"an objective factory must be callable, got {factory!r}")
    OBJECTIVES[key] = factory


def get_objective(name: str | Objective, **settings: object) -> Objective:
    """An objective by name, in snake or kebab case (``"smith"``, ``"fewest_transects"`` or
    ``"fewest-transects"``, ``"shortest_path"``), with its settings (e.g. ``a``, ``b`` for
    ``"smith"``), or the object itself.

    >>> get_objective("fewest-transects")
    FewestTransects(name='fewest_transects', maximise=False, needs_chords=False)
    >>> get_objective("smith", a=1.0, b=0.0).sense
    'max'
    """
    if not isinstance(name, str):
        return name
    key = objective_key(name)
    if key not in OBJECTIVES:
        raise InvalidParameterError(
            f"unknown objective {name!r}; expected one of {', '.join(sorted(OBJECTIVES))}"
        )
    return OBJECTIVES[key](**settings)
