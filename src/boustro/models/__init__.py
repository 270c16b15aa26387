"""Transect-length models behind one interface: exact chords, paper sigmoids, smooth form."""

# ruff: noqa: F401 (private names are re-exported for the old import paths; __all__ is public)

from .._validate import MAX_TRANSECTS, check_finite, check_spacing
from .base import (
    MAX_CANDIDATES,
    PAPER_WINDOW,
    Chords,
    TransectLengths,
    TransectModel,
    _components,
    _grid,
    _prepare,
    _window_mask,
    grid_size,
    transect_positions,
)
from .exact import ChordBounds, ExactModel, chord_bounds, chords_at, exact_chords, line_chords
from .paper import (
    _BAND_MIN_WORK,
    MAX_POINTS_PER_TRANSECT,
    Method,
    PaperModel,
    Trapezoid,
    _as_temperature,
    paper_lengths,
    paper_line_lengths,
    paper_weights,
    trapezoid_scale,
)
from .paper_band import _Band, _band, _band_integrand, _band_tau, _Group, _group_points
from .paper_integral import (
    _TARGET,
    _chunks,
    _full_grads,
    _full_lengths,
    _items,
    _sigmoid_integrand,
    _SigmoidIntegral,
    _trapezoid_weights,
)
from .smooth import SmoothModel, smooth_lengths

__all__ = [
    "MAX_CANDIDATES",
    "MAX_POINTS_PER_TRANSECT",
    "MAX_TRANSECTS",
    "PAPER_WINDOW",
    "ChordBounds",
    "Chords",
    "ExactModel",
    "Method",
    "PaperModel",
    "SmoothModel",
    "TransectLengths",
    "TransectModel",
    "Trapezoid",
    "check_finite",
    "check_spacing",
    "chord_bounds",
    "chords_at",
    "exact_chords",
    "grid_size",
    "line_chords",
    "paper_lengths",
    "paper_line_lengths",
    "paper_weights",
    "smooth_lengths",
    "transect_positions",
    "trapezoid_scale",
]
