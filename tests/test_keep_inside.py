"""``--keep-inside`` / ``keep_inside=True``: the path stays in the area (shapely), the coverage
stays 100% (measured here, independently, on the original boundary), the boundary passes are
exported with their own kind in every format and read back by the real readers; without it,
``outside_length_m`` is the length of the path outside the area, as shapely measures it."""

from __future__ import annotations

import csv
import itertools
import json
import math

import numpy as np
import pytest
import shapely

from boustro.errors import InvalidParameterError
from boustro.formats import MAV_CMD_NAV_WAYPOINT, write_mission
from boustro.geometry.region import Region, random_region
from boustro.io import embedded_field
from boustro.mission import plan_area
from boustro.plan.inside import clip_lanes
from boustro.plan.lanes import region_lanes
from boustro.plan.outside import outside_length
from boustro.plan.region import plan_region

from .conftest import run_cli

L_SHAPE = [(0, 0), (60, 0), (60, 20), (25, 20), (25, 50), (0, 50)]
HOLES = [[(5, 5), (15, 5), (15, 15), (5, 15)], [(40, 5), (48, 9), (44, 14)]]


def _lake() -> tuple[np.ndarray, list[np.ndarray]]:
    """A lake-like concave shore (lobes and bays) with an island."""
    th = np.linspace(0, 2 * math.pi, 80, endpoint=False)
    r = 100 * (1 + 0.3 * np.sin(3 * th) + 0.12 * np.cos(7 * th + 1))
    island = np.array([(10.0, 10.0), (30.0, 12.0), (25.0, 30.0)])
    return np.stack([r * np.cos(th), r * np.sin(th)], axis=1), [island]


def _shapely(shell, holes=()) -> shapely.Polygon:
    return shapely.Polygon(np.asarray(shell, float), [np.asarray(h, float) for h in holes])


def _check_inside_and_covered(plan, area: shapely.Polygon) -> float:
    """The path lies in ``area`` (to 1e-6 of its size) and the swaths cover all of it: lanes a
    flat band of ``reach`` either side, passes every point within ``reach`` (computed here, not
    by boustro's coverage code). Returns the covered share."""
    size = math.sqrt(area.area)
    path = shapely.LineString(plan.waypoints)
    assert area.buffer(1e-6 * size).contains(path)
    roles = np.array(plan.role())
    assert set(roles) <= {"lane", "boundary"}  # the passes around holes are replaced
    lanes = shapely.linestrings(plan.transects[roles == "lane"])
    passes = shapely.linestrings(plan.transects[roles == "boundary"])
    swaths = np.concatenate(
        [
            shapely.buffer(lanes, plan.reach, cap_style="flat"),
            shapely.buffer(passes, plan.reach, quad_segs=64),
        ]
    )
    # one swath at a time: GEOS's union of many nearly touching rectangles can lose one
    left = area
    for swath in swaths:
        left = left.difference(swath)
    covered = 1 - left.area / area.area
    assert covered >= 1 - 1e-9
    assert plan.stats.outside_length == 0.0
    assert plan.keep_inside
    return covered


def _independent_outside(waypoints: np.ndarray, area: shapely.Polygon) -> float:
    """The length of each segment outside ``area`` (a point within 1e-9 of its size of the
    boundary counts as on it: a move along a hole's edge is collinear with it only to
    rounding, and GEOS would count it in the hole)."""
    x0, y0, x1, y1 = area.bounds
    grown = area.buffer(1e-9 * math.hypot(x1 - x0, y1 - y0), join_style="mitre")
    return sum(
        shapely.LineString([a, b]).difference(grown).length
        for a, b in itertools.pairwise(waypoints)
    )


