"""The certified cover search's partial last round (``branch.PARTIAL_ROUND``; docs/scale.md,
"A partial last round"): where the next round would pass the work budget, the boxes of the
lowest bounds that it still allows are halved, and the others leave with their bounds in the
certificate's floor."""

from __future__ import annotations

import numpy as np
import pytest

import boustro.optimize.cover.branch as branch_module
import boustro.optimize.cover.search as search_module
from boustro.geometry.traced import traced_field
from boustro.optimize.cover import CoverCost, cover_optimum
from boustro.optimize.cover.boxes import Boxes

COST = CoverCost.time(5.0, 10.0)
SPACING = 10.0
BOX_BOUNDS = search_module.CoverSearch.box_bounds
BOXES_WITHIN = search_module.CoverSearch.boxes_within


def _field():
    region = traced_field(300, 2, radius=120.0)
    assert len(region.edges) > search_module.SIMPLIFY_EDGES  # simplified sandwiches
    return region


def _run(region, monkeypatch, on: bool, max_work: float = 1e5):
    """The model-only search (the model is the plan) with its box bounds and the boxes the
    partial round took recorded."""
    monkeypatch.setattr(branch_module, "PARTIAL_ROUND", on)
    calls: list[np.ndarray] = []
    fits: list[int] = []

    def record(self, boxes, *a, **k):
        out = BOX_BOUNDS(self, boxes, *a, **k)
        calls.append(out.copy())
        return out

    def record_fit(self, max_work):
        fits.append(BOXES_WITHIN(self, max_work))
        return fits[-1]

    monkeypatch.setattr(search_module.CoverSearch, "box_bounds", record)
    monkeypatch.setattr(search_module.CoverSearch, "boxes_within", record_fit)
    res = cover_optimum(region, SPACING, COST, None, n_angles=12, max_work=max_work)
    return res, calls, fits


def test_partial_round_halves_the_lowest_boxes_the_floor_keeps_the_others(monkeypatch):
    region = _field()
    off, off_calls, _ = _run(region, monkeypatch, False)
    on, calls, fits = _run(region, monkeypatch, True)
    assert "work budget" in off.info["stopped"] and "work budget" in on.info["stopped"]
    assert on.info["rounds"] == off.info["rounds"] + 1
    assert len(calls) == len(off_calls) + 1
    last, halves = calls[-2], calls[-1]
    fit = fits[0]
    assert 1 <= fit < len(last)
    rest = np.argsort(last, kind="stable")[fit:]
    # the boxes left out are in the floor: here they hold it (the halves are higher)
    assert last[rest].min() < halves.min()
    assert on.info["lower_bound"] == pytest.approx(min(last[rest].min(), halves.min()), abs=1e-9)
    assert off.info["lower_bound"] <= on.info["lower_bound"] <= on.fitness


def test_partial_round_floor_below_the_model_everywhere(monkeypatch):
    """The certificate's floor (the model is the plan here) below the model at a sweep of
    layouts: every half degree, four offsets."""
    region = _field()
    on, _, _ = _run(region, monkeypatch, True, max_work=2e5)
    ref = search_module.CoverSearch(region, SPACING, SPACING / 2, COST, None, False)
    theta, d = np.meshgrid(np.radians(np.arange(0, 180, 0.5)), np.arange(4) * SPACING / 4)
    z = np.zeros(theta.size)
    values = ref.point_values(Boxes(theta.ravel(), z, d.ravel(), z), exact=True)
    assert on.info["lower_bound"] <= values.min()


def test_partial_round_only_on_simplified_searches_without_keep_inside():
    region = _field()
    s = search_module.CoverSearch(
        region, SPACING, SPACING / 2, COST, lambda a, d: 0.0, False, keep_inside=True
    )
    assert not branch_module.partial_round(s)
    s = search_module.CoverSearch(region, SPACING, SPACING / 2, COST, lambda a, d: 0.0, False)
    assert branch_module.partial_round(s)
    small = traced_field(100, 1, radius=120.0)  # exact sandwiches: the search as before
    s = search_module.CoverSearch(small, SPACING, SPACING / 2, COST, lambda a, d: 0.0, False)
    assert s.sandwich.tolerance <= 0 and not branch_module.partial_round(s)


def test_boxes_within_is_the_most_boxes_the_budget_allows():
    """:meth:`boxes_within` is the largest ``n`` with :meth:`work_spent` ``(n)`` within the
    budget (a partial round takes no fewer boxes than the budget allows, nor more)."""
    region = _field()
    search = search_module.CoverSearch(region, SPACING, SPACING / 2, COST, None, False)
    assert search.boxes_within(1e9) == 0  # no work yet: no cost per layout known
    theta = np.radians(np.arange(0.0, 180.0, 7.0))
    z = np.zeros(len(theta))
    search.point_values(Boxes(theta, z + 2.0, z + 1.0, z + 2.0))  # some work spent
    assert search.work > 0
    assert search.boxes_within(search.work_spent(0) - 1.0) == 0
    for extra in (0.5, 1.5, 7.25, 40.5, 1000.5):
        budget = search.work_spent(0) + extra * (search.work_spent(1) - search.work_spent(0))
        n = search.boxes_within(budget)
        assert n == int(extra), (extra, n)
        assert search.work_spent(n) <= budget < search.work_spent(n + 1)
