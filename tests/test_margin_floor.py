"""The floor of margin 0's contour stretches (:mod:`boustro.plan.margin_floor`): below the
stretches its residual keeps, on one and two lane directions, and
:func:`boustro.plan.inside.inside_layout` makes the same choice with and without it."""

from __future__ import annotations

import math

import numpy as np

from boustro.geometry.region import Region
from boustro.plan import inside, margin_floor
from boustro.plan.contour import _contour_arcs
from boustro.plan.lanes import Lanes, region_lanes

from .plan_samples import SPACING, inside_areas

REACH = SPACING / 2


def _areas() -> list[Region]:
    return inside_areas(31, 3)


def _lanes(region: Region, layouts: list[tuple[float, float]]) -> list:
    """One grid of lanes per layout over the whole area (two: two directions crossing)."""
    return [
        region_lanes(region, SPACING, a, d, reach=REACH, holes=region.holes) for a, d in layouts
    ]


def _cases() -> list[tuple[Region, list]]:
    rng = np.random.default_rng(5)
    out = []
    for region in _areas():
        out.append((region, _lanes(region, [(0.0, SPACING / 2)])))
        for _ in range(4):
            layout = (rng.uniform(0, math.pi), rng.uniform(0, SPACING))
            out.append((region, _lanes(region, [layout])))
        two = [(rng.uniform(0, math.pi), rng.uniform(0, SPACING)) for _ in range(2)]
        out.append((region, _lanes(region, two)))
    # a decomposed plan's lanes: each cell of the L its own direction, over the whole L
    ell = _areas()[1]
    cells = [
        Region([(0, 0), (120, 0), (120, 40), (0, 40)]),
        Region([(0, 40), (50, 40), (50, 100), (0, 100)]),
    ]
    for a in (0.0, 0.4):
        grids = [(cells[0], a), (cells[1], a + math.pi / 2)]
        lanes = [region_lanes(c, SPACING, g, 1.0, reach=REACH) for c, g in grids]
        out.append((ell, lanes))
    return out


def _stretches(region: Region, cut: list) -> float:
    """The length of the contour stretches margin 0's residual keeps (0: none)."""
    geo, residual = inside._residual(region, cut, SPACING, REACH)
    if residual is None:
        return 0.0
    arcs = _contour_arcs(residual, REACH, geo.tol, geo.contour, SPACING / 2)
    return sum(float(np.linalg.norm(np.diff(a, axis=0), axis=1).sum()) for a in arcs)


def test_the_floor_is_below_the_stretches_and_near_them():
    shares = []
    for region, lanes in _cases():
        tol = 1e-9 * region.diameter
        cut = [inside.clip_lanes(ls, region, tol, 0.0, SPACING) for ls in lanes]
        floor, points = inside._geometry(region, SPACING).stretch_floor(cut, REACH)
        true = _stretches(region, cut)
        assert floor <= true, (floor, true)
        assert points > 0
        if true > 0:
            shares.append(floor / true)
    # it bounds most of them (the test points lie along the boundary, where the lanes' ends
    # leave the triangles): margin 0 is screened on it
    assert len(shares) >= 30
    assert np.median(shares) > 0.6


def test_a_covered_area_has_no_floor():
    # lanes along a rectangle four spacings high whose bands tile it exactly: nothing is left
    h = 4 * SPACING
    region = Region([(0, 0), (100, 0), (100, h), (0, h)])
    lanes = _lanes(region, [(0.0, SPACING / 2)])  # lines half a spacing from the bottom on
    tol = 1e-9 * region.diameter
    cut = [inside.clip_lanes(ls, region, tol, 0.0, SPACING) for ls in lanes]
    assert _stretches(region, cut) == 0.0
    assert inside._geometry(region, SPACING).stretch_floor(cut, REACH)[0] == 0.0
    # at 45 degrees the lanes' ends leave triangles along every edge
    slant = _lanes(region, [(math.pi / 4, 0.0)])
    cut = [inside.clip_lanes(ls, region, tol, 0.0, SPACING) for ls in slant]
    floor = inside._geometry(region, SPACING).stretch_floor(cut, REACH)[0]
    assert 0.0 < floor <= _stretches(region, cut)


