"""Certified minimum of a flown plan's cost (mission time, turns, path) over (angle, offset),
on any area: convex or concave, with holes (:func:`cover_optimum`)."""

from .bands import BandStats, EdgeSet, band_stats, edge_set
from .bounds import lower_bounds
from .cost import COVER_OBJECTIVES, CoverCost
from .plans import centred_offsets
from .sandwich import Sandwich
from .search import cover_optimum

__all__ = [
    "COVER_OBJECTIVES",
    "BandStats",
    "CoverCost",
    "EdgeSet",
    "Sandwich",
    "band_stats",
    "centred_offsets",
    "cover_optimum",
    "edge_set",
    "lower_bounds",
]
