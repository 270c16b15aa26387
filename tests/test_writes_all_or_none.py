"""Several output files of one command are written all or none (boustro._files).

A write that fails after the first of several files (a full disk) leaves every target as it was
and no temporary file: ``plan --out`` with ``--plot``, one ``.plan`` file per field, a batch's
per-layer files and a field's sortie files in ``--missions``.
"""

from __future__ import annotations

import errno
import json
import os

import pytest

import boustro.batch
from boustro._files import atomic_write_all
from boustro.batch import export
from boustro.batch.run import store_path

from .conftest import run_cli

NORTH = [[5.0, 52.0], [5.002, 52.0], [5.002, 52.001], [5.0, 52.001], [5.0, 52.0]]
SOUTH = [[5.0, 51.99], [5.003, 51.99], [5.0035, 51.991], [5.0, 51.9915], [5.0, 51.99]]


def _full_disk_after(monkeypatch, good: int) -> None:
    """``os.fsync`` succeeds ``good`` times, then fails as a full disk does."""
    calls = []
    real = os.fsync

    def fsync(fd):
        calls.append(fd)
        if len(calls) > good:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(fd)

    monkeypatch.setattr(os, "fsync", fsync)


def _two_fields(tmp_path):
    path = tmp_path / "two.geojson"
    features = [
        {
            "type": "Feature",
            "properties": {"name": n},
            "geometry": {"type": "Polygon", "coordinates": [r]},
        }
        for n, r in (("North", NORTH), ("South", SOUTH))
    ]
    path.write_text(json.dumps({"type": "FeatureCollection", "features": features}))
    return path


def test_helper_writes_all_or_none(tmp_path, monkeypatch):
    old = tmp_path / "a.txt"
    old.write_text("old")
    _full_disk_after(monkeypatch, 1)
    with pytest.raises(OSError, match="No space"):
        atomic_write_all([(old, "new a"), (tmp_path / "b.txt", "new b")])
    assert old.read_text() == "old"
    assert sorted(os.listdir(tmp_path)) == ["a.txt"]  # no b.txt, no temporary file
    monkeypatch.undo()
    atomic_write_all([(old, "new a"), (tmp_path / "b.txt", "new b")])
    assert (old.read_text(), (tmp_path / "b.txt").read_text()) == ("new a", "new b")


def test_plan_and_its_plot_all_or_none(capsys, tmp_path, monkeypatch):
    pytest.importorskip("matplotlib")
    out, plot = tmp_path / "m.geojson", tmp_path / "m.png"
    _full_disk_after(monkeypatch, 1)
    code, _, err = run_cli(capsys, "-q", "plan", "--spacing", "20", "--out", out, "--plot", plot)
    assert code == 2 and err.count("\n") == 1 and "No space left on device" in err
    assert os.listdir(tmp_path) == []


def test_one_plan_file_per_field_all_or_none(capsys, tmp_path, monkeypatch):
    area = _two_fields(tmp_path)
    out = tmp_path / "m.plan"
    _full_disk_after(monkeypatch, 1)
    code, _, err = run_cli(capsys, "-q", "plan", area, "--spacing", "20", "--altitude", "30",
                           "--out", out)  # fmt: skip
    assert code == 2 and "No space left on device" in err
    assert sorted(os.listdir(tmp_path)) == ["two.geojson"]
    monkeypatch.undo()
    code, _, err = run_cli(capsys, "-q", "plan", area, "--spacing", "20", "--altitude", "30",
                           "--out", out)  # fmt: skip
    assert code == 0, err
    assert sorted(os.listdir(tmp_path)) == ["m-North.plan", "m-South.plan", "two.geojson"]


def test_batch_layer_files_all_or_none(tmp_path, monkeypatch):
    pytest.importorskip("pyogrio")
    area = _two_fields(tmp_path)
    out = tmp_path / "plans.geojson"
    boustro.batch(area, out, spacing=20.0, workers=1)
    layers = sorted(p for p in os.listdir(tmp_path) if p.startswith("plans."))
    assert layers == ["plans.fields.geojson", "plans.lanes.geojson", "plans.paths.geojson"]
    for p in layers:  # what a previous run wrote (a new export replaces each)
        (tmp_path / p).write_text("previous")
    real = export._write_layer
    calls = []

    def second_fails(pyogrio, store, layer, target, path):
        calls.append(layer)
        if len(calls) == 2:
            raise OSError(errno.ENOSPC, "No space left on device")
        real(pyogrio, store, layer, target, path)

    monkeypatch.setattr(export, "_write_layer", second_fails)
    with pytest.raises(OSError, match="No space"):
        export.export_layers(store_path(str(out)), export.layer_paths(str(out)))
    assert [(tmp_path / p).read_text() for p in layers] == ["previous"] * 3
    assert not [p for p in os.listdir(tmp_path) if p.startswith(".boustro-")]


def test_batch_part_files_of_a_field_all_or_none(tmp_path, monkeypatch):
    area = tmp_path / "multi.geojson"
    geom = {"type": "MultiPolygon", "coordinates": [[NORTH], [SOUTH]]}
    feature = {"type": "Feature", "properties": {"name": "Both"}, "geometry": geom}
    area.write_text(json.dumps({"type": "FeatureCollection", "features": [feature]}))
    missions = tmp_path / "missions"
    _full_disk_after(monkeypatch, 1)
    with pytest.raises(OSError, match="No space"):
        boustro.batch(area, tmp_path / "plans.gpkg", spacing=20.0, workers=1,
                      missions=missions, mission_format="geojson")  # fmt: skip
    assert os.listdir(missions) == []
    monkeypatch.undo()
    boustro.batch(area, tmp_path / "again.gpkg", spacing=20.0, workers=1, missions=missions)
    assert sorted(os.listdir(missions)) == ["1-Both-part1.geojson", "1-Both-part2.geojson"]


def test_batch_refused_before_its_output_is_made(tmp_path, monkeypatch):
    """QA 19: an unreachable --scheduler (after its 30 s timeout) or a chunk size of 0 left an
    empty GeoPackage holding the run's options, which refused a rerun with other options."""
    distributed = pytest.importorskip("distributed")
    area = _two_fields(tmp_path)

    def unreachable(address, timeout):
        raise OSError(f"Timed out trying to connect to {address} after {timeout} s")

    monkeypatch.setattr(distributed, "Client", unreachable)
    with pytest.raises(boustro.errors.InvalidParameterError, match="cannot connect: Timed out"):
        boustro.batch(area, tmp_path / "plans.gpkg", spacing=20.0, scheduler="tcp://10.0.0.1:1")
    with pytest.raises(boustro.errors.InvalidParameterError, match="chunk_size must be >= 1"):
        boustro.batch(area, tmp_path / "plans.gpkg", spacing=20.0, chunk_size=0)
    assert sorted(os.listdir(tmp_path)) == ["two.geojson"]
