"""``boustro batch`` / ``boustro.batch``: a few hundred generated fields in a GeoPackage, every
one planned (equal to a single ``plan_area`` call) or reported; a run killed half-way and
resumed; a Dask LocalCluster equal to the local run; bad features as error rows; the geo-stack
entry ``boustro.plan_area`` and the GeoDataFrame helpers."""

from __future__ import annotations

import dataclasses
import json
import os
import sqlite3
import subprocess
import sys
import time
import warnings
from pathlib import Path

import distributed
import geopandas
import numpy as np
import pyogrio
import pyogrio.raw
import pytest
import shapely

import boustro
from boustro.batch import PlanOptions, read_plans, read_source
from boustro.batch.gpkg import Store
from boustro.cli import main
from boustro.errors import InvalidParameterError, PolygonFileError
from boustro.io import Area
from boustro.mission import plan_area
from boustro.sensors import Camera
from boustro.vehicle import Vehicle

SRC = Path(__file__).resolve().parents[1] / "src"
CRS = "EPSG:28992"  # Amersfoort / RD New, metres
N_GOOD = 240
BAD_NAMES = ["bow-tie", "point", "line", "empty", "null", "bad-spacing"]


def _convex(rng: np.random.Generator) -> shapely.Polygon:
    cx, cy = 150_000 + rng.uniform(0, 20_000, 2)
    r = rng.uniform(40, 150)
    angles = np.sort(rng.uniform(0, 2 * np.pi, int(rng.integers(4, 9))))
    pts = np.c_[cx + r * np.cos(angles), 450_000 + cy - 150_000 + r * np.sin(angles)]
    return shapely.Polygon(pts).convex_hull


def _write(
    path: Path, geoms: list, names: list, spacing: list, crs: str | None = CRS, driver="GPKG"
) -> None:
    wkb = np.array([None if g is None else shapely.to_wkb(g) for g in geoms], dtype=object)
    pyogrio.raw.write(
        str(path), wkb, [np.array(names, dtype=object), np.array(spacing, dtype=float)],
        ["name", "sp"], crs=crs, geometry_type="Polygon" if driver != "GPKG" else "Unknown",
        driver=driver,
    )  # fmt: skip


@pytest.fixture(scope="module")
def fields(tmp_path_factory) -> Path:
    """240 random convex fields (10-150 m radius, per-field spacing 8-20 m in column ``sp``),
    two concave ones and the bad features of BAD_NAMES, in a GeoPackage."""
    rng = np.random.default_rng(7)
    geoms = [_convex(rng) for _ in range(N_GOOD)]
    geoms += [
        shapely.Polygon([(0, 0), (300, 0), (300, 100), (100, 100), (100, 300), (0, 300)]),
        shapely.box(0, 0, 200, 200).difference(shapely.box(80, 80, 120, 120)),
    ]
    geoms = [shapely.affinity.translate(g, 170_000, 460_000) if i >= N_GOOD else g
             for i, g in enumerate(geoms)]  # fmt: skip
    names = [f"field {i}" for i in range(len(geoms))]
    spacing = list(rng.choice([8.0, 10.0, 15.0, 20.0], len(geoms)))
    geoms += [
        shapely.Polygon([(0, 0), (10, 10), (10, 0), (0, 10)]),
        shapely.Point(150_000, 450_000),
        shapely.LineString([(150_000, 450_000), (150_100, 450_000)]),
        shapely.Polygon(),
        None,
        _convex(rng),
    ]
    names += BAD_NAMES
    spacing += [10.0] * 5 + [-3.0]
    path = tmp_path_factory.mktemp("batch") / "fields.gpkg"
    _write(path, geoms, names, spacing)
    return path


def _layer(path, layer: str) -> dict:
    meta, _, wkb, data = pyogrio.raw.read(str(path), layer=layer)
    out = {str(k): v for k, v in zip(meta["fields"], data, strict=True)}
    out["geometry"] = wkb
    return out


def _check(rows: dict, lane_ids, path_ids) -> None:
    """Every field has one row and its lanes and paths: none twice, no lane without its row."""
    ids = list(rows["field_id"])
    assert len(ids) == len(set(ids)), "a field planned twice"
    counts = dict(zip(*np.unique(np.asarray(lane_ids, dtype=int), return_counts=True),
                      strict=True))  # fmt: skip
    for fid, status, n in zip(ids, rows["status"], rows["segments"], strict=True):
        assert counts.get(fid, 0) == (int(n) if status == "ok" else 0)
    assert set(counts) <= set(ids)
    assert sorted(path_ids) == sorted(
        f for f, s, p in zip(ids, rows["status"], rows["parts"], strict=True) if s == "ok"
        for _ in range(int(p))
    )  # fmt: skip


