"""Margin 0's boundary passes in the keep-inside bound (optimize/cover/inside_cut.py): every
counted stretch lies inside the passes the planner builds for lanes cut at the boundary, the
clearance beyond an edge, and the margin-0 bound with them below the real margin-0 plans."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from boustro.geometry.region import Region
from boustro.optimize.cover import CoverCost, band_stats
from boustro.optimize.cover.bounds import lower_bounds
from boustro.optimize.cover.inside_bound import _no_holes, _with_cut_passes, contour_edges
from boustro.optimize.cover.inside_cut import COT_MIN, cut_cores, cut_stretches
from boustro.optimize.cover.search import CoverSearch
from boustro.plan import inside
from boustro.plan.lanes import region_lanes

from .test_inside_bound import _adversarial, _areas

S = 10.0


def _gaps() -> list[Region]:
    """Areas whose edges face another part of the area across a gap: a hole 1.5 m and one
    0.5 m thick, a slot 2 m wide, a neck 3 m wide."""
    box = [(0, 0), (120, 0), (120, 70), (0, 70)]
    return [
        Region(box, [[(10, 30), (110, 30), (110, 31.5), (10, 31.5)]]),
        Region(box, [[(20, 30), (100, 30), (100, 30.5), (20, 30.5)]]),
        Region([(0, 0), (120, 0), (120, 60), (61, 60), (61, 10), (59, 10), (59, 60), (0, 60)]),
        Region([(0, 0), (50, 0), (50, 20), (53, 20), (53, 0), (100, 0), (100, 40), (0, 40)]),
    ]


def _margin0(region: Region, angle: float, offset: float) -> list[np.ndarray]:
    """The planner's boundary passes for the lanes of a layout cut at the boundary."""
    lanes = region_lanes(region, S, angle, offset, reach=S / 2, holes=region.holes)
    cut = inside.clip_lanes(lanes, region, 1e-9 * region.diameter, 0.0, S)
    return inside.boundary_passes(region, [cut], S, S / 2)[0]


def _angles(region: Region, rng: np.random.Generator) -> list[float]:
    """Random angles, and angles at 27-90 degrees (exactly, and just off it) to an edge."""
    e = region.edges
    along = np.arctan2(e[:, 1, 1] - e[:, 0, 1], e[:, 1, 0] - e[:, 0, 0]) % math.pi
    turns = [0.47, 0.55, 0.6, 1.2, math.pi / 2, math.pi / 2 + 1e-7, 1.5607, -0.47, -0.55, -1.3]
    return list(rng.uniform(0, math.pi, 4)) + list(
        (rng.choice(along, 8) + rng.choice(turns, 8)) % math.pi
    )


@pytest.mark.parametrize("index", range(15))
def test_counted_stretches_lie_in_the_margin0_passes(index):
    """Each stretch counted at margin 0 lies inside the planner's passes for lanes cut at the
    boundary (shapely, within 1e-3 m), and the rings holding one are no more than the passes."""
    import shapely

    region = (_adversarial() + _areas() + _gaps())[index]
    edges = contour_edges(region, S, S / 2)
    rng = np.random.default_rng(200 + index)
    counted = 0
    for angle in _angles(region, rng):
        passes = _margin0(region, angle, rng.uniform(0, S))
        lines = [shapely.LineString(p) for p in passes]
        union = shapely.union_all(lines).buffer(1e-5) if lines else shapely.Polygon()
        theta = np.array([angle % math.pi])
        core, k_lo = cut_cores(edges, theta, np.zeros(1), S)
        p0, _, rings = cut_stretches(edges, theta, np.zeros(1), S)
        assert rings[0] <= len(passes)
        assert p0[0] == pytest.approx(core.sum(), rel=1e-12)
        for j in np.flatnonzero(core[0] > 0):
            a, b = edges.strip[j]
            u = (b - a) / np.linalg.norm(b - a)
            start = a + (k_lo[0, j] - edges.feet[j, 2]) * u + edges.inward[j] * S / 2
            seg = shapely.LineString([start, start + core[0, j] * u])
            assert seg.difference(union).length <= 1e-3, (angle, j)
            counted += 1
    assert counted or not edges.core.any()


