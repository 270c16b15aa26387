"""The cover search's faster paths (issue 17's planning-time target) give the same answers as
the ones they replace: batched straight moves, the shared router, the driver's deferred moves,
the band kernel's sorts, turns found at once, compiled visibility and nearness."""

from __future__ import annotations

import dataclasses

import numpy as np

from boustro.geometry.region import Region, random_region
from boustro.geometry.traced import traced_field
from boustro.optimize.cover import band_lines, bands
from boustro.plan import (
    build_plan,
    drive_vehicle,
    edge_index,
    route_visibility,
    straight_moves,
    vehicle_stats,
)
from boustro.plan.edge_index import EdgeIndex
from boustro.plan.region import plan_region
from boustro.plan.routing import Router, router_for
from boustro.plan.visibility_kernel import segment_crossings
from boustro.vehicle import Vehicle, turn_between, turns_between


def _moves(region, rng, n=150):
    lo, hi = region.shell.vertices.min(0), region.shell.vertices.max(0)
    p = rng.uniform(lo, hi, (n, 2))
    q = p + rng.normal(0, 0.1 * region.diameter, (n, 2))
    v = region.shell.vertices
    q[:10] = v[rng.integers(0, len(v), 10)]  # ending on vertices
    p[10:20] = v[rng.integers(0, len(v), 10)]
    q[20:25] = p[20:25]  # zero length
    if region.holes:
        q[25:30] = region.holes[0].vertices.mean(axis=0)  # into a hole
    k = rng.integers(0, len(v), 10)  # along an edge's line, through both its vertices
    d = v[(k + 1) % len(v)] - v[k]
    p[30:40], q[30:40] = v[k] - 0.5 * d, v[k] + 1.5 * d
    return p, q


def test_straight_moves_at_once_equal_one_at_a_time_bit_for_bit():
    rng = np.random.default_rng(3)
    regions = [traced_field(150, 2, seed=1), *(random_region(rng, 12, 2) for _ in range(8))]
    for region in regions:
        for reach in (0.0, 0.02 * region.diameter):
            router = Router(region, reach=reach)
            p, q = _moves(region, rng)
            ok, outside = router._straight_many(p, q)
            single = [router._straight(a, b) for a, b in zip(p, q, strict=True)]
            assert ok.tolist() == [s[0] for s in single]
            assert outside.tolist() == [s[1] for s in single]  # inf where through a hole
            assert (~ok).any() and ok.any()
            paths = router.paths(p, q)
            for a, b, route in zip(p, q, paths, strict=True):
                one = router.path(a, b)
                assert route.length == one.length and route.outside == one.outside
                assert np.array_equal(route.points, one.points) and route.found == one.found


def test_inside_moves_at_once_equal_router_inside_one_at_a_time():
    """The visibility test's segments that touch a vertex (``route_visibility.decide``) are
    decided by ``inside_moves`` all at once: the same answer as ``Router.inside`` for each."""
    rng = np.random.default_rng(4)
    regions = [traced_field(150, 2, seed=1), *(random_region(rng, 12, 2) for _ in range(8))]
    for region in regions:
        router = Router(region, reach=0.02 * region.diameter)
        p, q = _moves(region, rng)
        v = region.shell.vertices  # from vertex to vertex: along edges, through others
        i, j = rng.integers(0, len(v), 40), rng.integers(0, len(v), 40)
        p, q = np.vstack([p, v[i]]), np.vstack([q, v[j]])
        single = [router.inside(a, b) for a, b in zip(p, q, strict=True)]
        assert straight_moves.inside_moves(router, p, q).tolist() == single
        assert any(single) and not all(single)
        assert (
            router._visible_many(p, q).tolist()
            == route_visibility.visible_tree(router, p, q).tolist()
        )


def _greedy_pass_by_pass(dist, entry_idx, exit_idx, first_pass, first_option):
    """The greedy order as ``tour._orders`` computed it before ``tour._greedy``: one pass's
    moves at a time (the reference)."""
    remaining = set(range(len(entry_idx))) - {first_pass}
    order = [first_pass]
    here = exit_idx[first_pass][first_option : first_option + 1]
    while remaining:
        best = (np.inf, -1, -1)
        for candidate in remaining:
            d = dist[np.ix_(here, entry_idx[candidate])].min(axis=0)
            j = int(np.argmin(d))
            if d[j] < best[0]:
                best = (float(d[j]), candidate, j)
        order.append(best[1])
        remaining.discard(best[1])
        here = exit_idx[best[1]][best[2] : best[2] + 1]
    return order


