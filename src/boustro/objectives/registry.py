"""The one registry of objectives by name: every objective module registers its own."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from .._registry import Registry
from ..errors import InvalidParameterError
from .base import Objective

__all__ = ["OBJECTIVES", "get_objective", "objective_key", "register_objective"]

#: The objectives by name (snake case), as the command line (in kebab case) and the optimisers'
#: ``objective=`` accept them. Each module of :mod:`boustro.objectives` registers its own with
#: :func:`register_objective`; a new module in the package is found on import (discovery).
OBJECTIVES: Registry[Callable[..., Objective]] = Registry("objective", "boustro.objectives")


def objective_key(name: str) -> str:
    """The registry's spelling of an objective name: ``"fewest-transects"`` ->
    ``"fewest_transects"``."""
    return OBJECTIVES.key(name)


def register_objective(
    name: str, factory: Callable[..., Objective] | None = None, *, replace: bool = False
) -> Any:
    """Register an objective: ``get_objective(name, **settings)`` will call
    ``factory(**settings)`` (a class or a function returning an objective).

    Without ``factory``, a decorator::

        @register_objective("longest-lane")
        @dataclass(frozen=True)
        class LongestLane(BaseObjective): ...
    """

    def add(item: Callable[..., Objective]) -> Callable[..., Objective]:
        if not callable(item):
            raise InvalidParameterError(f"an objective factory must be callable, got {item!r}")
        return OBJECTIVES.register(name, item, replace=replace)

    if factory is None:
        OBJECTIVES.key(name)  # a bad name fails here, not at decoration
        return add
    return add(factory)


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
    return OBJECTIVES.get_variant(name)(**settings)
