"""Every number in every export is finite, or nothing is written.

An area narrower than the spacing in every direction (a lake smaller than a sonar swath), convex
or not, is planned as one lane along its diameter: Eq. 1 needs two transects, so its fitness is
undefined and reported as ``null``. Any mission holding a non-finite number is refused by
:func:`boustro.io.formats.registry.render` before rendering.
"""

from __future__ import annotations

import csv
import dataclasses
import json
import math

import numpy as np
import pytest

from boustro.errors import InvalidParameterError
from boustro.io import embedded_field
from boustro.io.formats.registry import FORMATS, check_finite, render, write_mission
from boustro.mission import plan_area

from .conftest import run_cli

EXTENSIONS = {"geojson": ".geojson", "kml": ".kml", "gpx": ".gpx", "csv": ".csv"}
EXTENSIONS.update(plan=".plan", wpl=".waypoints")


def _strict_json(text: str):
    def refuse(token: str):
        raise AssertionError(f"non-standard JSON constant {token}")

    return json.loads(text, parse_constant=refuse)


def _read_back(path, fmt: str) -> int:
    """Read the file with its real reader; the number of waypoints/points found."""
    if fmt == "geojson":
        pyogrio = pytest.importorskip("pyogrio")
        _strict_json(path.read_text())
        _, _, geometry, _ = pyogrio.raw.read(path)
        return len(geometry)
    if fmt == "kml":
        kml = pytest.importorskip("fastkml.kml")
        doc = next(iter(kml.KML.from_string(path.read_bytes()).features))
        return len([f for f in doc.features if hasattr(f, "geometry")])
    if fmt == "gpx":
        gpxpy = pytest.importorskip("gpxpy")
        (route,) = gpxpy.parse(path.read_text()).routes
        return len(route.points)
    if fmt == "csv":
        with open(path, newline="") as fh:
            rows = list(csv.DictReader(fh))
        assert all(math.isfinite(float(r["lon"])) and math.isfinite(float(r["lat"])) for r in rows)
        return len(rows)
    if fmt == "plan":
        return len(_strict_json(path.read_text())["mission"]["items"])
    mavwp = pytest.importorskip("pymavlink.mavwp")
    return mavwp.MAVWPLoader().load(str(path))


@pytest.mark.parametrize("fmt", sorted(EXTENSIONS))
def test_a_spacing_wider_than_the_area_writes_a_valid_file(capsys, tmp_path, fmt):
    """The defect of issue 20: a NaN fitness made the GeoJSON writer crash (exit 1)."""
    out = tmp_path / f"x{EXTENSIONS[fmt]}"
    argv = ["plan", "--spacing", "500", "--decompose", "--altitude", "30", "--out", out]
    code, _, err = run_cli(capsys, *argv, "--format", fmt)
    assert code == 0, err
    assert _read_back(out, fmt) >= 2
    code, text, err = run_cli(capsys, *argv[:-2], "--json")
    summary = _strict_json(text)
    assert summary["n_transects"] == 1 and summary["fitness"] is None
    assert summary["covered_share"] == pytest.approx(1.0)


def test_a_concave_lake_narrower_than_the_swath_is_one_lane(capsys, tmp_path):
    """No --decompose: a concave area goes to the region planner by itself."""
    lake = tmp_path / "lake.json"
    ring = [[0, 0], [60, 0], [60, 50], [30, 10], [0, 50]]  # a deep V: concave
    lake.write_text(json.dumps(ring))
    out = tmp_path / "lake.geojson"
    code, text, err = run_cli(
        capsys, "plan", lake, "--crs", "EPSG:28992", "--swath", "120", "--out", out, "--json"
    )
    assert code == 0, err
    summary = _strict_json(text)
    assert summary["n_transects"] == 1 and summary["fitness"] is None
    assert summary["covered_share"] == pytest.approx(1.0)
    assert len(_strict_json(out.read_text())["features"]) >= 3


def test_any_area_narrower_than_the_spacing_is_one_lane(capsys, tmp_path):
    """The embedded field is nearly convex (planned on its hull at a usual spacing): at 500 m
    it is planned as the same single lane as with --decompose, over the area itself."""
    runs = [
        run_cli(capsys, "plan", "--spacing", "500", "--json", *extra)
        for extra in ([], ["--decompose"])
    ]
    assert all(code == 0 for code, _, _ in runs), runs
    plain, decomposed = (_strict_json(out) for _, out, _ in runs)
    assert plain == decomposed
    assert plain["n_transects"] == 1 and plain["hull_depth_m"] == 0.0
    square = tmp_path / "square.json"
    square.write_text(json.dumps([[0, 0], [100, 0], [100, 50], [0, 50]]))
    code, out, err = run_cli(
        capsys,
        "plan",
        square,
        "--crs",
        "planar",
        "--spacing",
        "112",
        "--method",
        "gradient",
        "--json",
    )
    assert code == 0, err
    summary = _strict_json(out)
    assert summary["n_transects"] == 1 and summary["fitness"] is None
    assert summary["covered_share"] == pytest.approx(1.0)
    assert summary["angle_deg"] == pytest.approx(math.degrees(math.atan2(50, 100)))


@pytest.fixture(scope="module")
def mission():
    return plan_area(embedded_field(), 25.0, altitude=30.0)


@pytest.mark.parametrize(
    "field", ["waypoints", "transects_lonlat", "home_lonlat", "summary", "area_ring"]
)
def test_a_non_finite_number_is_refused_before_anything_is_written(tmp_path, mission, field):
    if field == "summary":
        optimum = dataclasses.replace(mission.optimum, fitness=math.inf)
        bad = dataclasses.replace(mission, optimum=optimum)
    elif field == "area_ring":
        ring = mission.area.ring.copy()
        ring[3, 1] = np.nan
        bad = dataclasses.replace(mission, area=dataclasses.replace(mission.area, ring=ring))
    else:
        values = np.array(getattr(mission, field), dtype=float)
        values.reshape(-1)[-1] = np.nan
        bad = dataclasses.replace(mission, **{field: values})
    check_finite(mission)  # the unchanged mission passes
    for fmt in FORMATS:
        with pytest.raises(InvalidParameterError, match=f"cannot write {fmt}: mission.* finite"):
            render(bad, fmt)
        path = tmp_path / f"x{EXTENSIONS.get(fmt, '.out')}"
        with pytest.raises(InvalidParameterError, match="nothing written"):
            write_mission(bad, path, fmt)
        assert not path.exists()
