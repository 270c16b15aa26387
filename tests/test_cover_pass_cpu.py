"""The last pass's last level bounded lowest first, stopping once no box left can lower its
floor (:func:`~boustro.optimize.cover.last_pass._level_bounds`, eighteenth round): the
same floor as every box bounded, fewer boxes."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import boustro.optimize.cover.branch as branch_module
import boustro.optimize.cover.last_pass as last_pass_module
import boustro.optimize.cover.search as search_module
from boustro.optimize.cover import CoverCost, cover_optimum
from boustro.optimize.cover.one_tree import Multipliers
from boustro.optimize.cover.search import CoverSearch

from .plan_samples import benchmark_area, count_pass_boxes, plan_cost


def _pass(monkeypatch, index, budget, levels, slice_):
    """The search's lower bound and the boxes its last pass bounded."""
    region = benchmark_area(index)
    cost = CoverCost.time(5.0, 10.0)
    bounded = count_pass_boxes(monkeypatch)
    monkeypatch.setattr(last_pass_module, "BRANCH_BUDGET", budget)
    monkeypatch.setattr(last_pass_module, "BRANCH_LEVELS", levels)
    monkeypatch.setattr(last_pass_module, "BRANCH_SLICE", slice_)
    got = cover_optimum(region, 10.0, cost, plan_cost(region, cost, spacing=10.0))
    return got, sum(bounded)


@pytest.mark.parametrize(
    ("index", "budget", "levels", "fewer"),
    [
        (22, 12_000, 4, False),  # certified: no level is the last below the target
        # the budget ends the pass: before the last chunk's first level (576 boxes either way),
        # within it (785 -> 648 boxes; chunks of 4, 16, 64, 256, 209 with 48 children)
        (22, 600, 4, False),
        (22, 800, 4, True),
        (22, 12_000, 0, False),  # the levels end it: chunks of 4 and 16, nothing left to cut
        (22, 12_000, 1, True),  # 48 -> 44 boxes
        (5, 300, 4, False),  # the 4 lowest stay below: the others not bounded
    ],
)
def test_the_last_level_stops_early_with_the_same_floor(monkeypatch, index, budget, levels, fewer):
    """The benchmark's random areas 22 (certified by the pass) and 5 (not), with budgets and
    levels that end the pass at different levels: bounded 8 boxes at a time, lowest first, the
    lower bound is the one of every box of a level bounded at once, to the last bit, the
    certificate and the plan the same, the boxes bounded never more, and fewer where the
    pass's last level has boxes below the target. Fails where a level not the last stops early,
    where the boxes below the target are counted without their halves, where a box's bound is
    taken without its bound so far."""
    whole, n_whole = _pass(monkeypatch, index, budget, levels, 10**9)
    sliced, n_sliced = _pass(monkeypatch, index, budget, levels, 8)
    assert sliced.info["lower_bound"] == whole.info["lower_bound"]
    assert sliced.info["certified"] == whole.info["certified"]
    assert (sliced.fitness, sliced.angle, sliced.offset) == (
        whole.fitness,
        whole.angle,
        whole.offset,
    )
    assert n_sliced < n_whole if fewer else n_sliced <= n_whole


def test_a_boxs_bound_does_not_depend_on_the_boxes_bounded_with_it(monkeypatch):
    """What the early stop relies on: the pass's bounds of random area 5's retired boxes (the
    1-tree branched, warm multipliers) bounded all at once and 7 at a time in another order are
    the same to the last bit, and so are the multipliers they keep."""
    region = benchmark_area(5)
    cost = CoverCost.time(5.0, 10.0)
    seen = {}
    settle = CoverSearch.settle_branched

    def spy(self, lower, value, rtol):
        seen["search"], seen["parts"] = self, list(self.retired)
        seen["target"] = value - rtol * abs(value)
        return settle(self, lower, value, rtol)

    monkeypatch.setattr(CoverSearch, "settle_branched", spy)
    cover_optimum(region, 10.0, cost, plan_cost(region, cost, spacing=10.0))
    search = seen["search"]
    boxes, _, _, mult = branch_module.joined_parts(seen["parts"])
    take = branch_module.take_multipliers
    n = len(boxes.theta)
    assert n > 20
    search.branch = (last_pass_module.BRANCH_NODES, last_pass_module.BRANCH_RTOL * seen["target"])
    whole = take(mult, np.arange(n))
    at_once = search.box_bounds(boxes, tour_below=seen["target"], multipliers=whole)
    order = np.random.default_rng(1).permutation(n)
    apart = np.empty(n)
    values = None if mult is None else np.empty_like(mult.values)
    for k in range(0, n, 7):
        idx = order[k : k + 7]
        part = take(mult, idx)
        apart[idx] = search.box_bounds(boxes.take(idx), tour_below=seen["target"], multipliers=part)
        if values is not None and part is not None:
            values[idx] = part.values
    search.branch = None
    assert np.array_equal(at_once, apart)
    if values is not None and whole is not None:
        assert np.array_equal(whole.values, values)


