"""The search's screen of ``keep_inside`` layouts (issue 16, eleventh round): the floor of a
plan from its cut lanes and boundary passes (:func:`boustro.plan.tour_floor`,
:func:`boustro.plan.region_floor.plan_floor`) is below every plan, and the search screening
by it finds the same plan as without it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from boustro.geometry.region import Region, random_region
from boustro.mission import cover, plan_area
from boustro.optimize.cover import CoverCost
from boustro.optimize.cover import search as cover_search
from boustro.plan import inside
from boustro.plan.lanes import Lanes, region_lanes
from boustro.plan.region import plan_region
from boustro.plan.region_floor import plan_floor, tour_floor

SPACING, SPEED, TURN = 10.0, 5.0, 10.0
L_HOLES = Region(
    np.array([(0, 0), (120, 0), (120, 40), (40, 40), (40, 110), (0, 110)], dtype=float),
    [
        np.array([(60, 10), (80, 10), (80, 25), (60, 25)], dtype=float),
        np.array([(12, 60), (25, 60), (25, 80), (12, 80)], dtype=float),
    ],
)


def _areas() -> list[Region]:
    rng = np.random.default_rng(11)
    out = [L_HOLES]
    for _ in range(2):
        r = random_region(rng, int(rng.integers(6, 12)), 2, roughness=0.5)
        k = 200.0 / r.diameter
        out.append(Region(r.shell.vertices * k, [h.vertices * k for h in r.holes]))
    return out


@pytest.mark.parametrize("index", range(3))
def test_the_floor_is_below_every_plan(index):
    """On 12 layouts of each area: the floor's turns are the plan's, its length at most the
    plan's path and above the lanes and passes alone (its moves' floor is not empty)."""
    region = _areas()[index]
    rng = np.random.default_rng(index)
    above = 0
    for angle, offset in zip(rng.uniform(0, math.pi, 12), rng.uniform(0, SPACING, 12), strict=True):
        kw = dict(decompose_area=False, angle=angle, offset=offset, keep_inside=True)
        plan = plan_region(region, SPACING, **kw)
        length, turns = plan_floor(region, SPACING, **kw)
        st = plan.stats
        assert turns == st.n_turns
        assert length <= st.path_length * (1 + 1e-12)
        moves = st.path_length - st.transect_length - st.boundary_pass_length
        floor_moves = length - st.transect_length - st.boundary_pass_length
        assert floor_moves <= moves + 1e-9
        above += floor_moves > 0.4 * moves
    assert above >= 8  # the floor of the moves is not a trivial one


def test_no_floor_of_the_chords_layout():
    """(Without ``keep_inside`` the guaranteed layout has a floor since the eighteenth round:
    tests/test_open_floor.py.)"""
    kw = dict(decompose_area=False, angle=0.3, offset=1.0, layout="chords")
    assert plan_floor(L_HOLES, SPACING, **kw) is None
    kw = dict(decompose_area=False, angle=0.3, offset=1.0, keep_inside=True, layout="chords")
    assert plan_floor(L_HOLES, SPACING, **kw) is None


def test_path_floor_by_hand():
    """Three lanes 10 apart, their ends aligned: the moves' floor is a boustrophedon's, 2 x 10.
    A closed pass with corners at the middle lane's ends (where the path may enter it from
    either outer lane) lowers it to 10: a move from an outer lane's end to the middle lane or
    the pass is at least 10, and the middle lane joins the pass for free."""
    zeros = np.zeros(3)
    cut = Lanes(
        0.0, np.array([50.0, 15.0]), np.array([-1, 0, 1]), np.array([-10.0, 0.0, 10.0]),
        zeros - 40, zeros + 40, frozenset(),
    )  # fmt: skip
    assert tour_floor([cut], []) == (240.0 + 20.0, 2)
    ring = np.array([(10, 15), (50, 12), (90, 15), (50, 18), (10, 15)], dtype=float)
    passes = float(np.linalg.norm(np.diff(ring, axis=0), axis=1).sum())
    length, turns = tour_floor([cut], [ring])
    assert turns == 3 and length == pytest.approx(240.0 + passes + 10.0)


def test_the_layout_cache_returns_the_same_answer():
    region = _areas()[1]
    lanes = [region_lanes(region, SPACING, 0.7, 2.0, reach=SPACING / 2)]
    inside._LAYOUTS.clear()
    first = inside.inside_layout(region, lanes, SPACING, SPACING / 2)
    assert len(inside._LAYOUTS) == 1
    again = inside.inside_layout(region, lanes, SPACING, SPACING / 2)
    inside._CUTS.clear()  # the cut lanes and their floors made again as well
    inside._PASS_FLOORS.clear()
    key = inside._layout_key(region, lanes, SPACING, SPACING / 2)
    fresh = inside._inside_layout(region, lanes, SPACING, SPACING / 2, key)
    for got in (again, fresh):
        assert all(np.array_equal(a.t0, b.t0) for a, b in zip(got[0], first[0], strict=True))
        assert all(np.array_equal(a, b) for a, b in zip(got[1], first[1], strict=True))
        assert got[2] == first[2]
    again[1].clear()  # the cached lists are copies
    assert len(inside.inside_layout(region, lanes, SPACING, SPACING / 2)[1]) == len(first[1])


def test_the_screen_finds_the_same_plan(monkeypatch):
    """The L with two holes planned with the screen and without it: the same waypoints, and
    the screen skipped plans (``info["screened"]``)."""
    ring, holes = L_HOLES.shell.vertices, [h.vertices for h in L_HOLES.holes]
    kw = dict(crs=None, holes=holes, speed=SPEED, turn_time=TURN, keep_inside=True)
    screened = plan_area(ring, SPACING, decompose=False, **kw)
    monkeypatch.setattr(cover, "_screen", lambda *a, **k: None)
    plain = plan_area(ring, SPACING, decompose=False, **kw)
    assert np.array_equal(screened.waypoints, plain.waypoints)
    assert screened.optimum.info["screened"] > 0 and plain.optimum.info["screened"] == 0
    assert screened.optimum.info["plans"] < plain.optimum.info["plans"]
    assert (
        screened.optimum.info["plans"] + screened.optimum.info["screened"]
        == plain.optimum.info["plans"]
    )


def test_a_screen_above_the_best_plan_skips_it():
    """A search whose screen says every layout costs more than any plan makes one plan (the
    first) and screens the rest, counting them as tried."""
    region = L_HOLES
    made: list[tuple[float, float]] = []

    def evaluate(a: float, d: float) -> float:
        made.append((a, d))
        return 1000.0 + a

    res = cover_search.cover_optimum(
        region, SPACING, CoverCost.time(SPEED, TURN), evaluate,
        keep_inside=True, screen=lambda a, d, best: 2000.0, max_work=2e5,
    )  # fmt: skip
    assert len(made) == 1 == res.info["plans"]
    assert res.info["screened"] > 0
