"""The contour passes of a ``keep_inside`` plan (:mod:`boustro.plan.inside`): the boundary of
the area shrunk by half a spacing, the stretches of it that the lanes need, and a spur into
every convex corner of the area that it does not reach. Shapely is imported inside the
functions."""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

__all__ = ["MERGE_GAP", "Contour"]


class _Ring(NamedTuple):
    """One ring of the contour: its points ``v``, their arc lengths ``at``, its length, and
    the samples (every quarter spacing at most) tested against the residual."""

    v: NDArray[np.float64]
    at: NDArray[np.float64]
    total: float
    samples: Any  # shapely points


class Contour(NamedTuple):
    """What :func:`_contour_arcs` needs of an area that does not depend on the lanes (built
    once per area and spacing by :func:`contour_of`): the contour's rings, the area's corners
    and the area grown by ``tol`` (the spurs' test)."""

    rings: list[_Ring]
    corners: NDArray[np.float64]
    corner_points: Any  # shapely points
    first: NDArray[np.int64]  # the first occurrence of each distinct corner
    grown: Any


def contour_of(target: Any, half: float, tol: float) -> Contour:
    """The contour of the shapely area ``target``: the boundary of it shrunk by ``half``,
    without its slivers (a strip exactly a spacing wide shrinks to one), sampled."""
    import shapely

    inner = shapely.union_all(_pieces(target.buffer(-half, quad_segs=8), 1e-7 * half))
    rings = []
    if not inner.is_empty:
        step = half / 2
        for ring in shapely.get_parts(shapely.boundary(inner)):
            v = np.asarray(ring.coords, dtype=np.float64)
            if len(v) < 4:
                continue
            at = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(v, axis=0), axis=1))])
            total = float(at[-1])
            n = max(8, math.ceil(total / step))
            s = np.linspace(0.0, total, n + 1)[:-1]
            pts = np.stack([np.interp(s, at, v[:, 0]), np.interp(s, at, v[:, 1])], axis=1)
            rings.append(_Ring(v, at, total, shapely.points(pts)))
    corners = shapely.get_coordinates(shapely.boundary(target))
    _, first = np.unique(corners, axis=0, return_index=True)
    grown = target.buffer(tol, join_style="mitre")
    shapely.prepare(grown)
    return Contour(rings, corners, shapely.points(corners), first, grown)


def _pieces(geometry: Any, eps: float) -> list[Any]:
    """The polygons of ``geometry`` that are more than a rounding sliver (they survive a
    negative buffer of ``eps``)."""
    import shapely

    parts = shapely.get_parts(geometry)
    polys = parts[(shapely.get_type_id(parts) == 3) & ~shapely.is_empty(parts)]
    if not len(polys):
        return []
    # within eps of the boundary of a polygon with n vertices and perimeter P lies at most
    # eps (P + pi n eps) of its area (the offset curves are at most that long): a polygon of
    # twice that area has points deeper than eps, its buffer(-eps) is not empty; the others
    # are buffered (as g.buffer(-eps))
    n = shapely.get_num_coordinates(polys)
    kept = shapely.area(polys) > 2 * eps * (shapely.length(polys) + math.pi * n * eps)
    test = np.flatnonzero(~kept)
    if len(test):
        kept[test] = ~shapely.is_empty(shapely.buffer(polys[test], -eps, quad_segs=16))
    return list(polys[kept])


def _lines(geometry: Any, tol: float) -> list[NDArray[np.float64]]:
    """The line parts of ``geometry`` (merged where they meet) longer than ``tol``, as arrays."""
    import shapely

    merged = shapely.line_merge(geometry) if geometry.geom_type == "MultiLineString" else geometry
    out = []
    for g in shapely.get_parts(merged):
        if g.geom_type in ("LineString", "LinearRing") and g.length > tol:
            out.append(np.asarray(g.coords, dtype=np.float64))
    return out


def _contour_arcs(
    residual: Any,
    reach: float,
    tol: float,
    contour: Contour,
    half: float,
    known: list[NDArray[np.bool_]] | None = None,
) -> list[NDArray[np.float64]]:
    """The parts of the contour (:func:`contour_of`: the area's boundary shrunk by
    ``half``) within reach of the uncovered ``residual``: each covers its side of the residual
    near the boundary (a point within ``half`` of the boundary and in a disk of radius ``half``
    inside the area is within ``half`` of the contour). Each ring is sampled every ``half / 2``;
    a stretch between two samples is kept when both are within ``reach`` plus the step of the
    residual (so every needed point is kept), and kept stretches less than :data:`MERGE_GAP`
    spacings apart are driven as one pass. The passes are these stretches with their corner
    spurs (:func:`_corner_spurs`, which only add length: a spur leaves the contour and comes
    back to the same point). ``known`` (per ring): samples already known to be within reach
    plus the step of the residual (:func:`~boustro.plan.margin_floor.kept_samples`), not
    tested again."""
    import shapely

    if not contour.rings:
        return []
    shapely.prepare(residual)
    out: list[NDArray[np.float64]] = []
    for i, ring in enumerate(contour.rings):
        v, at, total = ring.v, ring.at, ring.total
        n = len(ring.samples)
        s = np.linspace(0.0, total, n + 1)[:-1]
        if known is None:
            near = shapely.dwithin(ring.samples, residual, reach + total / n)  # prepared
        else:
            near = known[i].copy()
            rest = np.flatnonzero(~near)
            near[rest] = shapely.dwithin(ring.samples[rest], residual, reach + total / n)
        runs = _runs(near, s, total, MERGE_GAP * 2 * half)
        if runs is None:
            out.append(v)
            continue
        for a, b in runs:
            out.append(_arc(v, at, a, b))
    return [line for line in out if np.linalg.norm(np.diff(line, axis=0), axis=1).sum() > tol]


