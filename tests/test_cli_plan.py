"""`boustro plan`, tested in-process on exit code, output and the files it writes."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest

from boustro import geo
from boustro.cli import main
from boustro.io import embedded_field

from .conftest import run_cli

FAST = {"n_angles": 36, "n_offsets": 8}
SHIPPED = dict(geo.METHOD_OPTIONS.get(geo.DEFAULT_METHOD, {}))


@pytest.fixture(autouse=True)
def _fast_optimiser(monkeypatch):
    """A coarse grid keeps tests that ask for --method grid quick; one test runs the shipped
    default (the certified global optimiser, fast on its own)."""
    monkeypatch.setitem(geo.METHOD_OPTIONS, "grid", FAST)


run = run_cli


def _ring_text(kind: str) -> str:
    ring = embedded_field().ring.tolist()
    if kind == "wkt":
        return "POLYGON ((" + ", ".join(f"{x} {y}" for x, y in ring) + "))"
    if kind == "kml":
        return (
            '<kml xmlns="http://www.opengis.net/kml/2.2"><Placemark><name>k</name><Polygon>'
            "<outerBoundaryIs><LinearRing><coordinates>"
            + " ".join(f"{x},{y}" for x, y in ring)
            + "</coordinates></LinearRing></outerBoundaryIs></Polygon></Placemark></kml>"
        )
    if kind == "json":
        return json.dumps(ring)
    return json.dumps({"type": "Polygon", "coordinates": [[*ring, ring[0]]]})


def test_default_plans_the_embedded_field(capsys, tmp_path, monkeypatch):
    monkeypatch.setitem(geo.METHOD_OPTIONS, geo.DEFAULT_METHOD, SHIPPED)  # the shipped default
    out_file = tmp_path / "plan.geojson"
    code, out, err = run(capsys, "plan", "--out", out_file)
    assert code == 0, err
    assert "covered          100.0000% of the area" in out
    assert "test parcel" in out and "EPSG:32632" in out and "10 m" in out
    assert f"{out_file} (geojson)" in out
    doc = json.loads(out_file.read_text())
    assert doc["boustro"]["covered_share"] >= 1 - 1e-9
    assert doc["boustro"]["method"] == geo.DEFAULT_METHOD


@pytest.mark.parametrize("kind", ["geojson", "json", "kml", "wkt"])
def test_area_formats(capsys, tmp_path, kind):
    area = tmp_path / f"field.{kind}"
    area.write_text(_ring_text(kind))
    code, out, err = run(capsys, "plan", area, "--spacing", "12", "--json")
    assert code == 0, err
    summary = json.loads(out)
    assert summary["crs"] == "EPSG:4326" and summary["plan_crs"] == "EPSG:32632"
    assert summary["spacing_m"] == 12 and summary["covered_share"] >= 1 - 1e-9
    assert summary["n_transects"] >= 15


def test_every_output_format(capsys, tmp_path):
    for ext in ("geojson", "kml", "gpx", "csv", "plan", "waypoints"):
        out_file = tmp_path / f"m.{ext}"
        code, _, err = run(capsys, "plan", "--spacing", "15", "--altitude", "30", "--out", out_file)
        assert code == 0, err
        assert out_file.stat().st_size > 100
    code, _, err = run(capsys, "plan", "--out", tmp_path / "m.xyz", "--format", "gpx")
    assert code == 0, err
    assert (tmp_path / "m.xyz").read_text().lstrip().startswith("<?xml")


def test_sensors_and_statistics(capsys):
    code, out, err = run(
        capsys, "plan", "--camera", "13.2,8.8,5472", "--altitude", "80", "--overlap", "70",
        "--speed", "5", "--turn-time", "10", "--turnaround", "8", "--json",
    )  # fmt: skip
    assert code == 0, err
    s = json.loads(out)
    assert s["spacing_m"] == pytest.approx(36.0)
    assert s["altitude_m"] == 80 and "GSD 2.19 cm/px" in s["sensor"]
    assert s["n_turns"] == s["n_transects"] - 1
    assert s["duration_s"] == pytest.approx(s["path_length_m"] / 5 + s["n_turns"] * 10)
    assert s["turnaround_m"] == 8
    code, out, err = run(capsys, "plan", "--swath", "30", "--nadir-gap", "4", "--json")
    assert code == 0, err
    s = json.loads(out)
    assert s["spacing_m"] == pytest.approx(13.0) and s["nadir_gap_m"] == 4
    assert s["covered_share"] >= 1 - 1e-9
    code, out, err = run(capsys, "plan", "--camera", "13.2,8.8,5472", "--gsd", "2")
    assert code == 0, err
    assert "GSD 2.00 cm/px" in out


def test_start_corner(capsys):
    ring = embedded_field().ring
    east = ring[np.argmax(ring[:, 0])]
    west = ring[np.argmin(ring[:, 0])]
    firsts = []
    for corner in (east, west):
        code, out, err = run(capsys, "plan", "--start", f"{corner[0]},{corner[1]}", "--json")
        assert code == 0, err
        assert json.loads(out)["covered_share"] >= 1 - 1e-9
    # Through the API the same: the first waypoint lies on the side of the start point.
    for corner in (east, west):
        m = geo.plan_area(embedded_field(), 10.0, start=corner, method="grid", options=FAST)
        firsts.append(m.waypoints_lonlat[0, 0])
    assert firsts[0] > firsts[1]


def test_projected_crs(capsys, tmp_path):
    pyproj = pytest.importorskip("pyproj")
    ring = embedded_field().ring
    x, y = pyproj.Transformer.from_crs(4326, 28992, always_xy=True).transform(*ring.T)
    area = tmp_path / "rd.wkt"
    area.write_text("POLYGON ((" + ", ".join(f"{a} {b}" for a, b in zip(x, y, strict=True)) + "))")
    out_file = tmp_path / "rd.csv"
    code, out, err = run(
        capsys, "plan", area, "--crs", "EPSG:28992", "--spacing", "10", "--out", out_file
    )
    assert code == 0, err
    assert "EPSG:28992" in out
    header = out_file.read_text().splitlines()[0]
    assert header == "seq,kind,transect,x,y,lon,lat"


def test_plot(capsys, tmp_path):
    pytest.importorskip("matplotlib")
    png = tmp_path / "plan.png"
    code, _, err = run(capsys, "plan", "--turnaround", "5", "--plot", png)
    assert code == 0, err
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def _write(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    ("setup", "extra", "match"),
    [
        (None, ["missing.geojson", "--spacing", "10"], "no such file"),
        # QA: an empty file said "malformed JSON at line 1 column 1" (KML: "malformed XML")
        ("empty.geojson", ["--spacing", "10"], "the file is empty"),
        ("empty.kml", ["--spacing", "10"], "the file is empty"),
        ("bad.geojson", ["--spacing", "10"], "malformed JSON at line 1 column 2"),
        ("nopoly.geojson", ["--spacing", "10"], "holds no Polygon"),
        ("lat.json", ["--spacing", "10"], "latitude 95 at vertex 2 is outside"),
        ("anti.json", ["--spacing", "10"], "between vertex 1 (179.99) and vertex 2 (-179.99)"),
        ("pole.json", ["--spacing", "10"], "encloses the North Pole"),
        ("hole_out.wkt", ["--spacing", "10"], "hole 1 lies outside the shell"),
        ("cross.json", ["--spacing", "10"], "self-intersecting"),
        ("hole.wkt", ["--spacing", "10"], "hole 1 touches or crosses the shell"),
        ("ok.json", [], "give the spacing"),
        ("ok.json", ["--spacing", "10", "--crs", "EPSG:0"], "unknown coordinate reference"),
        ("ok.json", ["--spacing", "10", "--method", "annealing"], "unknown method"),
        ("ok.json", ["--spacing", "10", "--gsd", "2"], "--gsd needs --camera"),
        ("ok.json", ["--spacing", "10", "--out", "OUT.plan"], "needs a mission altitude"),
        ("ok.json", ["--spacing", "10", "--out", "OUT.shp"], "cannot tell the format"),
        # (a spacing wider than the area is one lane now: tests/test_outputs_finite.py)
        ("ok.json", ["--spacing", "1e-4", "--out", "OUT.geojson"], "is too small for an area"),
    ],
)
def test_bad_inputs_write_nothing(capsys, tmp_path, setup, extra, match):
    ring = [[6.0, 51.0], [6.01, 51.0], [6.01, 51.01], [6.0, 51.01]]
    files = {
        "empty.geojson": "",
        "empty.kml": " \n",
        "bad.geojson": "{not json",
        "nopoly.geojson": json.dumps({"type": "FeatureCollection", "features": []}),
        "lat.json": json.dumps([[6.0, 51.0], [6.01, 95.0], [6.0, 51.01]]),
        "anti.json": json.dumps([[179.99, 0], [-179.99, 0], [-179.99, 0.01], [179.99, 0.01]]),
        "pole.json": json.dumps([[0, 85], [90, 85], [180, 85], [-90, 85]]),
        # Issue 7: concave areas and holes are planned now; bad holes are refused.
        "hole_out.wkt": "POLYGON ((6 51, 6.1 51, 6.1 51.1, 6 51), (6.05 51.08, 6.06 51.08, "
        "6.06 51.09, 6.05 51.08))",
        "cross.json": json.dumps([[6.0, 51.0], [6.01, 51.01], [6.01, 51.0], [6.0, 51.01]]),
        "hole.wkt": "POLYGON ((6 51, 6.1 51, 6.1 51.1, 6 51), (6.05 50.99, 6.06 51.01, 6.06 51.02,"
        " 6.05 51.01))",
        "ok.json": json.dumps(ring),
    }
    args = list(extra)
    if setup is not None:
        args.insert(0, _write(tmp_path, setup, files[setup]))
    else:
        args[0] = tmp_path / args[0]
    args = [str(a).replace("OUT", str(tmp_path / "out")) for a in args]
    before = set(os.listdir(tmp_path))
    code, _, err = run(capsys, "plan", *args)
    assert code == 2
    assert err.startswith("boustro: error: ") and match in err
    assert len(err.strip().splitlines()) == 1
    assert set(os.listdir(tmp_path)) == before  # no file written, no temporary left


def test_argument_errors(capsys):
    for argv in (
        ["plan", "--spacing", "0"],
        ["plan", "--spacing", "nan"],
        ["plan", "--spacing", "10", "--camera", "1,2,3", "--altitude", "5"],
        ["plan", "--camera", "1,2"],
        ["plan", "--start", "1"],
        ["plan", "--overlap", "100", "--swath", "5"],
    ):
        with pytest.raises(SystemExit) as exc:
            main(argv)
        assert exc.value.code == 2
    capsys.readouterr()


def test_help_mentions_the_guarantee(capsys):
    with pytest.raises(SystemExit):
        main(["plan", "--help"])
    out = capsys.readouterr().out
    assert "no part of the area is left outside every swath" in out
    assert "QGC WPL 110" in out


def test_fewest_transects_objective_flies_fewer_lanes(capsys):
    counts = {}
    for objective in ("smith", "fewest-transects"):
        code, out, err = run(capsys, "plan", "--objective", objective, "--json")
        assert code == 0, err
        summary = json.loads(out)
        assert summary["covered_share"] >= 1 - 1e-9
        counts[objective] = summary["n_transects"]
    assert counts["fewest-transects"] <= counts["smith"]


def test_json_spells_the_objective_as_the_cli_takes_it(capsys, tmp_path):
    # --json said fewest_transects for a convex area (the closed form's name) and
    # fewest-transects for a concave one (the certified search's), where --objective takes
    # fewest-transects: both now print the CLI's spelling, which reads back as --objective;
    # the old spelling is still accepted.
    area = tmp_path / "l.wkt"
    area.write_text("POLYGON ((0 0, 60 0, 60 20, 20 20, 20 60, 0 60, 0 0))")
    for args in ([], [str(area), "--crs", "planar", "--spacing", "5"]):
        code, out, err = run(capsys, "plan", *args, "--objective", "fewest-transects", "--json")
        assert code == 0, err
        summary = json.loads(out)
        assert summary["objective"] == "fewest-transects"
        assert all(c["objective"] == "fewest-transects" for c in summary.get("cells", []))
        code, again, err = run(capsys, "plan", *args, "--objective", "fewest_transects", "--json")
        assert code == 0, err
        assert json.loads(again)["n_transects"] == summary["n_transects"]
    with pytest.raises(SystemExit) as exit_:
        main(["plan", "--objective", "fewest_lanes", "--json"])
    assert exit_.value.code == 2 and "invalid choice: 'fewest-lanes'" in capsys.readouterr().err


def test_sweep_that_changes_nothing_says_so(capsys, tmp_path):
    # --sweep without --decompose used to change nothing silently where the area is planned as
    # one grid; with --no-decompose it can change nothing: one error, nothing written.
    out_file = tmp_path / "m.geojson"
    code, out, err = run(capsys, "plan", "--sweep", "30", "--no-decompose", "--out", out_file)
    assert code == 2 and not out and not out_file.exists()
    assert err.count("\n") == 1 and "--no-decompose plans one grid" in err
    code, out, err = run(capsys, "plan", "--sweep", "30", "--json")  # the convex embedded field
    assert code == 0, err
    assert "--sweep 30 changed nothing" in err
    code, plain, _ = run(capsys, "plan", "--json")
    for key in ("angle_deg", "offset", "n_transects", "path_length_m"):
        assert json.loads(out)[key] == json.loads(plain)[key]
    area = tmp_path / "l.wkt"  # a concave area: the note in --json's notes
    area.write_text("POLYGON ((0 0, 60 0, 60 20, 20 20, 20 60, 0 60, 0 0))")
    code, out, err = run(capsys, "plan", area, "--crs", "planar", "--spacing", "5",
                         "--sweep", "0", "--json")  # fmt: skip
    assert code == 0, err
    summary = json.loads(out)
    changed = any("--sweep 0 changed nothing" in n for n in summary.get("notes", []))
    assert changed == (summary["n_cells"] == 1) and changed == ("--sweep 0 " in err)


@pytest.mark.parametrize(
    ("out", "match"),
    [("OUT.gpkg", "cannot tell the format"), ("OUT.plan", "needs a mission altitude")],
)
def test_unwritable_output_is_refused_before_reading(capsys, tmp_path, out, match):
    """QA round 15: ``--out x.gpkg`` (and a ``.plan`` without an altitude) was refused only
    after the area was read and planned (minutes on a large field). The area here does not
    exist: the output's error comes first."""
    out = out.replace("OUT", str(tmp_path / "out"))
    code, _, err = run(
        capsys, "plan", str(tmp_path / "missing.geojson"), "--spacing", "10", "--out", out
    )
    assert code == 2 and match in err and "no such file" not in err
    assert os.listdir(tmp_path) == []


