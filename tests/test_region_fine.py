"""Issue 21 at finer spacing: boxes of many lines keep the pooled split bound (no branching,
``region_splits.NODE_LINES``), which bounds every layout sampled in them and is never below
the branched one."""

from __future__ import annotations

import math

import numpy as np
import pytest

from boustro.geometry.traced import traced_field
from boustro.optimize.cover.boxes import Boxes, box_radius
from boustro.optimize.smith_bb import region as region_module
from boustro.optimize.smith_bb import region_splits
from boustro.optimize.smith_bb.kernel import lines_range
from boustro.optimize.smith_bb.region import REGION_EXTEND, REGION_EXTEND_POOLED, _RegionSearch
from boustro.optimize.smith_bb.region_chains import DEGENERATE
from boustro.optimize.smith_bb.region_splits import NODE_LINES, NODES, split_nodes


def test_split_nodes_stop_above_the_line_count() -> None:
    assert split_nodes(NODE_LINES) == NODES > 0
    assert split_nodes(NODE_LINES + 1) == 0


def _near_a_line(search: _RegionSearch, theta: np.ndarray, d: np.ndarray) -> np.ndarray:
    x, y = search.v[None, :, 0], search.v[None, :, 1]
    h = -np.sin(theta)[:, None] * x + np.cos(theta)[:, None] * y
    r = np.mod(h - d[:, None], search.s)
    return np.minimum(r, search.s - r).min(axis=1) <= 0.5 * DEGENERATE + 1e-13


def test_boxes_of_many_lines_get_the_pooled_bound_above_the_samples(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A traced field with holes (400 vertices, 4 holes) at 1.2 m: more lines than
    ``NODE_LINES``, so its boxes are bounded without branching; that bound is above the
    branched one (forced by a larger ``NODE_LINES``) in some boxes, never below it, and above
    every layout sampled in the boxes (boxes around the best layouts of a coarse scan, where
    the bounds are tight enough to matter)."""
    region = traced_field(400, 4, seed=3, radius=90.0)
    search = _RegionSearch(region, 1.2, 0.5, 0.5)
    assert lines_range(search.real[0], search.s)[1] > NODE_LINES
    search.best, search.tol = 0.0, 0.0  # a cut far below: every box gets its full bound
    rng = np.random.default_rng(11)
    theta = rng.uniform(0, math.pi, 400)
    d = rng.uniform(0, search.s, 400)
    top = np.argsort(-search.values(theta, d))[:24]
    checked = 0
    for delta, eta in ((2e-4, 0.1), (5e-5, 0.03)):
        boxes = Boxes(
            theta[top], np.full(len(top), delta), d[top], np.full(len(top), eta * search.s)
        )
        search.top_eps = float(box_radius(boxes, search.radius).max())
        pooled = search.bounds(boxes)
        monkeypatch.setattr(region_splits, "NODE_LINES", 10**9)
        branched = search.bounds(boxes)
        monkeypatch.undo()
        assert (pooled >= branched - 1e-12).all()
        checked += int((pooled > branched + 1e-9).sum())
        for _ in range(8):
            t = boxes.theta + rng.uniform(-delta, delta, len(top))
            o = boxes.d + rng.uniform(-1, 1, len(top)) * boxes.eta
            values = search.values(t, o)
            ok = _near_a_line(search, t, o) | (values <= pooled + 1e-12)
            assert ok.all(), (t[~ok], o[~ok], values[~ok], pooled[~ok])
    assert checked >= 1  # the branching does tighten some of these boxes: the pooled bound ran


class _Stop(Exception):
    pass


def test_an_area_of_many_lines_may_double_its_budget_once_more(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The default budget extends up to ``REGION_EXTEND_POOLED`` times where the boxes keep the
    pooled bound (more lines than ``NODE_LINES``), ``REGION_EXTEND`` times otherwise; an
    explicit budget is a hard limit."""
    seen: list[float] = []

    def spy(*args: object, **kw: object) -> None:
        seen.append(float(args[9]))  # type: ignore[arg-type]  # solve's extend
        raise _Stop

    monkeypatch.setattr(region_module, "solve", spy)
    region = traced_field(400, 4, seed=3, radius=90.0)
    for spacing, max_work in ((1.2, None), (10.0, None), (1.2, 1e6)):
        with pytest.raises(_Stop):
            region_module.smith_bb_region(region, spacing, max_work=max_work)
    assert seen == [REGION_EXTEND_POOLED, REGION_EXTEND, 1.0]
    assert REGION_EXTEND_POOLED > REGION_EXTEND
