"""Sorties: each within its limit, every lane flown exactly once, the split of least time."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest
from pymavlink import mavwp

from boustro.cli import main
from boustro.errors import InvalidParameterError
from boustro.io import embedded_field
from boustro.mission import plan_area
from boustro.mission.sorties import lane_units, plan_sorties, split_mission

RTL = 20


@pytest.fixture(scope="module")
def mission():
    return plan_area(embedded_field(), 10.0, speed=8.0, turn_time=5.0, turnaround=5.0, altitude=30)


def _flown(sortie, home_plan):
    """Length (m) and time (s) of a sortie recomputed from its own waypoints and home."""
    plan = sortie.plan
    path = np.vstack([home_plan, plan.waypoints, home_plan]) / plan.ground_scale
    length = float(np.hypot(*np.diff(path, axis=0).T).sum())
    lanes = sum(k == "start" for k in plan.kinds)
    return length, length / plan.stats.speed + (lanes - 1) * plan.stats.turn_time


@pytest.mark.parametrize(("limit", "value"), [("max_time", 250.0), ("max_distance", 1200.0)])
def test_each_sortie_within_its_limit_and_every_lane_once(mission, limit, value):
    sorties = split_mission(mission, **{limit: value})
    assert len(sorties) > 1
    home = mission.projection.to_plan(mission.home)
    for s in sorties:
        length, time = _flown(s, home)
        assert length == pytest.approx(s.sortie.length, rel=1e-9)
        assert (time if limit == "max_time" else length) <= value + 1e-9
        assert s.plan.kinds[0] in ("run_in", "start") and s.plan.kinds[-1] in ("end", "run_out")
    # every lane exactly once, in the mission's order and direction, never cut
    np.testing.assert_array_equal(np.concatenate([s.transects for s in sorties]), mission.transects)
    assert sum(s.kinds.count("start") for s in sorties) == mission.kinds.count("start")
    assert [s.sortie.lanes for s in sorties] == [
        (a, b)
        for a, b in zip(
            [0] + [s.sortie.lanes[1] + 1 for s in sorties[:-1]],
            [s.sortie.lanes[1] for s in sorties],
            strict=True,
        )
    ]


def test_the_split_is_the_fewest_sorties_then_the_least_total_time_of_all_splits(mission):
    plan = mission.plan
    path = plan.waypoints / plan.ground_scale
    units = lane_units(plan.kinds)[:10]
    path = path[: units[-1][1] + 1]
    home = path[0] + np.array([150.0, -80.0])  # off to one side
    limit, speed, turn = 120.0, 8.0, 5.0
    along = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(path, axis=0).T))])

    def cost(i, j):
        a, b = units[i][0], units[j][1]
        length = np.hypot(*(path[a] - home)) + along[b] - along[a] + np.hypot(*(path[b] - home))
        return length / speed + (j - i) * turn

    n = len(units)
    for limit, turn in ((120.0, 5.0), (120.0, 60.0), (150.0, 60.0)):
        best = (np.inf, np.inf)  # (sorties, total time), compared in that order
        for r in range(n):
            for cuts in itertools.combinations(range(1, n), r):
                bounds = [0, *cuts, n]
                times = [cost(bounds[k], bounds[k + 1] - 1) for k in range(len(bounds) - 1)]
                if max(times) <= limit:
                    best = min(best, (len(times), sum(times)))
        found = plan_sorties(path, units, home, max_time=limit, speed=speed, turn_time=turn)
        assert np.isfinite(best[1]) and len(found) > 1
        assert len(found) == best[0]
        assert sum(t for *_, t in found) == pytest.approx(best[1], rel=1e-12)
        assert all(t <= limit for *_, t in found)


def test_no_more_sorties_than_needed_even_when_more_would_be_faster():
    """Home beside the lanes, a long turn: flying home between two lanes saves the turn, so
    the least total time alone would split a mission that fits one sortie."""
    lanes = 4
    path = np.array([[10.0 * k, 100.0 * ((k + e) % 2)] for k in range(lanes) for e in (0, 1)])
    units = [(2 * k, 2 * k + 1) for k in range(lanes)]
    home = np.array([15.0, 50.0])
    one = plan_sorties(path, units, home, max_time=1000.0, speed=10.0, turn_time=30.0)
    assert [(i, j) for i, j, *_ in one] == [(0, lanes - 1)]
    # had it split after the first lane: two more legs home (about 11 s) for one turn (30 s)
    assert one[0][3] == pytest.approx((np.hypot(15, 50) * 2 + 400 + 30) / 10 + 3 * 30)
    two = plan_sorties(path, units, home, max_time=80.0, speed=10.0, turn_time=30.0)
    assert len(two) == 2  # the limit needs two; not four single lanes (each about 21 s)
    assert all(t <= 80.0 for *_, t in two)


def test_sorties_around_a_hole():
    area = [(0, 0), (300, 0), (300, 300), (150, 300), (150, 150), (0, 150)]
    hole = [(200, 100), (250, 100), (250, 150), (200, 150)]
    m = plan_area(area, 10.0, crs=None, holes=[hole], speed=5.0)
    sorties = split_mission(m, max_distance=1500.0)
    assert len(sorties) > 2
    np.testing.assert_array_equal(np.concatenate([s.transects for s in sorties]), m.transects)
    assert sum(s.stats.n_transects for s in sorties) == m.stats.n_transects
    assert sum(s.stats.n_turns + 1 for s in sorties) == m.stats.n_turns + 1  # passes
    assert max(s.sortie.length for s in sorties) <= 1500.0


def test_lane_units_keep_run_ins_and_hole_passes_whole():
    kinds = ("run_in", "start", "end", "run_out", "via", "start", "loop", "loop", "end")
    assert lane_units(kinds) == [(0, 3), (5, 8)]


def test_limits_refused_clearly(mission):
    with pytest.raises(InvalidParameterError, match="alone takes"):
        split_mission(mission, max_distance=50.0)
    no_speed = plan_area(embedded_field(), 10.0)
    with pytest.raises(InvalidParameterError, match="speed"):
        split_mission(no_speed, max_time=100.0)
    with pytest.raises(InvalidParameterError, match="> 0"):
        split_mission(mission, max_distance=-1.0)
    assert split_mission(mission) == [mission]


def test_command_line_one_file_per_sortie(tmp_path, capsys):
    out = tmp_path / "m.waypoints"
    args = ["-q", "plan", "--speed", "8", "--altitude", "30", "--home", "6.0625,51.5120"]
    assert main([*args, "--max-flight-time", "300", "--out", str(out), "--json"]) == 0
    summaries = json.loads(capsys.readouterr().out)
    assert len(summaries) >= 2
    files = sorted(tmp_path.glob("m-*.waypoints"))
    assert len(files) == len(summaries)
    for path, summary in zip(files, summaries, strict=True):
        loader = mavwp.MAVWPLoader()
        loader.load(str(path))
        assert loader.wp(loader.count() - 1).command == RTL
        home = loader.wp(0)
        assert (home.y, home.x) == pytest.approx((6.0625, 51.5120))
        assert summary["sortie"]["duration_s"] <= 300
    geo = tmp_path / "m.geojson"
    assert main([*args, "--max-distance", "2000", "--out", str(geo)]) == 0
    doc = json.loads(geo.read_text())
    assert len(doc["boustro"]) >= 2  # one file with every sortie
    assert main(["plan", "--max-flight-time", "300"]) == 2
    assert "speed" in capsys.readouterr().err


@pytest.mark.parametrize(
    "extra",
    [
        ["--home", "6.06,91"],  # the start taken from the home
        ["--start", "1000,1000"],
        ["--start", "6.0625,51.512", "--home", "6.06,91", "--out", "OUT"],  # home alone bad
        ["--start", "6.0625,51.512", "--home", "6.06,91", "--max-flight-time", "2000"],
    ],
)
def test_a_start_or_home_off_the_globe_is_named_in_one_line(tmp_path, capsys, extra):
    # QA 2026-11-28: a latitude outside [-90, 90] projected to inf and was refused as "start
    # must be a finite (x, y) pair, got array([inf, inf])", "mission.home_lonlat[0] is not a
    # finite number" or "lane 1 alone takes inf s", never naming the point given.
    out = tmp_path / "m.waypoints"
    extra = [str(out) if a == "OUT" else a for a in extra]
    args = ["-q", "plan", "--speed", "8", "--altitude", "30", *extra]
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "inf" not in err.replace("info", "")
    assert "latitude" in err and "[-90, 90]" in err
    assert ("home" if "6.06,91" in extra else "start") in err
    assert not list(tmp_path.iterdir())


def test_split_mission_refuses_a_home_that_cannot_be_projected(mission):
    with pytest.raises(InvalidParameterError, match=r"home \(6\.06, 91\)"):
        split_mission(mission, home=(6.06, 91.0), max_distance=5000.0)


@pytest.mark.parametrize("home", [(6.06,), (6.06, 51.5, 3.0), [[6.06, 51.5]] * 2, ("a", 1), []])
def test_with_home_refuses_a_home_that_is_not_a_pair_by_name(mission, home):
    """QA round 13: ``with_home`` reshaped the home before checking it, so a home that was not
    a pair was a bare numpy ValueError ("cannot reshape array of size 3 into shape (2,)")."""
    with pytest.raises(InvalidParameterError, match="home must be a finite"):
        split_mission(mission, home=home, max_distance=5000.0)
