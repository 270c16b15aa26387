"""Connecting moves routed in the grown domain (plan/route_grown.py): shorter past the shell's
reflex corners, within the reach of the shell, never into a hole; keep-inside unchanged."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import shapely

import boustro.plan.routing as routing
from boustro.geometry.region import Region
from boustro.mission import plan_area
from boustro.plan.route_grown import grown_region
from boustro.plan.routing import Router

from .test_decomp_time import SPEED, TURN, _covered, _recomputed_time

L_SHELL = [(0, 0), (100, 0), (100, 40), (40, 40), (40, 100), (0, 100)]
L_HOLE = [(10, 10), (20, 10), (20, 20), (10, 20)]


def _sampled(points: np.ndarray, step: float = 0.05) -> np.ndarray:
    out = []
    for a, b in itertools.pairwise(points):
        n = max(2, int(np.linalg.norm(b - a) / step) + 1)
        out.append(a + np.linspace(0, 1, n)[:, None] * (b - a))
    return np.concatenate(out)


def test_a_move_past_a_reflex_corner_cuts_it_within_the_reach():
    region = Region(L_SHELL, [L_HOLE])
    shell, hole = shapely.Polygon(L_SHELL), shapely.Polygon(L_HOLE)
    area = shell.difference(hole)
    reach = 5.0
    router = Router(region, reach)
    p, q = np.array([90.0, 43.0]), np.array([43.0, 90.0])  # lanes' ends, 3 m outside
    inside = router._inside_detour(p, q)  # through the corner (40, 40): 100 m + the legs
    assert inside.length == pytest.approx(106.0)
    move = router.path(p, q)
    # through the corner of the shell grown by the reach, (45, 45)
    assert move.length == pytest.approx(2 * np.hypot(45, 2), rel=1e-5)
    assert move.length < inside.length - 15
    pts = shapely.points(_sampled(move.points))
    assert shapely.distance(shell, pts).max() <= reach * (1 + 1e-9)
    assert not shapely.intersects(hole.buffer(-1e-9), shapely.LineString(move.points))
    assert move.outside == pytest.approx(shapely.LineString(move.points).difference(area).length)
    # a move around the hole: in the grown domain too, never into it
    move = router.path((90.0, 43.0), (5.0, 5.0))
    assert not shapely.intersects(hole.buffer(-1e-9), shapely.LineString(move.points))
    assert move.length <= router._inside_detour(np.array([90.0, 43.0]), np.array([5.0, 5.0])).length
    # keep-inside (no reach): no grown domain, the move inside the area as before
    flat = Router(region, 0.0)
    assert flat._grown is None
    assert flat.path(p, q).length == pytest.approx(inside.length)


def test_an_end_beyond_the_reach_is_not_routed_in_the_grown_domain(monkeypatch):
    """A run-in's end lies up to the reach plus the run-in out: a move from it would fail the
    straight test on its first segment, so the grown domain is not searched for it (with
    run-ins most moves were, each rejected) and the move is the one inside the area."""
    router = Router(Region(L_SHELL, [L_HOLE]), 5.0)
    assert router._grown is not None
    asked = []
    grown_path = router._grown.path
    monkeypatch.setattr(router._grown, "path", lambda p, q: asked.append(1) or grown_path(p, q))
    p, q = np.array([90.0, 48.0]), np.array([43.0, 90.0])  # p 8 m above the arm, q 3 m out
    move = router.path(p, q)
    assert not asked
    inside = router._inside_detour(p, q)
    assert move.length == inside.length and np.array_equal(move.points, inside.points)
    # with both ends within the reach it is searched (and its move cuts the corner)
    assert router.path(np.array([90.0, 43.0]), q).length < inside.length - 10
    assert asked


def test_the_tours_distances_are_the_moves_flown():
    """The matrix a tour is ordered on (``Router.distances``) is the length of the move the
    router flies, for every pair of these few points (all within each other's nearest): grown
    moves past the corner (106 m inside against 90.09 m flown before), straight moves outside
    within the reach, moves from an end beyond the reach (routed inside, not grown)."""
    router = Router(Region(L_SHELL, [L_HOLE]), 5.0)
    pts = np.array(
        [(90, 43), (43, 90), (90, 48), (5, 5), (30, 30), (60, 20), (20, 60), (103, 20),
         (60, 43), (25, 25), (-3, 50), (43, 43)], dtype=float,
    )  # fmt: skip
    dist = router.distances(pts)
    grown = 0
    for i, j in itertools.permutations(range(len(pts)), 2):
        move = router.path(pts[i], pts[j])
        assert dist[i, j] == pytest.approx(move.length, rel=1e-9), (i, j)
        grown += not move.straight and move.length < router._inside_detour(pts[i], pts[j]).length
    assert grown >= 10


def test_pockets_the_dilation_closes_are_holes_of_the_grown_domain():
    """A C whose mouth (4 m) is narrower than twice the reach: the bay's middle, farther than
    the reach from the shell, is a hole of the grown domain."""
    c = [(0, 0), (60, 0), (60, 60), (0, 60), (0, 32), (40, 32), (40, 28), (0, 28)]
    region = Region(c)
    assert grown_region(region, 0.0) is None
    grown = grown_region(region, 3.0)
    assert grown is not None and len(grown.holes) == 0  # a 4 m slot: filled by 3 m either side
    bay = [
        (0, 0),
        (60, 0),
        (60, 60),
        (0, 60),
        (0, 31),
        (50, 31),
        (50, 10),
        (10, 10),
        (10, 29),
        (0, 29),
    ]
    grown = grown_region(Region(bay), 3.0)
    assert grown is not None and len(grown.holes) == 1  # the bay's inside, closed by its mouth
    hole = shapely.Polygon(grown.holes[0].vertices)
    assert shapely.distance(shapely.Polygon(bay).exterior, hole.centroid) > 3.0


def _mission(angle: float, grown: bool, monkeypatch):
    with monkeypatch.context() as m:
        if not grown:
            m.setattr(routing, "grown_region", lambda region, reach: None)
        routing.router_for.cache_clear()
        try:
            return plan_area(
                np.array(L_SHELL) * 2.0,
                9.0,
                crs=None,
                holes=[np.array(L_HOLE) * 2.0],
                speed=SPEED,
                turn_time=TURN,
                angle=angle,
            )
        finally:
            routing.router_for.cache_clear()


@pytest.mark.parametrize("angle", [15.0, 60.0, 75.0, 135.0])
def test_plans_never_longer_covered_timed_as_flown(angle, monkeypatch):
    """An L with a pond, 9 m lanes: the plan with moves in the grown domain is never longer than
    with moves inside the area (shorter at 60, 75 and 135 degrees, as long at 15), covers the
    original area, its time is its waypoints' length / speed plus its turns, its outside length
    is shapely's."""
    new = _mission(angle, True, monkeypatch)
    old = _mission(angle, False, monkeypatch)
    assert new.stats.duration <= old.stats.duration + 1e-9
    if angle != 15.0:
        assert new.stats.duration < old.stats.duration - 0.5
    area = shapely.Polygon(np.array(L_SHELL) * 2.0, [np.array(L_HOLE) * 2.0])
    assert _covered(new, area) == pytest.approx(1.0, abs=1e-9)
    assert new.stats.duration == pytest.approx(_recomputed_time(new), rel=1e-9)
    w = new.plan.waypoints
    segments = shapely.linestrings(np.stack([w[:-1], w[1:]], axis=1))
    # segment by segment (a path doubling back outside counts twice); the hole pass runs on
    # the hole's ring: the area's boundary counts as in it
    shapely_outside = shapely.length(shapely.difference(segments, area.buffer(1e-7))).sum()
    assert new.summary()["outside_length_m"] == pytest.approx(shapely_outside, rel=1e-6)


def test_a_point_inside_a_hole_is_measured_as_flown():
    """From a point strictly inside a hole the grown route's first segment crosses the hole, so
    the router flies the move inside the area: the matrix must not take the grown length
    (it was 4-11 m shorter than the move flown for these pairs)."""
    region = Region(L_SHELL, [[(60, 10), (90, 10), (90, 30), (60, 30)]])
    router = Router(region, 5.0)
    pts = np.array([(75, 20), (88, 28), (62, 28), (43, 90), (2, 98), (75, 9)], dtype=float)
    assert list(router.classify(pts)) == [1, 1, 1, 2, 0, 0]
    dist = router.distances(pts)
    for i, j in itertools.permutations(range(len(pts)), 2):
        assert dist[i, j] == pytest.approx(router.path(pts[i], pts[j]).length, rel=1e-9), (i, j)
    assert list(router._grown_ends(pts)) == [False, False, False, True, True, True]
