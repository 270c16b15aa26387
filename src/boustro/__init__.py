"""boustro: boustrophedon (lawnmower) coverage paths over polygons.

The names below are the curated API of the README's tour; each subpackage has its own
``__all__``. The pipeline and the one statement of its layer order are in
``docs/architecture.md``: :mod:`boustro.geometry` -> :mod:`boustro.models` ->
:mod:`boustro.objectives` -> :mod:`boustro.optimize` -> :mod:`boustro.plan`, with the edges
(:mod:`boustro.io`, :mod:`boustro.mission`, :mod:`boustro.plot`, :mod:`boustro.experiments`,
:mod:`boustro.cli`) never imported by the core, so ``import boustro`` loads no file formats,
projections, plotting or network code.
"""

from ._version import __version__
from .errors import (
    BoustroError,
    InvalidParameterError,
    InvalidPolygonError,
    MissingDependencyError,
    NonConvexPolygonError,
    NoTransectError,
    PolygonFileError,
    ProblemTooLargeError,
)
from .geometry import Frame, HalfPlanes, Polygon, halfplanes
from .geometry.region import Region
from .models import (
    ExactModel,
    PaperModel,
    TransectLengths,
    TransectModel,
    exact_chords,
    paper_lengths,
    transect_positions,
)
from .models.region import RegionExactModel, region_segments
from .models.region_soft import RegionSoftModel
from .models.smooth import (
    DEFAULT_SMOOTHING,
    SmoothModel,
    smooth_lengths,
    smoothing_from_temperature,
    temperature_from_smoothing,
)
from .objectives import (
    FewestTransects,
    ShortestPath,
    get_objective,
    objective_sense,
    path_length,
    register_objective,
)
from .objectives.smith import SmithFitness, smith_fitness
from .optimize import (
    GRID_200,
    OptimizeResult,
    TemperatureSchedule,
    gradient_descent,
    grid_search,
    hybrid,
    register_method,
)
from .optimize.exact import (
    best_offset,
    fewest_transects_optimum,
    global_optimum,
    shortest_path_optimum,
)
from .plan import Plan, PlanStats, build_plan, coverage, guaranteed_segments
from .plan.region import plan_region
from .plan.region_opt import optimize_region
from .scoring import Score, Segments, make_model, score, transect_segments
from .sensors import Camera, Swath

#: Names resolved on first use (``"module:attribute"``), so that ``import boustro`` loads no file
#: formats or projections: the batch (a callable package) and the geo-stack entry.
_LAZY = {"batch": "boustro.batch", "plan_area": "boustro.batch.geo:plan_area"}


def __getattr__(name: str) -> object:
    """``boustro.batch`` and ``boustro.plan_area``, imported on first use (see :data:`_LAZY`)."""
    target = _LAZY.get(name)
    if target is None:
        raise AttributeError(f"module 'boustro' has no attribute {name!r}")
    import importlib

    module, _, attribute = target.partition(":")
    found = importlib.import_module(module)
    return getattr(found, attribute) if attribute else found


__all__ = [
    "DEFAULT_SMOOTHING",
    "GRID_200",
    "BoustroError",
    "Camera",
    "ExactModel",
    "FewestTransects",
    "Frame",
    "HalfPlanes",
    "InvalidParameterError",
    "InvalidPolygonError",
    "MissingDependencyError",
    "NoTransectError",
    "NonConvexPolygonError",
    "OptimizeResult",
    "PaperModel",
    "Plan",
    "PlanStats",
    "Polygon",
    "PolygonFileError",
    "ProblemTooLargeError",
    "Region",
    "RegionExactModel",
    "RegionSoftModel",
    "Score",
    "Segments",
    "ShortestPath",
    "SmithFitness",
    "SmoothModel",
    "Swath",
    "TemperatureSchedule",
    "TransectLengths",
    "TransectModel",
    "__version__",
    "batch",
    "best_offset",
    "build_plan",
    "coverage",
    "exact_chords",
    "fewest_transects_optimum",
    "get_objective",
    "global_optimum",
    "gradient_descent",
    "grid_search",
    "guaranteed_segments",
    "halfplanes",
    "hybrid",
    "make_model",
    "objective_sense",
    "optimize_region",
    "paper_lengths",
    "path_length",
    "plan_area",
    "plan_region",
    "region_segments",
    "register_method",
    "register_objective",
    "score",
    "shortest_path_optimum",
    "smith_fitness",
    "smooth_lengths",
    "smoothing_from_temperature",
    "temperature_from_smoothing",
    "transect_positions",
    "transect_segments",
]
