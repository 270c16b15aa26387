"""boustro: boustrophedon (lawnmower) coverage paths over polygons.

Layers, each importing only those below it (see ``DESIGN.md``):

1. :mod:`boustro.geometry` - validated polygons, the normalised frame, half-planes.
2. :mod:`boustro.models` - transect-length models: exact chords, the paper's sigmoid integral;
   :mod:`boustro.smooth` - the smooth closed form (the paper's first item of future work).
3. :mod:`boustro.fitness` - fitness functions of transect lengths (Eq. 1 of the paper).
4. :mod:`boustro.scoring` - score a layout in user units.

Edges (never imported by the core): :mod:`boustro.io` (files), :mod:`boustro.cli`.
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
from .fitness import SmithFitness, smith_fitness
from .geometry import Frame, HalfPlanes, Polygon, halfplanes
from .models import (
    ExactModel,
    PaperModel,
    TransectLengths,
    TransectModel,
    exact_chords,
    paper_lengths,
    transect_positions,
)
from .scoring import Score, Segments, make_model, score, transect_segments
from .smooth import (
    DEFAULT_SMOOTHING,
    SmoothModel,
    smooth_lengths,
    smoothing_from_temperature,
    temperature_from_smoothing,
)

__all__ = [
    "DEFAULT_SMOOTHING",
    "BoustroError",
    "ExactModel",
    "Frame",
    "HalfPlanes",
    "InvalidParameterError",
    "InvalidPolygonError",
    "NoTransectError",
    "NonConvexPolygonError",
    "PaperModel",
    "Polygon",
    "PolygonFileError",
    "Score",
    "Segments",
    "SmithFitness",
    "SmoothModel",
    "TransectLengths",
    "TransectModel",
    "__version__",
    "exact_chords",
    "halfplanes",
    "make_model",
    "paper_lengths",
    "score",
    "smith_fitness",
    "smooth_lengths",
    "smoothing_from_temperature",
    "temperature_from_smoothing",
    "transect_positions",
    "transect_segments",
]
