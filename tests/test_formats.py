"""Mission files, each read back by an existing reader: GDAL (pyogrio), fastkml, gpxpy, csv,
the documented QGroundControl Plan format, and pymavlink's waypoint loader."""

from __future__ import annotations

import csv
import dataclasses
import json
import os

import numpy as np
import pyproj
import pytest

from boustro.errors import InvalidParameterError
from boustro.formats import (
    FORMATS,
    MAV_CMD_NAV_WAYPOINT,
    MAV_FRAME_GLOBAL_RELATIVE_ALT,
    atomic_write,
    format_for,
    render,
    write_mission,
)
from boustro.geo import plan_area
from boustro.io import Area, embedded_field

FAST: dict = {}  # the default (certified global) optimiser is fast enough for tests


@pytest.fixture(scope="module")
def mission():
    return plan_area(
        embedded_field(),
        10.0,
        options=FAST,
        turnaround=4.0,
        speed=3.0,
        turn_time=6.0,
        altitude=35.0,
    )


@pytest.fixture(scope="module")
def planar_mission():
    ring = np.array([(0, 0), (120, 0), (130, 70), (10, 80)], dtype=float)
    return plan_area(ring, 7.0, crs=None, options=FAST)


@pytest.fixture(scope="module")
def rd_mission():
    field = embedded_field()
    rd = pyproj.Transformer.from_crs("EPSG:4326", "EPSG:28992", always_xy=True)
    x, y = rd.transform(field.ring[:, 0], field.ring[:, 1])
    return plan_area(Area(np.stack([x, y], 1), "EPSG:28992", "rd", "<test>"), 10.0, options=FAST)


def test_geojson_read_by_gdal(tmp_path, mission):
    pyogrio = pytest.importorskip("pyogrio")
    shapely = pytest.importorskip("shapely")
    path = tmp_path / "plan.geojson"
    assert write_mission(mission, path) == "geojson"
    meta, _, geometry, fields = pyogrio.raw.read(path)
    assert meta["crs"] == "EPSG:4326"
    props = dict(zip(meta["fields"], fields, strict=True))
    geoms = shapely.from_wkb(geometry)
    role = props["role"]
    waypoints = [g for g, r in zip(geoms, role, strict=True) if r == "waypoint"]
    seq = props["seq"][role == "waypoint"].astype(int)
    assert seq.tolist() == list(range(len(mission.waypoints)))
    xy = np.array([[p.x, p.y] for p in waypoints])
    np.testing.assert_allclose(xy, mission.waypoints, atol=1e-12, rtol=0)
    assert list(props["kind"][role == "waypoint"]) == list(mission.kinds)
    (path_line,) = [g for g, r in zip(geoms, role, strict=True) if r == "path"]
    np.testing.assert_allclose(np.asarray(path_line.coords), mission.waypoints, atol=1e-12)
    transects = [g for g, r in zip(geoms, role, strict=True) if r == "transect"]
    assert len(transects) == mission.stats.n_transects
    for line, seg in zip(transects, mission.transects, strict=True):
        np.testing.assert_allclose(np.asarray(line.coords), seg, atol=1e-12)
    (area,) = [g for g, r in zip(geoms, role, strict=True) if r == "area"]
    assert area.is_valid and area.exterior.is_ccw
    doc = json.loads(path.read_text())
    assert doc["boustro"]["n_transects"] == mission.stats.n_transects


def test_geojson_projected_crs_is_named(tmp_path, rd_mission):
    pyogrio = pytest.importorskip("pyogrio")
    path = tmp_path / "plan.geojson"
    write_mission(rd_mission, path)
    meta, _, _, _ = pyogrio.raw.read(path)
    assert meta["crs"] == "EPSG:28992"
    doc = json.loads(path.read_text())
    (wp,) = [f for f in doc["features"] if f["properties"].get("seq") == 0]
    np.testing.assert_allclose(wp["geometry"]["coordinates"], rd_mission.waypoints[0])