def _consistent(path) -> dict:
    """The output's ``fields`` layer, read by GDAL, after :func:`_check` (not while a run
    writes: the three layers are read one after the other)."""
    rows, lanes, paths = (_layer(path, n) for n in ("fields", "lanes", "paths"))
    _check(rows, lanes["field_id"], paths["field_id"])
    return rows


def _snapshot(path) -> int:
    """While a run writes: every layer readable by GDAL, and one SQLite read transaction (a
    snapshot of the last commit) checked by :func:`_check`; the number of fields done."""
    for layer in ("fields", "lanes", "paths"):
        _layer(path, layer)
    db = sqlite3.connect(path)
    try:
        db.execute("BEGIN")
        found = db.execute("SELECT field_id, status, segments, parts FROM fields").fetchall()
        lane_ids = [r[0] for r in db.execute("SELECT field_id FROM lanes")]
        path_ids = [r[0] for r in db.execute("SELECT field_id FROM paths")]
        db.execute("COMMIT")
    finally:
        db.close()
    keys = ("field_id", "status", "segments", "parts")
    rows = {k: [r[i] for r in found] for i, k in enumerate(keys)}
    rows["segments"] = [-1 if v is None else v for v in rows["segments"]]
    _check(rows, lane_ids, path_ids)
    return len(found)


@pytest.fixture(scope="module")
def planned(fields, tmp_path_factory) -> tuple[Path, boustro.batch.BatchResult]:
    out = tmp_path_factory.mktemp("plans") / "plans.gpkg"
    result = boustro.batch(fields, out, spacing=10.0, columns={"spacing": "sp"}, workers=2)
    return out, result


def test_every_field_planned_or_reported(fields, planned):
    out, result = planned
    total = N_GOOD + 2 + len(BAD_NAMES)
    assert (result.total, result.planned, result.failed, result.skipped) == (
        total, N_GOOD + 2, len(BAD_NAMES), 0,
    )  # fmt: skip
    rows = _consistent(out)
    assert sorted(rows["field_id"]) == list(range(1, total + 1))
    status = dict(zip(rows["name"], rows["status"], strict=True))
    assert [n for n, s in status.items() if s == "error"] == BAD_NAMES or set(
        n for n, s in status.items() if s == "error"
    ) == set(BAD_NAMES)
    errors = dict(zip(rows["name"], rows["error"], strict=True))
    assert "Self-intersection" in errors["bow-tie"]
    assert errors["point"] == "not a polygon: a Point"
    assert errors["line"] == "not a polygon: a LineString"
    assert errors["empty"] == "empty geometry (Polygon)"
    assert errors["null"] == "no geometry (null)"
    assert "column 'sp' (spacing): expected a number > 0, got -3.0" in errors["bad-spacing"]
    assert all("\n" not in e for e in errors.values() if e)
    assert pyogrio.read_info(str(out), layer="lanes")["crs"] == CRS


@pytest.fixture()
def one_thread():
    """One torch thread, as in a worker (small fields plan several times faster so)."""
    import torch

    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)


def test_results_equal_single_plan_area_calls(fields, planned, one_thread):
    out, _ = planned
    rows, lanes = _layer(out, "fields"), _layer(out, "lanes")
    source = read_source(fields, columns=["sp"])
    by_id = {f.field_id: f for f in source.features}
    checked = 0
    for i, fid in enumerate(rows["field_id"]):
        if rows["status"][i] != "ok":
            continue
        feature = by_id[fid]
        poly = shapely.from_wkb(feature.wkb)
        area = Area(np.asarray(poly.exterior.coords)[:-1], CRS, feature.name, "test",
                    tuple(np.asarray(h.coords)[:-1] for h in poly.interiors))  # fmt: skip
        mission = plan_area(area, float(feature.values["sp"]))
        mine = [shapely.from_wkb(w) for w, f in zip(lanes["geometry"], lanes["field_id"],
                                                     strict=True) if f == fid]  # fmt: skip
        assert len(mine) == len(mission.transects) == rows["segments"][i]
        assert rows["lanes"][i] == mission.stats.n_transects
        got = np.array([np.asarray(line.coords) for line in mine])
        np.testing.assert_array_equal(got, mission.transects)  # float64 through the file
        assert rows["path_length_m"][i] == mission.stats.path_length
        assert rows["turns"][i] == mission.stats.n_turns
        assert rows["covered_share"][i] == mission.coverage.covered_share
        assert rows["method"][i] == mission.optimum.method
        checked += 1
    assert checked == N_GOOD + 2


def test_resume_skips_everything_done(fields, planned, tmp_path):
    out, _ = planned
    copy = tmp_path / "copy.gpkg"
    copy.write_bytes(out.read_bytes())
    again = boustro.batch(fields, copy, spacing=10.0, columns={"spacing": "sp"}, workers=2)
    assert (again.planned, again.failed, again.skipped) == (0, 0, again.total)
    with pytest.raises(InvalidParameterError, match=r"other settings \(options differ\)"):
        boustro.batch(fields, copy, spacing=12.0, columns={"spacing": "sp"}, workers=2)


