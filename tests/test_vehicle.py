"""The vehicle model: Dubins and Reeds-Shepp closed forms against references, turns that respect
the radius (measured from the waypoints), the every-other-lane order, the plan and its exports."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

from boustro.cli import main
from boustro.errors import InvalidParameterError
from boustro.io import embedded_field
from boustro.io.formats import write_mission
from boustro.mission import plan_area
from boustro.plan import build_plan, coverage, drive_vehicle
from boustro.vehicle import (
    DUBINS_WORDS,
    Vehicle,
    Word,
    dubins_length,
    dubins_path,
    dubins_words,
    end_pose,
    lane_order,
    reeds_shepp_length,
    reeds_shepp_path,
    reeds_shepp_words,
    skip_order,
    turn_between,
    turn_length,
)
from boustro.vehicle.curves import to_local


def _pose_error(a, b) -> float:
    d = (a[2] - b[2] + math.pi) % (2 * math.pi) - math.pi
    return float(np.hypot(a[0] - b[0], a[1] - b[1]) + abs(d))


def _random_poses(seed: int, n: int):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        yield rng.uniform(-10, 10, 3), rng.uniform(-10, 10, 3), float(rng.uniform(0.5, 4))


def circumradii(points: np.ndarray) -> np.ndarray:
    """The circumradius of every three consecutive points (inf for collinear ones)."""
    a, b, c = points[:-2], points[1:-1], points[2:]
    ab = np.linalg.norm(b - a, axis=1)
    bc = np.linalg.norm(c - b, axis=1)
    ca = np.linalg.norm(a - c, axis=1)
    cross = np.abs((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])
    with np.errstate(divide="ignore"):
        return np.where(cross > 1e-12 * ab * bc, ab * bc * ca / (2 * cross), np.inf)


# -- Dubins ---------------------------------------------------------------------------------
def test_every_dubins_word_reaches_the_goal():
    """Each word that exists, driven exactly from the start, ends at the goal pose: the closed
    forms of all six words are right (a wrong one lands elsewhere)."""
    seen = set()
    for start, goal, r in _random_poses(0, 400):
        x, y, phi = to_local(start, goal)
        for name, w in dubins_words(x / r, y / r, phi).items():
            if np.all(np.isfinite(w)):
                seen.add(name)
                end = end_pose(start, Word(name, tuple(w), 0.0), r)
                assert _pose_error(end, goal) < 1e-7, name
    assert seen == set(DUBINS_WORDS)


def _word_end(word: str, lengths, r: float) -> np.ndarray:
    return end_pose(np.zeros(3), Word(word, tuple(lengths), 0.0), r)


def test_dubins_is_the_shortest_of_a_brute_force_search():
    """Brute force: for each word, solve for its three lengths numerically (least squares from
    a grid of starts, independent of the closed forms); no solution is shorter than ours."""
    from scipy.optimize import least_squares

    starts = [(a, b, c) for a in (0.5, 4) for b in (0.5, 4) for c in (0.5, 4)]
    for start, goal, r in list(_random_poses(1, 6)):
        x, y, phi = to_local(start, goal)
        local_goal = np.array([x, y, phi])
        ours = float(dubins_length(start, goal, r))
        best = math.inf
        for word in DUBINS_WORDS:

            def residual(v, word=word, r=r, local_goal=local_goal):
                e = _word_end(word, v, r)
                d = (e[2] - local_goal[2] + math.pi) % (2 * math.pi) - math.pi
                return [e[0] - local_goal[0], e[1] - local_goal[1], r * d]

            bounds = ([0, 0, 0], [2 * math.pi, 1e3, 2 * math.pi])
            for s0 in starts:
                sol = least_squares(residual, s0, bounds=bounds)
                if np.max(np.abs(sol.fun)) < 1e-7:
                    best = min(best, r * float(np.sum(sol.x)))
        assert ours <= best + 1e-6
        assert ours == pytest.approx(best, rel=1e-6)  # and the brute force finds it


def test_dubins_published_values():
    # A half circle; straight ahead; a full-turn-free right angle (quarter circle).
    assert float(dubins_length((0, 0, 0), (0, 2, math.pi), 1.0)) == pytest.approx(math.pi)
    assert float(dubins_length((0, 0, 0), (7, 0, 0), 2.0)) == pytest.approx(7.0)
    assert float(dubins_length((0, 0, 0), (3, 3, math.pi / 2), 3.0)) == pytest.approx(1.5 * math.pi)
    # Straight back along its own line needs a full loop of width 2R: LRL/RLR or a CSC.
    assert float(dubins_length((0, 0, 0), (0, 0, math.pi), 1.0)) > 2 * math.pi
    assert dubins_path((0, 0, 0), (10, 0, 0), 1.0).letters in ("LSL", "RSR", "LSR", "RSL")


# -- Reeds-Shepp ----------------------------------------------------------------------------
def test_every_reeds_shepp_word_reaches_the_goal():
    count = 0
    for start, goal, r in _random_poses(2, 200):
        x, y, phi = to_local(start, goal)
        words = reeds_shepp_words(x / r, y / r, phi)
        assert len(words) == 44  # OMPL's candidates: the 48 words of Reeds and Shepp
        for letters, w in words:
            if np.all(np.isfinite(w)):
                count += 1
                end = end_pose(start, Word(letters, tuple(w), 0.0), r)
                assert _pose_error(end, goal) < 1e-7, letters
    assert count > 1000


def test_reeds_shepp_against_rsplan_and_dubins():
    """``rsplan`` (a published Python implementation) as the reference: ours is never longer,
    equal in most cases; where ours is shorter its path is verified to reach the goal (rsplan
    misses some words). Never longer than Dubins (forward-only paths are Reeds-Shepp paths)."""
    planner = pytest.importorskip("rsplan.planner")
    equal = 0
    n = 300
    for start, goal, r in _random_poses(3, n):
        ours = reeds_shepp_path(start, goal, r)
        assert _pose_error(end_pose(start, ours, r), goal) < 1e-7
        ref = planner.path(tuple(start), tuple(goal), r, 0.0, 0.05).total_length
        assert ours.length <= ref + 1e-9
        equal += abs(ours.length - ref) < 1e-6
        assert ours.length <= float(dubins_length(start, goal, r)) + 1e-9
        assert float(reeds_shepp_length(start, goal, r)) == pytest.approx(ours.length)
    assert equal > 0.6 * n


def test_reeds_shepp_published_values():
    assert float(reeds_shepp_length((0, 0, 0), (-3, 0, 0), 1.0)) == pytest.approx(3.0)
    # A half circle forward, or backward: pi R either way.
    assert float(reeds_shepp_length((0, 0, 0), (0, 2, math.pi), 1.0)) == pytest.approx(math.pi)
    # Parallel parking sideways by a small amount is far shorter than the Dubins loop.
    rs = float(reeds_shepp_length((0, 0, 0), (0, 0.5, 0), 1.0))
    assert rs < 0.5 * float(dubins_length((0, 0, 0), (0, 0.5, 0), 1.0))


# -- turns ----------------------------------------------------------------------------------
def test_turn_length_vectorised_and_closed_forms():
    v = Vehicle(turn_radius=6.0)
    gaps = np.array([12.0, 20.0, 30.0, -20.0])
    got = turn_length(v, gaps)
    # 2R <= gap: two quarter circles and the straight between them, pi R + gap - 2R.
    np.testing.assert_allclose(got, math.pi * 6 + np.abs(gaps) - 12, rtol=1e-12)
    along = np.linspace(-20, 20, 9)
    grid = turn_length(v, gaps[:, None], along[None, :])
    assert grid.shape == (4, 9)
    for i, g in enumerate(gaps):
        for j, a in enumerate(along):
            want = float(dubins_length((0, 0, 0), (a, g, math.pi), 6.0))
            assert grid[i, j] == pytest.approx(want)
    # 2R > gap: the bulb, longer than the half circle to the lane after next.
    assert float(turn_length(v, 10.0)) > float(turn_length(v, 20.0)) - 10
    assert float(turn_length(Vehicle(turn_radius=6.0, reverse=True), 10.0)) <= float(
        turn_length(v, 10.0)
    )
    assert float(turn_length(Vehicle(), 10.0, 5.0)) == pytest.approx(math.hypot(10, 5))


def test_turn_waypoints_respect_the_radius():
    for rev in (False, True):
        v = Vehicle(turn_radius=5.0, reverse=rev)
        for start, goal, _ in _random_poses(4, 50):
            turn = turn_between(v, start * 5, goal * 5, tolerance=0.02)
            assert np.allclose(turn.points[0], start[:2] * 5)
            assert np.allclose(turn.points[-1], goal[:2] * 5)
            # Split at cusps (a change of gear); each piece's curvature radius >= R.
            cusps = np.flatnonzero(np.diff(turn.gear) != 0) + 1
            for piece in np.split(np.arange(len(turn.points)), cusps):
                idx = np.concatenate([[max(piece[0] - 1, 0)], piece])
                pts = turn.points[np.unique(idx)]
                if len(pts) >= 3:
                    assert circumradii(pts).min() >= 5.0 * (1 - 1e-6)
            # Densified: on every arc, the sagitta of the chord between two waypoints (from the
            # heading turned between them) is within the tolerance; straights keep their ends.
            turned = np.abs((np.diff(turn.headings) + math.pi) % (2 * math.pi) - math.pi)
            assert np.all(5.0 * (1 - np.cos(turned / 2)) <= 0.02 + 1e-12)


def test_skip_order_and_its_choice():
    assert skip_order(7) == [0, 2, 4, 6, 5, 3, 1]
    lanes = np.array([[[0.0, 10 * i], [100.0, 10 * i]] for i in range(8)])
    lanes[1::2] = lanes[1::2, ::-1]
    order, driven, total = lane_order(Vehicle(turn_radius=6.0), lanes)
    assert order == skip_order(8)  # 2R = 12 > 10: every other lane turns less
    assert total == pytest.approx(
        6 * float(turn_length(Vehicle(turn_radius=6.0), 20.0))
        + 2 * 0
        + float(turn_length(Vehicle(turn_radius=6.0), 10.0))
    )
    d = driven[:, 1] - driven[:, 0]
    assert np.all(d[1:, 0] * d[:-1, 0] < 0)  # each lane against the one before
    order, _, _ = lane_order(Vehicle(turn_radius=4.0), lanes)
    assert order == list(range(8))  # 2R = 8 < 10: plain boustrophedon


def test_invalid_vehicle_is_one_clear_error():
    for bad in (
        dict(turn_radius=-1),
        dict(turn_radius=math.nan),
        dict(speed=0),
        dict(turn_time=-2),
    ):
        with pytest.raises(InvalidParameterError):
            Vehicle(**bad)
    with pytest.raises(InvalidParameterError):
        Vehicle(reverse="yes")  # type: ignore[arg-type]


# -- plans ----------------------------------------------------------------------------------
def _turn_runs(plan):
    """Index runs ``[exit, turn..., entry]`` of every turn in the path."""
    k = plan.kinds
    runs, i = [], 0
    while i < len(k):
        if k[i] == "turn":
            j = i
            while k[j] == "turn":
                j += 1
            runs.append(np.arange(i - 1, j + 1))
            i = j
        i += 1
    return runs


def test_plan_turns_respect_the_radius_and_count_in_the_stats():
    square = [(0, 0), (200, 0), (200, 150), (0, 150)]
    plan = build_plan(square, 10.0, 0.3, 0.0, speed=2.0, turn_time=3.0)
    turned = drive_vehicle(plan, Vehicle(turn_radius=8.0), tolerance=0.05)
    runs = _turn_runs(turned)
    assert len(runs) == turned.stats.n_turns
    for run in runs:
        pts = turned.waypoints[run]
        assert circumradii(pts).min() >= 8.0 * (1 - 1e-6)

    # Every lane still flown once, in full.
    def key(t):  # a lane whichever way it is driven
        return tuple(sorted(map(tuple, np.round(t, 9))))

    assert sorted(map(key, turned.transects)) == sorted(map(key, plan.transects))
    assert coverage(turned).covered_share == pytest.approx(1.0, abs=1e-9)
    # The path length counts the exact curves: the polyline through the waypoints is shorter
    # by the chords' sagittas only.
    poly = float(np.linalg.norm(np.diff(turned.waypoints, axis=0), axis=1).sum())
    assert poly <= turned.stats.path_length <= poly * (1 + 1e-3)
    lanes_len = turned.stats.transect_length
    assert turned.stats.path_length == pytest.approx(lanes_len + turned.stats.turn_length)
    assert turned.stats.duration == pytest.approx(turned.stats.path_length / 2 + 3 * runs.__len__())


def test_every_other_lane_when_shorter():
    square = [(0, 0), (100, 0), (100, 100), (0, 100)]
    plan = build_plan(square, 10.0, 0.0, 5.0)
    straight = drive_vehicle(plan, Vehicle(turn_radius=6.0)).stats
    ys = drive_vehicle(plan, Vehicle(turn_radius=6.0)).transects[:, 0, 1]
    assert not np.all(np.diff(ys) > 0)  # not in plain order
    # The chosen order turns less than the boustrophedon order would.
    v = Vehicle(turn_radius=6.0)
    plain = float(np.sum(turn_length(v, np.full(len(ys) - 1, 10.0))))
    assert straight.turn_length < plain


def test_plan_area_with_a_vehicle_and_every_export(tmp_path):
    mission = plan_area(
        embedded_field(), 10.0, vehicle=Vehicle(speed=4.0, turn_radius=6.0), altitude=30.0
    )
    base = plan_area(embedded_field(), 10.0, speed=4.0, altitude=30.0)
    s = mission.summary()
    assert s["vehicle"] == {
        "turns": "dubins",
        "turn_radius_m": 6.0,
        "reverse": False,
        "routed_moves": 0,
    }
    assert s["turn_length_m"] > 0 and s["path_length_m"] > base.summary()["path_length_m"]
    assert s["duration_s"] == pytest.approx(s["path_length_m"] / 4.0)
    assert "turn" in mission.kinds and s["covered_share"] == pytest.approx(1.0, abs=1e-9)
    n = len(mission.waypoints)
    mavwp = pytest.importorskip("pymavlink.mavwp")
    path = tmp_path / "m.waypoints"
    write_mission(mission, path)
    loader = mavwp.MAVWPLoader()
    assert loader.load(str(path)) == n + 2
    lonlat = np.array([[loader.wp(i).y, loader.wp(i).x] for i in range(2, n + 2)])
    np.testing.assert_allclose(lonlat, mission.waypoints_lonlat, atol=1e-9, rtol=0)
    write_mission(mission, tmp_path / "m.plan")
    items = json.loads((tmp_path / "m.plan").read_text())["mission"]["items"]
    assert sum(i["command"] == 16 for i in items) == n
    write_mission(mission, tmp_path / "m.csv")
    with open(tmp_path / "m.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["kind"] for r in rows] == list(mission.kinds)
    gpxpy = pytest.importorskip("gpxpy")
    write_mission(mission, tmp_path / "m.gpx")
    (route,) = gpxpy.parse((tmp_path / "m.gpx").read_text()).routes
    assert len(route.points) == n
    pyogrio = pytest.importorskip("pyogrio")
    write_mission(mission, tmp_path / "m.geojson")
    _, _, geometry, _ = pyogrio.raw.read(tmp_path / "m.geojson")
    assert len(geometry) >= n
    kml = pytest.importorskip("fastkml.kml")
    write_mission(mission, tmp_path / "m.kml")
    doc = next(iter(kml.KML.from_string((tmp_path / "m.kml").read_bytes()).features))
    (path_mark,) = [f for f in doc.features if getattr(f, "name", "") == "Path"]
    assert len(path_mark.geometry.coords) == n
    # The curve between lanes, from the file: three consecutive projected points' circumradius.
    xy = mission.plan.waypoints
    for run in _turn_runs(mission.plan):
        assert circumradii(xy[run]).min() >= 6.0 * mission.plan.ground_scale * (1 - 1e-6)


def test_cli_turn_radius_and_reverse(tmp_path, capsys):
    assert main(["-q", "plan", "--turn-radius", "6", "--reverse", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["vehicle"]["turns"] == "reeds-shepp" and out["turn_length_m"] > 0
    assert main(["-q", "plan", "--reverse"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--reverse needs --turn-radius" in err[0]
    with pytest.raises(SystemExit) as exc:  # argparse: one line on stderr, status 2
        main(["-q", "plan", "--turn-radius", "-3"])
    assert exc.value.code == 2


def test_a_turn_radius_beyond_the_projection_is_refused_in_one_line(tmp_path, capsys):
    # 1e8 m turns run 270,000 km from the field, where UTM maps back to inf: refused before
    # anything is written, naming the distance (it failed at the export, naming an array).
    out = tmp_path / "m.geojson"
    assert main(["-q", "plan", "--turn-radius", "1e8", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "cannot be mapped back" in err[0] and "km from the area" in err[0]
    assert not out.exists()


def test_turns_never_enter_a_hole():
    import shapely

    field = [(0, 0), (60, 0), (60, 20), (25, 20), (25, 50), (0, 50)]
    pond = [(5, 5), (15, 5), (15, 15), (5, 15)]
    mission = plan_area(field, 4.0, crs=None, holes=[pond], vehicle=Vehicle(turn_radius=3.0))
    hole = shapely.Polygon(pond)
    path = shapely.LineString(mission.waypoints)
    inside = path.difference(hole.exterior.buffer(1e-7)).intersection(hole)
    assert inside.length == 0.0  # along its edge (the hole pass), never inside
    assert "turn" in mission.kinds and mission.summary()["turn_length_m"] > 0
    assert mission.coverage.covered_share >= 1 - 1e-9
