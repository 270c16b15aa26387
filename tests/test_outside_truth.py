"""``outside_length_m`` is the length of the path flown (final waypoints, turn curves included)
outside the area or in a hole, whatever the plan (headland, vehicle, both, decomposed or not),
measured here independently with shapely on the original boundary; with ``keep_inside`` and a
turn radius the path stays in the area and covers all of it."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from boustro.mission import plan_area
from boustro.vehicle import Vehicle

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
    assert "turn" in plan.kinds  # the turns that fit are driven
    if routed:  # what was done is said
        assert any("routed" in n and "12 m" in n for n in summary["notes"])
