"""Walls outside the shell (optimize/cover/walls.py::shell_walls): segments in the pockets of the
area's dilation by how far a plan may leave it (``cover_optimum(outside=...)``), which no lane,
run-in or connecting move crosses; never above the router's real moves (which may pass outside
the area by up to the reach), and the box bounds stay below the real plans sampled in their boxes
(docs/mission_time.md, "Walls outside the shell")."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

import boustro.mission.cover as cover_module
import boustro.optimize.cover.bounds as bounds_module
from boustro.geometry import Polygon
from boustro.geometry.region import Region
from boustro.mission import plan_area
from boustro.mission.cover import OUTSIDE_FACTOR, _outside
from boustro.optimize.cover import CoverCost
from boustro.optimize.cover.boxes import Boxes
from boustro.optimize.cover.search import CoverSearch
from boustro.optimize.cover.walls import shell_walls
from boustro.plan.region import plan_region
from boustro.plan.routing import Router
from boustro.vehicle import Vehicle

from .conftest import random_regions
from .plan_samples import SPACING, bounds_and_plans, plan_cost, sample_boxes, scaled
from .test_cover_walls import _detour, _routed_and_bound

#: A field with a deep notch in its top side and a shallow one (3 m, less than the reach) in its
#: bottom side: straight moves pass under the shallow one outside the area, within the reach.
NOTCH_RING = [(0, 0), (60, 0), (75, 3), (90, 0), (160, 0), (160, 120), (110, 120), (95, 50)]
NOTCHES = Region(Polygon([*NOTCH_RING, (80, 120), (0, 120)]))


def _search(region, outside):
    cost = CoverCost.time(5.0, 10.0)
    return CoverSearch(region, SPACING, SPACING / 2, cost, None, False, outside=outside)


def _near_points(region, rng, reach):
    """A point of the area or within ``reach`` outside its shell (where a lane may end)."""
    shell = shapely.Polygon(region.shell.vertices)
    lo, hi = region.shell.vertices.min(axis=0) - reach, region.shell.vertices.max(axis=0) + reach
    while True:
        p = rng.uniform(lo, hi)
        point = shapely.Point(p)
        holes = (shapely.Polygon(h.vertices) for h in region.holes)
        if shell.distance(point) <= reach and not any(h.contains(point) for h in holes):
            return p


@pytest.mark.parametrize("case", ["notches", "random 0", "random 1"])
def test_moves_near_the_shell_are_never_below_the_walls_bound(case):
    """Points in the area or within the reach outside its shell (lane ends), in pairs at most
    two lines apart in the frames of random layouts: the router's move between them (straight
    where it stays within the reach of the area, else around the shell's reflex vertices) is
    never shorter than the walls' bound, which is above the straight distance for many on the
    notched field. There, with the walls in the pockets of the shell itself (``outside`` 0: a
    move within the reach outside the area crosses them), the bound exceeds some moves."""
    reach = SPACING / 2
    if case == "notches":
        region = NOTCHES
    else:
        region = scaled(random_regions(10, 2, n_holes=(0, 2))[int(case[-1])], 160.0)
    walls = shell_walls(_search(region, None).sandwich.exact.outer, OUTSIDE_FACTOR * reach)
    tight = shell_walls(_search(region, None).sandwich.exact.outer, 1e-9)
    assert len(walls) and len(tight)
    router = Router(region, reach=reach)
    search = _search(region, None)
    rng = np.random.default_rng(5)
    longer, above = 0, 0
    for _ in range(300):
        theta = float(rng.uniform(0, math.pi))
        a = _near_points(region, rng, reach)
        b = _near_points(region, rng, reach)
        if abs(-math.sin(theta) * (b - a)[0] + math.cos(theta) * (b - a)[1]) > 2 * SPACING:
            continue
        route, lower, straight = _routed_and_bound(router, walls, a, b, search, theta)
        if route is None:
            continue
        longer += lower > straight + 0.5
        above += _detour(tight, a, b, search, theta)[0] > route.length + 1e-6
    if case == "notches":  # random pairs rarely cross a random area's pockets
        assert longer >= 5
        assert above >= 1


def _zeros(st, *args, **kw):
    return np.zeros(st.count.shape[0])


@pytest.mark.parametrize("case", ["notches", "random"])
@pytest.mark.parametrize("turnaround", [0.0, 3.0])
def test_the_one_tree_with_shell_walls_never_exceeds_a_plan_in_the_box(
    case, turnaround, monkeypatch
):
    """The box bound with the 1-tree as its only bound on the moves beyond the lines' span (the
    lane-ends and piece-ends bounds off), the shell's walls at ``plan_cover``'s distance (reach
    plus run-in), against the real plans of layouts sampled in each box (boxes of radius up to
    1.5 m, single layouts, boxes of 0.1-1 mm), on a field with a notch shallower than the reach
    and on random concave areas with 0-2 holes; the point values are above those without the
    shell's walls somewhere."""
    monkeypatch.setattr(bounds_module, "lane_end_bound", _zeros)
    monkeypatch.setattr(bounds_module, "piece_end_bound", _zeros)
    region = NOTCHES if case == "notches" else scaled(random_regions(13, 1, n_holes=(0, 2))[0], 160)
    rng = np.random.default_rng(41 + int(turnaround))
    cost = CoverCost.time(5.0, float(rng.uniform(2.0, 30.0)), turnaround=turnaround)
    evaluate = plan_cost(region, cost, turnaround=turnaround)
    outside = OUTSIDE_FACTOR * (SPACING / 2 + turnaround)
    wide = sample_boxes(rng, 8)
    fine = Boxes(
        rng.uniform(0, math.pi, 6), rng.uniform(0, 2e-6, 6), rng.uniform(0, SPACING, 6),
        rng.uniform(1e-4, 1e-3, 6),
    )  # fmt: skip
    points = []
    for boxes in (wide, fine):
        search = CoverSearch(region, SPACING, SPACING / 2, cost, None, False, outside=outside)
        for box, point, plans in bounds_and_plans(search, evaluate, boxes, rng):
            assert box <= min(plans) + 1e-9
            assert point <= plans[0] + 1e-9
            points.append(point)
    plain = CoverSearch(region, SPACING, SPACING / 2, cost, None, False)
    both = Boxes(*(np.concatenate([w, f]) for w, f in zip(wide, fine, strict=True)))
    if case == "notches":
        assert (np.array(points) > plain.point_values(both, exact=True) + 1e-6).any()


