"""The walls inside the holes (optimize/cover/walls.py), inset into them: a move between the
two lanes a hole splits (from the hole's ring to its ring) must go around the hole, and the
1-tree's distances see it; never longer than the router's real moves, and the box bounds stay
below the real plans sampled in their boxes (docs/mission_time.md, "Walls inset into the
holes")."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

import boustro.optimize.cover.bounds as bounds_module
import boustro.optimize.cover.one_tree as one_tree_module
from boustro.geometry import Polygon
from boustro.geometry.region import Region
from boustro.optimize.cover import CoverCost
from boustro.optimize.cover.search import CoverSearch
from boustro.optimize.cover.walls import hole_walls, walls_in_frames
from boustro.plan.routing import Router

from .conftest import random_regions
from .plan_samples import SPACING, bounds_and_plans, plan_cost, sample_boxes, scaled

#: A rectangle with a triangular hole (no inner diagonal: its walls were its three edges).
SHELL = [(0.0, 0.0), (100.0, 0.0), (100.0, 60.0), (0.0, 60.0)]
TRIANGLE = [(40.0, 20.0), (60.0, 22.0), (48.0, 40.0)]


def _detour(walls, a, b, search, theta):
    """The kernel's lower bound between the points ``a`` and ``b`` (ranges of one point each)
    in the frame of the layout ``(theta, 0)``, past the walls; and the straight distance."""
    frames = walls_in_frames(walls, np.array([theta]), np.zeros(1), search.origin)[0]
    cs, sn = math.cos(theta), math.sin(theta)

    def frame(p):
        x, y = p[0] - search.origin[0], p[1] - search.origin[1]
        return cs * x + sn * y, -sn * x + cs * y

    (ua, va), (ub, vb) = frame(a), frame(b)
    straight = math.hypot(ua - ub, va - vb)
    lower = straight
    for w in range(len(frames)):
        lower = max(lower, one_tree_module._detour(ua, ua, va, ub, ub, vb, frames, w))
    return lower, straight


def _routed_and_bound(router, walls, a, b, search, theta):
    """The router's move from ``a`` to ``b`` (``None`` where it found no way), checked never
    below the walls' bound; that bound and the straight distance."""
    route = router.path(a, b)
    if not route.found:
        return None, 0.0, 0.0
    lower, straight = _detour(walls, a, b, search, theta)
    assert route.length >= lower - 1e-9
    return route, lower, straight


def _search(region):
    return CoverSearch(region, SPACING, SPACING / 2, CoverCost.time(5.0, 10.0), None, False)


def test_the_move_across_a_triangular_hole_goes_around_its_corner():
    """The two lanes the triangle splits on the line y = 30 end on its ring, 10.67 m apart
    through the hole; the router goes around the top corner (22.79 m). The walls' bound was the
    straight 10.67 m (the ring's own edges meet the move at its ends only: no proper crossing; at
    bc75ccd); the inset edges give the way around the corner, short of the route by the inset,
    never above it."""
    region = Region(Polygon(SHELL), [Polygon(TRIANGLE)])
    search = _search(region)
    walls = hole_walls(search.sandwich.exact.outer)
    chord = shapely.Polygon(TRIANGLE).intersection(shapely.LineString([(0, 30), (100, 30)]))
    a, b = np.asarray(chord.coords)
    route = Router(region, reach=SPACING / 2).path(a, b)
    assert route.found and not route.straight
    for theta in (0.0, math.pi):  # either direction of the lines
        lower, straight = _detour(walls, a, b, search, theta)
        assert straight == pytest.approx(32 / 3)
        assert route.length == pytest.approx(22.79, abs=0.01)
        assert lower <= route.length + 1e-9
        assert lower >= route.length - 1e-3  # the inset (0.1 mm here) only
    # the ring's own edges (no inset): no detour at all
    lower, straight = _detour(hole_walls(search.sandwich.exact.outer, inset=0.0), a, b, search, 0)
    assert lower == straight