def test_kml_read_by_fastkml(tmp_path, mission):
    kml = pytest.importorskip("fastkml.kml")
    path = tmp_path / "plan.kml"
    write_mission(mission, path)
    doc = next(iter(kml.KML.from_string(path.read_bytes()).features))
    placemarks = {f.name: f for f in doc.features if hasattr(f, "geometry")}
    coords = np.array(placemarks["Path"].geometry.coords)
    np.testing.assert_allclose(coords[:, :2], mission.waypoints_lonlat, atol=1e-9, rtol=0)
    assert coords[:, 2] == pytest.approx(35.0)
    area = np.array(placemarks[mission.name].geometry.exterior.coords)[:-1]  # the field's name
    assert len(area) == len(mission.area.ring)
    (folder,) = [f for f in doc.features if getattr(f, "name", "") == "Transects"]
    lines = [np.array(p.geometry.coords)[:, :2] for p in folder.features]
    np.testing.assert_allclose(np.array(lines), mission.transects_lonlat, atol=1e-9, rtol=0)


def test_kml_read_by_gdal(tmp_path, mission):
    pyogrio = pytest.importorskip("pyogrio")
    path = tmp_path / "plan.kml"
    write_mission(mission, path)
    layers = [name for name, _ in pyogrio.list_layers(path)]
    assert layers  # GDAL's KML driver opens it


def test_gpx_read_by_gpxpy(tmp_path, mission):
    gpxpy = pytest.importorskip("gpxpy")
    path = tmp_path / "plan.gpx"
    write_mission(mission, path)
    gpx = gpxpy.parse(path.read_text())
    (route,) = gpx.routes
    got = np.array([[p.longitude, p.latitude] for p in route.points])
    np.testing.assert_allclose(got, mission.waypoints_lonlat, atol=1e-9, rtol=0)
    assert [p.type for p in route.points] == list(mission.kinds)
    (track,) = gpx.tracks
    segs = np.array([[[p.longitude, p.latitude] for p in s.points] for s in track.segments])
    np.testing.assert_allclose(segs, mission.transects_lonlat, atol=1e-9, rtol=0)
    # the altitude (above take-off, as the route's description says) on every point
    assert {p.elevation for p in route.points} == {35.0}
    assert {p.elevation for s in track.segments for p in s.points} == {35.0}
    assert "35 m above take-off" in route.description


def test_gpx_without_an_altitude_has_no_elevation(mission):
    gpxpy = pytest.importorskip("gpxpy")
    no_alt = dataclasses.replace(mission, altitude=None)
    gpx = gpxpy.parse(render(no_alt, "gpx"))
    assert {p.elevation for p in gpx.routes[0].points} == {None}
    assert gpx.routes[0].description is None


def test_csv_read_back(tmp_path, mission, rd_mission, planar_mission):
    for m, cols in [
        (mission, ["seq", "kind", "transect", "lon", "lat", "altitude_m"]),
        (rd_mission, ["seq", "kind", "transect", "x", "y", "lon", "lat"]),
        (planar_mission, ["seq", "kind", "transect", "x", "y"]),
    ]:
        path = tmp_path / "plan.csv"
        write_mission(m, path)
        with open(path, newline="") as fh:
            rows = list(csv.DictReader(fh))
        assert list(rows[0]) == cols
        xy = np.array([[float(r[cols[3]]), float(r[cols[4]])] for r in rows])
        np.testing.assert_array_equal(xy, m.waypoints)
        assert [r["kind"] for r in rows] == list(m.kinds)
        assert [int(r["seq"]) for r in rows] == list(range(len(rows)))


def test_qgc_plan_matches_the_documented_format(tmp_path, mission):
    path = tmp_path / "mission.plan"
    write_mission(mission, path)
    assert_qgc_plan(json.loads(path.read_text()), mission, speed=3.0)


