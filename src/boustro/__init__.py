"""boustro: boustrophedon (lawnmower) coverage paths over polygons.

Layers, each importing only those below it (see ``DESIGN.md``):

1. :mod:`boustro.geometry` - validated polygons, the normalised frame, half-planes.
2. :mod:`boustro.models` - transect-length models: exact chords, the paper's sigmoid integral;
   :mod:`boustro.smooth` - the smooth closed form (the paper's first item of future work).
3. :mod:`boustro.fitness` - fitness functions of transect lengths (Eq. 1 of the paper).
4. :mod:`boustro.scoring` - score a layout in user units; :mod:`boustro.objectives` - fewest
   transects, shortest path.
5. :mod:`boustro.optimize` - grid search, gradient descent (SGD/Adam, temperature schedules),
   hybrid, and :mod:`boustro.global_opt` - the certified global optimum; one result type.
   :mod:`boustro.learned` - a planner network trained through the differentiable fitness.
6. :mod:`boustro.regions`, :mod:`boustro.decompose` - concave areas and holes;
   :mod:`boustro.plan` - ordered, coverage-guaranteed waypoints and statistics.

The functions ``optimize.optimize`` and ``decompose.decompose`` are not re-exported here, so
that ``boustro.optimize`` and ``boustro.decompose`` stay the modules.

Edges (never imported by the core): :mod:`boustro.io` (reading areas), :mod:`boustro.geo`
(coordinate systems, missions), :mod:`boustro.formats` (mission files), :mod:`boustro.plot`,
:mod:`boustro.plot_plan`, :mod:`boustro.experiments`, :mod:`boustro.cli`.
"""

from ._version import __version__
from .errors import (
    BoustroError,
    InvalidParameterError,
    InvalidPolygonError,
    NonConvexPolygonError,
    NoTransectError,
    PolygonFileError,
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
from .objectives import FewestTransects, ShortestPath, get_objective, path_length
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

__all__ = [
    "DEFAULT_SMOOTHING",
    "GRID_200",
    "BoustroError",
    "ExactModel",
    "FewestTransects",
    "Frame",
    "HalfPlanes",
    "InvalidParameterError",
    "InvalidPolygonError",
    "NoTransectError",
    "NonConvexPolygonError",
    "OptimizeResult",
    "PaperModel",
    "Plan",
    "PlanStats",
    "Polygon",
    "PolygonFileError",
    "Region",
    "RegionExactModel",
    "RegionSoftModel",
    "Score",
    "Segments",
    "ShortestPath",
    "SmithFitness",
    "SmoothModel",
    "TemperatureSchedule",
    "TransectLengths",
    "TransectModel",
    "__version__",
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
    "optimize_region",
    "paper_lengths",
    "path_length",
    "plan_region",
    "region_segments",
    "register_method",
    "score",
    "shortest_path_optimum",
    "smith_fitness",
    "smooth_lengths",
    "smoothing_from_temperature",
    "temperature_from_smoothing",
    "transect_positions",
    "transect_segments",
]
