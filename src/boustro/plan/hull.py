"""Nearly convex areas: the convex hull and how far it reaches beyond the polygon."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import (
    NonConvexPolygonError,
)
from ..geometry import Polygon
from ..scoring import as_polygon

if TYPE_CHECKING:
    pass

from .convex import _check_nonnegative

__all__ = [
    "convex_hull",
    "hull_depth",
    "nearly_convex",
]


# -- nearly convex areas ----------------------------------------------------------------------
def convex_hull(points: ArrayLike) -> NDArray[np.float64]:
    """Counter-clockwise convex hull ``(H, 2)`` of points ``(N, 2)`` (monotone chain)."""
    pts = np.unique(np.asarray(points, dtype=np.float64).reshape(-1, 2), axis=0)  # sorted

    def half(seq: NDArray[np.float64]) -> list[NDArray[np.float64]]:
        out: list[NDArray[np.float64]] = []
        for p in seq:
            while len(out) >= 2:
                a, b = out[-2], out[-1]
                if (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]) > 0:
                    break
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(pts[::-1])
    return np.array(lower[:-1] + upper[:-1])


def hull_depth(polygon: Polygon | ArrayLike) -> float:
    """How far the convex hull reaches beyond the polygon: the depth of its deepest pocket.

    For each hull edge that is not an edge of the polygon (the lid of a pocket), the largest
    distance from the lid's line of the polygon vertices it skips. Every point of the hull lies
    within this distance of the polygon, so transects planned on the hull leave the polygon by
    at most this much. 0 for a convex polygon.
    """
    poly = as_polygon(polygon)
    if poly.is_convex:
        return 0.0
    v = poly.vertices
    hull = convex_hull(v)
    where = {tuple(p): i for i, p in enumerate(v)}
    idx = [where[tuple(p)] for p in hull]
    depth = 0.0
    n = len(v)
    for a, b in zip(idx, idx[1:] + idx[:1], strict=True):
        skipped = [(a + k) % n for k in range(1, (b - a) % n)]
        if not skipped:
            continue
        p, q = v[a], v[b]
        lid = q - p
        dist = np.abs(lid[0] * (v[skipped, 1] - p[1]) - lid[1] * (v[skipped, 0] - p[0]))
        depth = max(depth, float(dist.max() / np.linalg.norm(lid)))
    return depth


def nearly_convex(polygon: Polygon | ArrayLike, tolerance: float) -> tuple[Polygon, float]:
    """The polygon itself if convex, else its convex hull if no pocket is deeper than tolerance.

    Real parcels are often convex but for digitising noise (the shipped field is 0.999 of its
    hull, with pockets 0.3 m deep). Planning the hull covers the polygon (it contains it), and
    the transects leave the polygon by at most the returned depth.

    Returns:
        ``(polygon to plan, depth)``.

    Raises:
        NonConvexPolygonError: a pocket is deeper than ``tolerance`` (units of the polygon).
    """
    poly = as_polygon(polygon)
    tolerance = _check_nonnegative("hull tolerance", tolerance)
    if poly.is_convex:
        return poly, 0.0
    depth = hull_depth(poly)
    if depth <= tolerance:
        return Polygon(convex_hull(poly.vertices)), depth
    try:
        poly.require_convex("a boustrophedon plan")
    except NonConvexPolygonError as exc:
        raise NonConvexPolygonError(
            f"{exc}; its convex hull reaches {depth:.3g} beyond it, more than the hull "
            f"tolerance {tolerance:g} (plan it as a concave area: boustro.decompose.plan_region)"
        ) from None
    raise AssertionError("unreachable")  # pragma: no cover