def _subprocess_batch(fields: Path, out: Path) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    cmd = [
        sys.executable,
        "-m",
        "boustro",
        "-q",
        "batch",
        str(fields),
        "--out",
        str(out),
        "--spacing",
        "10",
        "--spacing-column",
        "sp",
        "--workers",
        "2",
        "--chunk-size",
        "2",
    ]
    return subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE)


def test_killed_half_way_and_resumed(fields, planned, tmp_path):
    out = tmp_path / "plans.gpkg"
    proc = _subprocess_batch(fields, out)
    total = N_GOOD + 2 + len(BAD_NAMES)
    seen, reads = 0, 0
    deadline = time.monotonic() + 120
    try:
        # killed at the first commit seen: a batch whose workers no longer import torch wrote
        # all 248 rows between two reads when it waited for a third of them (CI, 2026-11-28)
        while seen < 1 and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.02)
            if out.exists() and os.path.getsize(out) > 0:
                seen = _snapshot(out)  # readable and whole, mid-run (created whole)
                reads += 1
    finally:
        proc.kill()  # a crash: no clean-up at all
        proc.wait()
    assert proc.returncode != 0, "the run ended before it could be killed"
    assert reads >= 1 and 0 < seen < total
    before = _consistent(out)  # the last commit, after the kill
    # the same command, resumed through the API (its fork server is already up: quicker)
    resumed = boustro.batch(fields, out, spacing=10.0, columns={"spacing": "sp"}, workers=2,
                            chunk_size=2)  # fmt: skip
    rows = _consistent(out)
    assert sorted(rows["field_id"]) == list(range(1, total + 1))  # none lost, none twice
    assert resumed.skipped == len(before["field_id"]) >= seen
    assert resumed.planned + resumed.failed == total - resumed.skipped
    assert list(rows["status"]).count("error") == len(BAD_NAMES)


def test_local_cluster_equals_local_run(fields, planned, tmp_path):
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        small = tmp_path / "small.gpkg"  # the command line's --scheduler ADDRESS too
        _write(small, [shapely.box(0, 0, 100, 50), shapely.box(0, 0, 40, 40)], ["a", "b"],
               [10.0, 10.0])  # fmt: skip
        argv = ["-q", "batch", str(small), "--out", str(tmp_path / "cli.gpkg"), "--spacing",
                "10", "--scheduler", cluster.scheduler_address]  # fmt: skip
        assert main(argv) == 0
        assert _layer(tmp_path / "cli.gpkg", "fields")["status"].tolist() == ["ok", "ok"]
        out = tmp_path / "dask.gpkg"
        result = boustro.batch(fields, out, spacing=10.0, columns={"spacing": "sp"},
                               client=client, chunk_size=16)  # fmt: skip
    assert (result.planned, result.failed) == (N_GOOD + 2, len(BAD_NAMES))
    for layer in ("lanes", "paths", "fields"):
        mine, theirs = _layer(out, layer), _layer(planned[0], layer)
        order_a, order_b = (
            np.argsort(mine["field_id"], kind="stable"),
            np.argsort(theirs["field_id"], kind="stable"),
        )
        assert set(mine) == set(theirs)
        for key in set(mine) - {"seconds", "cpu_seconds"}:  # the times differ, nothing else
            a, b = mine[key][order_a], theirs[key][order_b]
            same = np.array_equal(a, b, equal_nan=a.dtype.kind == "f")
            assert same, f"{layer}.{key} differs"


@pytest.mark.parametrize("suffix", [".gpkg", ".shp"])
def test_no_crs_layer_gives_error_rows_unless_crs_given(tmp_path, suffix):
    path = tmp_path / f"nocrs{suffix}"  # GDAL's "Undefined SRS"; a Shapefile without .prj
    with pytest.warns(UserWarning, match="'crs' was not provided"):
        _write(
            path,
            [shapely.box(0, 0, 100, 50), shapely.box(0, 0, 40, 40)],
            ["a", "b"],
            [10.0, 10.0],
            crs=None,
            driver="GPKG" if suffix == ".gpkg" else "ESRI Shapefile",
        )
    result = boustro.batch(path, tmp_path / "out.gpkg", spacing=10.0, workers=1)
    rows = _layer(tmp_path / "out.gpkg", "fields")
    assert (result.planned, result.failed) == (0, 2)
    assert all(e.startswith("the layer has no CRS: give it with --crs") for e in rows["error"])
    ok = boustro.batch(path, tmp_path / "planar.gpkg", spacing=10.0, crs="planar", workers=1)
    assert (ok.planned, ok.failed) == (2, 0)
    planar = [
        plan_area(shapely.box(0, 0, 100, 50), 10.0),
        plan_area(shapely.box(0, 0, 40, 40), 10.0),
    ]
    got = _layer(tmp_path / "planar.gpkg", "fields")["lanes"].tolist()
    assert got == [m.stats.n_transects for m in planar]


