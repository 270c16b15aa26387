"""The mission-format registry: one module per format, each registering itself; the CLI reads it."""

from __future__ import annotations

import importlib
import pkgutil

import pytest

import boustro.formats
import boustro.io.formats as formats
from boustro.errors import InvalidParameterError
from boustro.io.formats import FORMATS, format_for, register_format, render

from .conftest import run_cli


def test_formats_keep_their_shape_and_order():
    assert list(FORMATS) == ["geojson", "kml", "gpx", "csv", "plan", "wpl"]
    for name, (exts, renderer) in FORMATS.items():
        assert exts and all(e.startswith(".") for e in exts), name
        assert callable(renderer), name
    assert FORMATS["plan"][1] is formats.to_qgc_plan
    assert FORMATS["wpl"][0] == (".waypoints", ".txt", ".mission")
    assert boustro.formats is formats


def test_every_format_module_registers_itself():
    """Each public module of the package defines one registered renderer (found by discover)."""
    renderers = {renderer.__module__ for _, renderer in FORMATS.values()}
    modules = {
        info.name
        for info in pkgutil.iter_modules(formats.__path__, "boustro.io.formats.")
        if not info.name.rpartition(".")[2].startswith("_") and not info.name.endswith(".registry")
    }
    assert modules == renderers
    assert FORMATS.package == "boustro.io.formats"
    assert FORMATS.discover() == []  # all imported with the package


def test_reimporting_a_format_module_replaces_its_own_entry():
    module = importlib.reload(importlib.import_module("boustro.io.formats.gpx"))
    try:
        assert FORMATS["gpx"][1] is module.to_gpx
    finally:
        importlib.reload(module)


def test_a_name_is_registered_once():
    with pytest.raises(InvalidParameterError, match="already registered"):
        register_format("kml", extensions=(".kml2",))(lambda mission: "")
    with pytest.raises(InvalidParameterError, match="start with a dot"):
        register_format("dotless", extensions=("txt",))
    assert "kml" in FORMATS and FORMATS["kml"][1] is formats.to_kml


@pytest.fixture
def bytes_format():
    """A binary format registered at run time, and unregistered afterwards."""

    @register_format("names", extensions=(".names",))
    def to_names(mission):
        """Names, as bytes."""
        return b"\x00" + (mission.name or "").encode() + b"\xff"

    yield to_names
    FORMATS.pop("names")


def test_a_runtime_format_reaches_render_and_the_cli(capsys, tmp_path, bytes_format):
    assert format_for(tmp_path / "a.NAMES") == "names"
    by_extension = tmp_path / "mission.names"
    code, out, err = run_cli(capsys, "plan", "--out", by_extension)
    assert code == 0, err
    assert f"{by_extension} (names)" in out
    assert by_extension.read_bytes() == b"\x00test parcel\xff"
    by_option = tmp_path / "mission.dat"
    code, out, err = run_cli(capsys, "plan", "--format", "names", "--out", by_option)
    assert code == 0, err
    assert by_option.read_bytes() == by_extension.read_bytes()
    with pytest.raises(SystemExit):
        run_cli(capsys, "plan", "--help")
    assert "  .names          Names, as bytes.\n" in capsys.readouterr().out


def test_an_unregistered_format_is_refused(capsys, tmp_path, bytes_format):
    FORMATS.pop("names")
    try:
        with pytest.raises(SystemExit) as exit_:
            run_cli(capsys, "plan", "--format", "names", "--out", tmp_path / "m.dat")
        assert exit_.value.code == 2 and "invalid choice: 'names'" in capsys.readouterr().err
        with pytest.raises(InvalidParameterError, match=r"from its extension '\.names'"):
            format_for("m.names")
        with pytest.raises(InvalidParameterError, match="unknown format 'names'"):
            render(None, "names")
    finally:
        FORMATS.register("names", ((".names",), bytes_format))


NEW_MODULES = [
    "boustro.io.formats",
    "boustro.io.formats._common",
    "boustro.io.formats.registry",
    "boustro.io.formats.geojson",
    "boustro.io.formats.kml",
    "boustro.io.formats.gpx",
    "boustro.io.formats.waypoints_csv",
    "boustro.io.formats.qgc_plan",
    "boustro.io.formats.wpl",
    "boustro.io.area",
    "boustro.io.read",
    "boustro.io.read_geojson",
    "boustro.io.read_kml",
    "boustro.io.read_wkt",
    "boustro.mission",
    "boustro.mission.defaults",
    "boustro.mission.types",
    "boustro.mission.project",
    "boustro.mission.steps",
    "boustro.mission.map_back",
    "boustro.mission.pipeline",
]


@pytest.mark.parametrize("name", NEW_MODULES)
def test_split_modules_declare_what_they_export(name):
    module = importlib.import_module(name)
    assert module.__all__ and all(hasattr(module, n) for n in module.__all__), name


def test_split_packages_keep_one_object_per_setting():
    """The settings tests patch through boustro.geo reach plan_area's steps (same objects)."""
    import boustro.geo
    import boustro.io
    import boustro.io.read
    import boustro.mission
    from boustro.mission import defaults, pipeline, types

    assert boustro.geo.METHOD_OPTIONS is boustro.mission.METHOD_OPTIONS is defaults.METHOD_OPTIONS
    assert boustro.geo.REGION_OPTIONS is defaults.REGION_OPTIONS
    assert boustro.mission.plan_area is pipeline.plan_area is boustro.geo.plan_area
    assert boustro.mission.Mission is types.Mission
    assert boustro.io.Area is boustro.io.read.Area is boustro.geo.Area
    for name in set(boustro.io.__all__) - {"atomic_write"}:
        assert getattr(boustro.io, name) is getattr(boustro.io.read, name), name