@pytest.mark.parametrize(
    ("name", "shell", "holes", "spacing", "kw"),
    [
        ("convex", [(0, 0), (100, 0), (120, 70), (10, 90)], [], 10.0, {}),
        (
            "rectangle at 17 degrees",
            [(0, 0), (100, 0), (100, 40), (0, 40)],
            [],
            7.0,
            {"angle": math.radians(17), "offset": 1.0, "decompose_area": False},
        ),
        ("L-shape", L_SHAPE, [], 4.0, {}),
        ("L-shape, one angle", L_SHAPE, [], 4.0, {"decompose_area": False}),
        ("L-shape decomposed", L_SHAPE, [], 4.0, {"decompose_area": True}),
        ("holes", L_SHAPE, HOLES, 4.0, {}),
        ("holes decomposed", L_SHAPE, HOLES, 4.0, {"decompose_area": True}),
        ("lake", *_lake(), 12.0, {}),
        (
            "thin ring",
            [(0, 0), (10, 0), (10, 10), (0, 10)],
            [[(1, 1), (9, 1), (9, 9), (1, 9)]],
            1.0,
            {},
        ),
        ("sliver", [(0, 0), (100, 0), (100, 3), (0, 1)], [], 10.0, {}),
    ],
)
def test_the_path_stays_inside_and_covers_the_area(name, shell, holes, spacing, kw):
    plan = plan_region(Region(shell, holes), spacing, keep_inside=True, **kw)
    _check_inside_and_covered(plan, _shapely(shell, holes))
    free = plan_region(Region(shell, holes), spacing, **kw)
    assert free.stats.outside_length > 0 or name in ("sliver",)
    assert free.stats.outside_length == pytest.approx(
        _independent_outside(free.waypoints, _shapely(shell, holes)), rel=1e-5, abs=1e-5
    )


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_random_concave_areas_with_holes(seed):
    region = random_region(np.random.default_rng(seed), 24, 2)
    area = _shapely(region.shell.vertices, [h.vertices for h in region.holes])
    plan = plan_region(region, 0.07, keep_inside=True)
    _check_inside_and_covered(plan, area)
    assert plan.stats.boundary_pass_length > 0


def test_embedded_field_through_plan_area():
    field = embedded_field()
    inside = plan_area(field, 10.0, keep_inside=True)
    free = plan_area(field, 10.0)
    ring = inside.projection.to_plan(field.ring)
    area = _shapely(ring)
    # planned on the field itself (not its convex hull, as without the flag)
    covered = _check_inside_and_covered(inside.plan, area)
    assert inside.coverage.covered_share == pytest.approx(covered, abs=1e-9)
    assert inside.hull_depth == 0.0 and free.hull_depth > 0
    summary = inside.summary()
    assert summary["keep_inside"] is True and summary["outside_length_m"] == 0.0
    assert summary["boundary_pass_length_m"] > 0
    # without it the lanes reach past the boundary, and the summary says by how much
    measured = _independent_outside(free.plan.waypoints, area) / free.plan.ground_scale
    assert free.summary()["outside_length_m"] == pytest.approx(measured, rel=1e-5)
    assert measured > 100 and "keep_inside" not in free.summary()


def test_outside_length_is_measured_segment_by_segment():
    square = [(0, 0), (10, 0), (10, 10), (0, 10)]
    # out 5 to the right and back: 10 outside, although the line covers the same 5 twice
    path = [(5, 5), (15, 5), (5, 5)]
    assert outside_length(path, square) == pytest.approx(10.0)
    hole = Region(square, [[(4, 4), (6, 4), (6, 6), (4, 6)]])
    assert outside_length([(1, 5), (9, 5)], hole) == pytest.approx(2.0)
    assert outside_length([(0, 0), (10, 0), (10, 10)], square) == 0.0  # along the boundary


def test_lanes_are_cut_at_the_boundary_or_inside_it():
    region = Region(L_SHAPE)
    lanes = region_lanes(region, 4.0, math.radians(30), 0.0)
    area = _shapely(L_SHAPE)
    for margin in (0.0, 2.0):
        cut = clip_lanes(lanes, region, 1e-9, margin)
        assert len(cut.k) >= len(lanes.k) - 2
        lines = shapely.linestrings(cut.segments)
        inner = area.buffer(-margin + 1e-9)
        assert all(inner.covers(line) for line in lines)
    assert np.sum(lanes.t1 - lanes.t0) > np.sum(cut.t1 - cut.t0)


def test_boundary_passes_join_the_tour():
    plan = plan_region(Region(L_SHAPE, HOLES), 4.0, keep_inside=True)
    kinds = np.array(plan.kinds)
    roles = np.array(plan.role())
    assert (kinds == "contour").any() and (roles == "boundary").any()
    # every edge of a boundary pass is a transect of role boundary between consecutive
    # waypoints of kind contour
    w = plan.waypoints
    for t in np.flatnonzero(roles == "boundary"):
        a, b = plan.transects[t]
        i = np.flatnonzero((np.abs(w - a).max(axis=1) < 1e-9) & (kinds == "contour"))
        assert any(np.abs(w[j + 1] - b).max() < 1e-9 for j in i if j + 1 < len(w))
    # one turn per pass joined: lanes plus passes, minus one
    assert plan.stats.n_turns >= plan.stats.n_transects
    length = np.linalg.norm(np.diff(w, axis=0), axis=1).sum()
    assert plan.stats.path_length == pytest.approx(length)
    edges = np.linalg.norm(plan.transects[:, 1] - plan.transects[:, 0], axis=1)
    assert plan.stats.boundary_pass_length == pytest.approx(edges[roles == "boundary"].sum())


