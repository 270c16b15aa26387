"""``method="global"``: the exact optimiser of the objective's type, else the hybrid search."""

from __future__ import annotations

import dataclasses
import logging
from typing import Any

from numpy.typing import ArrayLike

from ..geometry import Polygon
from ..objectives import SmithFitness
from .exact import exact_solver
from .hybrid import hybrid
from .methods import _check_options, _takes, register_method
from .problem import _checked
from .result import OptimizeResult

__all__: list[str] = []

log = logging.getLogger("boustro")

#: The default objective (frozen: one instance serves every call).
_EQ1 = SmithFitness()


@register_method("global")
def _global(
    polygon: Polygon | ArrayLike, spacing: float, *, fitness: Any = None, **options: Any
) -> OptimizeResult:
    """``method="global"``: the exact optimiser of the objective's type
    (:data:`boustro.optimize.exact.EXACT`: Eq. 1 certified by branch and bound, fewest
    transects, shortest path); without one, the hybrid search, with a warning logged on the
    ``"boustro"`` logger and ``info["note"]`` saying so."""
    # the rule of every method (its checks; the exact solvers build no half-plane tensors)
    _checked(polygon, spacing, fitness, "the global optimiser")
    solver = exact_solver(_EQ1 if fitness is None else fitness)
    if solver is None:
        note = (
            f"no exact optimiser for the {type(fitness).__name__} objective "
            "(boustro.optimize.exact.EXACT): searched with the hybrid method instead"
        )
        log.warning("%s", note)
        _check_options("global", hybrid, options)
        result = hybrid(polygon, spacing, fitness=fitness, **options)
        return dataclasses.replace(result, info={**result.info, "note": note})
    if _takes(solver, "fitness"):
        options = {**options, "fitness": fitness}
    _check_options("global", solver, options)
    return solver(polygon, spacing, **options)
