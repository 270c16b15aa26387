"""Compatibility path: ``boustro.global_opt`` re-exports :mod:`boustro.optimize.exact`.

Patch settings such as ``WORK_LIMIT`` in their home, :mod:`boustro.optimize.exact.structure`.
"""

from .optimize.exact import (
    EXACT,
    best_offset,
    event_angles,
    fewest_transects_optimum,
    global_optimum,
    shortest_path_optimum,
)
from .optimize.exact.bounds import _evaluate_smith, _smith_pieces
from .optimize.exact.path import _evaluate_path, _path_minimise, _path_pieces
from .optimize.exact.search import MIN_TOL, _branch_and_bound, _check_tol
from .optimize.exact.smith import _attained, _spot_check, _weights
from .optimize.exact.structure import (
    BOUND_SLACK,
    EVENT_MERGE,
    WORK_LIMIT,
    _check_work,
    _structure,
    global_work,
)
from .optimize.exact.width import _width, _width_pieces

__all__ = [
    "BOUND_SLACK",
    "EVENT_MERGE",
    "EXACT",
    "MIN_TOL",
    "WORK_LIMIT",
    "_attained",
    "_branch_and_bound",
    "_check_tol",
    "_check_work",
    "_evaluate_path",
    "_evaluate_smith",
    "_path_minimise",
    "_path_pieces",
    "_smith_pieces",
    "_spot_check",
    "_structure",
    "_weights",
    "_width",
    "_width_pieces",
    "best_offset",
    "event_angles",
    "fewest_transects_optimum",
    "global_optimum",
    "global_work",
    "shortest_path_optimum",
]