def test_bad_combinations_are_one_clear_error(capsys):
    with pytest.raises(InvalidParameterError, match="nadir gap"):
        plan_region(Region(L_SHAPE), 4.0, keep_inside=True, nadir_gap=1.0)
    with pytest.raises(InvalidParameterError, match="keep_inside must be"):
        plan_area(embedded_field(), 10.0, keep_inside="yes")
    code, out, err = run_cli(capsys, "plan", "--keep-inside", "--swath", "20", "--nadir-gap", "3")
    assert code == 2 and out == "" and err.count("\n") == 1 and "--keep-inside" in err


def test_run_ins_end_at_the_boundary():
    plan = plan_region(Region(L_SHAPE, HOLES), 4.0, keep_inside=True, turnaround=3.0)
    _check_inside_and_covered(plan, _shapely(L_SHAPE, HOLES))
    kinds = np.array(plan.kinds)
    w = plan.waypoints
    assert (kinds == "run_in").any() and (kinds == "run_out").any()
    step = np.linalg.norm(np.diff(w, axis=0), axis=1)
    # a run-in leads to its lane's start, a run-out follows its end, none longer than asked
    assert np.all(step[kinds[:-1] == "run_in"] <= 3.0 + 1e-9)
    assert np.all(step[kinds[1:] == "run_out"] <= 3.0 + 1e-9)
    assert np.all(step > 0)


@pytest.fixture(scope="module")
def lonlat_mission():
    """A concave lon/lat area with a hole, planned with --keep-inside (speed and altitude)."""
    shell = [[5.0, 52.0], [5.004, 52.0], [5.004, 52.0012], [5.0016, 52.0012], [5.0016, 52.003]]
    shell += [[5.0, 52.003]]
    hole = [[5.0004, 52.0004], [5.001, 52.0004], [5.001, 52.0009], [5.0004, 52.0009]]
    return plan_area(
        shell, 12.0, holes=[hole], keep_inside=True, speed=3.0, altitude=30.0, turn_time=5.0
    )


