"""The time objective against a 1-degree brute force of the lane angle (issue 16): the search
plans the brute force's layouts whose bound could beat its best plan (optimize/cover/centred.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import boustro.optimize.cover.bounds as bounds_module
import boustro.optimize.cover.branch as branch_module
import boustro.optimize.cover.search as search_module
from boustro.geometry.region import Region
from boustro.mission import plan_area
from boustro.optimize.cover import CoverCost, centred_offsets, cover_optimum
from boustro.optimize.cover.centred import centred_boxes
from boustro.optimize.cover.search import CoverSearch
from boustro.plan.region import plan_region

from .conftest import random_regions
from .plan_samples import benchmark_area

SPEED, TURN_TIME, SPACING = 5.0, 10.0, 10.0


def _plan_time(region: Region, angle: float, offset: float) -> float:
    plan = plan_region(
        region, SPACING, decompose_area=False, angle=angle, offset=offset, speed=SPEED,
        turn_time=TURN_TIME,
    )  # fmt: skip
    return plan.stats.duration


def test_time_plan_is_never_longer_than_the_one_degree_brute_force():
    # random field 15 of the benchmark: at fff0927 the search's plan took 1340.33 s where the
    # brute force's 135-degree layout flies 1340.26 s (its box was retired, never planned)
    region = benchmark_area(15)
    angles = np.radians(np.arange(180.0))
    offsets = centred_offsets(region, angles, SPACING, SPACING / 2)
    brute = min(_plan_time(region, a, d) for a, d in zip(angles, offsets, strict=True))
    m = plan_area(
        region.shell.vertices, SPACING, crs=None, holes=[h.vertices for h in region.holes],
        speed=SPEED, turn_time=TURN_TIME, progress=False,
    )  # fmt: skip
    assert m.stats.duration <= brute * (1 + 1e-12)
    assert m.summary()["fitness"] == pytest.approx(m.stats.duration, rel=1e-9)


@pytest.mark.parametrize("seed", [3, 11])
def test_the_bound_at_each_brute_force_layout_is_below_its_plan(seed):
    """What the final sweep relies on: the bound at a layout itself (the exact area, with the
    lanes' ends and the 1-tree) is at most that layout's plan, at every whole degree."""
    cost = CoverCost.time(SPEED, TURN_TIME)
    for region in random_regions(seed, 2, n_holes=(1, 3)):
        k = 250.0 / region.diameter
        region = Region(region.shell.vertices * k, [h.vertices * k for h in region.holes])
        search = CoverSearch(region, SPACING, SPACING / 2, cost, None, False)
        boxes = centred_boxes(region, SPACING, SPACING / 2)
        assert len(boxes.theta) == 180
        bounds = search.point_values(boxes, exact=True)
        plans = np.array([_cost(region, a, d) for a, d in zip(boxes.theta, boxes.d, strict=True)])
        assert np.all(bounds <= plans * (1 + 1e-9))
        # the bound is not trivially low: within a few per cent of the plans
        assert np.median(bounds / plans) > 0.9
        assert math.isfinite(float(bounds.min()))


def _cost(region: Region, a: float, d: float) -> float:
    st = plan_region(
        region, SPACING, decompose_area=False, angle=float(a), offset=float(d), speed=SPEED,
        turn_time=TURN_TIME,
    ).stats  # fmt: skip
    return CoverCost.time(SPEED, TURN_TIME).of(st.path_length, st.n_turns)


def _search_pair(monkeypatch, module, flag, region):
    """The time search of ``region`` (routed plans) with ``module.flag`` off and on, and the
    layouts given a 1-tree in each."""
    cost = CoverCost.time(SPEED, TURN_TIME)
    counted: list[int] = []
    real = bounds_module.one_tree_bound

    def spy(st, *args, **kwargs):
        todo = kwargs.get("todo")
        counted[-1] += int(st.count.shape[0] if todo is None else todo.sum())
        return real(st, *args, **kwargs)

    monkeypatch.setattr(bounds_module, "one_tree_bound", spy)
    runs, trees = [], []
    for on in (False, True):
        monkeypatch.setattr(module, flag, on)
        counted.append(0)
        runs.append(
            cover_optimum(
                region, SPACING, cost, lambda a, d: _cost(region, a, d), boustrophedon=False
            )
        )
        trees.append(counted[-1])
    return runs, trees


@pytest.mark.parametrize("index", range(2))
def test_point_one_trees_only_below_the_model_give_the_same_search(index, monkeypatch):
    """branch.POINT_TOURS_BELOW_MODEL: the same plan, rounds and certificate, fewer 1-trees."""
    region = random_regions(71, 2, n_holes=(1, 3))[index]
    region = Region(region.shell.vertices * 130, [h.vertices * 130 for h in region.holes])
    (a, b), (n_a, n_b) = _search_pair(monkeypatch, branch_module, "POINT_TOURS_BELOW_MODEL", region)
    assert (a.angle, a.offset, a.fitness) == (b.angle, b.offset, b.fitness)
    # the same layouts tried: planned, or ruled out by their point's bound (search.
    # SKIP_RULED_OUT), which has its 1-tree at more points with the flag off
    assert a.info["rounds"] == b.info["rounds"]
    assert a.info["plans"] + a.info["ruled_out"] == b.info["plans"] + b.info["ruled_out"]
    assert b.info["lower_bound"] == pytest.approx(a.info["lower_bound"], rel=1e-12)
    assert n_b < n_a


@pytest.mark.parametrize("index", range(2))
def test_box_one_trees_stopped_at_the_take_out_value(index, monkeypatch):
    """search.STOP_TOUR_AT_KEEP: a box's 1-tree steps stop once the box is taken out; the same
    plans and rounds, a true certificate (below the plan) as tight as before to 1e-4."""
    region = random_regions(71, 2, n_holes=(1, 3))[index]
    region = Region(region.shell.vertices * 130, [h.vertices * 130 for h in region.holes])
    (a, b), _ = _search_pair(monkeypatch, search_module, "STOP_TOUR_AT_KEEP", region)
    assert (a.angle, a.offset, a.fitness) == (b.angle, b.offset, b.fitness)
    assert a.info["rounds"] == b.info["rounds"]
    assert b.info["lower_bound"] <= b.fitness
    assert b.info["lower_bound"] == pytest.approx(a.info["lower_bound"], rel=1e-4)