def test_the_test_points_lie_within_reach_of_their_samples_and_deep_enough(monkeypatch):
    # convex and reflex corners and a hole: points near corners are dropped
    region = Region(
        [(0, 0), (200, 0), (200, 60), (100, 20), (0, 60)], [[(20, 10), (40, 10), (30, 20)]]
    )
    geo = inside._Geometry(region, SPACING)
    # some too far; some between reach + step and reach + 2 step (a check a step too loose)
    monkeypatch.setattr(margin_floor, "ALONG", tuple(np.linspace(-1.5, 1.5, 61)))
    tests = margin_floor.test_points(geo.target, geo.contour.rings, SPACING, REACH)
    import shapely

    boundary = shapely.boundary(geo.target)
    for ring, t in zip(geo.contour.rings, tests, strict=True):
        q = shapely.get_coordinates(ring.samples)[t.sample]
        assert len(t.points) > 0 and t.n == len(ring.samples)
        assert np.all(np.linalg.norm(t.points - q, axis=1) <= REACH + t.step)
        depth = shapely.distance(shapely.points(t.points), boundary)
        assert np.all(depth >= margin_floor.DEPTH * SPACING)
        assert np.all(shapely.contains_xy(geo.target, t.points[:, 0], t.points[:, 1]))


def test_the_disks_of_uncovered_test_points_miss_every_footprint():
    # the argument's step: a test point the boxes test calls uncovered has its disk (radius
    # DEPTH spacings) outside the lanes' footprints (inside._lane_footprint, as the residual)
    import shapely

    depth = margin_floor.DEPTH * SPACING
    near = 0
    for region, lanes in _cases():
        tol = 1e-9 * region.diameter
        cut = [inside.clip_lanes(ls, region, tol, 0.0, SPACING) for ls in lanes]
        cut = [ls for ls in cut if len(ls.k)]
        segments = np.concatenate([ls.segments for ls in cut])
        angles = np.concatenate([np.full(len(ls.k), ls.angle) for ls in cut])
        foot = inside._lane_footprint(segments, angles, region.centre, REACH, SPACING)
        geo = inside._geometry(region, SPACING)
        geo.stretch_floor(cut, REACH)  # its test points built
        for ring in geo._tests[REACH]:
            free = margin_floor._uncovered(ring.points, cut, REACH + depth, depth)
            d = shapely.distance(shapely.points(ring.points), foot)
            assert np.all(d[free] >= depth * (1 - 1e-9)), d[free].min() / depth
            assert np.all(d[~free] < 2 * depth)  # covered: in a box grown by the depth
            near += int(np.sum(free & (d < 2 * depth)))
    assert near > 0  # some uncovered points lie within two depths of a footprint


def test_a_test_point_within_its_depth_of_a_box_keeps_no_sample():
    # one lane along x, 100 long, reach 5; spacing 10: test points' depth 0.2. Each pair: a
    # point inside the box grown by the depth (across, past either end), then one outside
    lane = Lanes(
        0.0,
        np.zeros(2),
        np.array([0]),
        np.array([0.0]),
        np.array([0.0]),
        np.array([100.0]),
        frozenset(),
    )
    pts = [(50, 5.1), (50, 5.3), (50, -5.1), (50, -5.3), (100.1, 0), (100.3, 0)]
    pts += [(-0.1, 1), (-0.3, 1)]
    tests = [margin_floor.RingTests(np.array(pts, dtype=float), np.arange(8), 8, 1.0)]
    kept = margin_floor.kept_samples(tests, [lane], 5.0, 10.0)[0]
    assert kept.tolist() == [False, True] * 4


def _dense_uncovered(points, lanes, across, grow):
    """margin_floor._uncovered's predicate, every point against every lane."""
    free = np.ones(len(points), dtype=bool)
    for ls in lanes:
        u = np.array([math.cos(ls.angle), math.sin(ls.angle)])
        n = np.array([-u[1], u[0]])
        t, c = (points - ls.origin) @ u, (points - ls.origin) @ n
        hit = (
            (np.abs(c[:, None] - ls.c[None, :]) <= across)
            & (t[:, None] >= ls.t0[None, :] - grow)
            & (t[:, None] <= ls.t1[None, :] + grow)
        ).any(axis=1)
        free &= ~hit
    return free


