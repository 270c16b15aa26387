"""The one registry of optimisers by name, and the entry point that dispatches to them."""

from __future__ import annotations

import importlib
import inspect
from collections.abc import Callable
from functools import lru_cache
from typing import Any

from numpy.typing import ArrayLike

from .._registry import Registry
from ..errors import InvalidParameterError
from ..geometry import Polygon
from ..objectives import Objective
from .result import OptimizeResult

__all__ = ["METHODS", "Method", "optimize", "register_method", "resolve_method"]

#: An optimiser: ``method(polygon, spacing, *, fitness=None, **options) -> OptimizeResult``.
Method = Callable[..., OptimizeResult]

#: Optimisers by name; :func:`optimize` dispatches here. Each is called as
#: ``method(polygon, spacing, fitness=fitness, **options)`` and returns an
#: :class:`OptimizeResult`. The modules of :mod:`boustro.optimize` register their own with
#: :func:`register_method` (a new module in the package is found on import). A value may be a
#: lazy entry ``"module:function"``, imported on first use (:func:`resolve_method`):
#: ``"learned"`` is, so that importing boustro does not load the network code.
METHODS: Registry[Method | str] = Registry("method", "boustro.optimize", snake_case=False)


@lru_cache(maxsize=256)
def _accepts(function: Callable[..., Any], names: tuple[str, ...]) -> str | None:
    """``None`` if ``function(polygon, spacing, **options)`` takes options of these names (or
    has no signature to check against: the call will tell), else what it refuses. Names, not
    values, decide it, so it is kept per function and names: ``inspect.signature`` costs tens
    of microseconds, a fast optimiser's whole call a millisecond."""
    try:
        signature = inspect.signature(function)
    except (TypeError, ValueError):
        return None
    try:
        signature.bind_partial(None, None, **dict.fromkeys(names))
    except TypeError as exc:
        unknown = [name for name in names if name not in signature.parameters]
        return f"option {unknown[0]!r}" if unknown else f"these options ({exc})"
    return None


def _takes(function: Callable[..., Any], name: str) -> bool:
    """Whether ``function``'s signature has a parameter ``name`` (kept, as :func:`_accepts`)."""
    try:
        return _has_parameter(function, name)
    except TypeError:  # an unhashable callable: not kept
        return _has_parameter.__wrapped__(function, name)


@lru_cache(maxsize=256)
def _has_parameter(function: Callable[..., Any], name: str) -> bool:
    return name in inspect.signature(function).parameters


def _check_options(method: str, function: Callable[..., Any], options: dict[str, Any]) -> None:
    """Refuse option names that ``function`` does not take, BEFORE calling it (a TypeError
    raised inside the call, e.g. by a user's objective, then propagates as it is)."""
    try:
        refused = _accepts(function, tuple(options))
    except TypeError:  # an unhashable callable: not kept
        refused = _accepts.__wrapped__(function, tuple(options))
    if refused is not None:
        raise InvalidParameterError(
            f"method {method!r} takes no {refused} (see its function's documentation)"
        )


def register_method(name: str, method: Method | str | None = None, *, replace: bool = False) -> Any:
    """Register an optimiser: ``optimize(p, s, method=name, fitness=f, **opts)`` will call
    ``method(p, s, fitness=f, **opts)``, which must return an :class:`OptimizeResult`. A string
    ``"module:function"`` is a lazy entry, imported on first use. Without ``method``, a
    decorator::

        @register_method("random")
        def random_search(polygon, spacing, *, fitness=None, n=500): ...
    """

    def add(item: Method | str) -> Method | str:
        if not (callable(item) or (isinstance(item, str) and ":" in item)):
            raise InvalidParameterError(
                f"a method must be callable or a 'module:function' string, got {item!r}"
            )
        return METHODS.register(name, item, replace=replace)

    if method is None:
        METHODS.key(name)  # a bad name fails here, not at decoration
        return add
    return add(method)


register_method("learned", "boustro.learned:learned")


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
