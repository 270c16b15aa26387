"""``outside_length_m`` is the length of the path flown (final waypoints, turn curves included)
outside the area or in a hole, whatever the plan (headland, vehicle, both, decomposed or not),
measured here independently with shapely on the original boundary; with ``keep_inside`` and a
turn radius the path stays in the area and covers all of it."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from boustro.mission import plan_area
from boustro.mission.crosshatch import plan_crosshatch
from boustro.vehicle import Vehicle, every_turn, turn_between

from .test_keep_inside import _check_inside_and_covered, _independent_outside

SHAPES = {
    "L": ([(0, 0), (100, 0), (100, 100), (70, 100), (70, 30), (0, 30)], []),
    "U": ([(0, 0), (100, 0), (100, 100), (70, 100), (70, 30), (30, 30), (30, 100), (0, 100)], []),
    "ring": (
        [(0, 0), (100, 0), (100, 100), (0, 100)],
        [[(30, 30), (70, 30), (70, 70), (30, 70)]],
    ),
}
R12 = Vehicle(turn_radius=12.0)
SETTINGS = {
    "headland": {"headland": 1},
    "vehicle": {"vehicle": R12},
    "both": {"headland": 1, "vehicle": R12},
    "vehicle decomposed": {"vehicle": R12, "decompose": True},
    "vehicle one grid": {"vehicle": R12, "decompose": False},
    "headland decomposed": {"headland": 1, "decompose": True},
    "vehicle, time objective": {"vehicle": Vehicle(turn_radius=6.0, speed=3.0)},
}


def _plan(shape: str, **kw):
    shell, holes = SHAPES[shape]
    mission = plan_area(shell, 10.0, crs=None, holes=holes, **kw)
    return mission, shapely.Polygon(shell, holes)


@pytest.mark.parametrize("shape", sorted(SHAPES))
@pytest.mark.parametrize("setting", sorted(SETTINGS))
def test_outside_length_is_that_of_the_path_flown(shape, setting):
    mission, area = _plan(shape, **SETTINGS[setting])
    want = _independent_outside(np.asarray(mission.waypoints), area)
    got = mission.summary()["outside_length_m"]
    assert got == pytest.approx(want, rel=1e-6, abs=1e-6)
    if "vehicle" in SETTINGS[setting] and "headland" not in SETTINGS[setting]:
        assert mission.plan.vehicle is not None and "turn" in mission.kinds  # curves measured


def test_the_reviewers_numbers():
    """The L-shape: with a headland nothing is outside (main reported ~150 m); with a vehicle
    the turns reach far beyond the area (main reported 35 m against shapely's 455 m)."""
    headland, area = _plan("L", headland=1)
    assert headland.stats.outside_length == 0.0
    assert _independent_outside(np.asarray(headland.waypoints), area) == 0.0
    driven, area = _plan("L", vehicle=R12)
    assert driven.stats.outside_length > 400.0


@pytest.mark.parametrize("shape", sorted(SHAPES))
@pytest.mark.parametrize("speed", [None, 3.0])
def test_keep_inside_with_a_turn_radius_stays_inside_and_covers(shape, speed):
    mission, area = _plan(shape, vehicle=Vehicle(turn_radius=12.0, speed=speed), keep_inside=True)
    plan = mission.plan
    frame_area = shapely.Polygon(
        mission.projection.to_plan(np.asarray(area.exterior.coords)),
        [mission.projection.to_plan(np.asarray(h.coords)) for h in area.interiors],
    )
    assert _check_inside_and_covered(plan, frame_area) >= 1 - 1e-9
    assert _independent_outside(np.asarray(mission.waypoints), area) == pytest.approx(0, abs=1e-6)
    summary = mission.summary()
    assert summary["outside_length_m"] == 0.0
    assert summary["covered_share"] == pytest.approx(1.0, abs=1e-9)
    routed = summary["vehicle"]["routed_moves"]
    assert routed == plan.routed_moves
    if routed:  # what was done is said
        assert any("routed" in n and "12 m" in n for n in summary["notes"])


@pytest.mark.parametrize("shape", sorted(SHAPES))
def test_keep_inside_turns_the_other_way_or_reverses_rather_than_leave(shape):
    """A turn whose shortest path leaves the area takes a longer one that stays inside (a loop
    the other way, reversing where the vehicle may): with reverse most turns are driven."""
    forward, _ = _plan(shape, vehicle=R12, keep_inside=True)
    reverse, area = _plan(shape, vehicle=Vehicle(turn_radius=12.0, reverse=True), keep_inside=True)
    assert reverse.plan.routed_moves <= 1 < forward.plan.routed_moves
    assert reverse.kinds.count("turn") > forward.kinds.count("turn")
    assert any("longer path" in n for n in reverse.plan.notes)
    assert _independent_outside(np.asarray(reverse.waypoints), area) == pytest.approx(0, abs=1e-6)
    assert reverse.coverage.covered_share == pytest.approx(1.0, abs=1e-9)


def test_every_turn_is_sorted_and_reaches_the_goal():
    start, goal = (0.0, 0.0, 0.0), (0.0, 10.0, np.pi)
    for vehicle in (R12, Vehicle(turn_radius=12.0, reverse=True)):
        turns = every_turn(vehicle, start, goal)
        lengths = [t.length for t in turns]
        assert lengths == sorted(lengths) and len(turns) > 2
        assert lengths[0] == pytest.approx(turn_between(vehicle, start, goal).length)
        for t in turns:
            assert np.allclose(t.points[-1], goal[:2])
            steps = np.linalg.norm(np.diff(t.points, axis=0), axis=1)
            assert steps.sum() == pytest.approx(t.length, rel=5e-3)  # chords of the curve


def test_crosshatch_measures_both_passes_and_the_move_between():
    shell, holes = SHAPES["U"]
    mission = plan_crosshatch(shell, 10.0, crs=None, holes=holes, vehicle=R12)
    area = shapely.Polygon(shell, holes)
    want = _independent_outside(np.asarray(mission.waypoints), area)
    assert mission.stats.outside_length == pytest.approx(want, rel=1e-6, abs=1e-6)
    assert want > 0
