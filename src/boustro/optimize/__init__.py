"""Optimisers over (angle, offset): one entry point, one registry of methods, one result type."""

from __future__ import annotations

import dataclasses
import importlib
import inspect
import logging
from collections.abc import Callable
from typing import Any

from numpy.typing import ArrayLike

from ..errors import InvalidParameterError
from ..geometry import Polygon
from ..objectives import Objective, SmithFitness
from . import exact
from .descent import _descend as _descend
from .descent import _Descent as _Descent
from .descent import _wrap_ as _wrap_
from .exact import EXACT, exact_solver
from .gradient import (
    DEFAULT_GUIDE,
    ZOOM_ANGLE,
    ZOOM_OFFSET,
    GradientOptions,
    gradient_descent,
)
from .grid import GRID_200, grid_search
from .hybrid import _grid_peaks as _grid_peaks
from .hybrid import hybrid
from .problem import _CHUNK_ELEMENTS as _CHUNK_ELEMENTS
from .problem import _check_count as _check_count
from .problem import _check_positive as _check_positive
from .problem import _Problem as _Problem
from .problem import _problem as _problem
from .problem import evaluate_grid, evaluate_pairs, exact_fitness
from .result import OptimizeResult, canonical
from .schedule import DEFAULT_SCHEDULE, TemperatureSchedule
from .schedule import _with_temperature as _with_temperature

__all__ = [
    "DEFAULT_GUIDE",
    "DEFAULT_SCHEDULE",
    "EXACT",
    "GRID_200",
    "METHODS",
    "ZOOM_ANGLE",
    "ZOOM_OFFSET",
    "GradientOptions",
    "Method",
    "Objective",
    "OptimizeResult",
    "TemperatureSchedule",
    "canonical",
    "evaluate_grid",
    "evaluate_pairs",
    "exact",
    "exact_fitness",
    "gradient_descent",
    "grid_search",
    "hybrid",
    "optimize",
    "register_method",
    "resolve_method",
]

log = logging.getLogger("boustro")

#: An optimiser: ``method(polygon, spacing, *, fitness=None, **options) -> OptimizeResult``.
Method = Callable[..., OptimizeResult]


def _check_options(method: str, function: Callable[..., Any], options: dict[str, Any]) -> None:
    """Refuse option names that ``function`` does not take, BEFORE calling it (a TypeError
    raised inside the call, e.g. by a user's objective, then propagates as it is)."""
    try:
        signature = inspect.signature(function)
    except (TypeError, ValueError):  # no signature to check against: the call will tell
        return
    try:
        signature.bind_partial(None, None, **options)
    except TypeError as exc:
        unknown = [name for name in options if name not in signature.parameters]
        what = f"option {unknown[0]!r}" if unknown else f"these options ({exc})"
        raise InvalidParameterError(
            f"method {method!r} takes no {what} (see its function's documentation)"
        ) from None


def _global(
    polygon: Polygon | ArrayLike, spacing: float, *, fitness: Any = None, **options: Any
) -> OptimizeResult:
    """``method="global"``: the exact optimiser of the objective's type
    (:data:`boustro.optimize.exact.EXACT`: Eq. 1 certified by branch and bound, fewest
    transects, shortest path); without one, the hybrid search, with a warning logged on the
    ``"boustro"`` logger and ``info["note"]`` saying so."""
    _problem(polygon, spacing, fitness, "the global optimiser")  # the rule of every method
    solver = exact_solver(SmithFitness() if fitness is None else fitness)
    if solver is None:
        note = (
            f"no exact optimiser for the {type(fitness).__name__} objective "
            "(boustro.optimize.exact.EXACT): searched with the hybrid method instead"
        )
        log.warning("%s", note)
        _check_options("global", hybrid, options)
        result = hybrid(polygon, spacing, fitness=fitness, **options)
        return dataclasses.replace(result, info={**result.info, "note": note})
    if "fitness" in inspect.signature(solver).parameters:
        options = {**options, "fitness": fitness}
    _check_options("global", solver, options)
    return solver(polygon, spacing, **options)


#: Optimisers by name; :func:`optimize` dispatches here. Each is called as
#: ``method(polygon, spacing, fitness=fitness, **options)`` and returns an
#: :class:`OptimizeResult`. A value may be a lazy entry ``"module:function"``, imported on first
#: use (:func:`resolve_method`): ``"learned"`` is, so that importing boustro does not load the
#: network code.
METHODS: dict[str, Method | str] = {
    "grid": grid_search,
    "gradient": gradient_descent,
    "hybrid": hybrid,
    "global": _global,
    "learned": "boustro.learned:learned",
}


def register_method(name: str, method: Method | str, *, replace: bool = False) -> None:
    """Register an optimiser: ``optimize(p, s, method=name, fitness=f, **opts)`` will call
    ``method(p, s, fitness=f, **opts)``, which must return an :class:`OptimizeResult`. A string
    ``"module:function"`` is a lazy entry, imported on first use."""
    if not isinstance(name, str) or not name:
        raise InvalidParameterError(f"a method name must be a non-empty string, got {name!r}")
    if name in METHODS and not replace:
        raise InvalidParameterError(f"method {name!r} is already registered")
    if not (callable(method) or (isinstance(method, str) and ":" in method)):
        raise InvalidParameterError(
            f"a method must be callable or a 'module:function' string, got {method!r}"
        )
    METHODS[name] = method


def resolve_method(name: str) -> Method:
    """The optimiser registered as ``name``, importing a lazy entry."""
    if name not in METHODS:
        raise InvalidParameterError(
            f"unknown method {name!r}; expected one of {', '.join(sorted(METHODS))}"
        )
    entry = METHODS[name]
    if isinstance(entry, str):
        module, _, attribute = entry.partition(":")
        entry = getattr(importlib.import_module(module), attribute)
    return entry


def optimize(
    polygon: Polygon | ArrayLike,
    spacing: float,
    *,
    method: str = "grid",
    fitness: Objective | None = None,
    **options: Any,
) -> OptimizeResult:
    """Optimise the angle and offset of a boustrophedon layout.

    Args:
        polygon: convex polygon, user units.
        spacing: transect spacing, user units (smaller than the polygon's diameter).
        method: a name in :data:`METHODS`: ``"grid"`` (:func:`grid_search`), ``"gradient"``
            (:func:`gradient_descent`), ``"hybrid"`` (:func:`hybrid`), ``"global"`` (the exact
            optimiser of the objective, :data:`boustro.optimize.exact.EXACT`: for Eq. 1
            :func:`boustro.global_opt.global_optimum`, the certified optimum with an upper
            bound in ``upper_bound``; the hybrid search for an objective without one) or
            ``"learned"`` (:func:`boustro.learned.learned`: the shipped planner network,
            ``refine=True`` for its exact refinement).
        fitness: the objective (default Eq. 1 with a = b = 0.5), maximised or minimised as its
            sense says.
        **options: passed to the method; names it does not take are refused before the call.

    >>> r = optimize([(0, 0), (2, 0), (2, 1), (0, 1)], 0.25, method="grid", n_angles=4)
    >>> r.method, round(r.angle, 4), round(r.fitness, 4)
    ('grid', 0.0, 0.9472)
    """
    function = resolve_method(method)
    _check_options(method, function, {"fitness": fitness, **options})
    return function(polygon, spacing, fitness=fitness, **options)