@pytest.mark.parametrize("seed", [71, 53])
def test_moves_between_points_on_the_holes_rings_are_never_below_the_walls_bound(seed):
    """Points on the holes' rings (where lanes cut at a hole end) and inside the area, in pairs
    on lines at most two apart, in the frames of random layouts: the router's move between
    them (around the holes) is never shorter than the walls' bound, which is above the straight
    distance for many (a move from a ring across its hole)."""
    region = scaled(random_regions(seed, 1, n_holes=(2, 3))[0], 150.0)
    search = _search(region)
    walls = hole_walls(search.sandwich.exact.outer)
    router = Router(region, reach=SPACING / 2)
    rng = np.random.default_rng(seed)
    rings = [shapely.LinearRing(h.vertices) for h in region.holes]
    longer = 0
    for _ in range(150):
        theta = float(rng.uniform(0, math.pi))
        ring = rings[int(rng.integers(len(rings)))]
        a = np.asarray(ring.interpolate(float(rng.uniform(0, ring.length))).coords[0])
        if rng.uniform() < 0.5:  # the other end on a ring too
            other = rings[int(rng.integers(len(rings)))]
            b = np.asarray(other.interpolate(float(rng.uniform(0, other.length))).coords[0])
        else:
            b = a + rng.uniform(-25, 25, 2)
            if not region.contains(b):
                continue
        route, lower, straight = _routed_and_bound(router, walls, a, b, search, theta)
        longer += route is not None and lower > straight + 0.5
    assert longer >= 10


def _zeros(st, *args, **kw):
    return np.zeros(st.count.shape[0])


def _triangles(index):
    """A rectangle with triangular holes: one in the middle, one 1 mm from the side, one
    sliver-thin (a 20 m triangle 2 cm high)."""
    holes = [
        [(30.0, 20.0), (52.0, 23.0), (38.0, 45.0)],
        [(0.001, 40.0), (25.0, 48.0), (8.0, 58.0)],
        [(60.0, 50.0), (80.0, 50.02), (70.0, 50.03 + 0.01 * index)],
    ]
    return Region(Polygon([(0, 0), (100, 0), (100, 80), (0, 80)]), [Polygon(h) for h in holes])


@pytest.mark.parametrize("case", ["random", "triangles"])
@pytest.mark.parametrize("index", range(2))
def test_the_one_tree_with_inset_walls_never_exceeds_a_plan_in_the_box(case, index, monkeypatch):
    """The box bound with the 1-tree as its only bound on the moves beyond the lines' span (the
    lane-ends and piece-ends bounds switched off) against the real plans of layouts sampled in
    each box (boxes and single layouts), on random areas with 1-3 holes and on triangular holes
    in the middle, 1 mm from the side and sliver-thin; there the point values are above those with
    the walls of the rings themselves somewhere."""
    monkeypatch.setattr(bounds_module, "lane_end_bound", _zeros)
    monkeypatch.setattr(bounds_module, "piece_end_bound", _zeros)
    if case == "random":
        region = scaled(random_regions(91, 2, n_holes=(1, 3))[index], 160.0)
    else:
        region = _triangles(index)
    rng = np.random.default_rng(23 + index)
    cost = CoverCost.time(5.0, float(rng.uniform(2.0, 30.0)))
    evaluate = plan_cost(region, cost)
    boxes = sample_boxes(rng, 10)
    points = []
    for box, point, plans in bounds_and_plans(_search(region), evaluate, boxes, rng):
        assert box <= min(plans) + 1e-9
        assert point <= plans[0] + 1e-9
        points.append(point)
    if case == "random":  # layouts drawn at random: the walls rarely decide their 1-tree
        return
    flat = _search(region)  # the walls of the rings themselves (no inset)
    flat.walls.frames = lambda outer, th, d, o: walls_in_frames(  # type: ignore[method-assign]
        hole_walls(outer, inset=0.0), th, d, o
    )
    assert (np.array(points) > flat.point_values(boxes, exact=True) + 1e-6).any()


def test_a_plan_with_a_move_through_a_hole_is_not_called_certified(monkeypatch):
    """The router's straight fallback (no way found inside the area) flies through the hole,
    which the walls' premise rules out: such a plan keeps no certificate (a review's area, a
    traced side routed through inner domains and a hole 1 m from the shell; forced certified to
    test the rule). The coarse routing found no way there until the thirteenth round's walks
    along the boundary; the fallback is now forced by a router that finds none."""
    import dataclasses

    from boustro.io.area import Area
    from boustro.mission import cover as mission_cover
    from boustro.mission import plan_area
    from boustro.plan.routing import Router

    real = mission_cover.cover_optimum

    def certified(*args, **kwargs):
        result = real(*args, **kwargs)
        return dataclasses.replace(result, info={**result.info, "certified": True, "gap": 0.0})

    monkeypatch.setattr(mission_cover, "cover_optimum", certified)
    left = [(0.1 * (i % 2), 100 - 0.2 * i) for i in range(501)]
    shell = np.array([(0, 0), (200, 0), (200, 100), *left[:-1]], float)
    tri = np.array([(80, 1.0), (100, 99.0), (120, 1.0)])
    area = Area(shell, "planar", "x", "t", (tri,))
    with monkeypatch.context() as m:
        m.setattr(Router, "_coarse_path", lambda self, pa, qa: None)  # no way found
        mission = plan_area(area, 9.0, speed=5.0, turn_time=10.0, angle=90.0)
    assert any(n.startswith("no connecting move inside the area") for n in mission.plan.notes)
    assert mission.optimum.info["certified"] is False
    assert "crosses a hole" in mission.optimum.info["uncertified"]
    clear = plan_area(area, 9.0, speed=5.0, turn_time=10.0, angle=2.864788975654116)
    assert not any(n.startswith("no connecting") for n in clear.plan.notes)
    assert clear.optimum.info["certified"] is True  # the rule leaves other plans alone