def _corner_spurs(
    line: NDArray[np.float64], contour: Contour, half: float, reach: float, tol: float
) -> NDArray[np.float64]:
    """``line`` (a contour part) with a spur into every convex corner of the area it does not
    reach: from the contour's corner ``V`` towards the area's corner ``C`` to the point ``P``
    half a spacing short of it and back. The swath of ``V -> P`` covers the corner (every point
    between ``C``, ``V`` and the feet of ``V`` on the two edges is within half a spacing of
    it); the spur is ``|VC| - spacing / 2`` long, millimetres at an obtuse corner, where a
    patch of its own would cost a move there and back."""
    import shapely

    corners, first, grown = contour.corners, contour.first, contour.grown
    d = shapely.distance(contour.corner_points, shapely.LineString(line))
    pick = (d > reach * (1 + 1e-9)) & (d < 4 * half)
    spurs: dict[int, list[NDArray[np.float64]]] = {}
    idx = np.flatnonzero(pick)
    idx = idx[np.isin(idx, first)]
    if not len(idx):
        return line
    # each corner's nearest contour point, all at once (the same norms as one by one)
    near = np.argmin(np.linalg.norm(line[None] - corners[idx][:, None], axis=2), axis=1)
    found = []
    for i, j in zip(idx, near, strict=True):
        c, v = corners[i], line[j]
        gap = float(np.linalg.norm(v - c))
        if gap <= half or gap > d[i] * (1 + 1e-6) + tol:  # V must be the contour's corner
            continue
        found.append((int(j), v, c + (v - c) / gap * (half * (1 - 1e-3))))  # C inside the swath
    if found:
        legs = np.array([[v, p] for _, v, p in found])
        for (j, v, p), ok in zip(
            found, shapely.covers(grown, shapely.linestrings(legs)), strict=True
        ):
            if ok:
                spurs.setdefault(j, []).extend([p, v])
    if not spurs:
        return line
    parts = []
    for j, point in enumerate(line):
        parts.append(point[None])
        if j in spurs:
            parts.append(np.asarray(spurs[j]))
    return np.concatenate(parts)


#: Kept stretches of a contour closer than this many spacings along it are driven as one pass.
MERGE_GAP = 2.0


def _runs(
    flag: NDArray[np.bool_], s: NDArray[np.float64], total: float, gap: float
) -> list[tuple[float, float]] | None:
    """The stretches ``(a, b)`` (arc length; ``b`` may pass ``total``: round the ring) between
    flagged samples at ``s`` of a ring, neighbouring flagged samples joined, stretches closer
    than ``gap`` merged; ``None`` for the whole ring."""
    n = len(flag)
    if flag.all():
        return None
    first = int(np.argmin(flag))  # start the scan at an unflagged sample
    idx = (np.arange(n) + first) % n
    pos = s[idx] + np.where(idx < first, total, 0.0)
    runs: list[list[float]] = []
    i = 0
    while i < n:
        if not flag[idx[i]]:
            i += 1
            continue
        j = i
        while j + 1 < n and flag[idx[j + 1]]:
            j += 1
        a = pos[i - 1]  # the unflagged neighbours bound the stretch
        b = pos[j + 1] if j + 1 < n else pos[0] + total
        if runs and a - runs[-1][1] < gap:
            runs[-1][1] = b
        else:
            runs.append([a, b])
        i = j + 1
    if len(runs) > 1 and runs[0][0] + total - runs[-1][1] < gap:
        runs[0][0] = runs.pop()[0] - total
    if any(b - a >= total for a, b in runs):
        return None
    return [(a, b) for a, b in runs]


def _arc(
    v: NDArray[np.float64], at: NDArray[np.float64], a: float, b: float
) -> NDArray[np.float64]:
    """The part of the closed polyline ``v`` (arc lengths ``at``) from ``a`` to ``b``."""
    total = float(at[-1])
    ring_at = np.concatenate([at[:-1] - total, at[:-1], at[:-1] + total, [2 * total]])
    ring_v = np.concatenate([v[:-1], v[:-1], v[:-1], v[:1]])
    inner = (ring_at > a) & (ring_at < b)

    def point(x: float) -> NDArray[np.float64]:
        return np.array([np.interp(x, ring_at, ring_v[:, 0]), np.interp(x, ring_at, ring_v[:, 1])])

    return np.concatenate([point(a)[None], ring_v[inner], point(b)[None]])
