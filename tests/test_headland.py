"""Headlands: passes around the boundary and the holes, lanes in the inner field, turns inside
the field, the whole field covered (measured with shapely), nothing of the path outside it."""

from __future__ import annotations

import json

import numpy as np
import pytest
import shapely

from boustro.cli import main
from boustro.errors import InvalidParameterError
from boustro.geometry.region import Region
from boustro.io import embedded_field
from boustro.io.formats import write_mission
from boustro.mission import plan_area
from boustro.plan import headland
from boustro.plan.routing import Router
from boustro.sensors import Swath
from boustro.vehicle import Vehicle

from .test_vehicle import circumradii

# An L-shaped field with a pond (planar metres): concave corners, convex corners and a hole.
L_FIELD = [(0, 0), (240, 0), (240, 90), (110, 90), (110, 220), (0, 220)]
POND = [(45, 120), (65, 120), (65, 140), (45, 140)]
SQUARE = [(0, 0), (120, 0), (120, 90), (0, 90)]


def _field(mission) -> shapely.Polygon:
    """The whole field as given (projected to the plan frame for lon/lat input)."""
    area = mission.area
    proj = mission.projection
    return shapely.Polygon(proj.to_plan(area.ring), [proj.to_plan(h) for h in area.holes])


def _footprints(mission) -> shapely.Geometry:
    """Every swath, built here with shapely (flat-ended bands along the lanes, round-jointed
    bands along the headland passes and hole passes), in the plan frame."""
    plan = mission.plan
    reach = plan.reach
    parts = []
    for seg, role in zip(plan.transects, plan.role(), strict=True):
        line = shapely.LineString(seg)
        if role == "lane":
            parts.append(line.buffer(reach, cap_style="flat"))
        else:
            parts.append(line.buffer(reach, quad_segs=64))
    return shapely.union_all(parts)


def _check(mission, passes: int) -> None:
    field = _field(mission)
    plan = mission.plan
    assert plan.headland == passes
    # The whole field covered, measured on the original boundary.
    missed = field.difference(_footprints(mission)).area
    assert missed <= 1e-9 * field.area
    assert mission.coverage.covered_share >= 1 - 1e-9
    # Nothing of the path outside the field (boundary included).
    path = shapely.LineString(plan.waypoints)
    assert path.difference(field.buffer(1e-7)).length == 0.0
    # Lanes in the inner field (a lane's line lies within half a spacing of it: its band
    # reaches into the inner field), headland passes in the band; their kinds and roles.
    inner = field.buffer(-(passes - 0.02) * plan.spacing).buffer(plan.spacing / 2)
    roles = plan.role()
    for seg, role in zip(plan.transects, roles, strict=True):
        if role == "lane":
            assert inner.buffer(1e-6).covers(shapely.LineString(seg))
    assert "headland" in roles and "headland" in mission.kinds
    assert mission.summary()["headland_length_m"] * plan.ground_scale == pytest.approx(
        sum(
            np.linalg.norm(s[1] - s[0])
            for s, r in zip(plan.transects, roles, strict=True)
            if r == "headland"
        )
    )


@pytest.mark.parametrize("passes", [1, 2])
def test_headland_covers_the_whole_field_with_a_hole(passes):
    mission = plan_area(L_FIELD, 10.0, crs=None, holes=[POND], headland=passes)
    _check(mission, passes)
    # Passes around the hole as well as around the boundary: points within the band around
    # the pond lie on headland passes.
    pond = shapely.Polygon(POND)
    pts = [
        shapely.Point(p)
        for p, k in zip(mission.waypoints, mission.kinds, strict=True)
        if k == "headland"
    ]
    near_pond = [p for p in pts if 0 < pond.distance(p) < passes * 10]
    assert len(near_pond) >= 4 * passes


@pytest.mark.parametrize(
    ("corridor", "passes"), [(25.0, 2), (20.0 + 5e-3, 2), (27.0, 2), (47.0, 3), (41.0, 3)]
)
def test_headland_covers_a_corridor_too_narrow_for_the_next_pass(corridor, passes):
    # A hole `corridor` from two sides of the boundary: between 2k and 2k + 1 spacings wide,
    # pass k + 1 and the inner field stop short of the corridor's middle; it used to be left
    # uncovered (25 m at 10 m, 2 passes: 11.5 m2; a QA run: 5 mm along a hole in UTM).
    c = corridor
    hole = [(c, c), (c + 40, c), (c + 40, c + 30), (c, c + 30)]
    mission = plan_area([(0, 0), (300, 0), (300, 200), (0, 200)], 10.0, crs=None,
                        holes=[hole], headland=passes)  # fmt: skip
    _check(mission, passes)