def _random_lanes(rng, count, angle):
    """``count`` lanes on 40 lines at ``angle``, some lines with two, in no order."""
    k = rng.integers(-20, 20, count)
    t0 = rng.uniform(-50, 40, count)
    t1 = t0 + rng.uniform(0.5, 30, count)
    return Lanes(angle, rng.uniform(-5, 5, 2), k, 0.3 + 9.0 * k, t0, t1, frozenset())


def test_the_boxes_test_of_the_lanes_near_each_point_is_the_test_of_all():
    rng = np.random.default_rng(8)
    for _ in range(20):
        lanes = [_random_lanes(rng, 60, rng.uniform(0, math.pi)) for _ in range(2)]
        across, grow = rng.uniform(4.5, 12), rng.uniform(0, 1)
        pts = rng.uniform(-60, 60, (500, 2))
        # points on the grown boxes' sides and ends (in the first lanes' frame)
        ls = lanes[0]
        u = np.array([math.cos(ls.angle), math.sin(ls.angle)])
        n = np.array([-u[1], u[0]])
        mid = ((ls.t0 + ls.t1) / 2)[:, None] * u
        left = ls.origin + (ls.c + across)[:, None] * n + mid
        right = ls.origin + (ls.c - across)[:, None] * n + mid
        end = ls.origin + ls.c[:, None] * n + (ls.t1 + grow)[:, None] * u
        pts = np.concatenate([pts, left, right, end])
        want = _dense_uncovered(pts, lanes, across, grow)
        assert np.array_equal(margin_floor._uncovered(pts, lanes, across, grow), want)
        assert 0 < want.sum() < len(pts)


def test_the_boxes_test_takes_memory_of_points_plus_lanes():
    # 4000 points against 4000 lanes: 128 MB each of the all-pairs test's arrays
    import tracemalloc

    rng = np.random.default_rng(9)
    k = np.arange(4000)
    lanes = [Lanes(0.1, np.zeros(2), k, 9.0 * k, np.zeros(4000), np.full(4000, 50.0), frozenset())]
    pts = np.stack([rng.uniform(-10, 60, 4000), rng.uniform(0, 36000, 4000)], axis=1)
    tracemalloc.start()
    try:
        margin_floor._uncovered(pts, lanes, 4.68, 0.18)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 16e6, peak


def test_the_area_rule_gives_no_floor_where_a_kept_piece_is_not_sure():
    region = Region([(0, 0), (100, 0), (100, 100), (0, 100)])
    cut = [
        inside.clip_lanes(ls, region, 1e-9 * region.diameter, 0.0, SPACING)
        for ls in _lanes(region, [(0.3, 1.0)])
    ]
    geo = inside._geometry(region, SPACING)
    assert geo.stretch_floor(cut, REACH)[0] > 0
    tests = geo._tests[REACH]
    # a perimeter this long would let the residual's polygons be slivers (_pieces' area rule)
    assert margin_floor.stretch_floor(tests, cut, REACH, SPACING, 1e12, 4) == 0.0
    assert margin_floor.stretch_floor(tests, cut, REACH, SPACING, 400.0, 4) > 0


def _layouts(monkeypatch, floor_on: bool) -> tuple[list, int]:
    """Every case's inside_layout (bytes) and how many residuals it computed."""
    residuals = []
    real = inside._residual

    def counted(*args, **kwargs):
        residuals.append(1)
        return real(*args, **kwargs)

    with monkeypatch.context() as m:
        m.setattr(inside, "_residual", counted)
        if not floor_on:
            m.setattr(inside._Geometry, "stretch_floor", lambda self, lanes, reach: (0.0, 0))
        out = []
        for region, lanes in _cases():
            inside._LAYOUTS.clear()
            cut, passes, uncovered = inside.inside_layout(region, lanes, SPACING, REACH)
            rows = [(x.k.tobytes(), x.c.tobytes(), x.t0.tobytes(), x.t1.tobytes()) for x in cut]
            out.append((rows, [p.tobytes() for p in passes], uncovered))
    return out, len(residuals)


def test_inside_layout_is_the_same_with_the_floor(monkeypatch):
    on, with_floor = _layouts(monkeypatch, True)
    off, without = _layouts(monkeypatch, False)
    assert on == off  # the same lanes, passes and uncovered area
    # margin 0's residual skipped on most layouts (margin 1/2's is always laid)
    assert with_floor < 0.7 * without