def assert_qgc_plan(doc: dict, mission, speed: float | None = None) -> None:
    """``doc`` is a QGroundControl Plan file as documented, flying ``mission``'s waypoints at
    its altitude (also the web API's and the browser's downloads, tests/test_web_*.py)."""
    # Top level and mission object as documented for QGroundControl Plan files.
    assert doc["fileType"] == "Plan" and doc["version"] == 1
    assert set(doc) >= {"fileType", "version", "groundStation", "mission"}
    m = doc["mission"]
    assert m["version"] == 2
    assert set(m) >= {"firmwareType", "vehicleType", "cruiseSpeed", "hoverSpeed", "items"}
    home = m["plannedHomePosition"]
    assert len(home) == 3
    np.testing.assert_allclose(home[1::-1], mission.home_lonlat, atol=1e-12)
    items = m["items"]
    assert [i["doJumpId"] for i in items] == list(range(1, len(items) + 1))
    assert all(i["type"] == "SimpleItem" and i["autoContinue"] is True for i in items)
    if speed is not None:
        assert items[0]["command"] == 178 and items[0]["params"][1] == speed  # DO_CHANGE_SPEED
    nav = [i for i in items if i["command"] == MAV_CMD_NAV_WAYPOINT]
    assert len(nav) == len(mission.waypoints)
    for item in nav:
        assert item["frame"] == MAV_FRAME_GLOBAL_RELATIVE_ALT
        assert len(item["params"]) == 7
        assert item["params"][6] == item["Altitude"] == mission.altitude
        assert item["AltitudeMode"] == 1
    latlon = np.array([i["params"][4:6] for i in nav])
    np.testing.assert_allclose(latlon[:, ::-1], mission.waypoints_lonlat, atol=1e-12, rtol=0)


def test_wpl_loaded_by_pymavlink(tmp_path, mission):
    mavwp = pytest.importorskip("pymavlink.mavwp")
    path = tmp_path / "mission.waypoints"
    write_mission(mission, path)
    assert path.read_text().splitlines()[0] == "QGC WPL 110"
    loader = mavwp.MAVWPLoader()
    count = loader.load(str(path))
    assert count == len(mission.waypoints) + 2  # home + change speed + waypoints
    home = loader.wp(0)
    assert (home.seq, home.current, home.frame) == (0, 1, 0)
    np.testing.assert_allclose([home.y, home.x], mission.home_lonlat, atol=1e-9)
    speed = loader.wp(1)
    assert speed.command == 178 and speed.param2 == pytest.approx(3.0)
    got = [loader.wp(i) for i in range(2, count)]
    assert all(w.command == MAV_CMD_NAV_WAYPOINT for w in got)
    assert all(w.frame == MAV_FRAME_GLOBAL_RELATIVE_ALT and w.z == 35.0 for w in got)
    assert [w.seq for w in got] == list(range(2, count))
    lonlat = np.array([[w.y, w.x] for w in got])
    np.testing.assert_allclose(lonlat, mission.waypoints_lonlat, atol=1e-9, rtol=0)


def test_mission_formats_need_altitude_and_geography(tmp_path, planar_mission):
    no_altitude = plan_area(embedded_field(), 10.0, options=FAST, check_coverage=False)
    for name in ("m.plan", "m.waypoints"):
        with pytest.raises(InvalidParameterError, match="needs a mission altitude"):
            write_mission(no_altitude, tmp_path / name)
    for name in ("m.kml", "m.gpx", "m.plan"):
        with pytest.raises(InvalidParameterError, match="planar coordinates"):
            write_mission(planar_mission, tmp_path / name)
    assert sorted(os.listdir(tmp_path)) == []


def test_format_from_extension():
    assert format_for("a.GeoJSON") == "geojson"
    assert format_for("a.waypoints") == "wpl"
    assert format_for("a.xyz", "kml") == "kml"
    assert set(FORMATS) == {"geojson", "kml", "gpx", "csv", "plan", "wpl"}
    with pytest.raises(InvalidParameterError, match="cannot tell the format"):
        format_for("a.xyz")
    with pytest.raises(InvalidParameterError, match="unknown format"):
        format_for("a.kml", "shapefile")


def test_atomic_write_never_leaves_half_a_file(tmp_path, monkeypatch):
    target = tmp_path / "mission.plan"
    target.write_text("old mission")
    os.chmod(target, 0o640)
    atomic_write(target, "new mission")
    assert target.read_text() == "new mission"
    assert (os.stat(target).st_mode & 0o777) == 0o640

    def broken_replace(src, dst):
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", broken_replace)
    with pytest.raises(OSError, match="disk full"):
        atomic_write(target, "newer mission")
    assert target.read_text() == "new mission"
    assert sorted(os.listdir(tmp_path)) == ["mission.plan"]
