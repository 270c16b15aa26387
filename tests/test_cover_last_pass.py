"""The last pass over the retired boxes on the window class (:data:`~boustro.optimize.cover.
last_pass.BRANCH_REACH`, nineteenth round): where the lowest retired box is farther below the
discard value than :data:`~boustro.optimize.cover.last_pass.BRANCH_RTOL` of the plan, the pass
runs with the lowest box alone first, the 1-tree branched within that box's distance to the
discard value, and its own budget of boxes; farther than ``BRANCH_REACH`` it does not run."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import boustro.optimize.cover.last_pass as last_pass_module
from boustro.optimize.cover.boxes import Boxes

VALUE, RTOL = 1000.0, 1e-3
TARGET = VALUE - RTOL * VALUE  # 999: the discard value


def _pass(bounds, got, lower=900.0, whole=None):
    """:func:`~.last_pass.settle_branched` over retired boxes of 1 degree (radius 57.3 m)
    whose bounds so far are ``bounds``, with a stub of ``box_bounds`` that gives every box, and
    every half of it, its root box's ``got`` (``whole``: a root box itself, unhalved, gets
    ``whole[root]`` instead where given): the floor returned and each call's (root boxes, the
    branching's window, boxes left in the budget)."""
    n = len(bounds)
    boxes = Boxes(
        np.radians(np.arange(n, dtype=np.float64)), np.full(n, np.radians(0.5)), np.zeros(n),
        np.ones(n),
    )  # fmt: skip
    calls: list[tuple[list[int], float, int]] = []

    def box_bounds(part, tour_below, multipliers):
        assert tour_below == TARGET
        root = np.rint(np.degrees(part.theta)).astype(int)
        calls.append((sorted(set(root.tolist())), search.branch[1], search.branch_left))
        out = np.asarray(got, dtype=np.float64)[root]
        for i, r in enumerate(root.tolist()):
            if whole and r in whole and part.delta[i] == np.radians(0.5):
                out[i] = whole[r]
        return out

    search = SimpleNamespace(
        retired=[(boxes, np.asarray(bounds, dtype=np.float64), np.asarray(bounds), None)],
        ends=True, tour=True, rest_floor=np.inf, work=0.0, bound_evaluations=0, branch=None,
        branch_left=0, radius=57.3, box_bounds=box_bounds,
    )  # fmt: skip
    floor = last_pass_module.settle_branched(search, lower, VALUE, RTOL)
    assert search.branch is None and search.retired == []
    return floor, calls


def test_the_window_class_starts_with_the_lowest_box_branched_within_its_distance():
    """Lowest box 9 s below the discard value (beyond 0.3% of the plan, within 1.5%): the first
    call bounds it alone, with the branching's window 9 s and the window class's budget; every
    box reaching the target, the floor is the least of them (above the discard value)."""
    bounds = [995.0, 990.0, 996.0, 997.0]
    got = [1001.0, 1000.0, 1002.0, 1003.0]
    floor, calls = _pass(bounds, got)
    assert calls[0][0] == [1]  # the lowest alone
    assert all(window == pytest.approx(9.0) for _, window, _ in calls)
    assert calls[0][2] == last_pass_module.BRANCH_REACH_BUDGET - 1
    assert sorted(r for c in calls for r in c[0]) == [0, 1, 2, 3]  # each box once
    assert floor == 1000.0


def test_the_window_class_stops_after_the_lowest_box_where_it_stays_below():
    """The lowest box's bound stays at 992 however far it is halved: only its own levels are
    bounded (the cheap early stop: no other box), and the floor is its bound, 992, above the
    floor before (900) and below the other boxes' (995-997)."""
    bounds = [995.0, 990.0, 996.0, 997.0]
    got = [1001.0, 992.0, 1002.0, 1003.0]
    floor, calls = _pass(bounds, got)
    assert {r for c in calls for r in c[0]} == {1}
    assert len(calls) == last_pass_module.BRANCH_LEVELS + 1  # every level, one slice each
    assert floor == 992.0


def test_the_window_class_keeps_the_lowest_bound_where_its_box_halves_lower():
    """A box whose 1-tree bound comes out below its bound so far keeps its bound so far (its
    halves too): the floor is the lowest box's own 990, not the 950 the stub gives."""
    floor, _ = _pass([995.0, 990.0], [1001.0, 950.0])
    assert floor == 990.0


