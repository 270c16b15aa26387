"""The 1-tree's steps at single layouts (optimize/cover/one_tree.py, ``POINT_TREE_STEPS``): the
search's point values take 120 subgradient steps where boxes take 40. Any multipliers give a
lower bound (Held and Karp), so more steps may only raise a value, never above a plan: checked
against the real plans at the layouts (random areas with holes, and the adversarial areas of
tests/test_cover_sound.py: holes a millimetre from the side, a grid of square holes whose edges
lie along the lines), and in boxes with the box bounds taking as many steps."""

from __future__ import annotations

import math

import numpy as np
import pytest

import boustro.optimize.cover.one_tree as one_tree_module
import boustro.optimize.cover.search as search_module
from boustro.geometry import Polygon
from boustro.geometry.region import Region
from boustro.optimize.cover import CoverCost
from boustro.optimize.cover.boxes import Boxes
from boustro.optimize.cover.search import CoverSearch

from .conftest import random_regions
from .plan_samples import SPACING, plan_cost, plans_in_boxes, sample_boxes, scaled


def _square(x0: float, y0: float, w: float, h: float) -> Polygon:
    return Polygon(np.array([[x0, y0], [x0 + w, y0], [x0 + w, y0 + h], [x0, y0 + h]])[::-1])


def _near_side() -> Region:
    """100 x 80 m, a hole 1 mm from the left side, one 2 mm from the right (issue 16)."""
    shell = Polygon(np.array([[0, 0], [100, 0], [100, 80], [0, 80]], dtype=float))
    return Region(shell, [_square(0.001, 30, 60, 10), _square(40, 50, 59.998, 8)])


def _grid_of_holes() -> Region:
    """120 x 120 m with 3 x 3 square holes of 12 m, 27 m apart: lines along their edges."""
    shell = Polygon(np.array([[0, 0], [120, 0], [120, 120], [0, 120]], dtype=float))
    holes = [_square(18 + 36 * i, 18 + 36 * j, 12, 12) for i in range(3) for j in range(3)]
    return Region(shell, holes)


def _regions() -> list[tuple[str, Region]]:
    out = [
        (f"random {i}", scaled(r, 170.0))
        for i, r in enumerate(random_regions(71, 3, n_holes=(1, 3)))
    ]
    return [*out, ("near side", _near_side()), ("grid of holes", _grid_of_holes())]


def _layouts(rng: np.random.Generator, n: int) -> Boxes:
    """``n`` single layouts: random angles and offsets, and the axis angles (lines along the
    adversarial areas' edges) at offsets on and beside the holes' edges."""
    theta = np.concatenate([rng.uniform(0, math.pi, n - 4), [0.0, 0.0, math.pi / 2, 1e-7]])
    d = np.concatenate([rng.uniform(0, SPACING, n - 4), [0.0, 3.0, 6.0, 1e-6]])
    return Boxes(theta, np.zeros(n), d, np.zeros(n))


@pytest.mark.parametrize("index", range(5))
def test_point_values_with_more_steps_stay_below_the_plans_and_above_fewer_steps(
    index, monkeypatch
):
    """At single layouts the 120-step value is at least the 40-step one (the same start and the
    same first 40 steps, the best kept) and never above the real plan there."""
    name, region = _regions()[index]
    rng = np.random.default_rng(5 + index)
    cost = CoverCost.time(5.0, float(rng.uniform(2.0, 30.0)))
    evaluate = plan_cost(region, cost)
    search = CoverSearch(region, SPACING, SPACING / 2, cost, None, False)
    layouts = _layouts(rng, 12)
    many = search.point_values(layouts, exact=True)
    monkeypatch.setattr(search_module, "POINT_TREE_STEPS", 40)
    few = search.point_values(layouts, exact=True)
    assert (many >= few - 1e-9).all(), name
    assert (many > few + 1e-6).any(), name
    for i in range(len(layouts.theta)):
        plan = evaluate(float(layouts.theta[i]), float(layouts.d[i]))
        assert many[i] <= plan + 1e-9, (name, i, many[i], plan)


@pytest.mark.parametrize("index", range(5))
def test_box_bounds_with_many_steps_never_exceed_a_plan_in_the_box(index, monkeypatch):
    """The box bounds with the 1-tree at 120 steps (as the point values take) against the real
    plans of layouts sampled in each box."""
    monkeypatch.setattr(one_tree_module, "ONE_TREE_STEPS", search_module.POINT_TREE_STEPS)
    name, region = _regions()[index]
    rng = np.random.default_rng(17 + index)
    cost = CoverCost.time(5.0, float(rng.uniform(2.0, 30.0)))
    evaluate = plan_cost(region, cost)
    search = CoverSearch(region, SPACING, SPACING / 2, cost, None, False)
    boxes = sample_boxes(rng, 8, delta=0.005)
    search.top_eps = float((boxes.delta * search.radius + boxes.eta).max()) * 1.5
    box = search.box_bounds(boxes)
    for i, plans in enumerate(plans_in_boxes(evaluate, boxes, rng)):
        assert box[i] <= min(plans) + 1e-9, (name, i, box[i], min(plans))
