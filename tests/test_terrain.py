"""Terrain: altitudes AMSL from a synthetic GeoTIFF DEM, written here with rasterio."""

from __future__ import annotations

import json

import numpy as np
import pytest
import rasterio
from affine import Affine
from pymavlink import mavwp
from pyproj import Transformer

from boustro.cli import main
from boustro.errors import InvalidParameterError
from boustro.io import embedded_field
from boustro.io.formats import render
from boustro.mission import plan_area
from boustro.mission.terrain import follow_terrain, open_dem

UTM = "EPSG:32632"  # the embedded field's zone
X0, Y0, PIXEL = 295900.0, 5711250.0, 2.0  # north-west corner of the DEM, metres
SIZE = 400  # pixels each way: 800 m, the field and a margin
TO_UTM = Transformer.from_crs("EPSG:4326", UTM, always_xy=True)


def plane(x, y):
    return 0.05 * (x - X0) - 0.02 * (y - Y0) + 30.0


def bump(x, y):
    r2 = (x - 296260.0) ** 2 + (y - 5710870.0) ** 2
    return 12.0 + 25.0 * np.exp(-r2 / (2 * 40.0**2))


def from_origin(x0, y0, dx, dy):
    return Affine(dx, 0.0, x0, 0.0, -dy, y0)


def write_dem(path, f, *, crs=UTM):
    cols, rows = np.meshgrid(np.arange(SIZE), np.arange(SIZE))
    x, y = X0 + (cols + 0.5) * PIXEL, Y0 - (rows + 0.5) * PIXEL  # pixel centres
    with rasterio.open(
        path,
        "w",
        driver="GTiff",
        height=SIZE,
        width=SIZE,
        count=1,
        dtype="float64",
        crs=crs,
        transform=from_origin(X0, Y0, PIXEL, PIXEL),
    ) as dst:
        dst.write(f(x, y), 1)
    return path


def _ground_truth(f, lonlat):
    x, y = TO_UTM.transform(lonlat[:, 0], lonlat[:, 1])
    return f(np.asarray(x), np.asarray(y))


@pytest.fixture(scope="module")
def mission():
    return plan_area(embedded_field(), 10.0, altitude=50.0, turnaround=10.0)


def test_a_plane_is_reproduced_exactly(tmp_path, mission):
    m = follow_terrain(mission, write_dem(tmp_path / "plane.tif", plane), tolerance=0.5)
    t = m.terrain
    assert t.kinds == mission.kinds  # a plane needs no added point
    np.testing.assert_allclose(t.ground, _ground_truth(plane, t.lonlat), atol=1e-6)
    np.testing.assert_allclose(t.amsl - 50.0, t.ground)
    assert t.home_ground == pytest.approx(_ground_truth(plane, m.home_lonlat[None])[0])


def test_a_bump_is_followed_within_the_tolerance(tmp_path, mission):
    tol = 0.5
    m = follow_terrain(mission, write_dem(tmp_path / "bump.tif", bump), tolerance=tol)
    t = m.terrain
    assert sum(k == "terrain" for k in t.kinds) > 10  # points added over the bump
    assert tuple(k for k in t.kinds if k != "terrain") == mission.kinds
    np.testing.assert_allclose(t.ground, _ground_truth(bump, t.lonlat), atol=0.05)
    # between consecutive waypoints the straight climb stays within tol of height above ground
    x, y = TO_UTM.transform(t.lonlat[:, 0], t.lonlat[:, 1])
    p = np.column_stack([x, y])
    s = np.linspace(0, 1, 50)[:, None]
    worst = 0.0
    for k in range(len(p) - 1):
        pts = p[k] + s * (p[k + 1] - p[k])
        flown = t.amsl[k] + s[:, 0] * (t.amsl[k + 1] - t.amsl[k])
        worst = max(worst, float(np.abs(flown - bump(pts[:, 0], pts[:, 1]) - 50.0).max()))
    assert worst <= tol + 0.05  # the DEM's bilinear interpolation of the bump, 2 m pixels


