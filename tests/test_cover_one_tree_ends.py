"""The 1-tree's collapsed lane-end ranges (optimize/cover/one_tree.py, ``_lane_ends``): a
counted line's first lane starts in ``[in_lo - t, in_lo]`` and its last lane ends in ``[in_hi,
in_hi + t]`` whatever the outer projection's extremes (issue 16, random area 35: a box whose
band catches a wedge beyond a notch let the line's last lane end anywhere in 105 m). Sound on
adversarial areas (a notch with the lines along its step, thin holes, lines along the edges,
run-ins, a turn radius), and the outer extremes no longer weaken the bound."""

from __future__ import annotations

import math

import numpy as np
import pytest

import boustro.optimize.cover.bounds as bounds_module
from boustro.geometry import Polygon
from boustro.geometry.region import Region
from boustro.optimize.cover import CoverCost, band_stats
from boustro.optimize.cover.boxes import Boxes
from boustro.optimize.cover.one_tree import one_tree_bound
from boustro.optimize.cover.search import CoverSearch
from boustro.vehicle import Vehicle

from .plan_samples import SPACING, plan_cost, plans_in_boxes


def _zeros(st, *args, **kw):
    return np.zeros(st.count.shape[0])


def _region(case: str) -> Region:
    """An adversarial area: ``notch`` an L whose step edge runs along the lines (angle 0),
    ``sliver`` a rectangle with a 2 cm wide hole and a square one, ``edges`` a rectangle with a
    rectangular hole (the lines along its edges at angles 0 and pi / 2)."""
    square = Polygon(np.array([[10, 70], [20, 70], [20, 80], [10, 80]], dtype=float))
    if case == "notch":
        shell = np.array([[0, 0], [100, 0], [100, 50], [40, 50], [40, 100], [0, 100]], float)
        return Region(Polygon(shell), [square])
    shell = Polygon(np.array([[0, 0], [100, 0], [100, 90], [0, 90]], dtype=float))
    if case == "sliver":
        sliver = np.array([[40.0, 30.0], [55.0, 45.02], [70.0, 60.0]])
        return Region(shell, [Polygon(sliver), square])
    return Region(shell, [Polygon(np.array([[30, 30], [70, 30], [70, 50], [30, 50]], float))])


def _boxes(rng: np.random.Generator, angles: list[float], n: int) -> Boxes:
    """``n`` boxes at ``angles`` (each within 0.03 rad), radii up to 4 mrad and 1.5 m."""
    theta = np.array(angles)[rng.integers(0, len(angles), n)] + rng.uniform(-0.03, 0.03, n)
    return Boxes(
        theta, rng.uniform(0, 4e-3, n), rng.uniform(0, SPACING, n), rng.uniform(0.02, 1.5, n)
    )


CASES = [
    ("notch", "plain", [0.0]),
    ("notch", "turnaround", [0.0]),
    ("notch", "vehicle", [0.0, math.pi / 2]),
    ("sliver", "plain", [math.pi / 4, 0.0]),
    ("sliver", "turnaround", [math.pi / 4]),
    ("edges", "plain", [0.0, math.pi / 2]),
    ("edges", "turnaround", [0.0, math.pi / 2]),
    ("edges", "vehicle", [0.0]),
]


@pytest.mark.parametrize(("area", "case", "angles"), CASES)
def test_collapsed_one_tree_never_exceeds_a_plan_in_the_box(area, case, angles, monkeypatch):
    """The box bound with the 1-tree as its only bound on the moves beyond the lines' span (the
    lane-ends and piece-ends bounds switched off) is at most every real plan sampled in the box
    (centre and three random layouts): 3 m run-ins or a 6 m turn radius's driven turns."""
    monkeypatch.setattr(bounds_module, "lane_end_bound", _zeros)
    monkeypatch.setattr(bounds_module, "piece_end_bound", _zeros)
    region = _region(area)
    rng = np.random.default_rng(len(area) * 7 + len(case))
    turnaround = 3.0 if case == "turnaround" else 0.0
    cost = CoverCost.time(5.0, float(rng.uniform(2.0, 30.0)), turnaround=turnaround)
    vehicle = Vehicle(turn_radius=6.0) if case == "vehicle" else None
    evaluate = plan_cost(region, cost, turnaround=turnaround, vehicle=vehicle)
    search = CoverSearch(region, SPACING, SPACING / 2, cost, None, False)
    boxes = _boxes(rng, angles, 12)
    search.top_eps = float((boxes.delta * search.radius + boxes.eta).max()) * 1.5
    box = search.box_bounds(boxes)
    for i, plans in enumerate(plans_in_boxes(evaluate, boxes, rng)):
        assert box[i] <= min(plans) + 1e-9


@pytest.mark.parametrize("turnaround", [0.0, 3.0])
def test_the_outer_extremes_do_not_weaken_the_one_tree(turnaround):
    """Boxes straddling the notch's step (the band's edge catches the wide part beyond it at
    some layouts of the box, not at others): the outer projection reaches 60 m past the inner
    one on some counted line, and the 1-tree bound is the same with the outer extremes moved to
    the inner ones (before the collapse it was up to 3.2 s lower there)."""
    region = _region("notch")
    cost = CoverCost.time(5.0, 10.0, turnaround=turnaround)
    search = CoverSearch(region, SPACING, SPACING / 2, cost, None, False)
    rng = np.random.default_rng(0)
    boxes = _boxes(rng, [0.0], 40)
    eps = float((boxes.delta * search.radius + boxes.eta).max())
    lv = search.sandwich.level(eps, 0.0)
    st = band_stats(
        lv.inner, lv.outer, boxes.theta, boxes.d, SPACING, SPACING / 2, search.origin,
        search.k_range(eps + SPACING), search.n_holes, search.tol,
        inner_reach=search._inner_reach(),
    )  # fmt: skip
    counted = st.count >= 1
    reach = np.where(counted, st.out_hi - st.in_hi, 0.0)
    assert np.nanmax(reach) > 50.0  # the wide part beyond the step, on a counted line
    tree = one_tree_bound(st, SPACING, cost, steps=60)
    inner = st._replace(out_lo=st.in_lo.copy(), out_hi=st.in_hi.copy())
    assert (tree > 0).all()
    np.testing.assert_array_equal(tree, one_tree_bound(inner, SPACING, cost, steps=60))