def test_greedy_order_all_passes_at_once_equals_pass_by_pass():
    """``tour._greedy`` takes every pass's moves from the last exit at once: the same order as
    pass by pass, ties (small integer distances) included."""
    from boustro.plan.tour import _greedy

    rng = np.random.default_rng(8)
    for trial in range(300):
        n = int(rng.integers(1, 30))
        sizes = rng.choice([1, 2, 4, 8, 16], n)
        entry_idx, exit_idx, at = [], [], 1
        for k in sizes:
            entry_idx.append(np.arange(at, at + 2 * k, 2))
            exit_idx.append(np.arange(at + 1, at + 2 * k, 2))
            at += 2 * k
        dist = rng.integers(0, 4 if trial % 2 else 1000, (at, at)).astype(np.float64)
        first = int(rng.integers(n))
        option = int(rng.integers(sizes[first]))
        want = _greedy_pass_by_pass(dist, entry_idx, exit_idx, first, option)
        assert _greedy(dist, entry_idx, exit_idx, first, option) == want


def test_router_is_built_once_per_region_and_reach():
    region = random_region(np.random.default_rng(5), 10, 1)
    assert router_for(region, 1.0) is router_for(region, 1.0)
    assert router_for(region, 2.0) is not router_for(region, 1.0)
    assert router_for(region, 1.0).reach == 1.0


def test_plan_with_the_shared_router_equals_a_fresh_one():
    region = random_region(np.random.default_rng(7), 14, 2)
    s = region.diameter / 25
    kw = dict(decompose_area=False, angle=0.7, offset=0.3, reach=s / 2)
    first = plan_region(region, s, **kw)
    router_for.cache_clear()
    fresh = plan_region(region, s, **kw)
    again = plan_region(region, s, **kw)  # the cached router
    for other in (fresh, again):
        assert np.array_equal(first.waypoints, other.waypoints)
        assert first.kinds == other.kinds
        assert first.stats == other.stats


def test_band_sorts_sort_in_place_with_their_partners():
    bands._compiled()  # the numba dispatchers in the helpers' module's globals
    rng = np.random.default_rng(11)
    for sort_pairs, sort_keys in (
        (band_lines._sort_pairs, band_lines._sort_keys),
        (band_lines._sort_pairs.py_func, band_lines._sort_keys.py_func),
    ):
        for n in (0, 1, 2, 7, 40):
            key = rng.integers(0, 5, n).astype(np.float64)  # ties
            other = rng.normal(size=n)
            ids = np.arange(n, dtype=np.int64)
            k1, o1, k2, i2, k3 = key.copy(), other.copy(), key.copy(), ids.copy(), key.copy()
            lo, hi = (1, n - 1) if n > 2 else (0, n)
            sort_pairs(k1, o1, lo, hi)
            sort_pairs(k2, i2, lo, hi)
            sort_keys(k3, lo, hi)
            expect = np.argsort(key[lo:hi], kind="stable") + lo  # insertion sort is stable
            assert np.array_equal(k1[lo:hi], key[expect]) and np.array_equal(
                o1[lo:hi], other[expect]
            )
            assert np.array_equal(i2[lo:hi], ids[expect]) and np.array_equal(k3, k1)
            assert np.array_equal(k1[:lo], key[:lo]) and np.array_equal(k1[hi:], key[hi:])


def test_turns_at_once_equal_one_at_a_time():
    rng = np.random.default_rng(2)
    m = 300
    starts = np.c_[rng.normal(0, 20, (m, 2)), rng.uniform(-4, 4, m)]
    goals = np.c_[rng.normal(0, 20, (m, 2)), rng.uniform(-4, 4, m)]
    # lane ends: U-turns between parallel lanes (ties between mirror words), and no move
    goals[:50] = (
        starts[:50] + np.c_[np.zeros(50), rng.choice([6.0, 10.0, 12.0], 50), np.full(50, np.pi)]
    )
    starts[:50, 2] = 0.0
    goals[:50, 2] = np.pi
    goals[50:55] = starts[50:55]
    for vehicle in (Vehicle(turn_radius=6.0), Vehicle(turn_radius=6.0, reverse=True)):
        batch = turns_between(vehicle, starts, goals, 0.05)
        for a, b, turn in zip(starts, goals, batch, strict=True):
            one = turn_between(vehicle, a, b, 0.05)
            assert turn.word == one.word and turn.length == one.length
            assert np.array_equal(turn.points, one.points)
            assert np.array_equal(turn.headings, one.headings)
            assert np.array_equal(turn.gear, one.gear)
    assert turns_between(Vehicle(turn_radius=6.0), np.zeros((0, 3)), np.zeros((0, 3))) == []


