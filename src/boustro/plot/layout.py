"""Plot a transect layout: the polygon, its transects in driving order, the turns between them."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..errors import InvalidParameterError
from ..geometry import Polygon
from ..scoring import Segments, as_polygon

__all__ = ["plot_layout"]


def _segment_array(segments: Segments | ArrayLike) -> np.ndarray:
    seg = segments.segments if isinstance(segments, Segments) else segments
    arr = np.asarray(seg, dtype=np.float64)
    if arr.size == 0:
        return np.zeros((0, 2, 2))
    if arr.ndim != 3 or arr.shape[1:] != (2, 2):
        raise InvalidParameterError(
            f"expected segments of shape (T, 2, 2) (start and end of each transect), "
            f"got shape {arr.shape}"
        )
    return arr


def plot_layout(
    polygon: Polygon | ArrayLike,
    segments: Segments | ArrayLike,
    ax: Any = None,
    *,
    turns: bool = True,
    start: bool = True,
    title: str | None = None,
    polygon_kwargs: dict[str, Any] | None = None,
    transect_kwargs: dict[str, Any] | None = None,
    turn_kwargs: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Draw a polygon and a layout of transects, in the polygon's units, with equal axes.

    Args:
        polygon: the polygon (a :class:`~boustro.geometry.Polygon` or ``(N, 2)`` vertices).
        segments: the transects, a :class:`~boustro.scoring.Segments` (e.g.
            ``boustro.score(...).layout``) or an array ``(T, 2, 2)`` of ``[start, end]`` in
            driving order.
        ax: matplotlib axes to draw on (default: the current axes of pyplot).
        turns: draw the turns joining the end of each transect to the start of the next.
        start: mark the start of the first transect.
        title: axes title (none by default).
        polygon_kwargs, transect_kwargs, turn_kwargs: styles passed to matplotlib, overriding
            the defaults.

    Returns:
        The artists, by name: ``"polygon"`` (a Polygon patch), ``"transects"`` (a
        LineCollection), and where drawn ``"turns"`` (a LineCollection) and ``"start"`` (a
        Line2D).
    """
    from matplotlib.collections import LineCollection
    from matplotlib.patches import Polygon as PolygonPatch

    if ax is None:
        import matplotlib.pyplot as plt

        ax = plt.gca()
    poly = as_polygon(polygon)
    seg = _segment_array(segments)
    artists: dict[str, Any] = {}
    style = {"facecolor": "#dbe9f6", "edgecolor": "#1f4e79", "linewidth": 1.5, "zorder": 1}
    artists["polygon"] = ax.add_patch(
        PolygonPatch(poly.vertices, closed=True, **{**style, **(polygon_kwargs or {})})
    )
    style = {"colors": "#c0392b", "linewidths": 1.8, "zorder": 3}
    artists["transects"] = ax.add_collection(
        LineCollection(list(seg), **{**style, **(transect_kwargs or {})})
    )
    if turns and len(seg) > 1:
        joins = np.stack([seg[:-1, 1], seg[1:, 0]], axis=1)
        style = {"colors": "#7f8c8d", "linewidths": 1.0, "linestyles": "dashed", "zorder": 2}
        artists["turns"] = ax.add_collection(
            LineCollection(list(joins), **{**style, **(turn_kwargs or {})})
        )
    if start and len(seg):
        (artists["start"],) = ax.plot(
            seg[0, 0, 0], seg[0, 0, 1], marker="o", color="#27ae60", zorder=4, linestyle=""
        )
    points = np.concatenate([poly.vertices, seg.reshape(-1, 2)])
    lo, hi = points.min(axis=0), points.max(axis=0)
    pad = 0.05 * float(np.max(hi - lo))
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")
    if title is not None:
        ax.set_title(title)
    return artists