def test_a_failing_worker_loses_nothing(fields, tmp_path, monkeypatch):
    from boustro.batch import run as run_module

    def broken(chunks, job, count):
        for chunk in chunks:
            yield chunk, RuntimeError("worker lost\nwith two lines")

    monkeypatch.setattr(run_module, "run_local", broken)
    out = tmp_path / "lost.gpkg"
    result = boustro.batch(fields, out, spacing=10.0, columns={"spacing": "sp"}, workers=2)
    rows = _layer(out, "fields")
    assert result.failed == result.total == len(rows["field_id"])
    assert set(rows["error"]) == {
        "the worker planning it failed: RuntimeError: worker lost with two lines"
    }


def test_a_shapefile_output_says_its_renamed_columns_once(tmp_path, caplog):
    # GDAL cuts a Shapefile's column names to 10 characters; pyogrio said so in ten
    # RuntimeWarnings echoing its own source line, even with -q.
    small = tmp_path / "small.gpkg"
    _write(small, [shapely.box(0, 0, 100, 50)], ["a"], [10.0])
    out = tmp_path / "plans.shp"
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a warning that escapes fails the test
        result = boustro.batch(small, out, spacing=10.0, workers=1)
    assert (result.planned, result.failed) == (1, 0)
    said = [r.getMessage() for r in caplog.records if "renamed columns" in r.getMessage()]
    assert len(said) == 1 and "'transect_length_m' to 'transect_l'" in said[0]
    assert str(tmp_path / "plans.fields.shp") in said[0]
    assert "transect_l" in pyogrio.read_info(str(tmp_path / "plans.fields.shp"))["fields"]


def test_a_missing_missions_folder_is_made_and_a_file_refused(tmp_path, capsys):
    # ``--missions DIR`` refused a DIR that did not exist yet ("no such folder").
    small = tmp_path / "small.gpkg"
    _write(small, [shapely.box(0, 0, 100, 50)], ["a"], [10.0])
    folder = tmp_path / "new" / "missions"
    code = main(["batch", str(small), "--out", str(tmp_path / "o.gpkg"), "--spacing", "10",
                 "--workers", "1", "--missions", str(folder), "-q"])  # fmt: skip
    assert code == 0, capsys.readouterr().err
    assert sorted(p.name for p in folder.iterdir()) == ["1-a.geojson"]
    a_file = tmp_path / "a_file"
    a_file.write_text("x")
    with pytest.raises(InvalidParameterError, match="a file, not a folder"):
        boustro.batch(small, tmp_path / "p.gpkg", spacing=10.0, workers=1, missions=a_file)
    assert a_file.read_text() == "x" and not (tmp_path / "p.gpkg").exists()


def test_the_other_warnings_of_an_output_are_passed_on():
    from boustro.batch.export import _say_renamed

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        warnings.warn("Normalized/laundered field name: 'long_name' to 'long_nam'", stacklevel=1)
        warnings.warn("GDAL says something else", RuntimeWarning, stacklevel=1)
    with warnings.catch_warnings(record=True) as passed:
        warnings.simplefilter("always")
        _say_renamed("x.shp", caught)
    assert [str(w.message) for w in passed] == ["GDAL says something else"]


def test_cli_batch_missions_and_other_formats(fields, tmp_path, capsys):
    small = tmp_path / "small.gpkg"
    rng = np.random.default_rng(1)
    _write(small, [_convex(rng) for _ in range(3)], ["a", "b/c", "d"], [10.0, 12.0, 15.0])
    missions = tmp_path / "missions"
    missions.mkdir()
    argv = ["-q", "batch", str(small), "--out", str(tmp_path / "plans.fgb"), "--spacing-column",
            "sp", "--missions", str(missions), "--mission-format", "plan", "--altitude", "40",
            "--workers", "1", "--json"]  # fmt: skip
    assert main(argv) == 0
    summary = json.loads(capsys.readouterr().out)
    assert (summary["planned"], summary["failed"]) == (3, 0)
    for layer in ("lanes", "paths", "fields"):
        assert pyogrio.read_info(str(tmp_path / f"plans.{layer}.fgb"))["features"] > 0
    files = sorted(p.name for p in missions.iterdir())
    assert files == ["1-a.plan", "2-b_c.plan", "3-d.plan"]
    plan = json.loads((missions / "1-a.plan").read_text())
    assert plan["fileType"] == "Plan"
    rows = _layer(tmp_path / "plans.fields.fgb", "plans.fields")
    assert sorted(rows["mission"]) == files


