"""Shapes: validated polygons, the normalised frame, half-planes, regions with holes."""

# ruff: noqa: F401 (private names are re-exported for the old import paths; __all__ is public)

from .halfplanes import PAD_OFFSET, HalfPlanes, halfplanes, paper_eq2_halfplanes
from .polygon import (
    COORDINATE_LIMIT,
    MIN_RELATIVE_EXTENT,
    RELATIVE_TOLERANCE,
    Frame,
    Polygon,
    _as_vertex_array,
    _cross,
    _drop_collinear,
    _drop_duplicates,
    as_polygon,
    rotation_matrix,
)
from .random import random_convex_polygon
from .region import (
    TOUCH_TOLERANCE,
    Region,
    as_region,
    points_in_ring,
    random_region,
    segment_distances,
)
from .shapes import PAPER_PARALLELOGRAM, PAPER_SPACING

__all__ = [
    "COORDINATE_LIMIT",
    "MIN_RELATIVE_EXTENT",
    "PAD_OFFSET",
    "PAPER_PARALLELOGRAM",
    "PAPER_SPACING",
    "RELATIVE_TOLERANCE",
    "TOUCH_TOLERANCE",
    "Frame",
    "HalfPlanes",
    "Polygon",
    "Region",
    "as_polygon",
    "as_region",
    "halfplanes",
    "paper_eq2_halfplanes",
    "points_in_ring",
    "random_convex_polygon",
    "random_region",
    "rotation_matrix",
    "segment_distances",
]