def test_mavlink_files_in_the_global_frame(tmp_path, mission):
    m = follow_terrain(mission, write_dem(tmp_path / "bump.tif", bump))
    path = tmp_path / "m.waypoints"
    path.write_text(render(m, "wpl"))
    loader = mavwp.MAVWPLoader()
    loader.load(str(path))
    wps = [loader.wp(i) for i in range(loader.count())]
    assert all(w.frame == 0 for w in wps)  # MAV_FRAME_GLOBAL: AMSL
    assert wps[0].z == pytest.approx(m.terrain.home_ground, abs=1e-5)
    np.testing.assert_allclose([w.z for w in wps[1:]], m.terrain.amsl, atol=1e-5)
    doc = json.loads(render(m, "plan"))
    items = doc["mission"]["items"]
    assert len(items) == len(m.terrain.points)
    assert {it["frame"] for it in items} == {0} and {it["AltitudeMode"] for it in items} == {3}
    np.testing.assert_allclose([it["params"][6] for it in items], m.terrain.amsl)
    np.testing.assert_allclose([it["AMSLAltAboveTerrain"] for it in items], m.terrain.amsl)
    assert {it["Altitude"] for it in items} == {50.0}
    assert doc["mission"]["plannedHomePosition"][2] == pytest.approx(m.terrain.home_ground)


def test_gpx_route_over_terrain_amsl(tmp_path, mission):
    gpxpy = pytest.importorskip("gpxpy")
    m = follow_terrain(mission, write_dem(tmp_path / "bump.tif", bump))
    gpx = gpxpy.parse(render(m, "gpx"))
    (route,) = gpx.routes
    assert [p.type for p in route.points] == list(m.terrain.kinds)  # the added points too
    got = np.array([[p.longitude, p.latitude] for p in route.points])
    np.testing.assert_allclose(got, m.terrain.lonlat, atol=1e-9, rtol=0)
    np.testing.assert_allclose([p.elevation for p in route.points], m.terrain.amsl, atol=1e-3)
    assert "above mean sea level" in route.description
    # no altitude above take-off mixed in: the track (lanes' ends) has no elevation
    assert {p.elevation for s in gpx.tracks[0].segments for p in s.points} == {None}


def test_a_dem_in_lonlat_works_too(tmp_path, mission):
    lon0, lat0 = 6.058, 51.516
    step = 2e-5
    path = tmp_path / "ll.tif"
    cols, rows = np.meshgrid(np.arange(600), np.arange(600))
    lon, lat = lon0 + (cols + 0.5) * step, lat0 - (rows + 0.5) * step
    z = 100 + 1000 * (lon - lon0) + 2000 * (lat - lat0)
    with rasterio.open(
        path, "w", driver="GTiff", height=600, width=600, count=1, dtype="float64",
        crs="EPSG:4326", transform=from_origin(lon0, lat0, step, step),
    ) as dst:  # fmt: skip
        dst.write(z, 1)
    t = follow_terrain(mission, path).terrain
    expected = 100 + 1000 * (t.lonlat[:, 0] - lon0) + 2000 * (t.lonlat[:, 1] - lat0)
    np.testing.assert_allclose(t.ground, expected, atol=1e-6)


def test_bad_dems_refused(tmp_path, mission):
    small = tmp_path / "small.tif"
    with rasterio.open(
        small, "w", driver="GTiff", height=10, width=10, count=1, dtype="float64",
        crs=UTM, transform=from_origin(X0, Y0, PIXEL, PIXEL),
    ) as dst:  # fmt: skip
        dst.write(np.zeros((10, 10)), 1)
    with pytest.raises(InvalidParameterError, match="outside the DEM"):
        follow_terrain(mission, small)
    junk = tmp_path / "junk.tif"
    junk.write_bytes(b"not a tiff")
    with pytest.raises(InvalidParameterError, match=r"junk\.tif"):
        open_dem(junk)
    no_alt = plan_area(embedded_field(), 10.0)
    with pytest.raises(InvalidParameterError, match="height above ground"):
        follow_terrain(no_alt, write_dem(tmp_path / "p.tif", plane))