@pytest.mark.parametrize("corridor", [1e-6, 3e-6, 1e-3, 0.5, 3.0, 8.0])
@pytest.mark.parametrize("passes", [1, 2])
def test_headland_covers_a_corridor_narrower_than_a_spacing(corridor, passes):
    # A hole less than a spacing from two sides of the boundary: no pass goes between them
    # (pass 1 lies half a spacing inside), nor do lanes; it used to be left uncovered whatever
    # the passes (3 m at 10 m: 96 m2, covered_share 0.9967). A contour shallower than half
    # the corridor covers it; 3 um and 1 um, narrower than the shallowest contour, were left
    # uncovered (1.8e-4 m2, covered_share 0.999999997): a pass along the hole covers them.
    c = corridor
    hole = [(c, c), (c + 40, c), (c + 40, c + 30), (c, c + 30)]
    mission = plan_area([(0, 0), (300, 0), (300, 200), (0, 200)], 10.0, crs=None,
                        holes=[hole], headland=passes)  # fmt: skip
    _check(mission, passes)


def test_headland_covers_the_gap_between_two_holes():
    # Two holes 5 m apart at 10 m: no pass between them; it used to be left uncovered (345 m2).
    holes = [
        [(50, 40), (90, 40), (90, 110), (50, 110)],
        [(95, 40), (135, 40), (135, 110), (95, 110)],
    ]
    mission = plan_area([(0, 0), (200, 0), (200, 150), (0, 150)], 10.0, crs=None, holes=holes,
                        headland=1)  # fmt: skip
    _check(mission, 1)


@pytest.mark.parametrize(
    ("width", "length", "spacing", "passes"),
    [(1e-4, 0.9, 10.0, 1), (21e-6, 2.0, 10.0, 1), (3e-4, 3.0, 30.0, 1), (1e-3, 0.05, 10.0, 2)],
)
def test_headland_covers_a_short_narrow_corridor_between_holes(width, length, spacing, passes):
    # A review: two holes side by side, ``width`` apart along ``length``: the whole corridor is
    # under 1e-6 spacing^2 and was dropped as the buffers' rounding (100 um x 0.9 m: 9e-5 m2).
    holes = [
        [(40, 40), (60, 40), (60, 40 + length), (40, 40 + length)],
        [(60 + width, 40), (80, 40), (80, 40 + length), (60 + width, 40 + length)],
    ]
    mission = plan_area([(0, 0), (200, 0), (200, 120), (0, 120)], spacing, crs=None, holes=holes,
                        headland=passes, angle=0.2)  # fmt: skip
    _check(mission, passes)


@pytest.mark.parametrize(("turnaround", "holes"), [(15.0, []), (15.0, [POND]), (4.0, [POND])])
def test_headland_run_ins_end_in_the_field(turnaround, holes):
    # A run-in longer than the headland band used to end outside the field (a QA run: 272 m of
    # the path outside with --headland 1 --turnaround 15); it is cut at the boundary now, and
    # the moves between run-outs routed inside.
    mission = plan_area(L_FIELD, 10.0, crs=None, holes=holes, headland=1, turnaround=turnaround)
    _check(mission, 1)
    assert mission.stats.outside_length == 0.0
    kinds = mission.kinds
    assert "run_in" in kinds and "run_out" in kinds
    w = np.asarray(mission.plan.waypoints)
    field = _field(mission)
    cut = 0
    for i, k in enumerate(kinds):
        if k in ("run_in", "run_out"):  # full length, or cut where it meets the boundary
            end = w[i + 1 if k == "run_in" else i - 1]
            run = np.linalg.norm(w[i] - end)
            assert run <= turnaround * (1 + 1e-9)
            if run < turnaround * (1 - 1e-9):  # the whole run would leave the field, or it
                whole = end + (w[i] - end) * turnaround / run  # stops at the band round a hole
                near_hole = any(
                    shapely.Point(w[i]).distance(h) < 10.0 + 1e-6 for h in field.interiors
                )
                assert near_hole or not field.contains(shapely.LineString([end, whole]))
                cut += not near_hole
    assert cut > 0 if turnaround > 10 else cut == 0


