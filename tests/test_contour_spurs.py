"""The contour's corner spurs and the residual's slivers, computed in bulk
(:func:`boustro.plan.contour._corner_spurs`, :func:`boustro.plan.contour._pieces`), against the
one-by-one computations they replaced (issue 16: the same plans, faster)."""

from __future__ import annotations

import math

import numpy as np
import shapely

from boustro.plan.contour import _corner_spurs, _pieces, contour_of


def _spurs_one_by_one(line, contour, half, reach, tol):
    corners, first, grown = contour.corners, contour.first, contour.grown
    d = shapely.distance(contour.corner_points, shapely.LineString(line))
    pick = (d > reach * (1 + 1e-9)) & (d < 4 * half)
    spurs: dict[int, list] = {}
    for i in np.flatnonzero(pick)[np.isin(np.flatnonzero(pick), first)]:
        c = corners[i]
        j = int(np.argmin(np.linalg.norm(line - c, axis=1)))
        v = line[j]
        gap = float(np.linalg.norm(v - c))
        if gap <= half or gap > d[i] * (1 + 1e-6) + tol:
            continue
        p = c + (v - c) / gap * (half * (1 - 1e-3))
        if grown.covers(shapely.LineString([v, p])):
            spurs.setdefault(j, []).extend([p, v])
    if not spurs:
        return line
    parts = []
    for j, point in enumerate(line):
        parts.append(point[None])
        if j in spurs:
            parts.append(np.asarray(spurs[j]))
    return np.concatenate(parts)


def _star(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    a = np.sort(rng.uniform(0, 2 * math.pi, n))
    r = 100 * (1 + 0.4 * np.sin(3 * a)) * rng.uniform(0.85, 1.0, n)
    return np.stack([r * np.cos(a), r * np.sin(a)], axis=1)


def test_corner_spurs_bulk_equals_one_by_one():
    spurs = 0
    for seed in range(4):
        hole = shapely.Point(10, 5).buffer(20, quad_segs=3)
        target = shapely.Polygon(_star(60, seed), [hole.exterior.coords[::-1]])
        half, reach, tol = 5.0, 5.0, 1e-9 * 300
        contour = contour_of(target, half, tol)
        for ring in contour.rings:
            for a, b in [(0, len(ring.v)), (0, len(ring.v) // 3), (len(ring.v) // 2, len(ring.v))]:
                line = ring.v[a:b]
                if len(line) < 2:
                    continue
                got = _corner_spurs(line, contour, half, reach, tol)
                want = _spurs_one_by_one(line, contour, half, reach, tol)
                assert got.shape == want.shape and np.array_equal(got, want)
                spurs += len(got) - len(line)
    assert spurs > 0  # the comparison saw spurs


def test_pieces_bulk_equals_one_by_one():
    square = shapely.box(0, 0, 10, 10)
    sliver = shapely.box(20, 0, 30, 1e-9)
    thin = shapely.box(40, 0, 50, 1e-3)
    geom = shapely.MultiPolygon([square, sliver, thin])
    eps = 1e-6
    got = _pieces(geom, eps)
    want = [g for g in shapely.get_parts(geom) if not g.buffer(-eps).is_empty]
    assert [g.wkb for g in got] == [g.wkb for g in want]
    assert len(got) == 2  # the sliver is dropped, the 1 mm strip kept
    assert _pieces(shapely.Polygon(), eps) == []