def test_no_shell_walls_where_a_plan_may_leave_the_area_farther():
    """``plan_cover`` gives the search the distance only without ``finish`` (a vehicle's turns,
    headland passes) and without keep-inside."""
    options = {"reach": 5.0, "turnaround": 2.0}
    assert _outside(options, False, None) == pytest.approx(7.0 * OUTSIDE_FACTOR)
    assert _outside(options, True, None) is None
    assert _outside(options, False, lambda plan: plan) is None


class _Searched(Exception):
    """Raised by the stand-in search once it has seen its keywords."""


@pytest.mark.parametrize(
    "kw, given",
    [
        ({}, True),
        ({"vehicle": Vehicle(turn_radius=6.0)}, False),
        ({"headland": 1}, False),
        ({"keep_inside": True}, False),
    ],
)
def test_plan_area_gives_the_search_the_distance_only_without_turns_headland_or_keep_inside(
    kw, given, monkeypatch
):
    """What ``plan_area`` (time objective, one grid) passes the search as ``outside``: reach
    plus run-in times :data:`OUTSIDE_FACTOR` on its own; nothing with a vehicle's turns,
    headland passes or keep-inside (their paths may lie farther out: a wall there would cut
    moves the plan flies)."""
    seen: list[object] = []

    def search(*args, **kwargs):
        seen.append(kwargs.get("outside"))
        raise _Searched

    monkeypatch.setattr(cover_module, "cover_optimum", search)
    ring = [(0, 0), (160, 0), (160, 120), (110, 120), (95, 50), (80, 120), (0, 120)]
    with pytest.raises(_Searched):
        plan_area(
            ring, 10.0, crs=None, speed=5.0, turn_time=10.0, turnaround=3.0, decompose=False,
            **kw,
        )  # fmt: skip
    if given:
        assert seen == [pytest.approx(OUTSIDE_FACTOR * (5.0 + 3.0))]
    else:
        assert seen == [None]


def _farthest(path: np.ndarray, body) -> float:
    """How far from ``body`` (shapely) the polyline ``path`` lies, sampled every 1 cm."""
    line = shapely.segmentize(shapely.LineString(path), 0.01)
    return float(shapely.distance(body, shapely.points(shapely.get_coordinates(line))).max())


def test_straight_moves_pass_outside_beyond_the_reach_but_within_the_factor():
    """The router's straight moves over a V notch (sampled every sixteenth of its reach) pass
    farther than the reach from the area between the samples (up to 1/32 beyond it), never
    farther than :data:`OUTSIDE_FACTOR` times it: a factor of 1 would put walls where plans
    fly."""
    ring = [(0, 0), (100, 0), (100, 100), (54, 100), (50, 96), (46, 100), (0, 100)]
    v_notch = Region(Polygon(ring))
    body = shapely.Polygon(v_notch.shell.vertices)
    reach = 4.5
    router = Router(v_notch, reach=reach)
    rng = np.random.default_rng(0)
    farthest = 0.0
    for _ in range(400):
        p = np.array([rng.uniform(30, 46), rng.uniform(96, 100 + reach)])
        q = np.array([rng.uniform(54, 70), rng.uniform(96, 100 + reach)])
        route = router.path(p, q)
        if route.straight and route.found:
            farthest = max(farthest, _farthest(route.points, body))
    assert reach * 1.01 < farthest <= OUTSIDE_FACTOR * reach


@pytest.mark.parametrize("reach, turnaround", [(4.5, 0.0), (6.0, 3.0), (4.5, 12.0)])
def test_real_plans_lie_within_the_distance_plan_cover_gives(reach, turnaround):
    """Real plans (lanes, run-ins and run-outs, routed and straight moves, hole passes) of
    random layouts on the notched field, a thin slot and a random concave area with holes lie
    within ``OUTSIDE_FACTOR * (reach + run-in)`` of the shell: the premise of the shell's
    walls."""
    slot = Region(Polygon([(0, 0), (100, 0), (100, 100), (52, 100), (52, 20), (48, 20),
                           (48, 100), (0, 100)]))  # fmt: skip
    rng = np.random.default_rng(int(reach + turnaround))
    for region in (NOTCHES, slot, scaled(random_regions(77, 1, n_holes=(1, 2))[0], 160.0)):
        body = shapely.Polygon(region.shell.vertices)
        for _ in range(3):
            plan = plan_region(
                region, SPACING, decompose_area=False, angle=float(rng.uniform(0, math.pi)),
                offset=float(rng.uniform(0, SPACING)), turnaround=turnaround, reach=reach,
            )  # fmt: skip
            assert _farthest(plan.waypoints, body) <= OUTSIDE_FACTOR * (reach + turnaround)