def test_clearance_beyond_the_edges():
    """The hole's long edges see the area 1.5 m and 0.5 m beyond them, the slot's sides 2 m;
    the shells' edges of the box see nothing (``inf``)."""
    thick, thin, slot, _ = _gaps()
    for region, gap in ((thick, 1.5), (thin, 0.5)):
        e = contour_edges(region, S, S / 2)
        y = region.holes[0].vertices[:, 1]
        on_hole = np.isin(e.strip[:, :, 1], y).all(axis=1) & (e.core > 0)
        assert on_hole.sum() == 2 and np.allclose(e.clear[on_hole], gap, rtol=1e-6)
        assert np.all(np.isinf(e.clear[~on_hole & (e.core > 0)]))
    e = contour_edges(slot, S, S / 2)
    vertical = np.isclose(e.angle, math.pi / 2) & (e.core > 0) & (e.clear < 10)
    assert vertical.sum() == 2 and np.allclose(e.clear[vertical], 2.0, rtol=1e-6)


def test_a_stretch_counts_only_where_the_lanes_cannot_come_back_over_its_triangles():
    """On the 0.5 m hole's long edges, lanes at angle ``phi`` may come back into the area within
    ``s/2 cot phi > 0.5`` of the edge: not counted; at 85 degrees (``s/2 cot phi`` = 0.44 m)
    and with the clearance widened, counted; never at 90 degrees (no triangle)."""
    thin = _gaps()[1]
    e = contour_edges(thin, S, S / 2)
    y = thin.holes[0].vertices[:, 1]
    hole = np.flatnonzero(np.isin(e.strip[:, :, 1], y).all(axis=1) & (e.core > 0))
    assert len(hole) == 2
    for deg, counts in ((40.0, False), (60.0, False), (85.0, True), (90.0, False)):
        core, _ = cut_cores(e, np.array([math.radians(deg)]), np.zeros(1), S)
        assert (core[0, hole] > 0).all() == counts and (core[0, hole] > 0).any() == counts
    wide = e._replace(clear=np.full_like(e.clear, np.inf))
    core, _ = cut_cores(wide, np.array([math.radians(40.0)]), np.zeros(1), S)
    assert (core[0, hole] > 0).all()
    # a box of angles reaching 90 degrees (85 +- 5.2): the triangles may vanish, none counted
    core, _ = cut_cores(wide, np.array([math.radians(85.0)]), np.array([0.09]), S)
    assert not (core[0, hole] > 0).any()
    # up to the last angle COT_MIN allows, counted
    top = math.atan(1 / COT_MIN) * (1 - 1e-9)
    core, _ = cut_cores(wide, np.array([top]), np.zeros(1), S)
    assert (core[0, hole] > 0).all()


@pytest.mark.parametrize("index", [0, 3, 6, 8, 12, 13])
def test_margin0_bound_with_its_passes_below_the_margin0_plans(index):
    """The margin-0 bound with its passes at a layout is below that layout's real plan with
    its lanes cut at the boundary (lanes, passes, moves and turns, as the planner drives it)."""
    region = (_adversarial() + _areas() + _gaps())[index]
    cost = CoverCost.time(5.0, 10.0)
    search = CoverSearch(region, S, S / 2, cost, None, False, keep_inside=True)
    rng = np.random.default_rng(300 + index)
    lifted = 0
    for angle in _angles(region, rng)[:8]:
        offset = rng.uniform(0, S)
        theta, d = np.array([angle % math.pi]), np.array([offset])
        zero, st0 = _zero_bound(search, theta, d)
        bound = _with_cut_passes(zero, st0, cost, S, search.contour, theta, np.zeros(1))
        plan = _forced_plan(region, angle % math.pi, offset, cost)
        assert bound[0] <= plan + 1e-6
        lifted += bound[0] > zero[0] + 1e-9
    assert lifted


def _zero_bound(search: CoverSearch, theta: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, Any]:
    """The margin-0 bound without passes at the layouts ``(theta, d)`` and its band stats."""
    lv0 = search.sandwich.level(0.0, 0.0)
    st0 = band_stats(
        lv0.inner, lv0.outer, theta, d, S, 0.0, search.origin, search.k_range(0.0),
        search.n_holes, search.tol, inner_reach=0.0,
    )  # fmt: skip
    kw = {"boustrophedon": False, "ends": None, "runins": False}
    return lower_bounds(_no_holes(st0), lv0, search.cost, S, **kw), st0