def test_walls_of_a_concave_hole_stay_inside_it():
    """An L-shaped hole: its long inset diagonals leave it, and a wall outside a hole would
    charge moves that fly there (a review's mutant without the inside check passed the rest)."""
    from boustro.optimize.cover.bands import edge_set

    hole = np.array([[40, 20], [40, 60], [50, 60], [50, 30], [80, 30], [80, 20]], float)
    shell = np.array([[0, 0], [120, 0], [120, 80], [0, 80]], float)
    walls = hole_walls(edge_set([shell, hole[::-1]], [-1, 0]))
    assert len(walls) >= 3
    inside = shapely.Polygon(hole)
    assert all(inside.covers(shapely.LineString([w[:2], w[2:]])) for w in walls)


def _walls_of_every_pair(es, per_ring=6, inset=1e-6):
    """The former ``hole_walls`` (before 2026-11-28): every pair of the inset ring's vertices
    sorted by length, tested in order; ``O(n^2)`` per ring."""
    from boustro.optimize.cover.walls import _inset_rings, _ring_starts

    starts = _ring_starts(es)
    ends = np.append(starts[1:], len(es.xy))
    extent = float(np.ptp(es.xy[:, :2], axis=0).max()) if len(es.xy) else 0.0
    out = []
    for a, b in zip(starts, ends, strict=True):
        if es.hole[a] < 0 or b - a < 3:
            continue
        poly = shapely.Polygon(es.xy[a:b, :2])
        if not poly.is_valid or poly.area <= 0:
            continue
        shapely.prepare(poly)
        for ring in _inset_rings(poly, inset * extent):
            i, j = np.triu_indices(len(ring), 1)
            seg = np.concatenate([ring[i], ring[j]], axis=1)
            length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
            kept = []
            for k in np.argsort(-length):
                if shapely.covered_by(shapely.LineString([seg[k, :2], seg[k, 2:]]), poly):
                    kept.append(seg[k])
                    if len(kept) >= per_ring:
                        break
            out.extend(kept)
    return np.asarray(out, dtype=np.float64).reshape(-1, 4)


def test_walls_equal_those_of_every_pair_sorted():
    """The walls listed in shells of decreasing length are the former sort of every pair's: on
    random areas' holes (several per area), traced holes of 200 to 2000 vertices and a 2000-vertex
    star (its long chords leave it); where lengths tie (a square, a regular 2000-gon) the same
    lengths, each wall inside its hole (the order among equal lengths was the sort's own)."""
    from boustro.geometry.traced import traced_field
    from boustro.optimize.cover.bands import edge_set

    shell = np.array([[-500, -500], [500, -500], [500, 500], [-500, 500]], float)
    holes = [traced_field(n, 0, seed=n, radius=40.0).shell.vertices for n in (200, 700, 2000)]
    rng = np.random.default_rng(5)
    t = np.linspace(0, 2 * np.pi, 2000, endpoint=False)
    holes.append(np.c_[np.cos(t), np.sin(t)] * (30 + 15 * rng.random(2000))[:, None])
    sets = [edge_set([shell, h[::-1]], [-1, 0]) for h in holes]
    for region in random_regions(6, 31, n_holes=(1, 3)):
        big = scaled(region, 300.0)
        rings = [big.shell.vertices] + [h.vertices for h in big.holes]
        sets.append(edge_set(rings, [-1, *range(len(big.holes))]))
    for es in sets:
        got = hole_walls(es)
        assert len(got) and np.array_equal(got, _walls_of_every_pair(es))
    square = np.array([[0, 0], [10, 0], [10, 10], [0, 10]], float)
    for h in (square, np.c_[np.cos(t), np.sin(t)] * 30):
        es = edge_set([shell, h[::-1]], [-1, 0])
        got, before = hole_walls(es), _walls_of_every_pair(es)
        length = np.hypot(*(got[:, 2:] - got[:, :2]).T)
        assert np.array_equal(length, np.hypot(*(before[:, 2:] - before[:, :2]).T))
        inside = shapely.Polygon(h)
        assert all(inside.covers(shapely.LineString([w[:2], w[2:]])) for w in got)
