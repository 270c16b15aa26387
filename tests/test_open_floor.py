"""The floor of a plan without ``keep_inside`` (eighteenth round,
:func:`boustro.plan.region_floor.plan_floor` without it: its lanes and hole passes, a floor of
its moves): below every plan with the plan's turns, near it, and the decomposed plan's cells
screening their edge layouts by it (``_Search._centred``) make the same plan."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from boustro.geometry.region import Region
from boustro.mission import decomposed
from boustro.optimize import OptimizeResult
from boustro.optimize.cover import CoverCost
from boustro.plan.cells import decompose
from boustro.plan.region import plan_region
from boustro.plan.region_floor import lanes_floor, plan_floor, screen_floor

from .test_inside_floor import L_HOLES, SPACING, _areas
from .test_keep_inside_screen import _centred_values
from .test_lanes_floor import COSTS, _more_areas


def _cells() -> list[Region]:
    """The merged cells of two areas with holes (a decomposition's cells keep the holes they
    surround: their plans fly hole passes)."""
    out = []
    for region in (L_HOLES, _areas()[1]):
        out += list(decompose(region, 0.4, merge=True, min_width=2 * SPACING).cells)
    return out


def _regions() -> list[Region]:
    return _areas() + _more_areas() + _cells()


@pytest.mark.parametrize("turnaround", [0.0, 4.0])
def test_the_open_floor_is_below_every_plan(turnaround):
    """On 6 layouts of each area (holes, no hole, a decomposition's cells with a hole): the
    floor's turns are the plan's, its length at most the plan's path and at least its lanes and
    hole passes, and (without run-ins) near the plan on most layouts."""
    rng = np.random.default_rng(7)
    near = laid = with_holes = 0
    for region in _regions():
        for angle, offset in zip(
            rng.uniform(0, math.pi, 6), rng.uniform(0, SPACING, 6), strict=True
        ):
            kw = dict(decompose_area=False, angle=angle, offset=offset, turnaround=turnaround)
            plan = plan_region(region, SPACING, **kw)
            length, turns = plan_floor(region, SPACING, **kw)
            st = plan.stats
            assert turns == st.n_turns
            assert length <= st.path_length * (1 + 1e-12)
            assert length >= st.transect_length + st.hole_pass_length - 1e-9
            near += length > 0.95 * st.path_length
            laid += 1
            with_holes += st.hole_pass_length > 0
    assert with_holes >= 6
    assert near >= 0.8 * laid or turnaround > 0  # run-ins and run-outs are not in the floor


def test_the_screen_without_keep_inside_is_the_plan_floor():
    """Without ``keep_inside`` the screen returns the plan floor's cost (no cheap floor: the
    margins are keep-inside's), whatever ``best``."""
    kw = dict(decompose_area=False, angle=0.7, offset=3.0)
    for cost in COSTS:
        full = cost.of(*plan_floor(L_HOLES, SPACING, **kw))
        assert lanes_floor(L_HOLES, SPACING, cost.of, **kw) is None
        for t in (0.0, full, math.inf):
            assert screen_floor(L_HOLES, SPACING, cost.of, lambda f, t=t: f > t, **kw) == full


def test_no_hole_pass_no_ring():
    """With hole passes off the plan flies no hole pass: neither does the floor."""
    kw = dict(decompose_area=False, angle=0.2, offset=2.0, hole_passes=False)
    plan = plan_region(L_HOLES, SPACING, **kw)
    length, turns = plan_floor(L_HOLES, SPACING, **kw)
    assert turns == plan.stats.n_turns
    assert length <= plan.stats.path_length


@pytest.mark.parametrize(
    ("shape", "holes"),
    [
        ([(0, 0), (100, 0), (100, 30), (30, 30), (30, 100), (0, 100)], []),
        (
            [(0, 0), (120, 0), (120, 40), (40, 40), (40, 110), (0, 110)],
            [[(60, 10), (80, 10), (80, 25), (60, 25)], [(12, 60), (25, 60), (25, 80), (12, 80)]],
        ),
    ],
)
def test_centred_layouts_screened_without_keep_inside_keep_the_same_plan(monkeypatch, shape, holes):
    """The time objective without ``keep_inside``: the decomposed plan's cells plan their
    edge layouts only where their floor is below the cell's best plan; the same plan and
    optimum as planning every one, fewer cell plans."""
    with_screen, fewer = _centred_values(monkeypatch, shape, holes, screen=True, inside=False)
    without, every = _centred_values(monkeypatch, shape, holes, screen=False, inside=False)
    assert np.array_equal(with_screen.waypoints, without.waypoints)
    assert with_screen.optimum.fitness == without.optimum.fitness
    assert with_screen.optimum.info["decomposed"] == without.optimum.info["decomposed"]
    assert fewer < every


def _open_search() -> decomposed._Search:
    """A decomposition's cell search without ``keep_inside`` (the time objective, 10 m)."""
    frame = SimpleNamespace(
        sensor=SimpleNamespace(spacing=SPACING, reach=SPACING / 2),
        proj=SimpleNamespace(scale_min=1.0),
    )
    options = dict(turnaround=0.0, reach=SPACING / 2, nadir_gap=0.0, ground_scale=1.0)
    options.update(speed=5.0, turn_time=10.0, area=None)
    return decomposed._Search(frame, CoverCost.time(5.0, 10.0), "guaranteed", options)


def test_centred_keeps_the_best_edge_layout(monkeypatch):
    """A 100 x 60 m rectangle: its lanes laid from an edge at 0 degrees (6 lanes) beat those at
    90 (10 lanes). Told a best plan 1% above the 0-degree one, ``_centred`` plans it (its floor
    is below) and keeps it, and does not plan the 90-degree one (its floor is above)."""
    cell = Region(np.array([(0, 0), (100, 0), (100, 60), (0, 60)], dtype=float))
    search = _open_search()
    angles = decomposed._edge_angles(cell)
    offsets = decomposed.centred_offsets(cell, angles, SPACING, SPACING / 2)
    values = [search.value(cell, float(a), float(d)) for a, d in zip(angles, offsets, strict=True)]
    assert len(values) == 2 and values[0] < 0.9 * values[1]
    given = OptimizeResult(
        angle=1.0, offset=0.0, fitness=1.01 * min(values), spacing=SPACING, method="cover",
        evaluations=0, seconds=0.0, info={"lower_bound": 0.9 * min(values), "rtol": 1e-3},
    )  # fmt: skip
    planned = []
    real = decomposed._Search.value

    def value(self, cell, angle, offset):
        planned.append(angle)
        return real(self, cell, angle, offset)

    monkeypatch.setattr(decomposed._Search, "value", value)
    got = search._centred(cell, given)
    assert got.fitness == min(values)
    assert planned == [float(angles[int(np.argmin(values))])]


def test_a_cut_lane_and_its_hole_ring_by_hand():
    """A 100 x 10 m strip, its one lane (y = 5) cut by a 20 x 4 m hole into 0-40 and 60-100:
    the floor is the lanes (80 m) and the hole's whole closed ring (48 m, driven from a corner
    round to it: its moves count 0) and the two cut ends' entries, 2 m each to the nearest
    corner less the largest (2 m): 130 m, 2 turns (the plan flies 152 m)."""
    strip = np.array([(0, 0), (100, 0), (100, 10), (0, 10)], dtype=float)
    region = Region(strip, [np.array([(40, 3), (60, 3), (60, 7), (40, 7)], dtype=float)])
    kw = dict(decompose_area=False, angle=0.0, offset=0.0)
    length, turns = plan_floor(region, SPACING, **kw)
    assert (length, turns) == (pytest.approx(130.0, abs=1e-9), 2)
    assert plan_region(region, SPACING, **kw).stats.path_length >= length
