"""Optimisers over (angle, offset): one entry point, one registry of methods, one result type."""

from __future__ import annotations

from ..objectives import Objective
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
from .methods import METHODS, Method, optimize, register_method, resolve_method
from .methods import _check_options as _check_options
from .problem import _CHUNK_ELEMENTS as _CHUNK_ELEMENTS
from .problem import Problem, evaluate_grid, evaluate_pairs, exact_fitness, prepare_problem
from .problem import _check_count as _check_count
from .problem import _check_positive as _check_positive
from .problem import _Problem as _Problem
from .problem import _problem as _problem
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
    "Problem",
    "TemperatureSchedule",
    "canonical",
    "evaluate_grid",
    "evaluate_pairs",
    "exact",
    "exact_fitness",
    "exact_solver",
    "gradient_descent",
    "grid_search",
    "hybrid",
    "optimize",
    "prepare_problem",
    "register_method",
    "resolve_method",
]

METHODS.discover()  # every module of the package registers its methods ("global": certified)
