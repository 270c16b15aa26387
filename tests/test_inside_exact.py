"""Issue 16 (tenth round): four cuts in :mod:`boustro.plan.inside` that must not change a plan.
Each is checked bit for bit against the code it replaced (kept here as the reference): the
corner spurs cached per area (:meth:`inside._Geometry.spurs`), the lanes' intervals in the
shrunk area found for all lanes at once (:func:`inside._shrunk_intervals`), the runs of
pass segments near the residual found with arrays (:func:`inside._near`), and the pieces
kept without a negative buffer where their area shows a deep point
(:func:`boustro.plan.contour._pieces`)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
import shapely.affinity

from boustro.geometry.region import Region
from boustro.plan import inside
from boustro.plan.cells import _frame
from boustro.plan.contour import _corner_spurs, _pieces
from boustro.plan.lanes import region_lanes

from .conftest import random_regions
from .plan_samples import SPACING, scaled


def _areas() -> list[Region]:
    ell = [(0, 0), (120, 0), (120, 40), (50, 40), (50, 100), (0, 100)]
    quad = [(0, 0), (160, 10), (140, 90), (20, 120)]
    out = [Region(ell), Region(quad, [[(70, 30), (95, 35), (85, 60)]])]
    return out + [scaled(r, 150.0) for r in random_regions(23, 3, n_holes=(1, 2))]


def _layouts(region: Region, rng: np.random.Generator, n: int = 4):
    for _ in range(n):
        angle, offset = rng.uniform(0, math.pi), rng.uniform(0, SPACING)
        yield [region_lanes(region, SPACING, angle, offset, reach=SPACING / 2, holes=region.holes)]


def _intervals_before(lanes, inner):
    """:func:`inside._shrunk_intervals` as it was: part by part."""
    u, _ = _frame(lanes.angle)
    if len(lanes.k) == 0 or inner.is_empty:
        return [[] for _ in lanes.k]
    parts = shapely.intersection(shapely.linestrings(lanes.segments), inner)
    rows = []
    for g in parts:
        row = []
        for line in shapely.get_parts(g):
            if line.geom_type == "LineString" and not line.is_empty:
                t = (np.asarray(line.coords) - lanes.origin) @ u
                row.append((float(t.min()), float(t.max())))
        rows.append(row)
    return rows


def _near_before(lines, rest, far):
    """:func:`inside._near` as it was: segment by segment."""
    if not lines or rest.is_empty:
        return []
    segs = np.concatenate([np.stack([line[:-1], line[1:]], axis=1) for line in lines])
    owner = np.concatenate([np.full(len(line) - 1, i) for i, line in enumerate(lines)])
    keep = shapely.dwithin(shapely.linestrings(segs), rest, far)
    out = []
    for i, line in enumerate(lines):
        flags = keep[owner == i]
        d = np.diff(line, axis=0)
        norm = np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-300)
        back = np.einsum("ij,ij->i", d[:-1], d[1:]) / (norm[:-1] * norm[1:]) < -1 + 1e-9
        j = 0
        while j < len(flags):
            if not flags[j]:
                j += 1
                continue
            k = j
            while k + 1 < len(flags) and flags[k + 1] and not back[k]:
                k += 1
            out.append(line[j : k + 2])
            j = k + 1
    return out


def _same_lines(a, b):
    assert len(a) == len(b)
    for p, q in zip(a, b, strict=True):
        assert np.array_equal(p, q)


def test_shrunk_intervals_equal_part_by_part():
    rng = np.random.default_rng(5)
    rows = 0
    for region in _areas():
        inner = inside._geometry(region, SPACING).shrunk(SPACING / 2)
        for lanes in _layouts(region, rng):
            for ls in lanes:
                i, a, b = inside._shrunk_intervals(ls, inner)
                got = [[] for _ in ls.k]
                for lane, lo, hi in zip(i.tolist(), a.tolist(), b.tolist(), strict=True):
                    got[lane].append((lo, hi))
                assert got == _intervals_before(ls, inner)
                rows += sum(len(r) > 1 for r in got)
    assert rows > 0  # some lanes cross a bay or a hole: two intervals on one line


def _clip_before(lanes, area, tol, margin, spacing):
    """:func:`inside.clip_lanes` as it was before the fourteenth round: interval by interval,
    from the rows of :func:`_intervals_before` or of the line's chords."""
    from boustro.plan.lanes import Lanes, _intervals_on_lines

    u, n = _frame(lanes.angle)
    if margin > 0:
        rows = _intervals_before(lanes, inside._geometry(area, spacing).shrunk(margin))
    else:
        rows = _intervals_on_lines(area.edges - lanes.origin, u, n, lanes.c)
    k, c, t0, t1 = [], [], [], []
    for i, row in enumerate(rows):
        for a, b in row:
            lo, hi = max(a, float(lanes.t0[i])), min(b, float(lanes.t1[i]))
            if hi - lo > tol:
                k.append(int(lanes.k[i]))
                c.append(float(lanes.c[i]))
                t0.append(lo)
                t1.append(hi)
    return Lanes(lanes.angle, lanes.origin, np.array(k, dtype=np.int64),
                 np.array(c, dtype=np.float64), np.array(t0, dtype=np.float64),
                 np.array(t1, dtype=np.float64), lanes.cut)  # fmt: skip


