"""The 1-tree bound on a routed tour's moves (optimize/cover/one_tree.py): against real plans
sampled in boxes, against a brute force over the lanes' orders, and what it adds."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

import boustro.optimize.cover.bounds as bounds_module
import boustro.optimize.cover.one_tree as one_tree_module
import boustro.optimize.cover.search as search_module
from boustro.geometry import Polygon
from boustro.geometry.region import Region
from boustro.optimize.cover import CoverCost, band_stats, cover_optimum
from boustro.optimize.cover.boxes import Boxes, split_boxes, split_parents
from boustro.optimize.cover.extremes import line_extremes
from boustro.optimize.cover.one_tree import Multipliers, one_tree_bound
from boustro.optimize.cover.search import CoverSearch
from boustro.plan.region import plan_region
from boustro.vehicle import Vehicle

from .conftest import random_regions
from .plan_samples import SPACING, plan_cost, plans_in_boxes, sample_boxes, scaled


def _zeros(st, *args, **kw):
    return np.zeros(st.count.shape[0])


@pytest.mark.parametrize("case", ["plain", "turnaround", "vehicle"])
@pytest.mark.parametrize("index", range(3))
def test_one_tree_bound_alone_never_exceeds_a_plan_in_the_box(case, index, monkeypatch):
    """The box bound with the 1-tree as its only bound on the moves beyond the lines' span
    (the lane-ends and piece-ends bounds switched off) against the real plans of layouts
    sampled in each box; areas with 1-3 holes, a turn costing 2 to 30 s, 3 m run-ins or a
    6 m turn radius's driven turns."""
    monkeypatch.setattr(bounds_module, "lane_end_bound", _zeros)
    monkeypatch.setattr(bounds_module, "piece_end_bound", _zeros)
    region = scaled(random_regions(53, 3, n_holes=(1, 3))[index], 170.0)
    rng = np.random.default_rng(11 + index)
    turnaround = 3.0 if case == "turnaround" else 0.0
    cost = CoverCost.time(5.0, float(rng.uniform(2.0, 30.0)), turnaround=turnaround)
    vehicle = Vehicle(turn_radius=6.0) if case == "vehicle" else None
    evaluate = plan_cost(region, cost, turnaround=turnaround, vehicle=vehicle)
    search = CoverSearch(region, SPACING, SPACING / 2, cost, None, False)
    n = 10
    boxes = sample_boxes(rng, n)
    search.top_eps = float((boxes.delta * search.radius + boxes.eta).max()) * 1.5
    box = search.box_bounds(boxes)
    points = search.point_values(boxes, exact=True)
    search.tour = False  # the same bounds without the 1-tree: the lines' span only
    assert (points > search.point_values(boxes, exact=True) + 1e-6).all()
    assert (box > search.box_bounds(boxes) + 1e-6).any()
    for i, plans in enumerate(plans_in_boxes(evaluate, boxes, rng)):
        assert box[i] <= min(plans) + 1e-9
        assert points[i] <= plans[0] + 1e-9