def test_every_export_holds_the_boundary_passes(tmp_path, lonlat_mission):
    import fastkml.kml
    import gpxpy
    import pyogrio
    from pymavlink import mavwp

    m = lonlat_mission
    roles = list(m.plan.role())
    n_boundary = roles.count("boundary")
    assert n_boundary > 0 and roles.count("lane") > 0
    # GeoJSON through GDAL: every transect with its pass, every waypoint with its kind
    write_mission(m, tmp_path / "p.geojson")
    meta, _, geometry, fields = pyogrio.raw.read(tmp_path / "p.geojson")
    props = dict(zip(meta["fields"], fields, strict=True))
    role = props["role"]
    assert list(props["pass"][role == "transect"]) == roles
    assert list(props["kind"][role == "waypoint"]) == list(m.kinds)
    lines = shapely.from_wkb(geometry)[role == "transect"]
    np.testing.assert_allclose(
        np.array([np.asarray(g.coords) for g in lines]), m.transects, atol=1e-12
    )
    # KML through fastkml: "Boundary pass N" placemarks, in order
    write_mission(m, tmp_path / "p.kml")
    doc = next(iter(fastkml.kml.KML.from_string((tmp_path / "p.kml").read_bytes()).features))
    (folder,) = [f for f in doc.features if getattr(f, "name", "") == "Transects"]
    names = [p.name.rsplit(" ", 1)[0] for p in folder.features]
    label = {"lane": "Transect", "boundary": "Boundary pass"}
    assert names == [label[r] for r in roles]
    # GPX through gpxpy: route points typed by kind, the passes a track of type boundary
    write_mission(m, tmp_path / "p.gpx")
    gpx = gpxpy.parse((tmp_path / "p.gpx").read_text())
    assert [p.type for p in gpx.routes[0].points] == list(m.kinds)
    lanes_track, boundary_track = gpx.tracks
    assert boundary_track.type == "boundary" and lanes_track.type is None
    assert len(boundary_track.segments) == n_boundary
    pts = np.array([[[p.longitude, p.latitude] for p in s.points] for s in boundary_track.segments])
    pick = np.array(roles) == "boundary"
    np.testing.assert_allclose(pts, m.transects_lonlat[pick], atol=1e-9, rtol=0)
    # CSV: the kind column
    write_mission(m, tmp_path / "p.csv")
    with open(tmp_path / "p.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["kind"] for r in rows] == list(m.kinds) and "contour" in m.kinds
    # QGroundControl .plan and MAVLink .waypoints: positions only (no format has a kind), the
    # boundary passes' waypoints among them in order
    write_mission(m, tmp_path / "p.plan")
    items = json.loads((tmp_path / "p.plan").read_text())["mission"]["items"]
    nav = np.array([i["params"][4:6] for i in items if i["command"] == MAV_CMD_NAV_WAYPOINT])
    np.testing.assert_allclose(nav[:, ::-1], m.waypoints_lonlat, atol=1e-12, rtol=0)
    write_mission(m, tmp_path / "p.waypoints")
    loader = mavwp.MAVWPLoader()
    count = loader.load(str(tmp_path / "p.waypoints"))
    got = np.array([[loader.wp(i).y, loader.wp(i).x] for i in range(2, count)])
    np.testing.assert_allclose(got, m.waypoints_lonlat, atol=1e-9, rtol=0)
    # and the path stays in the area: in the plan frame, and in lon/lat to the projection's
    # rounding (1e-7 degrees, about a centimetre: straight edges in lon/lat are not straight in
    # the projection)
    ring = m.projection.to_plan(m.area.ring)
    _check_inside_and_covered(
        m.plan, _shapely(ring, [m.projection.to_plan(h) for h in m.area.holes])
    )
    area = _shapely(m.area.ring, m.area.holes)
    assert area.buffer(1e-7).contains(shapely.LineString(m.waypoints_lonlat))


def test_command_line(tmp_path, capsys):
    wkt = tmp_path / "area.wkt"
    wkt.write_text(
        "POLYGON ((0 0, 60 0, 60 20, 25 20, 25 50, 0 50, 0 0), (5 5, 15 5, 15 15, 5 15, 5 5))"
    )
    out = tmp_path / "plan.geojson"
    args = ["-q", "plan", wkt, "--crs", "planar", "--spacing", "4", "--json"]
    code, text, err = run_cli(capsys, *args, "--keep-inside", "--out", out)
    assert code == 0, err
    inside = json.loads(text)
    assert inside["keep_inside"] is True and inside["outside_length_m"] == 0.0
    assert inside["covered_share"] >= 1 - 1e-9
    doc = json.loads(out.read_text())
    passes = {f["properties"].get("pass") for f in doc["features"]}
    assert passes == {None, "lane", "boundary"}
    code, text, err = run_cli(capsys, *args)
    free = json.loads(text)
    assert free["outside_length_m"] > 50 and "keep_inside" not in free
    with pytest.raises(SystemExit):
        run_cli(capsys, "plan", "--help")
    text = capsys.readouterr().out
    assert "--keep-inside" in text and "boundary passes" in text


@pytest.mark.parametrize(
    ("shell", "spacing"),
    [
        ([(0, 0), (3, 0), (0, 2)], 10.0),  # smaller than the spacing: one patch, no lane
        ([(0, 0), (10, 0), (10, 1.5), (0, 1.5)], 2.0),  # narrower than a spacing
        ([(0, 0), (100, 0), (50, 3)], 5.0),  # a sliver with two sharp corners
    ],
)
def test_areas_no_lane_fits_in_are_covered_by_passes(shell, spacing):
    plan = plan_region(Region(shell), spacing, keep_inside=True)
    assert plan.stats.n_transects == 0 and len(plan.transects) > 0
    _check_inside_and_covered(plan, _shapely(shell))


def test_chords_stay_inside_without_passes():
    m = plan_area(
        [(0, 0), (30, 0), (30, 20), (0, 20)], 5.0, crs=None, keep_inside=True, layout="chords"
    )
    assert set(m.plan.role()) == {"lane"} and m.stats.outside_length == 0.0
    area = _shapely([(0, 0), (30, 0), (30, 20), (0, 20)])
    assert area.buffer(1e-9).contains(shapely.LineString(m.plan.waypoints))
    assert m.coverage.covered_share < 1  # chords promise no coverage, passes or not


def test_every_field_of_a_file(tmp_path, capsys):
    doc = {
        "type": "FeatureCollection",
        "features": [
            {
                "type": "Feature",
                "properties": {"name": name},
                "geometry": {"type": "Polygon", "coordinates": [ring]},
            }
            for name, ring in [
                ("L", [[0, 0], [60, 0], [60, 20], [25, 20], [25, 50], [0, 50], [0, 0]]),
                ("square", [[100, 0], [140, 0], [140, 40], [100, 40], [100, 0]]),
            ]
        ],
    }
    path = tmp_path / "fields.geojson"
    path.write_text(json.dumps(doc))
    code, text, err = run_cli(
        capsys, "-q", "plan", path, "--crs", "planar", "--spacing", "6", "--keep-inside", "--json"
    )
    assert code == 0, err
    out = json.loads(text)
    assert [f["name"] for f in out] == ["L", "square"]
    assert all(f["keep_inside"] and f["outside_length_m"] == 0.0 for f in out)
    assert all(f["covered_share"] >= 1 - 1e-9 for f in out)