@pytest.mark.parametrize("margin", [0.0, SPACING / 2, 3 * SPACING])
def test_clip_lanes_equal_the_loop_before(margin):
    """The lanes cut with arrays (fourteenth round) are the lanes the interval-by-interval loop
    cut, byte for byte (the layout cache's keys), at both margins and one past the area's
    width (nothing left); with parts dropped as shorter than ``tol`` (a huge one)."""
    rng = np.random.default_rng(11)
    split = dropped = 0
    for region in _areas():
        for lanes in _layouts(region, rng, 3):
            for ls in lanes:
                for tol in (1e-9 * region.diameter, 0.3 * SPACING):
                    got = inside.clip_lanes(ls, region, tol, margin, SPACING)
                    want = _clip_before(ls, region, tol, margin, SPACING)
                    assert got.angle == want.angle and got.cut == want.cut
                    for x, y in zip(got[2:6], want[2:6], strict=True):
                        assert x.dtype == y.dtype and x.tobytes() == y.tobytes()
                    split += len(np.unique(got.k)) < len(got.k)
                    dropped += len(want.k) < len(_clip_before(ls, region, 0.0, margin, SPACING).k)
    if margin < SPACING:
        assert split > 0 and dropped > 0  # lanes split by bays or holes; parts dropped by tol


def test_near_and_spurs_equal_the_code_before():
    """On the margin-1/2 residual of several layouts: the contour stretches' spurs (cached)
    equal :func:`_corner_spurs`, are read-only, and come from the cache on the second call;
    :func:`inside._near` equals the loop before, on the passes with spurs (runs split at the
    spurs' tips) and on lines with a single point in between."""
    rng = np.random.default_rng(8)
    hits = tips = 0
    for region in _areas():
        for lanes in _layouts(region, rng, 3):
            tol = 1e-9 * region.diameter
            half = [inside.clip_lanes(ls, region, tol, SPACING / 2, SPACING) for ls in lanes]
            geo, residual = inside._residual(region, half, SPACING, SPACING / 2)
            if residual is None:
                continue
            arcs = inside._contour_arcs(residual, SPACING / 2, tol, geo.contour, SPACING / 2)
            passes = []
            for line in arcs:
                before = len(geo._spurs)
                got = geo.spurs(line, SPACING / 2)
                hits += len(geo._spurs) == before
                assert not got.flags.writeable
                assert np.array_equal(got, _corner_spurs(line, geo.contour, SPACING / 2,
                                                         SPACING / 2, tol))  # fmt: skip
                assert geo.spurs(line.copy(), SPACING / 2) is got
                passes.append(got)
            tips += sum(len(p) for p in passes) - sum(len(a) for a in arcs)
            for far in (SPACING, SPACING / 4):
                _same_lines(inside._near(passes, residual, far),
                            _near_before(passes, residual, far))  # fmt: skip
            odd = [np.array([[0.0, 0.0], [1.0, 0.0]]), *passes, np.array([[1.0, 1.0]])]
            _same_lines(inside._near(odd, residual, SPACING),
                        _near_before(odd, residual, SPACING))  # fmt: skip
    assert tips > 0  # spurs were added, so _near split runs at their tips
    assert hits > 0  # a stretch met again in another layout came from the cache


@pytest.mark.parametrize("n", [0, 1])
def test_near_of_nothing(n):
    rest = shapely.box(0, 0, 1, 1)
    lines = [np.array([[5.0, 5.0], [6.0, 5.0]])] * n
    assert inside._near(lines, rest, 1.0) == _near_before(lines, rest, 1.0) == []
    assert _pieces(rest, 1e-7)


def _pieces_before(geometry, eps):
    """:func:`boustro.plan.contour._pieces` as it was: every polygon buffered."""
    polys = [g for g in shapely.get_parts(geometry) if g.geom_type == "Polygon" and not g.is_empty]
    if not polys:
        return []
    kept = ~shapely.is_empty(shapely.buffer(polys, -eps, quad_segs=16))
    return [g for g, ok in zip(polys, kept, strict=True) if ok]


