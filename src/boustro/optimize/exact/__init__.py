"""Exact optimisers, one per objective, and the table that picks one by objective type."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ...objectives import FewestTransects, ShortestPath, SmithFitness, objective_sense
from ..result import OptimizeResult
from .path import shortest_path_optimum
from .smith import best_offset, global_optimum
from .structure import WORK_LIMIT, event_angles, global_work
from .width import fewest_transects_optimum

__all__ = [
    "EXACT",
    "WORK_LIMIT",
    "ExactSolver",
    "best_offset",
    "event_angles",
    "exact_solver",
    "fewest_transects_optimum",
    "global_optimum",
    "global_work",
    "shortest_path_optimum",
]

#: An exact optimiser: ``solver(polygon, spacing, **options) -> OptimizeResult``; it takes the
#: objective as ``fitness=`` if it has that parameter.
ExactSolver = Callable[..., OptimizeResult]

#: The exact optimiser of each objective type, used by ``optimize(..., method="global")``. An
#: objective whose exact type is not here is searched by the hybrid method instead (with a
#: warning). Add an entry to give a new objective type its exact optimiser.
EXACT: dict[type, ExactSolver] = {
    SmithFitness: global_optimum,
    FewestTransects: fewest_transects_optimum,
    ShortestPath: shortest_path_optimum,
}


def exact_solver(objective: Any) -> ExactSolver | None:
    """The exact optimiser of ``objective``'s type (not of a subclass, which may compute
    something else), or ``None``; also ``None`` when the objective's sense is not the one its
    type's solver optimises (e.g. ``FewestTransects(maximise=True)``).

    >>> from boustro.objectives import FewestTransects
    >>> exact_solver(FewestTransects()).__name__
    'fewest_transects_optimum'
    """
    solver = EXACT.get(type(objective))
    if solver is None or objective_sense(objective) != _default_sense(type(objective)):
        return None
    return solver


_SENSES: dict[type, str] = {}


def _default_sense(kind: type) -> str:
    """The sense of a default instance of the objective type ``kind`` (its exact solver's),
    kept per type."""
    if kind not in _SENSES:
        _SENSES[kind] = objective_sense(kind())
    return _SENSES[kind]