def test_beyond_the_reach_or_within_the_old_window_the_pass_is_as_before():
    """Lowest box 16 s below (beyond 1.5% of the plan): no pass, the floor as it was. Within
    0.3% (2 s below): the chunk of the 4 lowest first, the branching's window 3 s (0.3% of the
    plan) and the budget of :data:`~.last_pass.BRANCH_BUDGET`, as before the window class."""
    floor, calls = _pass([983.0, 995.0], [1001.0, 1002.0])
    assert calls == [] and floor == 900.0
    bounds = [997.5, 997.0, 998.0, 998.5, 998.7]
    floor, calls = _pass(bounds, [1000.0] * 5)
    assert calls[0][0] == [0, 1, 2, 3]
    assert calls[0][1] == pytest.approx(3.0)
    assert calls[0][2] == last_pass_module.BRANCH_BUDGET - 4
    assert floor == 1000.0


def test_the_window_class_does_not_start_where_its_budget_cannot_reach_every_box(monkeypatch):
    """Six boxes below the discard value, each reaching it at its first bound: with a budget of
    five boxes the pass cannot certify (a box left unbounded keeps its bound below it), so it
    bounds none (the early fail) and the floor is the lowest box's 990; with six it bounds
    each once and the floor is the least of theirs (1000)."""
    bounds = [995.0, 990.0, 996.0, 997.0, 996.5, 995.5]
    got = [1001.0, 1000.0, 1002.0, 1003.0, 1004.0, 1005.0]
    monkeypatch.setattr(last_pass_module, "BRANCH_REACH_BUDGET", 5)
    floor, calls = _pass(bounds, got)
    assert calls == [] and floor == 990.0
    monkeypatch.setattr(last_pass_module, "BRANCH_REACH_BUDGET", 6)
    floor, calls = _pass(bounds, got)
    assert sorted(r for c in calls for r in c[0]) == [0, 1, 2, 3, 4, 5] and floor == 1000.0


def test_the_window_class_stops_where_the_boxes_left_outnumber_the_budget_left(monkeypatch):
    """The lowest box reaches the discard value only once halved (1 + 4 boxes of a budget of
    9): the five boxes left then outnumber the four left in the budget, so the pass stops
    after the first chunk (no other box bounded) and the floor is the least bound of the
    boxes left (995). Within 0.3% of the plan the pass is as before, without it: six boxes
    and a budget of five, its first chunk of four is bounded (the two left are over it)."""
    bounds = [995.0, 990.0, 996.0, 997.0, 996.5, 995.5]
    got = [1001.0, 1000.0, 1002.0, 1003.0, 1004.0, 1005.0]
    monkeypatch.setattr(last_pass_module, "BRANCH_REACH_BUDGET", 9)
    floor, calls = _pass(bounds, got, whole={1: 992.0})
    assert {r for c in calls for r in c[0]} == {1} and len(calls) == 2
    assert floor == 995.0
    monkeypatch.setattr(last_pass_module, "BRANCH_BUDGET", 5)
    floor, calls = _pass([997.0, 996.5, 997.5, 998.0, 997.8, 997.2], got)
    assert calls[0][0] == [0, 1, 2, 5] and len(calls) == 1 and floor == 997.8


@pytest.mark.parametrize("lowest", [995.5, 987.0])
def test_the_window_class_spans_from_the_old_window_to_the_reach(lowest):
    """Lowest box 3.5 s below the discard value (just past 0.3% of the plan) and 12 s below
    (1.2%, within 1.5%): the window class, the lowest box alone first, the branching's window
    its distance (a review: a class starting at twice the old window, or a reach of 1%,
    passed the tests above)."""
    floor, calls = _pass([lowest, 996.0], [1001.0, 1002.0])
    assert calls[0][0] == [0] and calls[0][1] == pytest.approx(999.0 - lowest)
    assert floor == 1000.0  # the plan


def test_the_window_class_certifies_random_74_with_the_same_plan(monkeypatch):
    """The benchmark's random area 74 (its lowest retired box 3.7 s, 0.36% of the plan, below
    the discard value): certified by the window class, not without it (``BRANCH_REACH`` at
    ``BRANCH_RTOL``), with the same plan and plans made, a floor between the two and below the
    real plans of a 3-degree sweep (a review: the branch's tests were all stubbed)."""
    from boustro.optimize.cover import CoverCost, cover_optimum

    from .plan_samples import benchmark_area, plan_cost
    from .test_cover_one_tree_branch import _certified_by_the_pass

    region = benchmark_area(74)
    cost = CoverCost.time(5.0, 10.0)
    evaluate = plan_cost(region, cost, spacing=10.0)
    got = cover_optimum(region, 10.0, cost, evaluate)
    monkeypatch.setattr(last_pass_module, "BRANCH_REACH", last_pass_module.BRANCH_RTOL)
    _certified_by_the_pass(got, cover_optimum(region, 10.0, cost, evaluate), evaluate, seed=74)