def test_the_area_file_is_never_overwritten_by_the_mission(capsys, tmp_path, monkeypatch):
    """QA round 18: ``boustro plan field.geojson --out field.geojson`` replaced the user's
    field boundary by the mission; a field's own file name (``FILE-<name>.ext``) too."""
    monkeypatch.chdir(tmp_path)
    area = tmp_path / "field.geojson"
    ring = embedded_field().ring.tolist()
    doc = {"type": "Polygon", "coordinates": [[*ring, ring[0]]]}
    area.write_text(json.dumps(doc))
    before = area.read_bytes()
    for out in ("field.geojson", str(area), "./sub/../field.geojson"):
        (tmp_path / "sub").mkdir(exist_ok=True)
        code, _, err = run(capsys, "plan", "field.geojson", "--spacing", "10", "--out", out)
        assert code == 2 and "is the area file itself" in err, err
        assert area.read_bytes() == before
    two = {"type": "FeatureCollection", "features": []}
    for name in ("a", "b"):
        two["features"].append({"type": "Feature", "properties": {"name": name}, "geometry": doc})
    (tmp_path / "m-a.geojson").write_text(json.dumps(two))
    # two fields a and b, each its own .plan file m-a.geojson and m-b.geojson: the first the input
    argv = ["plan", "m-a.geojson", "--spacing", "10", "--altitude", "30", "--format", "plan"]
    code, _, err = run(capsys, *argv, "--out", "m.geojson")
    assert code == 2 and "--out m-a.geojson: is the area file itself" in err, err
    assert json.loads((tmp_path / "m-a.geojson").read_text()) == two
    assert not (tmp_path / "m-b.geojson").exists()  # nothing written
    code, _, err = run(capsys, *argv, "--out", "n.geojson")
    assert code == 0 and (tmp_path / "n-a.geojson").exists(), err