def test_command_line_dem(tmp_path, capsys):
    dem = write_dem(tmp_path / "bump.tif", bump)
    out = tmp_path / "m.plan"
    args = ["-q", "plan", "--altitude", "40", "--dem", str(dem), "--terrain-tolerance", "0.3"]
    assert main([*args, "--out", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)["terrain"]
    assert summary["height_above_ground_m"] == 40 and summary["tolerance_m"] == 0.3
    assert summary["added_points"] > 0 and summary["amsl_max_m"] > 12 + 25 + 40 - 1
    assert json.loads(out.read_text())["mission"]["globalPlanAltitudeMode"] == 3
    assert main(["plan", "--altitude", "40", "--dem", str(tmp_path / "missing.tif")]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1
    assert main(["plan", "--terrain-tolerance", "2"]) == 2


def test_everything_together_in_qgc_files(tmp_path, capsys):
    """Camera, sorties, terrain and crosshatch at once: each sortie's file in order."""
    dem = write_dem(tmp_path / "bump.tif", bump)
    out = tmp_path / "m.plan"
    args = ["-q", "plan", "--camera", "dji-phantom-4-pro", "--altitude", "60"]
    args += ["--front-overlap", "75", "--speed", "8", "--max-flight-time", "400"]
    args += ["--dem", str(dem), "--crosshatch", "--out", str(out), "--json"]
    assert main(args) == 0
    summaries = json.loads(capsys.readouterr().out)
    files = sorted(tmp_path.glob("m-*.plan"))
    assert len(files) == len(summaries) >= 2
    lanes = 0
    for path, summary in zip(files, summaries, strict=True):
        items = json.loads(path.read_text())["mission"]["items"]
        commands = [it["command"] for it in items]
        assert commands[0] == 178 and commands[-1] == 20  # speed first, return to launch last
        waypoints = [it for it in items if it["command"] == 16]
        assert {it["frame"] for it in waypoints} == {0}
        trig = [it["params"][0] for it in items if it["command"] == 206]
        n = summary["sortie"]["lanes"][1] - summary["sortie"]["lanes"][0] + 1
        assert trig == [pytest.approx(summary["camera"]["trigger_distance_m"]), 0] * n
        lanes += n
        assert summary["sortie"]["duration_s"] <= 400
    assert lanes == sum(p["n_transects"] for p in summaries[0]["crosshatch"])


def test_a_cameras_height_passes_the_checks_before_reading(tmp_path, capsys):
    """A .plan output and ``--dem`` are refused before reading without a height, but a
    camera with ``--gsd`` (no ``--altitude``) has one: its flying height."""
    dem = write_dem(tmp_path / "bump.tif", bump)
    out = tmp_path / "m.plan"
    args = ["-q", "plan", "--camera", "sony-rx1r-ii", "--gsd", "1.5", "--dem", str(dem)]
    assert main([*args, "--out", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["terrain"]["height_above_ground_m"] == pytest.approx(summary["altitude_m"])
    assert json.loads(out.read_text())["mission"]["globalPlanAltitudeMode"] == 3


def test_an_unreadable_dem_is_one_line_on_the_command_line(tmp_path):
    """rasterio logged 'GDAL signalled an error: ...' at INFO before boustro's error: two lines
    in a terminal (pytest's own log handlers hide it: a real process is run)."""
    import os
    import subprocess
    import sys

    import boustro

    src = os.path.dirname(os.path.dirname(boustro.__file__))
    env = {**os.environ, "PYTHONPATH": src}
    missing = str(tmp_path / "missing.tif")
    cmd = [sys.executable, "-m", "boustro", "plan", "--altitude", "40", "--dem", missing]
    done = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=tmp_path)
    assert done.returncode == 2 and done.stdout == ""
    (line,) = done.stderr.splitlines()
    assert line.startswith(f"boustro: error: --dem {missing}: ")
    assert os.listdir(tmp_path) == []