def _ranges(st, la, turnaround):
    """The counted lanes' end ranges of layout ``la`` (the kernel's own helper, plain)."""
    m = 2 * int(st.count[la].sum())
    lo, hi, v = np.empty(m), np.empty(m), np.empty(m)
    ext = line_extremes(st, turnaround)[la]  # as one_tree_bound
    n = one_tree_module._lane_ends(
        st.count[la], ext, st.first_hi[la], st.last_lo[la],
        st.pieces[la], 0, SPACING, turnaround, lo, hi, v,
        np.empty(m // 2, dtype=np.int64), np.empty(m // 2, dtype=np.int64),
    )  # fmt: skip
    return n, lo, hi, v


def _brute_path(n, lo, hi, v):
    """The least sum of range distances over every order and direction of the lanes."""

    def dist(a, b):
        g = max(max(lo[a], lo[b]) - min(hi[a], hi[b]), 0.0)
        return math.hypot(v[a] - v[b], g)

    best = math.inf
    for order in itertools.permutations(range(1, n)):
        order = (0, *order)
        for flips in itertools.product((0, 1), repeat=n):
            total = 0.0
            for i in range(n - 1):
                a = 2 * order[i] + 1 - flips[i]  # the exit of lane i
                b = 2 * order[i + 1] + flips[i + 1]  # the entry of the next
                total += dist(a, b)
                if total >= best:
                    break
            best = min(best, total)
    return best


@pytest.mark.parametrize("turnaround", [0.0, 2.0])
def test_one_tree_never_exceeds_the_shortest_path_over_the_lanes(turnaround):
    """On boxes whose plans have 3-6 counted lanes (a small area with a hole, a wide
    spacing), the 1-tree bound is at most the brute-force shortest path over the lanes' end
    ranges (every order and direction), and within 10% of it on average."""
    region = scaled(random_regions(61, 1, n_holes=(1, 1))[0], 45.0)
    cost = CoverCost.time(5.0, 10.0, turnaround=turnaround)
    search = CoverSearch(region, SPACING, SPACING / 2, cost, None, False)
    rng = np.random.default_rng(3)
    n_boxes = 24
    boxes = Boxes(
        rng.uniform(0, math.pi, n_boxes),
        np.zeros(n_boxes),
        rng.uniform(0, SPACING, n_boxes),
        rng.uniform(0, 0.8, n_boxes),
    )
    eps = float(boxes.eta.max())
    lv = search.sandwich.level(eps, 0.0)
    st = band_stats(
        lv.inner, lv.outer, boxes.theta, boxes.d, SPACING, SPACING / 2, search.origin,
        search.k_range(eps + SPACING), search.n_holes, search.tol,
        inner_reach=search._inner_reach(),
    )  # fmt: skip
    tree = one_tree_bound(st, SPACING, cost, steps=200) / cost.per_length
    ratios = []
    for la in range(n_boxes):
        n, lo, hi, v = _ranges(st, la, turnaround)
        if not 3 <= n <= 6:
            continue
        brute = _brute_path(n, lo, hi, v)
        assert tree[la] <= brute + 1e-9
        ratios.append(tree[la] / brute)
    assert len(ratios) >= 8
    assert np.mean(ratios) >= 0.9


def test_a_moves_detour_past_a_wall_is_never_longer_than_the_routed_move():
    """The walls inside a random area's holes (the exact level: the holes themselves), in the
    frames of random layouts: for random pairs of ranges on the lines and points in them, the
    router's connecting move (the planner's, around the holes) is never shorter than the
    kernel's lower bound between the ranges, which exceeds the straight distance for some."""
    from boustro.optimize.cover.walls import hole_walls, walls_in_frames
    from boustro.plan.routing import Router

    region = scaled(random_regions(71, 1, n_holes=(2, 2))[0], 120.0)
    search = CoverSearch(region, SPACING, SPACING / 2, CoverCost.time(5.0, 10.0), None, False)
    walls = hole_walls(search.sandwich.exact.outer)
    assert len(walls) >= 4
    router = Router(region, reach=SPACING / 2)
    rng = np.random.default_rng(5)
    theta = rng.uniform(0, math.pi, 6)
    frames = walls_in_frames(walls, theta, np.zeros(6), search.origin)
    longer = 0
    for la in range(6):
        cs, sn = math.cos(theta[la]), math.sin(theta[la])
        for _ in range(60):
            ka, kb = rng.integers(-6, 7, 2)
            ranges = np.sort(rng.uniform(-70, 70, (2, 2)), axis=1)
            ranges[:, 1] = np.minimum(ranges[:, 1], ranges[:, 0] + rng.uniform(0, 8, 2))
            (la_, ha), (lb, hb) = ranges
            va, vb = ka * SPACING, kb * SPACING
            lower = math.hypot(va - vb, max(max(la_, lb) - min(ha, hb), 0.0))
            for w in range(len(walls)):
                lower = max(lower, one_tree_module._detour(la_, ha, va, lb, hb, vb, frames[la], w))
            ua, ub = rng.uniform(la_, ha), rng.uniform(lb, hb)
            p = search.origin + np.array([cs * ua - sn * va, sn * ua + cs * va])
            q = search.origin + np.array([cs * ub - sn * vb, sn * ub + cs * vb])
            if not (region.contains(p) and region.contains(q)):
                continue
            route = router.path(p, q)
            if not route.found:
                continue
            assert route.length >= lower - 1e-9
            longer += lower > math.hypot(va - vb, max(max(la_, lb) - min(ha, hb), 0.0)) + 1e-6
    assert longer >= 5


@pytest.mark.parametrize("index", range(2))
def test_deferred_one_trees_give_the_certificate_of_a_one_tree_at_every_box(index, monkeypatch):
    """Boxes taken out by their other bounds get their 1-tree only after the search, and only
    where it could lower the floor (search.DEFER_TOUR): the same plan, rounds and certificate
    as a 1-tree at every box, with fewer boxes' 1-trees computed."""
    region = scaled(random_regions(71, 2, n_holes=(1, 3))[index], 260.0)
    cost = CoverCost.time(5.0, 10.0)
    evaluate = plan_cost(region, cost)
    deferred: list[int] = []
    settle = CoverSearch.settle_deferred

    def spy(self, lower):
        deferred.append(sum(len(b) for _, b, _ in self.deferred))
        if self.deferred:  # the deferred boxes' own minimum, a 1-tree at every one of them
            kept = list(self.deferred)
            boxes = Boxes(*(np.concatenate([b[f] for b, _, _ in kept]) for f in range(4)))
            base = np.concatenate([v for _, v, _ in kept])
            full = self.box_bounds(boxes, tour_below=self.best[0])
            assert (full >= base - 1e-9).all() and (full > base + 1e-6).any()
            self.deferred = [(boxes, base, None)]
            # stopped at the best plan as the full 1-trees' steps (at inf, the steps of a
            # box whose 1-tree passes the best plan go on: with the walls inset into the
            # holes every deferred box of area 0 passes it)
            got = settle(self, self.best[0])
            assert got == pytest.approx(min(float(full.min()), self.best[0]), rel=1e-12)
            self.deferred = kept
        return settle(self, lower)

    monkeypatch.setattr(CoverSearch, "settle_deferred", spy)
    runs = {}
    for defer in (False, True):
        monkeypatch.setattr(search_module, "WARM_TOUR", True)
        monkeypatch.setattr(search_module, "DEFER_TOUR", defer)
        # stopped at the take-out value, the 1-trees of boxes taken out are not deferred
        monkeypatch.setattr(search_module, "STOP_TOUR_AT_KEEP", False)
        runs[defer] = cover_optimum(region, SPACING, cost, evaluate, boustrophedon=False)
    assert deferred[0] == 0 and deferred[1] > 0
    a, b = runs[False], runs[True]
    assert (a.angle, a.offset, a.fitness) == (b.angle, b.offset, b.fitness)
    assert a.info["rounds"] == b.info["rounds"]
    assert b.info["lower_bound"] == pytest.approx(a.info["lower_bound"], rel=1e-12)
    assert b.info["lower_bound"] <= b.fitness


@pytest.mark.parametrize("index", range(3))
def test_warm_started_one_trees_stay_below_the_plans_and_rise(index, monkeypatch):
    """Halves of boxes whose 1-trees start from their parent's best multipliers
    (search.WARM_TOUR): still below the real plans sampled in each half, and above the cold
    start's bounds on the whole (the steps go on where the parent's stopped)."""
    monkeypatch.setattr(bounds_module, "lane_end_bound", _zeros)
    monkeypatch.setattr(bounds_module, "piece_end_bound", _zeros)
    region = scaled(random_regions(59, 3, n_holes=(1, 3))[index], 200.0)
    rng = np.random.default_rng(5 + index)
    cost = CoverCost.time(5.0, float(rng.uniform(2.0, 30.0)))
    evaluate = plan_cost(region, cost)
    search = CoverSearch(region, SPACING, SPACING / 2, cost, None, False)
    n = 8
    parents = Boxes(
        rng.uniform(0, math.pi, n), np.full(n, 0.004), rng.uniform(0, SPACING, n), np.full(n, 0.8)
    )
    search.top_eps = float((parents.delta * search.radius + parents.eta).max()) * 1.5
    mult = search.multipliers(n)
    assert mult is not None and not mult.warm.any()
    search.box_bounds(parents, multipliers=mult)
    assert mult.warm.all() and np.abs(mult.values).max() > 0
    halves = split_boxes(parents, search.radius)
    index_of = split_parents(parents, search.radius)
    assert len(index_of) == len(halves.theta)
    np.testing.assert_allclose(np.abs(halves.theta - parents.theta[index_of]), halves.delta)
    warm = Multipliers(mult.values[index_of], mult.warm[index_of], mult.k0)
    warm_bounds = search.box_bounds(halves, multipliers=warm)
    cold_bounds = search.box_bounds(halves)
    assert warm_bounds.sum() > cold_bounds.sum()
    for i in range(len(halves.theta)):
        plans = []
        for _ in range(2):
            a = halves.theta[i] + rng.uniform(-halves.delta[i], halves.delta[i])
            o = halves.d[i] + rng.uniform(-halves.eta[i], halves.eta[i])
            plans.append(evaluate(float(a), float(o)))
        assert warm_bounds[i] <= min(plans) + 1e-9


def test_a_move_along_a_hole_edge_is_not_charged_a_detour_past_it():
    # A review's reproducer: two lanes ending on one hole edge, the routed move runs along the
    # edge (a wall); rounding gave the collinear "crossing" either sign and the detour past the
    # wall's end charged a 7.0 m move 23.0 m: the point value was 511.5 s, above the plan's 509.5.
    def sq(x0, y0, w, h):
        return Polygon(np.array([[x0, y0], [x0 + w, y0], [x0 + w, y0 + h], [x0, y0 + h]])[::-1])

    shell = Polygon(np.array([[0, 0], [100, 0], [100, 80], [0, 80]], float))
    region = Region(shell, [sq(30, 20, 15, 30), sq(45.001, 20, 15, 30)])
    cost = CoverCost.time(5.0, 10.0)
    a, d = 0.008603252016391654, 2.1716931289126897
    search = CoverSearch(region, 7.0, 3.5, cost, None, False)
    value = search.point_values(Boxes(*(np.array([x]) for x in (a, 0.0, d, 0.0))), exact=True)[0]
    plan = plan_region(region, 7.0, decompose_area=False, angle=a, offset=d, speed=5.0,
                       turn_time=10.0)  # fmt: skip
    assert value <= cost.of(plan.stats.path_length, plan.stats.n_turns) + 1e-9