def test_pieces_equal_the_buffered_test():
    """Residual-like collections: boxes, slivers a few eps thin (kept or not by the buffer),
    spikes, a ring, a line mixed in; the same pieces as buffering every one."""
    rng = np.random.default_rng(2)
    eps = 1e-7 * SPACING
    dropped = 0
    for _ in range(20):
        geoms = []
        for _ in range(12):
            x, y = rng.uniform(0, 100, 2)
            w = rng.choice([rng.uniform(0.1, 10), eps * rng.uniform(0.5, 4)])
            h = rng.uniform(eps, 20)
            box = shapely.box(x, y, x + w, y + h)
            geoms.append(shapely.affinity.rotate(box, rng.uniform(0, 180), origin=(x, y)))
        geoms.append(shapely.Polygon([(0, 0), (50, 0), (50, 3 * eps)]))  # a spike
        geoms.append(
            shapely.box(0, 0, 10, 10).difference(shapely.box(eps, eps, 10 - eps, 10 - eps))
        )
        geoms.append(shapely.LineString([(0, 0), (5, 5)]))
        collection = shapely.GeometryCollection(geoms)
        got = _pieces(collection, eps)
        want = _pieces_before(collection, eps)
        assert len(got) == len(want)
        dropped += len(shapely.get_parts(collection)) - 1 - len(got)  # the line is never kept
        assert all(shapely.equals_exact(a, b, 0.0) for a, b in zip(got, want, strict=True))
    assert dropped > 20  # slivers and the thin ring dropped, the rest kept
    assert _pieces(shapely.Polygon(), eps) == []


def test_pieces_keep_a_deep_piece_that_geos_erodes_away_at_utm_coordinates():
    """A review: at UTM-sized coordinates GEOS's ``buffer(-eps)`` of a valid piece 2.5e-4 m
    deep is empty for ``eps`` 2.5e-8 m (the buffered test dropped it, leaving it uncovered);
    the area rule keeps it, as it keeps the same piece moved to the origin."""
    piece = shapely.from_wkt(
        "POLYGON ((512346.5413830811 5412353.990505062, 512346.6981799225 5412353.987653996, "
        "512346.6986246743 5412353.987145826, 512346.5389255167 5412353.990049666, "
        "512346.5413830811 5412353.990505062))"
    )
    eps = 1e-7 * 0.25
    assert piece.is_valid and piece.exterior.distance(piece.centroid) > 1000 * eps
    moved = shapely.affinity.translate(piece, -512345, -5412345)
    assert len(_pieces(moved, eps)) == 1
    assert len(_pieces(piece, eps)) == 1


def test_the_spur_cache_is_bounded_by_its_points(monkeypatch):
    """A review: the cache was bounded by its count of stretches (1024 whole rings of a traced
    field per area); now by their points, the oldest forgotten, the answers the same."""
    monkeypatch.setattr(inside, "SPUR_CACHE", 60)
    monkeypatch.setattr(inside, "_GEOMETRIES", {})  # not an area another test filled
    region = next(iter(_areas()))
    rng = np.random.default_rng(3)
    tol = 1e-9 * region.diameter
    seen = 0
    for lanes in _layouts(region, rng, 4):
        half = [inside.clip_lanes(ls, region, tol, SPACING / 2, SPACING) for ls in lanes]
        geo, residual = inside._residual(region, half, SPACING, SPACING / 2)
        if residual is None:
            continue
        for line in inside._contour_arcs(residual, SPACING / 2, tol, geo.contour, SPACING / 2):
            got = geo.spurs(line, SPACING / 2)
            assert np.array_equal(got, _corner_spurs(line, geo.contour, SPACING / 2,
                                                     SPACING / 2, tol))  # fmt: skip
            kept = sum(k[1] + len(v) for k, v in geo._spurs.items())
            assert kept == geo._spur_points
            assert len(geo._spurs) == 1 or kept <= 60
            seen += 1
    assert seen > 0


@pytest.mark.parametrize("margin", [0.0, 1.0])
def test_clip_lanes_keep_the_chords_ends_on_ties_of_signed_zeros(margin):
    """A lane's end equal to its chord's end keeps the chord's (as ``max`` / ``min`` did): a
    lane from ``-0.0`` on a chord from ``0.0`` gives ``0.0``, byte for byte (np.maximum
    returns its second argument on ties)."""
    from boustro.plan.lanes import Lanes

    square = Region([(0, 0), (10, 0), (10, 4), (0, 4)])
    ls = Lanes(0.0, np.zeros(2), np.arange(2, dtype=np.int64), np.array([2.0, 3.0]),
               np.array([-0.0, 1.0]), np.array([10.0, 9.0]), frozenset())  # fmt: skip
    if margin > 0:  # the shrunk square's chords start at x = 1: the origin there
        ls = ls._replace(origin=np.array([1.0, 0.0]), c=np.array([2.0, 2.5]))
    got = inside.clip_lanes(ls, square, 1e-9, margin, 2.0)
    want = _clip_before(ls, square, 1e-9, margin, 2.0)
    for x, y in zip(got[2:6], want[2:6], strict=True):
        assert x.tobytes() == y.tobytes()