def test_headland_on_a_convex_field_and_the_embedded_field():
    _check(plan_area(SQUARE, 10.0, crs=None, headland=3), 3)
    _check(plan_area(embedded_field(), 10.0, headland=2), 2)


def test_turns_stay_inside_the_field_and_respect_the_radius():
    for reverse in (False, True):
        v = Vehicle(turn_radius=6.0, reverse=reverse, speed=3.0)
        mission = plan_area(L_FIELD, 10.0, crs=None, holes=[POND], headland=2, vehicle=v)
        _check(mission, 2)
        field = _field(mission)
        turns = np.array([k == "turn" for k in mission.kinds])
        assert turns.sum() > 50
        assert field.buffer(1e-7).covers(shapely.MultiPoint(mission.waypoints[turns]))
        if not reverse:  # forward only: every turn's curvature radius >= 6 m
            k = mission.kinds
            i = 0
            while i < len(k):
                if k[i] == "turn":
                    j = i
                    while k[j] == "turn":
                        j += 1
                    run = mission.waypoints[i - 1 : j + 1]
                    assert circumradii(run).min() >= 6.0 * (1 - 1e-6)
                    i = j
                i += 1
        s = mission.summary()
        assert s["turn_length_m"] > 0
        assert s["duration_s"] == pytest.approx(s["path_length_m"] / 3.0)


def test_a_narrow_headland_keeps_straight_moves_with_a_note():
    # One 10 m pass cannot hold a Dubins turn of radius 6 m between neighbouring lanes.
    mission = plan_area(SQUARE, 10.0, crs=None, headland=1, vehicle=Vehicle(turn_radius=6.0))
    _check(mission, 1)
    assert any("would leave the field" in n for n in mission.plan.notes)


def test_headland_errors():
    with pytest.raises(InvalidParameterError, match=r"no inner field|splits"):
        plan_area(SQUARE, 10.0, crs=None, headland=5)
    # A band that cuts the inner field in two (the pond 45 m from the sides, 3 passes of 10 m
    # around it and the boundary) is refused: one inner field is planned.
    with pytest.raises(InvalidParameterError, match=r"splits the inner field into 2 parts"):
        plan_area(L_FIELD, 10.0, crs=None, holes=[POND], headland=3)
    with pytest.raises(InvalidParameterError, match="whole number"):
        plan_area(SQUARE, 10.0, crs=None, headland=1.5)
    with pytest.raises(InvalidParameterError, match="between 0 and"):
        plan_area(SQUARE, 10.0, crs=None, headland=-1)
    # A JSON ``true`` (the page's API) is not one pass: refused as ``turn_radius: true`` is.
    with pytest.raises(InvalidParameterError, match="whole number"):
        plan_area(SQUARE, 10.0, crs=None, headland=True)
    # A nadir gap: the passes would not cover their own blind strip (and the lanes, reaching
    # farther than half a spacing, left a plain rectangle's field by 358 m): refused.
    with pytest.raises(InvalidParameterError, match="nadir gap"):
        plan_area(SQUARE, Swath(24.0, nadir_gap=4.0), crs=None, headland=2)