def test_cli_a_directory_of_fields_is_one_line_saying_so(tmp_path, capsys):
    # QA: `boustro batch folder/` said "folder: no such file" of a folder that exists
    folder = tmp_path / "fields"
    folder.mkdir()
    _write(folder / "a.gpkg", [shapely.box(0, 0, 100, 100)], ["a"], [10.0])
    assert main(["batch", str(folder), "--out", str(tmp_path / "o.gpkg"), "--spacing", "10"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "is a directory, not a vector file" in err, err
    assert "no such file" not in err and not (tmp_path / "o.gpkg").exists()


def test_cli_a_file_of_several_layers_needs_layer(tmp_path, capsys):
    # QA round 19: `plan` read every layer of a GeoPackage, `batch` the first one silently
    two = tmp_path / "two.gpkg"
    for layer, x in (("north", 0), ("south", 1000)):
        wkb = np.array([shapely.to_wkb(shapely.box(x, 0, x + 100, 100))], dtype=object)
        pyogrio.raw.write(str(two), wkb, [np.array([layer], dtype=object)], ["name"],
                          crs=CRS, geometry_type="Polygon", driver="GPKG", layer=layer,
                          append=layer == "south")  # fmt: skip
    out = tmp_path / "o.gpkg"
    assert main(["batch", str(two), "--out", str(out), "--spacing", "10"]) == 2
    err = capsys.readouterr().err
    assert err == (
        f"boustro: error: {two}: 2 layers with geometries (north, south): give one with "
        "--layer, or plan each in its own batch\n"
    )
    assert not out.exists()
    assert main(["-q", "batch", str(two), "--out", str(out), "--spacing", "10",
                 "--layer", "south"]) == 0  # fmt: skip
    assert _layer(out, "fields")["name"].tolist() == ["south"]


def test_cli_bad_input_is_one_line(tmp_path, capsys):
    assert main(["batch", str(tmp_path / "missing.gpkg"), "--out", str(tmp_path / "o.gpkg"),
                 "--spacing", "10"]) == 2  # fmt: skip
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no such file" in err
    assert not (tmp_path / "o.gpkg").exists()
    not_ours = tmp_path / "other.gpkg"
    _write(not_ours, [shapely.box(0, 0, 1, 1)], ["x"], [1.0])
    assert main(["batch", str(not_ours), "--out", str(not_ours), "--spacing", "10"]) == 2
    assert "not the output of a boustro batch" in capsys.readouterr().err
    assert main(["batch", str(not_ours), "--out", str(tmp_path / "o.xyz"), "--spacing", "1"]) == 2
    assert "Could not infer driver" in capsys.readouterr().err
    assert main(["batch", str(not_ours), "--out", str(tmp_path / "o.gpkg")]) == 2
    assert "give the spacing" in capsys.readouterr().err
    assert main(["batch", str(not_ours), "--out", str(tmp_path / "o.gpkg"), "--spacing", "1",
                 "--sweep", "30", "--no-decompose"]) == 2  # fmt: skip
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--no-decompose plans one grid" in err
    assert not (tmp_path / "o.gpkg").exists()


def test_store_is_valid_between_commits(tmp_path):
    """A reader during a write transaction sees the last commit (WAL)."""
    path = str(tmp_path / "s.gpkg")
    store = Store(path, CRS, {"x": 1})
    blob = None
    store.append({"fields": [(blob, 1, "a", "ok", *[None] * 20)]})
    store.db.execute("BEGIN IMMEDIATE")
    store.db.execute("INSERT INTO fields (field_id, name) VALUES (2, 'b')")
    assert _layer(path, "fields")["field_id"].tolist() == [1]
    store.db.execute("ROLLBACK")
    store.close()
    assert sqlite3.connect(path).execute("PRAGMA journal_mode").fetchone()[0] == "delete"


def test_plan_area_for_the_geo_stack():
    box = shapely.box(0, 0, 120, 80)
    plan = boustro.plan_area(box, 10.0)
    single = plan_area(box, 10.0)
    np.testing.assert_array_equal(
        np.array([line.coords for line in plan.lanes.geoms]), single.transects
    )
    assert plan.path.equals(shapely.LineString(single.waypoints))
    assert shapely.geometry.shape(plan.lanes).equals(plan.lanes)  # __geo_interface__ round trip
    multi = shapely.MultiPolygon([box, shapely.box(500, 0, 560, 60)])
    both = boustro.plan_area(multi, 10.0)
    assert len(both.missions) == 2 and both.path.geom_type == "MultiLineString"
    same = boustro.plan_area(shapely.geometry.mapping(multi), 10.0)
    assert same.lanes.equals(both.lanes)
    doc = both.__geo_interface__
    kinds = [f["properties"]["kind"] for f in doc["features"]]
    assert kinds.count("path") == 2 and kinds.count("lane") == len(both.lanes.geoms)
    with pytest.raises(boustro.InvalidPolygonError, match="Self-intersection"):
        boustro.plan_area(shapely.Polygon([(0, 0), (10, 10), (10, 0), (0, 10)]), 1.0)
    with pytest.raises(PolygonFileError):
        boustro.plan_area(shapely.Point(0, 0), 1.0)
    with pytest.raises(PolygonFileError, match=r"\(N, 2\) ring .* boustro.mission.plan_area"):
        boustro.plan_area(np.array([(0, 0), (10, 0), (10, 10)]), 1.0)


def test_geodataframes_in_and_out(tmp_path):
    frame = geopandas.GeoDataFrame(
        {"name": ["a", "b"], "sp": [10.0, 20.0]},
        geometry=[shapely.box(0, 0, 100, 50), shapely.box(0, 0, 60, 60)],
        crs=CRS,
    )
    out = tmp_path / "frame.gpkg"
    result = boustro.batch(frame, out, spacing=10.0, columns={"spacing": "sp"}, workers=1)
    assert (result.planned, result.failed) == (2, 0)
    plans = read_plans(out)
    assert set(plans) == {"lanes", "paths", "fields"}
    assert plans["fields"]["name"].tolist() == ["a", "b"]
    assert plans["lanes"].crs.to_epsg() == 28992
    assert len(plans["lanes"]) == int(plans["fields"]["segments"].sum())
    from_plan = geopandas.GeoDataFrame.from_features(boustro.plan_area(frame.geometry[0], 10.0))
    assert len(from_plan) == plans["fields"]["lanes"][0] + 1  # lanes and the path
    no_crs = frame.set_crs(None, allow_override=True)
    bare = boustro.batch(no_crs, tmp_path / "bare.gpkg", spacing=10.0, workers=1)
    assert bare.failed == 2


def test_options_checked_before_any_work():
    with pytest.raises(InvalidParameterError, match="no per-field column for colour"):
        PlanOptions(spacing=1.0, columns={"colour": "c"})
    with pytest.raises(InvalidParameterError):
        PlanOptions(spacing=1.0, objective="nonsense")
    assert PlanOptions(columns={"spacing": "sp"}).for_field({"sp": 4}).spacing_arg() == 4.0


def test_import_boustro_stays_light():
    code = (
        "import sys, boustro; bad = [m for m in ('shapely', 'pyproj', 'boustro.batch', "
        "'boustro.io', 'boustro.mission', 'distributed', 'geopandas') if m in sys.modules]; "
        "print(','.join(bad)); print(callable(boustro.batch), boustro.plan_area.__module__)"
    )
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert done.stdout.splitlines() == ["", "True boustro.batch.geo"]


@dataclasses.dataclass(frozen=True)
class _Killer(PlanOptions):
    """Options whose field with spacing 13 kills its worker process (an out-of-memory kill)."""

    def for_field(self, values):
        if values.get("sp") == 13.0:
            os._exit(3)
        return super().for_field(values)


def test_a_field_that_kills_its_worker_is_its_own_error_row(tmp_path):
    path = tmp_path / "killer.gpkg"
    rng = np.random.default_rng(5)
    spacing = [10.0] * 12
    spacing[5] = 13.0
    _write(path, [_convex(rng) for _ in range(12)], [f"f{i}" for i in range(12)], spacing)
    out = tmp_path / "out.gpkg"
    options = _Killer(spacing=10.0, columns={"spacing": "sp"})
    result = boustro.batch(path, out, options, workers=2, chunk_size=4)
    rows = _consistent(out)
    assert (result.planned, result.failed) == (11, 1)
    error = dict(zip(rows["name"], rows["error"], strict=True))["f5"]
    assert error.startswith("the worker planning it failed: BrokenProcessPool")


def test_multipolygon_feature_is_planned_part_by_part_with_a_progress_bar(tmp_path, capsys):
    path = tmp_path / "multi.gpkg"
    multi = shapely.MultiPolygon([shapely.box(0, 0, 100, 60), shapely.box(300, 0, 380, 80)])
    _write(path, [multi], ["two parts"], [10.0])
    out = tmp_path / "out.gpkg"
    result = boustro.batch(path, out, spacing=10.0, workers=1, progress=True)
    assert result.planned == 1 and "field/s" in capsys.readouterr().err
    rows, paths = _consistent(out), _layer(out, "paths")
    parts = [plan_area(Area(np.asarray(p.exterior.coords)[:-1], CRS, "p", "t"), 10.0)
             for p in multi.geoms]  # fmt: skip
    assert rows["parts"].tolist() == [2] and paths["part"].tolist() == [1, 2]
    assert rows["lanes"].tolist() == [sum(m.stats.n_transects for m in parts)]
    assert rows["path_length_m"][0] == pytest.approx(sum(m.stats.path_length for m in parts))


def test_vehicle_headland_and_keep_inside_equal_single_plan_area_calls(
    tmp_path, capsys, one_thread
):
    """``--turn-radius`` (per field from a column), ``--reverse``, ``--headland`` and
    ``--keep-inside``: each field's plan is that of one ``plan_area`` call with the same options,
    its coverage reported; a bad column value is that field's error row."""
    rng = np.random.default_rng(11)
    geoms = [_convex(rng) for _ in range(3)]
    geoms.append(shapely.affinity.translate(
        shapely.Polygon([(0, 0), (300, 0), (300, 100), (100, 100), (100, 300), (0, 300)]),
        170_000, 460_000))  # fmt: skip
    geoms.append(_convex(rng))
    radius = [4.0, 6.0, 9.0, 5.0, -1.0]
    path = tmp_path / "vehicle.gpkg"
    _write(path, geoms, [f"f{i}" for i in range(5)], radius)  # the column "sp" is the radius
    out = tmp_path / "out.gpkg"
    argv = ["-q", "batch", str(path), "--out", str(out), "--spacing", "10", "--reverse",
            "--turn-radius-column", "sp", "--headland", "1", "--keep-inside", "--workers", "2",
            "--json"]  # fmt: skip
    assert main(argv) == 0
    assert json.loads(capsys.readouterr().out)["failed"] == 1
    rows, lanes, paths = _consistent(out), _layer(out, "lanes"), _layer(out, "paths")
    order = np.argsort(rows["field_id"])  # rows in the order the fields finished
    rows = {k: v[order] for k, v in rows.items()}
    assert rows["error"][4] == "column 'sp' (turn_radius): expected a number >= 0, got -1.0"
    for i, geom in enumerate(geoms[:4]):
        area = Area(np.asarray(geom.exterior.coords)[:-1], CRS, f"f{i}", "test")
        mission = plan_area(area, 10.0, vehicle=Vehicle(turn_radius=radius[i],
                            reverse=True), headland=1, keep_inside=True)  # fmt: skip
        mine = [
            np.asarray(shapely.from_wkb(w).coords)
            for w, f in zip(lanes["geometry"], lanes["field_id"], strict=True)
            if f == i + 1
        ]
        np.testing.assert_array_equal(np.array(mine), mission.transects)
        line = [shapely.from_wkb(w) for w, f in zip(paths["geometry"], paths["field_id"],
                                                     strict=True) if f == i + 1]  # fmt: skip
        np.testing.assert_array_equal(np.asarray(line[0].coords), mission.waypoints)
        assert rows["path_length_m"][i] == mission.stats.path_length
        assert rows["turns"][i] == mission.stats.n_turns
        assert rows["covered_share"][i] == mission.coverage.covered_share > 0.999
        assert mission.stats.n_transects > 0
    plain = plan_area(Area(np.asarray(geoms[0].exterior.coords)[:-1], CRS, "f0", "t"), 10.0)
    assert rows["path_length_m"][0] != plain.stats.path_length  # the options did something


def test_vehicle_options_bad_values(tmp_path, capsys):
    """A bad per-field headland is an error row; options that cannot go together are one
    line on the command line (exit status 2) and one error of the API, before any work."""
    path = tmp_path / "h.gpkg"
    rng = np.random.default_rng(12)
    _write(path, [_convex(rng) for _ in range(3)], ["a", "b", "c"], [1.0, 1.5, 2.0])
    out = tmp_path / "h-out.gpkg"
    result = boustro.batch(path, out, spacing=10.0, columns={"headland": "sp"}, turn_radius=5.0,
                           workers=1)  # fmt: skip
    rows = _layer(out, "fields")
    assert (result.planned, result.failed) == (2, 1)
    assert rows["error"][1] == "column 'sp' (headland): expected a whole number >= 0, got 1.5"
    two = plan_area(Area(np.asarray(shapely.from_wkb(_layer(path, "h")["geometry"][2]).exterior
                                    .coords)[:-1], CRS, "c", "t"), 10.0, headland=2,
                    vehicle=Vehicle(turn_radius=5.0))  # fmt: skip
    assert rows["path_length_m"][2] == two.stats.path_length
    argv = ["batch", str(path), "--out", str(tmp_path / "x.gpkg"), "--spacing", "10"]
    assert main([*argv, "--reverse"]) == 2
    assert capsys.readouterr().err == "boustro: error: --reverse needs --turn-radius\n"
    assert main([*argv, "--images-in-turns"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "need --camera" in err
    assert not (tmp_path / "x.gpkg").exists()
    with pytest.raises(InvalidParameterError, match="--reverse needs --turn-radius"):
        boustro.batch(path, tmp_path / "y.gpkg", spacing=10.0, reverse=True)
    with pytest.raises(InvalidParameterError, match="headland must be >= 0"):
        PlanOptions(spacing=10.0, headland=-1)
    assert not (tmp_path / "y.gpkg").exists()


def test_camera_with_image_height_and_front_overlap(tmp_path, capsys):
    """``--camera`` with 3 or 4 numbers (or a preset) and ``--front-overlap``, as in plan."""
    path = tmp_path / "cam.gpkg"
    _write(path, [shapely.box(150_000, 450_000, 150_200, 450_120)], ["a"], [1.0])
    for extra in (["--camera", "13.2,8.8,5472"], ["--camera", "13.2,8.8,5472,3648",
                                                   "--front-overlap", "80"]):  # fmt: skip
        out = tmp_path / f"cam{len(extra)}.gpkg"
        argv = ["-q", "batch", str(path), "--out", str(out), "--altitude", "60", "--workers", "1",
                *extra]  # fmt: skip
        assert main(argv) == 0, capsys.readouterr().err
        cam = Camera(13.2, 8.8, 5472, altitude=60.0, side_overlap=0.7,
                             image_height=3648 if len(extra) > 2 else None,
                             front_overlap=0.8 if len(extra) > 2 else None)  # fmt: skip
        single = plan_area(shapely.box(150_000, 450_000, 150_200, 450_120), cam, crs=CRS,
                           altitude=60.0)  # fmt: skip
        rows = _layer(out, "fields")
        assert rows["spacing_m"][0] == single.spacing
        assert rows["lanes"][0] == single.stats.n_transects


@pytest.mark.parametrize("crs", [CRS, "EPSG:4326"])
def test_invalid_field_error_is_that_of_check_area(tmp_path, crs):
    """An invalid field's row says what ``check_area`` says (``boustro plan``'s refusal, with
    GEOS's reason and the hint to --repair), whether the worker checks it before planning
    (longitude/latitude) or only when planning fails (a projected CRS)."""
    from boustro.batch.source import Feature
    from boustro.batch.worker import _area
    from boustro.io.repair import check_area

    x, y = (150_000, 450_000) if crs == CRS else (5.0, 52.0)
    k = 100.0 if crs == CRS else 0.001
    bow = shapely.Polygon([(x, y), (x + k, y + k), (x + k, y), (x, y + k)])
    spike = shapely.Polygon([(x, y), (x + k, y), (x + k, y + k), (x + k, y + k / 2),
                             (x + 2 * k, y + k / 2), (x + k, y + k / 2), (x, y + k)])  # fmt: skip
    path = tmp_path / "bad.gpkg"
    _write(path, [bow, spike], ["bow", "spike"], [10.0, 10.0], crs=crs)
    boustro.batch(path, tmp_path / "out.gpkg", spacing=10.0, workers=1)
    rows = _layer(tmp_path / "out.gpkg", "fields")
    for i, (geom, name) in enumerate(((bow, "bow"), (spike, "spike")), start=1):
        error = rows["error"][list(rows["field_id"]).index(i)]
        area = _area(geom, Feature(i, name, shapely.to_wkb(geom)), crs, 1, 1)
        with pytest.raises(boustro.InvalidPolygonError) as refused:
            check_area(area)
        assert error == str(refused.value)
        assert "try --repair" in error


def test_settings_of_an_earlier_output_still_resume():
    """The options added with the vehicle ones are stored only when given, so an output of the
    earlier version (the same settings) is resumed, and one of other options is refused."""
    plain = PlanOptions(spacing=10.0).settings()
    added = {"front_overlap", "images_in_turns", "turn_radius", "reverse", "headland",
             "keep_inside"}  # fmt: skip
    assert not added & set(plain) and {"spacing", "camera", "columns"} <= set(plain)
    assert PlanOptions(spacing=10.0, headland=1).settings()["headland"] == 1
    assert PlanOptions(spacing=10.0, turn_radius=0.0).settings()["turn_radius"] == 0.0
    assert PlanOptions(camera=(1.0, 2.0, 3.0, None)).settings()["camera"] == [1.0, 2.0, 3.0]


def test_a_hole_touching_the_shell_at_a_point_is_planned(tmp_path):
    """QA round 13: as ``boustro plan`` (io.repair.detach_holes), a hole touching the shell at
    one point (valid for GEOS) is cut back from it and planned: an ``ok`` row, not an error."""
    x, y = 150_000, 450_000
    shell = [(x, y), (x + 100, y), (x + 100, y + 100), (x, y + 100)]
    hole = [(x + 50, y), (x + 60, y + 20), (x + 40, y + 20)]
    path = tmp_path / "touch.gpkg"
    _write(path, [shapely.Polygon(shell, [hole])], ["touch"], [10.0])
    boustro.batch(path, tmp_path / "out.gpkg", spacing=10.0, workers=1)
    rows = _layer(tmp_path / "out.gpkg", "fields")
    assert list(rows["status"]) == ["ok"], rows["error"]
    assert rows["covered_share"][0] == pytest.approx(1.0)