def _forced_plan(region: Region, angle: float, offset: float, cost: CoverCost) -> float:
    """The cost of ``plan_region``'s keep-inside plan with its lanes cut at the boundary."""
    from boustro.plan.region import plan_region

    real = inside._inside_layout

    def margin0(area, lanes, spacing, reach, key=None):
        tol = 1e-9 * area.diameter
        cut = [inside.clip_lanes(ls, area, tol, 0.0, spacing) for ls in lanes]
        passes, uncovered = inside.boundary_passes(area, cut, spacing, reach)
        return cut, passes, uncovered

    inside._inside_layout = margin0
    inside._LAYOUTS.clear()
    try:
        plan = plan_region(
            region, S, angle=angle, offset=offset, keep_inside=True, decompose_area=False,
            speed=5.0, turn_time=10.0,
        )  # fmt: skip
    finally:
        inside._inside_layout = real
        inside._LAYOUTS.clear()
    return cost.of(plan.stats.path_length, plan.stats.n_turns)


def test_a_decomposition_cell_search_bounds_as_before():
    """A cell search of a decomposition (``moves_on_passes`` off: its floor screens candidate
    decompositions) bounds its boxes and layouts without margin 0's passes and the near rule
    at the layouts, as before them; a search of the whole area counts them (higher here)."""
    import boustro.optimize.cover.inside_bound as ib
    from boustro.optimize.cover.boxes import Boxes

    region = _areas()[0]
    cost = CoverCost.time(5.0, 10.0)
    rng = np.random.default_rng(5)
    n = 12
    boxes = Boxes(rng.uniform(0, math.pi, n), np.zeros(n), rng.uniform(0, S, n), np.zeros(n))
    got = {}
    for moves, cut, near in ((False, "bound", True), (False, "off", False), (True, "bound", True)):
        search = CoverSearch(region, S, S / 2, cost, None, False, keep_inside=True)
        search.moves_on_passes = moves
        ib.CUT_PASSES, ib.NEAR_AT_LAYOUTS = cut, near
        try:
            got[(moves, cut)] = search.point_values(boxes)
        finally:
            ib.CUT_PASSES, ib.NEAR_AT_LAYOUTS = "bound", True
    assert np.array_equal(got[(False, "bound")], got[(False, "off")])
    assert (got[(True, "bound")] >= got[(False, "off")]).all()
    assert (got[(True, "bound")] > got[(False, "off")] + 1e-9).any()


@pytest.mark.parametrize("index", range(15))
def test_a_box_counts_no_more_than_any_layout_in_it(index):
    """Per stretch, a box's counted part (``theta +- delta``) lies inside the part counted at
    every angle of the box, and its travel along the lanes is no more: the box's terms hold at
    each of its layouts (boxes straddling ~27 degrees, 89.4 degrees and random ones)."""
    region = (_adversarial() + _areas() + _gaps())[index]
    edges = contour_edges(region, S, S / 2)
    rng = np.random.default_rng(500 + index)
    e = region.edges
    along = np.arctan2(e[:, 1, 1] - e[:, 0, 1], e[:, 1, 0] - e[:, 0, 0]) % math.pi
    n = 40
    turn = rng.choice([0.47, 0.5, 0.6, 1.0, 1.55, 1.5607], n) * rng.choice([-1, 1], n)
    theta = np.concatenate([(rng.choice(along, n) + turn) % math.pi, rng.uniform(0, math.pi, n)])
    delta = rng.choice([0.005, 0.02, 0.05], 2 * n)
    core, k_lo = cut_cores(edges, theta, delta, S)
    p, a, rings = cut_stretches(edges, theta, delta, S)
    inner = 0
    for i in np.flatnonzero((core > 0).any(axis=1)):
        for angle in (
            theta[i] - delta[i],
            theta[i] + delta[i],
            theta[i] + rng.uniform(-1, 1) * delta[i],
        ):
            at = np.array([angle % math.pi])
            c1, k1 = cut_cores(edges, at, np.zeros(1), S)
            p1, a1, r1 = cut_stretches(edges, at, np.zeros(1), S)
            on = core[i] > 0
            assert (c1[0, on] > 0).all(), (theta[i], delta[i], angle)
            assert (k1[0, on] <= k_lo[i, on] + 1e-9).all()
            assert (k1[0, on] + c1[0, on] >= k_lo[i, on] + core[i, on] - 1e-9).all()
            assert p[i] <= p1[0] + 1e-9 and a[i] <= a1[0] + 1e-9 and rings[i] <= r1[0]
            inner += 1
    assert inner or not edges.core.any()
