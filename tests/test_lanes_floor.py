"""The search's cheap screen of ``keep_inside`` layouts (issue 16, seventeenth round): the floor
from the lanes alone (:func:`boustro.plan.region_floor.lanes_floor`) is below the plan floor
(:func:`~boustro.plan.region_floor.plan_floor`) whatever the cost, and
:func:`~boustro.plan.region_floor.screen_floor` screens out exactly the layouts the plan floor
screens out."""

from __future__ import annotations

import math

import numpy as np
import pytest

from boustro.geometry.region import Region, random_region
from boustro.optimize.cover import CoverCost
from boustro.plan.region import plan_region
from boustro.plan.region_floor import lanes_floor, plan_floor, screen_floor

from .test_inside_floor import SPACING, _areas

#: The mission's time objective, and the path length alone (no turn pays for a pass's ends:
#: the lanes' moves' floor is counted only where a turn costs at least the longest of them).
COSTS = (CoverCost.time(5.0, 10.0), CoverCost.path_length())


def _more_areas() -> list[Region]:
    rng = np.random.default_rng(5)
    out = []
    for _ in range(4):
        r = random_region(rng, int(rng.integers(6, 14)), int(rng.integers(0, 3)), roughness=0.6)
        k = 150.0 / r.diameter
        out.append(Region(r.shell.vertices * k, [h.vertices * k for h in r.holes]))
    return out


def _layouts(index: int, n: int) -> list[dict]:
    rng = np.random.default_rng(index)
    pairs = zip(rng.uniform(0, math.pi, n), rng.uniform(0, SPACING, n), strict=True)
    return [dict(decompose_area=False, angle=a, offset=d, keep_inside=True) for a, d in pairs]


@pytest.mark.parametrize("index", range(7))
def test_the_lanes_floor_is_below_the_plan_floor(index):
    """On 10 layouts of each area and either cost, the cheap floor is at most the plan floor's
    cost (and so below every plan's, test_inside_floor), and not a trivial one."""
    region = (_areas() + _more_areas())[index]
    close = 0
    for kw in _layouts(index, 10):
        floor = plan_floor(region, SPACING, **kw)
        for cost in COSTS:
            full = cost.of(*floor)
            cheap = lanes_floor(region, SPACING, cost.of, **kw)
            assert cheap <= full
            close += cheap > 0.8 * full
    assert close >= 10


@pytest.mark.parametrize("index", range(3))
def test_the_screen_rules_out_what_the_plan_floor_rules_out(index):
    """Against thresholds just above and below the plan floor's cost, and far below it (where
    the lanes alone rule the layout out), the screen rules out exactly where the plan floor
    does, and never returns more than it."""
    region = _areas()[index]
    cost = COSTS[0]
    cheap_ones = 0
    for kw in _layouts(index + 10, 8):
        full = cost.of(*plan_floor(region, SPACING, **kw))
        for t in (full * (1 + 1e-6), full * (1 - 1e-6), full * 0.9, full * 0.5):
            got = screen_floor(region, SPACING, cost.of, lambda f, t=t: f > t, **kw)
            assert (got > t) == (full > t)
            assert got <= full
            cheap_ones += got < full
    assert cheap_ones > 0  # some layouts were screened by their lanes alone


def test_no_pass_where_the_lanes_cover_the_area():
    """A rectangle whose lanes at 0 degrees cover it exactly at some offsets (margin 0, no
    pass): the cheap floor counts no pass there (one turn fewer than the lanes and a pass)."""
    rect = Region(np.array([(0, 0), (100, 0), (100, 40), (0, 40)], dtype=float))
    bare = 0
    for offset in np.linspace(0, SPACING, 11)[:-1]:
        kw = dict(decompose_area=False, angle=0.0, offset=float(offset), keep_inside=True)
        plan = plan_region(rect, SPACING, **kw)
        bare += plan.stats.boundary_pass_length == 0
        for cost in COSTS:
            floor = cost.of(*plan_floor(rect, SPACING, **kw))
            assert lanes_floor(rect, SPACING, cost.of, **kw) <= floor
    assert bare > 0