def _scaled(region, size):
    k = size / region.diameter
    return Region(region.shell.vertices * k, [h.vertices * k for h in region.holes])


def test_vehicle_stats_are_the_driven_plans_stats():
    square = [(0, 0), (120, 0), (120, 90), (0, 90)]
    rng = np.random.default_rng(4)
    plain, holed = (_scaled(random_region(rng, 12, h), 300.0) for h in (0, 2))
    plans = [
        build_plan(square, 10.0, 0.3, speed=2.0, turn_time=5.0),
        build_plan(square, 10.0, 0.3, turnaround=4.0),
        plan_region(plain, 10.0, decompose_area=False, angle=0.4, offset=0.1),
        plan_region(holed, 10.0, decompose_area=False, angle=1.1, offset=0.2),
    ]
    for plan in plans:
        for vehicle in (Vehicle(turn_radius=6.0), Vehicle(turn_radius=4.0, reverse=True)):
            for field in (None, holed if plan.region is holed else None):
                driven = drive_vehicle(plan, vehicle, field=field).stats
                stats = vehicle_stats(plan, vehicle, field=field)
                # all but the length outside, measured on the driven curves only
                assert dataclasses.replace(stats, outside_length=driven.outside_length) == driven
                assert driven.turn_length > 0 or field is not None  # all refused: outside


def test_compiled_visibility_equals_the_trees(monkeypatch):
    rng = np.random.default_rng(8)
    regions = [traced_field(120, 2, seed=3), *(random_region(rng, 14, 2) for _ in range(6))]
    for region in regions:
        router = Router(region, reach=0.0)
        v = np.concatenate([region.shell.vertices] + [h.vertices for h in region.holes])
        p = rng.uniform(v.min(0), v.max(0), (300, 2))
        q = rng.uniform(v.min(0), v.max(0), (300, 2))
        i = rng.integers(0, len(v), (150, 2))
        p[:150], q[:150] = v[i[:, 0]], v[i[:, 1]]  # vertex to vertex
        j = rng.integers(0, len(v) - 1, 50)  # along an edge, through its vertices
        p[150:200], q[150:200] = 2 * v[j] - v[j + 1], 3 * v[j + 1] - 2 * v[j]
        monkeypatch.setattr(route_visibility, "DENSE_EDGES", 10**9)
        dense = router._visible_many(p, q)
        monkeypatch.setattr(route_visibility, "DENSE_EDGES", 0)
        grid = router._visible_many(p, q)
        tree = route_visibility.visible_tree(router, p, q)
        assert np.array_equal(dense, tree) and dense.any() and (~dense).any()
        assert np.array_equal(grid, tree)
    proper, touched = segment_crossings(
        np.array([[0.0, 0.0], [0.0, 0.0]]), np.array([[2.0, 2.0], [2.0, 0.0]]),
        np.array([[0.0, 2.0], [1.0, 0.0]]), np.array([[2.0, 0.0], [1.0, -1.0]]), 1e-12,
    )  # fmt: skip
    assert proper.tolist() == [True, False] and touched.tolist() == [False, True]


def test_compiled_nearness_equals_the_trees(monkeypatch):
    rng = np.random.default_rng(9)
    for region in (traced_field(120, 2, seed=5), *(random_region(rng, 14, 2) for _ in range(5))):
        index = EdgeIndex(region, 1e-9 * region.diameter)
        v = np.concatenate([region.shell.vertices] + [h.vertices for h in region.holes])
        p = rng.uniform(v.min(0), v.max(0), (2000, 2))
        p[:200] = v[rng.integers(0, len(v), 200)] + rng.normal(0, 1e-9 * region.diameter, (200, 2))
        answers = []
        for dense in (10**9, 0):
            monkeypatch.setattr(edge_index, "DENSE_EDGES", dense)
            r = 0.02 * region.diameter
            answers.append(
                (index.within(p, r, len(region.shell)), index.near(p), index.classify(p))
            )
        for a, b in zip(*answers, strict=True):
            assert np.array_equal(a, b)
        assert answers[0][1].any() and not answers[0][1].all() and answers[0][0].any()