def _level(monkeypatch, bounds, got, level, left, mult=None):
    """:func:`~.last_pass._level_bounds` over boxes of 1 degree x 1 m (halved into 4 each at a
    radius of 57.3 m) whose bounds so far are ``bounds`` and whose bounds with the 1-tree would be
    ``got`` (a stub of :meth:`~CoverSearch.box_bounds`, which writes each box's ``got`` into its
    multipliers, warm, as the 1-tree writes its best ones back), 2 at a time: its answer and the
    boxes bounded."""
    n = len(bounds)
    boxes = search_module._Boxes(
        np.linspace(0.0, 1.0, n), np.full(n, np.radians(1.0)), np.zeros(n), np.ones(n)
    )
    asked: list[int] = []

    def box_bounds(part, tour_below, multipliers):
        idx = np.searchsorted(boxes.theta, part.theta)
        asked.extend(idx.tolist())
        if multipliers is not None:
            multipliers.values[:] = np.asarray(got)[idx].reshape(-1, 1, 1, 1)
            multipliers.warm[:] = True
        return np.asarray(got, dtype=np.float64)[idx]

    fake = SimpleNamespace(box_bounds=box_bounds, branch_left=left, radius=57.3)
    monkeypatch.setattr(last_pass_module, "BRANCH_SLICE", 2)
    monkeypatch.setattr(last_pass_module, "BRANCH_LEVELS", 4)
    out = last_pass_module._level_bounds(
        fake, boxes, np.asarray(bounds, dtype=np.float64), mult, 100.0, level
    )
    return out, sorted(asked)


def test_the_last_level_keeps_each_boxs_bound_so_far(monkeypatch):
    """At the pass's last level a box whose 1-tree bound comes out below its bound so far counts
    at its bound so far (each half keeps its parent's): the least is 1, not 0, found after the 2
    lowest boxes (the next one's bound so far, 5, cannot lower it)."""
    bounds = [5.0, 1.0, 6.0, 1.1, 7.0, 8.0]
    got = [9.0, 0.0, 9.0, 3.0, 9.0, 9.0]
    (values, least), asked = _level(monkeypatch, bounds, got, 4, 10**9)
    assert values is None and least == 1.0 and asked == [1, 3]


def test_a_level_is_the_last_once_its_halves_pass_the_budget(monkeypatch):
    """Level 0 of 4: with 5 boxes of budget left, the 2 lowest boxes, below the target, halve
    into 8: the level is the last and stops (least 2); with 8 left it is not (8 halves fit, the
    others come out above the target), so every box is bounded and the bounds are returned as
    they came."""
    bounds = [5.0, 1.0, 6.0, 1.1, 7.0, 8.0]
    got = [200.0, 2.0, 200.0, 3.0, 200.0, 200.0]  # the target is 100
    (values, least), asked = _level(monkeypatch, bounds, got, 0, 5)
    assert values is None and least == 2.0 and asked == [1, 3]
    (values, least), asked = _level(monkeypatch, bounds, got, 0, 8)
    assert values is not None and np.array_equal(values, got) and asked == list(range(6))


def test_a_level_keeps_the_multipliers_of_each_slice(monkeypatch):
    """A level bounded 2 boxes at a time writes each box's multipliers back where the box is
    (its halves at the next level start from them): every box's, in the boxes' order, warm (a
    review of the merged main: a level that dropped them passed every other test, both sides of
    the sliced-against-whole comparison dropping them alike)."""
    bounds = [5.0, 1.0, 6.0, 1.1, 7.0, 8.0]
    got = [200.0, 2.0, 200.0, 3.0, 200.0, 201.0]
    mult = Multipliers(np.zeros((6, 1, 3, 2)), np.zeros(6, dtype=bool), 0)
    (values, _), asked = _level(monkeypatch, bounds, got, 0, 10**9, mult)
    assert values is not None and asked == list(range(6))
    assert np.array_equal(mult.values[:, 0, 0, 0], got) and mult.warm.all()
