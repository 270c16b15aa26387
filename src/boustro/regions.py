"""Compatibility path: ``boustro.regions`` re-exports :mod:`boustro.geometry.region` (the
regions), :mod:`boustro.models.region` and ``region_soft`` (their models) and
:mod:`boustro.optimize.region_grid` (their grid evaluation)."""

# ruff: noqa: F401 (private names are re-exported for the old import paths; __all__ is public)

from .geometry.polygon import _cross
from .geometry.region import (
    TOUCH_TOLERANCE,
    Region,
    _as_polygon,
    _check_holes,
    _point_segment_distance,
    _ring_segments,
    as_region,
    points_in_ring,
    random_region,
    segment_distances,
)
from .models.region import (
    Per,
    RegionEdges,
    RegionExactModel,
    RegionSegments,
    _as_tensors,
    _project,
    _segments_at,
    region_edges,
    region_segments,
    segment_moments,
)
from .models.region_soft import (
    RegionSoftModel,
    _check_smoothing,
    _g,
    _Trapezoids,
    _trapezoids,
    soft_indicator,
    soft_region_lengths,
)
from .optimize.region_grid import _CHUNK_CROSSINGS, evaluate_region_grid

__all__ = [
    "TOUCH_TOLERANCE",
    "Region",
    "RegionEdges",
    "RegionExactModel",
    "RegionSegments",
    "RegionSoftModel",
    "as_region",
    "evaluate_region_grid",
    "points_in_ring",
    "random_region",
    "region_edges",
    "region_segments",
    "segment_distances",
    "segment_moments",
    "soft_indicator",
    "soft_region_lengths",
]