def test_cli_headland_and_export(tmp_path, capsys):
    wkt = tmp_path / "field.wkt"
    ring = ", ".join(f"{x} {y}" for x, y in [*L_FIELD, L_FIELD[0]])
    hole = ", ".join(f"{x} {y}" for x, y in [*POND, POND[0]])
    wkt.write_text(f"POLYGON (({ring}), ({hole}))")
    out = tmp_path / "m.csv"
    argv = ["-q", "plan", str(wkt), "--crs", "planar", "--spacing", "10", "--headland", "2"]
    assert main([*argv, "--turn-radius", "6", "--json", "--out", str(out)]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["headland_passes"] == 2 and summary["covered_share"] >= 1 - 1e-9
    text = out.read_text().splitlines()
    kinds = {line.split(",")[1] for line in text[1:]}
    assert {"headland", "turn", "start", "end"} <= kinds
    assert main([*argv[:-1], "9", "--json"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "headland" in err[0]


def test_headland_mission_read_by_pymavlink(tmp_path):
    mavwp = pytest.importorskip("pymavlink.mavwp")
    mission = plan_area(embedded_field(), 10.0, headland=2, altitude=2.0)
    path = tmp_path / "m.waypoints"
    write_mission(mission, path)
    loader = mavwp.MAVWPLoader()
    n = loader.load(str(path))
    assert n == len(mission.waypoints) + 1 or n == len(mission.waypoints) + 2
    got = np.array([[loader.wp(i).y, loader.wp(i).x] for i in range(n - len(mission.waypoints), n)])
    np.testing.assert_allclose(got, mission.waypoints_lonlat, atol=1e-9, rtol=0)


def _traced(n: int = 3000, a: float = 250.0, b: float = 150.0, noise: float = 0.3) -> np.ndarray:
    """A traced boundary: an ellipse whose radius walks randomly, 0.3 m of noise per vertex at
    about 0.7 m spacing (the exploratory test's field, 500 x 300 m, 3000 vertices)."""
    rng = np.random.default_rng(3)
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    r = 1 + 0.01 * rng.standard_normal(n).cumsum() / 10
    x = a * np.cos(t) * r + noise * rng.standard_normal(n)
    y = b * np.sin(t) * r + noise * rng.standard_normal(n)
    poly = shapely.Polygon(np.c_[x, y])
    poly = poly if poly.is_valid else poly.buffer(0)
    return np.asarray(poly.exterior.coords)[:-1]


def test_headland_on_a_traced_boundary_is_about_its_rings_length():
    # Spikes into every corner of the band farther than reach made 32.7 km of headland around
    # this field's 1.3 km ring; now the spikes reach only as far as the noise's corners need.
    mission = plan_area(_traced(), 15.0, crs=None, headland=1, angle=0.0)
    _check(mission, 1)
    plan = mission.plan
    rings = headland.headland_rings(plan.region, plan.spacing, 1)
    ring = sum(shapely.LineString(r).length for rs in rings for r in rs)
    assert mission.summary()["headland_length_m"] < 1.6 * ring


@pytest.mark.parametrize("passes", [1, 2])
@pytest.mark.parametrize("name", ["square", "L", "traced"])
def test_spikes_cover_the_band_without_the_gap_passes(name, passes):
    # The rings and their spikes alone cover the whole field less the inner field (the gap
    # passes are only the guarantee): measured with swaths of 64 segments per quarter circle.
    ring = {"square": np.asarray(SQUARE, float), "L": np.asarray(L_FIELD, float)}.get(name)
    field = Region(_traced(1200, 100.0, 60.0) if ring is None else ring, [])
    spacing, reach = 10.0, 5.0
    router = Router(field, reach=0.0)
    rings = headland.headland_rings(field, spacing, passes)
    driven = []
    for k, rs in enumerate(rings):
        outer = headland._offset(field, k * spacing)
        inner = headland._offset(field, (k + 0.5) * spacing)
        driven += headland._spikes(outer, inner, rs, reach, spacing, router)
    swaths = shapely.buffer([shapely.LineString(d) for d in driven], reach, quad_segs=64)
    inner = headland._offset(field, (passes - headland._OVERLAP) * spacing)
    whole = headland._shapely_region(field)
    assert whole.difference(shapely.union_all([*swaths, inner])).area <= 1e-9 * whole.area
    assert all(whole.buffer(1e-7).covers(shapely.LineString(d)) for d in driven)


def test_a_spike_stops_a_reach_short_of_the_corner():
    # A 90-degree corner lies sqrt(2) * 5 m from the pass at 10 m: its spike is that less
    # 0.99 reach long, driven there and back, one per corner.
    mission = plan_area(SQUARE, 10.0, crs=None, headland=1, angle=0.0)
    _check(mission, 1)
    spike = 2**0.5 * 5.0 - (1 - headland._SHORT) * 5.0
    ring = 2 * (110 + 80)
    assert mission.summary()["headland_length_m"] == pytest.approx(ring + 4 * 2 * spike)


def test_headland_at_utm_coordinates_is_the_same_as_near_the_origin():
    # GEOS's rounding at 5e6 m left slivers of 3e-8..7e-8 m2 between the swaths: 6 gap passes,
    # 648 m more headland on this star than at the origin (a review).
    star = np.array(
        [((200 if i % 2 == 0 else 60) * np.cos(np.pi * i / 5),
          (200 if i % 2 == 0 else 60) * np.sin(np.pi * i / 5)) for i in range(10)]
    )  # fmt: skip
    near = plan_area(star, 10.0, crs=None, headland=2, angle=0.0)
    far = plan_area(star + np.array([512345.6, 5123456.7]), 10.0, crs=None, headland=2, angle=0.0)
    _check(far, 2)
    assert far.summary()["headland_length_m"] == pytest.approx(
        near.summary()["headland_length_m"], rel=1e-9
    )
