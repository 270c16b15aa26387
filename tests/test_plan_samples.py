"""The soundness tests' reference (tests/plan_samples.py): real plans' costs, the box's centre
first, the others at layouts inside the box."""

from __future__ import annotations

import numpy as np

from boustro.optimize.cover import CoverCost

from .conftest import random_regions
from .plan_samples import plan_cost, plans_in_boxes, sample_boxes, scaled


def test_plans_in_boxes_are_real_plans_of_the_box():
    region = scaled(random_regions(31, 1, n_holes=(1, 1))[0], 150.0)
    assert abs(region.diameter - 150.0) < 1e-9
    cost = CoverCost.time(5.0, 10.0)
    evaluate = plan_cost(region, cost)
    rng = np.random.default_rng(1)
    boxes = sample_boxes(rng, 6, delta=0.3)
    assert np.all((boxes.delta == 0) | (boxes.delta <= 0.3)) and (boxes.delta > 0).any()
    seen = []
    for i, plans in enumerate(plans_in_boxes(evaluate, boxes, rng)):
        assert len(plans) == 4
        assert plans[0] == evaluate(float(boxes.theta[i]), float(boxes.d[i]))
        assert all(p > 0 for p in plans)
        seen.append(len(set(plans)) > 1)
    assert any(seen)  # layouts drawn inside a box of some width give other plans