def test_altitude_formats_are_those_that_need_one():
    """``ALTITUDE_FORMATS`` (checked before planning) is exactly the formats whose renderer
    refuses a mission without an altitude."""
    from boustro.errors import InvalidParameterError
    from boustro.io.formats import FORMATS, render
    from boustro.io.formats._common import ALTITUDE_FORMATS
    from boustro.mission import plan_area

    mission = plan_area(embedded_field(), 10.0)
    assert mission.altitude is None
    refused = set()
    for fmt in FORMATS:
        try:
            render(mission, fmt)
        except InvalidParameterError as exc:
            assert ALTITUDE_FORMATS[fmt] in str(exc)
            refused.add(fmt)
    assert refused == set(ALTITUDE_FORMATS)


@pytest.mark.parametrize(
    ("extra", "match"),
    [
        (["--max-flight-time", "300"], "a maximum flight time needs the speed"),
        (["--dem", "DIR/none.tif", "--altitude", "30"], "--dem DIR/none.tif"),
        (["--dem", "DIR/none.tif"], "--dem needs the height above ground"),
        (["--terrain-tolerance", "2"], "--terrain-tolerance needs --dem"),
        (["--turn-time", "10"], "--turn-time needs --speed"),  # QA round 18: was ignored
    ],
)
def test_flight_option_errors_come_before_reading(capsys, tmp_path, extra, match):
    """QA round 15: ``--max-flight-time`` without ``--speed`` and an unreadable ``--dem`` (or
    one without a height) were refused only after the area was read and planned."""
    extra = [a.replace("DIR", str(tmp_path)) for a in extra]
    match = match.replace("DIR", str(tmp_path))
    missing = str(tmp_path / "missing.geojson")
    code, _, err = run(capsys, "plan", missing, "--spacing", "10", *extra)
    assert code == 2 and match in err and "no such file" not in err.split(match)[0]
