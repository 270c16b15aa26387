"""Every area format read through one layer: KMZ, QGroundControl ``.plan``, and through
pyogrio/GDAL Shapefile (plain, zipped), GeoPackage, FlatGeobuf; binary files never reach the
text readers; their errors are one line naming the file, with nothing written."""

from __future__ import annotations

import builtins
import io
import json
import os
import sqlite3
import zipfile

import numpy as np
import pyogrio
import pyogrio.raw
import pytest
import shapely

from boustro.errors import MissingDependencyError, PolygonFileError
from boustro.io import read_area, read_areas
from boustro.io import read_zip as zip_module

from .conftest import run_cli
from .test_crs_safety import HOSTILE, pyproj_never_sees  # noqa: F401

RD = "EPSG:28992"
SHELL = [(155000.0, 463000.0), (155300.0, 463000.0), (155300.0, 463200.0), (155000.0, 463200.0)]
HOLE = [(155100.0, 463050.0), (155150.0, 463050.0), (155150.0, 463100.0), (155100.0, 463100.0)]
FIELDS = [
    ("north", shapely.Polygon(SHELL, [HOLE])),
    ("", shapely.box(156000, 463000, 156200, 463100)),  # unnamed: "field 2"
    (
        "twin",
        shapely.MultiPolygon(
            [
                shapely.box(157000, 463000, 157100, 463100),
                shapely.box(157200, 463000, 157300, 463100),
            ]
        ),
    ),
]
DRIVERS = {".gpkg": "GPKG", ".shp": "ESRI Shapefile", ".fgb": "FlatGeobuf"}
KML_RING = "5.0,52.0 5.003,52.0 5.003,52.002 5.0,52.002 5.0,52.0"
KML = (
    '<kml xmlns="http://www.opengis.net/kml/2.2"><Document>'
    "<Placemark><name>{name}</name><Polygon><outerBoundaryIs><LinearRing><coordinates>"
    f"{KML_RING}</coordinates></LinearRing></outerBoundaryIs></Polygon></Placemark>"
    "</Document></kml>"
)


def _write(path, fields=FIELDS, crs=RD, column="name"):
    geoms = np.array(
        [
            shapely.to_wkb(shapely.MultiPolygon([g]) if g.geom_type == "Polygon" else g)
            for _, g in fields
        ],
        dtype=object,
    )
    names = np.array([n or None for n, _ in fields], dtype=object)
    pyogrio.raw.write(
        str(path),
        geoms,
        geometry_type="MultiPolygon",
        field_data=[names],
        fields=[column],
        crs=crs,
        driver=DRIVERS[os.path.splitext(path)[1]],
        # FlatGeobuf's spatial index would reorder the features
        layer_options={"SPATIAL_INDEX": "NO"} if str(path).endswith(".fgb") else None,
    )
    return path


def _zip(path, members):
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as zf:
        for name, data in members.items():
            zf.writestr(name, data)
    return path


def _one_line(code, err, name):
    lines = [line for line in err.strip().splitlines() if line]
    assert code == 2, err
    assert len(lines) == 1 and "Traceback" not in err, err
    assert str(name) in lines[0], err
    return lines[0]


# -- GDAL formats ------------------------------------------------------------------------------
@pytest.mark.parametrize("ext", sorted(DRIVERS))
def test_a_gdal_file_reads_every_polygon_with_names_holes_and_crs(tmp_path, ext):
    areas = read_areas(_write(tmp_path / f"fields{ext}"))
    assert [a.name for a in areas] == ["north", "field 2", "twin part 1", "twin part 2"]
    assert {a.crs for a in areas} == {RD}
    north = areas[0]
    assert shapely.Polygon(north.ring).normalize().equals(shapely.Polygon(SHELL).normalize())
    assert len(north.holes) == 1
    assert shapely.Polygon(north.holes[0]).equals(shapely.Polygon(HOLE))
    assert len(north.ring) == 4  # the closing vertex dropped, as every reader does
    assert read_area(tmp_path / f"fields{ext}").name == "north"


def test_a_name_from_an_id_column_and_a_lone_field_named_by_the_stem(tmp_path):
    (a,) = read_areas(_write(tmp_path / "parcel.gpkg", FIELDS[1:2], column="id"))
    assert a.name == "parcel"
    areas = read_areas(_write(tmp_path / "ids.gpkg", FIELDS[:2], column="id"))
    assert [a.name for a in areas] == ["north", "field 2"]


@pytest.mark.parametrize("name", ["fields.shp.zip", "fields.zip"])
def test_a_zipped_shapefile(tmp_path, name):
    _write(tmp_path / "in.shp")
    members = {
        f"in{e}": (tmp_path / f"in{e}").read_bytes() for e in (".shp", ".shx", ".dbf", ".prj")
    }
    areas = read_areas(_zip(tmp_path / name, members))
    assert [a.name for a in areas] == ["north", "field 2", "twin part 1", "twin part 2"]
    assert areas[0].crs == RD and len(areas[0].holes) == 1


def test_a_layer_without_crs_is_lonlat_and_the_command_line_crs_overrides(tmp_path):
    with pytest.warns(UserWarning, match="'crs' was not provided"):  # pyogrio's, writing
        path = _write(tmp_path / "nocrs.fgb", [("a", shapely.box(5, 52, 5.003, 52.002))], crs=None)
    assert read_area(path).crs == "EPSG:4326"
    assert read_area(_write(tmp_path / "rd.gpkg"), crs="EPSG:4326").crs == "EPSG:4326"


def test_boustro_plan_a_geopackage_end_to_end(capsys, tmp_path):
    path = _write(tmp_path / "fields.gpkg", FIELDS[:2])
    code, out, err = run_cli(capsys, "plan", path, "--spacing", "20", "--json")
    assert code == 0, err
    result = json.loads(out)
    assert [r["name"] for r in result] == ["north", "field 2"]
    assert all(r["n_transects"] > 0 and r["crs"] == RD for r in result)
    assert result[0]["holes"] == 1


def test_a_geopackage_under_another_extension_plans_without_gdal_warnings(capsys, tmp_path):
    # QA: a .gpkg renamed .json was planned, but pyogrio's RuntimeWarning about the
    # "non conformant file extension" (GDAL's) reached stderr as a multi-line Python warning
    path = _write(tmp_path / "fields.gpkg", FIELDS[:1])
    renamed = tmp_path / "fields.json"
    path.rename(renamed)
    code, out, err = run_cli(capsys, "plan", renamed, "--spacing", "20", "--json")
    assert code == 0, err
    assert json.loads(out)["name"] == "north"
    assert "Warning" not in err and "GDAL" not in err, err


# -- hostile CRS, missing pyogrio, corrupt files ------------------------------------------------
@pytest.fixture
def gdal_never_opens(monkeypatch):
    def refuse(*args, **kwargs):
        pytest.fail(f"GDAL was asked to open {args[:1]}")

    monkeypatch.setattr(pyogrio, "list_layers", refuse)
    monkeypatch.setattr(pyogrio.raw, "read", refuse)


@pytest.mark.usefixtures("pyproj_never_sees", "gdal_never_opens")
@pytest.mark.parametrize("kind", ["proj-nadgrids", "wkt1-extension", "wkt2-parameterfile"])
def test_a_hostile_crs_in_a_geopackage_is_refused_before_gdal_and_proj(capsys, tmp_path, kind):
    path = _write(tmp_path / "hostile.gpkg")
    with sqlite3.connect(path) as db:
        db.execute(
            "UPDATE gpkg_spatial_ref_sys SET definition = ? WHERE srs_id = 28992", (HOSTILE[kind],)
        )
    db.close()
    out = tmp_path / "m.geojson"
    code, _, err = run_cli(capsys, "plan", path, "--spacing", "20", "--out", out)
    assert "is refused" in _one_line(code, err, path)
    assert not out.exists()


@pytest.mark.usefixtures("pyproj_never_sees", "gdal_never_opens")
def test_a_hostile_prj_is_refused_before_gdal_and_proj(capsys, tmp_path):
    path = _write(tmp_path / "hostile.shp")
    (tmp_path / "hostile.prj").write_text(HOSTILE["wkt1-extension"])
    code, _, err = run_cli(capsys, "plan", path, "--spacing", "20")
    assert "is refused" in _one_line(code, err, path)


@pytest.mark.usefixtures("pyproj_never_sees", "gdal_never_opens")
@pytest.mark.parametrize("suffix", [".PRJ", ".Prj"])
def test_a_hostile_prj_in_any_letter_case_is_refused_before_gdal(capsys, tmp_path, suffix):
    """GDAL opens ``.PRJ`` as well as ``.prj``: the check before GDAL must see both."""
    path = _write(tmp_path / "hostile.shp")
    (tmp_path / "hostile.prj").unlink(missing_ok=True)
    (tmp_path / f"hostile{suffix}").write_text(HOSTILE["wkt1-extension"])
    code, _, err = run_cli(capsys, "plan", path, "--spacing", "20")
    assert "is refused" in _one_line(code, err, path) and suffix in err


@pytest.mark.usefixtures("gdal_never_opens")
@pytest.mark.parametrize("tail", [b"\n\x00", b"<!-- \xe9 -->\n"])
def test_a_disguised_vrt_is_refused_and_gdal_never_guesses(capsys, tmp_path, tail):
    """A VRT naming another file, made "binary" by one NUL or one non-UTF-8 byte, must not
    reach GDAL (which would open the file it names)."""
    target = tmp_path / "poly.csv"
    target.write_text('WKT\n"POLYGON((5 52,5.001 52,5.001 52.001,5 52.001,5 52))"\n')
    vrt = (
        f"<OGRVRTDataSource><OGRVRTLayer name='s'><SrcDataSource>{target}</SrcDataSource>"
        "<SrcLayer>poly</SrcLayer><GeometryType>wkbPolygon</GeometryType>"
        "<GeometryField encoding='WKT' field='WKT'/></OGRVRTLayer></OGRVRTDataSource>"
    ).encode()
    path = tmp_path / "evil.bin"
    path.write_bytes(vrt + tail)
    code, out, err = run_cli(capsys, "plan", path, "--spacing", "10", "--json")
    assert "neither UTF-8 text nor a binary area format" in _one_line(code, err, str(path))
    assert out == ""


def test_missing_pyogrio_is_one_line_naming_the_extra(capsys, tmp_path, monkeypatch):
    path = _write(tmp_path / "fields.gpkg")
    real = builtins.__import__

    def no_pyogrio(name, *args, **kwargs):
        if name == "pyogrio" or name.startswith("pyogrio."):
            raise ImportError(f"No module named {name!r}")
        return real(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_pyogrio)
    with pytest.raises(
        MissingDependencyError,
        match=r"^reading \.gpkg needs pyogrio: pip "
        r"install 'boustro\[geo\]'$",
    ):
        read_areas(path)
    code, _, err = run_cli(capsys, "plan", path, "--spacing", "20")
    assert "pip install 'boustro[geo]'" in _one_line(code, err, ".gpkg")


def _half_gpkg(tmp_path):
    data = _write(tmp_path / "whole.gpkg").read_bytes()
    (tmp_path / "half.gpkg").write_bytes(data[: len(data) // 2])
    return tmp_path / "half.gpkg"


def _random(tmp_path, name):
    (tmp_path / name).write_bytes(np.random.default_rng(7).bytes(5000))
    return tmp_path / name


def _text(path, text):
    path.write_text(text)
    return path


def _sqlite(path):
    with sqlite3.connect(path) as db:
        db.execute("CREATE TABLE t (a)")
    db.close()
    return path


CORRUPT = {
    "half.gpkg": _half_gpkg,
    "random.shp": lambda p: _random(p, "random.shp"),
    "random.fgb": lambda p: _random(p, "random.fgb"),
    "random.parquet": lambda p: _random(p, "random.parquet"),
    "random.bin": lambda p: _random(p, "random.bin"),
    "not-a-geopackage.sqlite": lambda p: _sqlite(p / "not-a-geopackage.sqlite"),
    # GDAL would open a VRT whatever its name, and read the files it names
    "vrt.gpkg": lambda p: _text(
        p / "vrt.gpkg",
        '<OGRVRTDataSource><OGRVRTLayer name="x">'
        "<SrcDataSource>/etc/passwd</SrcDataSource></OGRVRTLayer>"
        "</OGRVRTDataSource>",
    ),
    "geojson.shp": lambda p: _text(p / "geojson.shp", '{"type": "Polygon", "coordinates": []}'),
    "nokml.kmz": lambda p: _zip(p / "nokml.kmz", {"readme.txt": "hello"}),
    "nokml.zip": lambda p: _zip(p / "nokml.zip", {"a/b.txt": "hello"}),
    "truncated.kmz": lambda p: (
        p.joinpath("truncated.kmz").write_bytes(
            _zip(p / "t.kmz", {"doc.kml": KML.format(name="x")}).read_bytes()[:60]
        )
        and p / "truncated.kmz"
    ),
}


@pytest.mark.parametrize("name", sorted(CORRUPT))
def test_a_corrupt_binary_is_one_line_naming_the_file_and_nothing_written(capsys, tmp_path, name):
    path = CORRUPT[name](tmp_path)
    out = tmp_path / "mission.geojson"
    code, _, err = run_cli(capsys, "plan", path, "--spacing", "20", "--out", out)
    line = _one_line(code, err, path)
    assert "codec can't decode" not in line
    assert not out.exists()
    with pytest.raises(PolygonFileError):
        read_areas(path)


# -- KMZ ---------------------------------------------------------------------------------------
def test_a_kmz_reads_its_doc_kml(tmp_path):
    path = _zip(
        tmp_path / "field.kmz",
        {"files/other.kml": KML.format(name="other"), "doc.kml": KML.format(name="meadow")},
    )
    area = read_area(path)
    assert area.name == "meadow" and area.crs == "EPSG:4326"
    assert area.ring.tolist() == [[5.0, 52.0], [5.003, 52.0], [5.003, 52.002], [5.0, 52.002]]


def test_a_kmz_without_doc_kml_reads_its_first_kml(capsys, tmp_path):
    path = _zip(
        tmp_path / "field.kmz",
        {"img.png": b"\x89PNG", "a.kml": KML.format(name="a"), "b.kml": KML.format(name="b")},
    )
    assert read_area(path).name == "a"
    code, out, err = run_cli(capsys, "plan", path, "--spacing", "20", "--json")
    assert code == 0, err
    assert json.loads(out)["name"] == "a"


def test_a_zip_bomb_is_refused_by_ratio_and_by_size(tmp_path, monkeypatch):
    bomb = _zip(tmp_path / "bomb.kmz", {"doc.kml": b"<" + b" " * (4 * 1024 * 1024)})
    with pytest.raises(PolygonFileError, match=r"bomb.kmz: doc.kml: compressed \d+ to 1.*zip bomb"):
        read_area(bomb)
    monkeypatch.setattr(zip_module, "MAX_MEMBER_BYTES", 100)
    big = _zip(tmp_path / "big.kmz", {"doc.kml": KML.format(name="x")})
    with pytest.raises(PolygonFileError, match=r"big\.kmz: doc\.kml: .* over the limit of 100"):
        read_area(big)


def test_a_zip_member_whose_header_lies_is_cut_at_the_limit(tmp_path, monkeypatch):
    path = _zip(tmp_path / "liar.kmz", {"doc.kml": KML.format(name="x")})
    monkeypatch.setattr(zip_module, "MAX_MEMBER_BYTES", 100)
    archive = zipfile.ZipFile(io.BytesIO(path.read_bytes()))
    info = archive.getinfo("doc.kml")
    info.file_size = 50  # the header claims less than the data
    with pytest.raises(PolygonFileError):  # zipfile's CRC/size check or the bounded read
        zip_module.read_member(archive, info, "liar.kmz")


# -- QGroundControl .plan ----------------------------------------------------------------------
LATLON = [[52.0, 5.0], [52.0, 5.003], [52.002, 5.003], [52.002, 5.0]]
PLAN = {
    "fileType": "Plan",
    "groundStation": "QGroundControl",
    "version": 1,
    "mission": {
        "items": [
            {"type": "SimpleItem", "command": 22, "params": [0, 0, 0, 0, 52.0, 5.0, 30]},
            {"type": "ComplexItem", "complexItemType": "survey", "polygon": LATLON, "version": 5},
        ]
    },
    "geoFence": {
        "circles": [],
        "version": 2,
        "polygons": [
            {
                "inclusion": True,
                "polygon": [[51.99, 4.99], [51.99, 5.01], [52.01, 5.01]],
                "version": 1,
            },
            {
                "inclusion": False,
                "polygon": [[52.0, 5.0], [52.0, 5.001], [52.001, 5.001]],
                "version": 1,
            },
        ],
    },
    "rallyPoints": {"points": [], "version": 2},
}


def test_a_plan_file_gives_its_surveys_and_inclusion_fences_as_lonlat(tmp_path):
    path = tmp_path / "mission.plan"
    path.write_text(json.dumps(PLAN))
    areas = read_areas(path)
    assert [a.name for a in areas] == ["survey 2", "geofence 1"]
    assert areas[0].ring.tolist() == [[5.0, 52.0], [5.003, 52.0], [5.003, 52.002], [5.0, 52.002]]
    assert areas[1].ring.tolist() == [[4.99, 51.99], [5.01, 51.99], [5.01, 52.01]]
    assert {a.crs for a in areas} == {"EPSG:4326"}
    (tmp_path / "as.json").write_text(json.dumps(PLAN))  # sniffed by content too
    assert [a.name for a in read_areas(tmp_path / "as.json")] == ["survey 2", "geofence 1"]


def test_a_plan_names_the_fences_it_does_not_avoid(tmp_path, caplog):
    """QA round 15: an exclusion geofence (a no-fly zone over the survey) and the fence's
    circles were dropped without a word, and the plan crossed them."""
    path = tmp_path / "mission.plan"
    circle = {"circle": {"center": [52.0, 5.0], "radius": 9}, "inclusion": False, "version": 1}
    stay = {**circle, "inclusion": True}  # an inclusion circle: a boundary, not an obstacle
    fence = {**PLAN["geoFence"], "circles": [circle, stay]}
    path.write_text(json.dumps({**PLAN, "geoFence": fence}))
    read_areas(path)
    said = [r.getMessage() for r in caplog.records if "not an obstacle" in r.getMessage()]
    assert len(said) == 2
    assert "geoFence.polygons[1] (an exclusion fence)" in said[0]
    assert "geoFence.circles[0] (an exclusion circle)" in said[1]
    (left,) = [r.getMessage() for r in caplog.records if "circles[1]" in r.getMessage()]
    assert "(an inclusion circle) is not a boundary" in left and "hole" not in left
    caplog.clear()
    path.write_text(
        json.dumps({**PLAN, "geoFence": {"polygons": PLAN["geoFence"]["polygons"][:1]}})
    )
    read_areas(path)
    assert "not an obstacle" not in caplog.text


def test_a_plan_without_a_polygon_is_one_line(capsys, tmp_path):
    path = tmp_path / "waypoints.plan"
    path.write_text(json.dumps({**PLAN, "mission": {"items": []}, "geoFence": {}}))
    code, _, err = run_cli(capsys, "plan", path, "--spacing", "20")
    assert "no survey polygon" in _one_line(code, err, path)
    path.write_text(json.dumps({"type": "Polygon"}))
    code, _, err = run_cli(capsys, "plan", path, "--spacing", "20")
    assert "not a QGroundControl plan" in _one_line(code, err, path)


def test_an_open_geojson_ring_is_read_closed_with_a_warning(tmp_path, caplog):
    # QA 2026-11-28: Fields2Cover's strips.geojson ends each ring 1.1 km from its first
    # position (a typo in the last position); the ring was closed silently and the spike was
    # refused as a self-intersection with no word of the open ring
    square = [[6.0, 51.0], [6.001, 51.0], [6.001, 51.001], [6.0, 51.001]]
    doc = {
        "type": "Polygon",
        "coordinates": [square, [[6.0004, 51.0004], [6.0006, 51.0004], [6.0006, 51.0006]]],
    }
    path = tmp_path / "open.geojson"
    path.write_text(json.dumps(doc))
    with caplog.at_level("WARNING"):
        area = read_area(path)
    np.testing.assert_array_equal(area.ring, square)
    assert len(area.holes) == 1 and len(area.holes[0]) == 3
    said = [r.getMessage() for r in caplog.records if "not closed" in r.getMessage()]
    assert len(said) == 2
    assert any("[6.0, 51.001]" in m and "hole" not in m for m in said)
    assert any("hole 1" in m and "[6.0006, 51.0006]" in m for m in said)
    caplog.clear()
    doc["coordinates"] = [[*square, square[0]]]
    path.write_text(json.dumps(doc))
    with caplog.at_level("WARNING"):
        np.testing.assert_array_equal(read_area(path).ring, square)
    assert "not closed" not in caplog.text


def test_a_gpx_file_is_named_as_such_not_as_a_kml_without_a_polygon(tmp_path, capsys):
    """QA round 15: reading back the GPX that ``boustro plan`` wrote (or a walked boundary's
    track) said 'no Polygon in the file (expected a KML Polygon placemark)'."""
    path = tmp_path / "mission.gpx"
    ring = [[6.0, 51.0], [6.001, 51.0], [6.001, 51.001], [6.0, 51.001]]
    code, _, _ = run_cli(capsys, "plan", "--spacing", "20", "--out", path)
    assert code == 0
    for name in (path, tmp_path / "as.xml"):
        if name != path:
            name.write_bytes(path.read_bytes())
        code, _, err = run_cli(capsys, "plan", name, "--spacing", "20")
        line = _one_line(code, err, name)
        assert "a GPX file holds routes and tracks, not an area" in line
        assert "expected a KML Polygon" not in line
    ok = tmp_path / "ok.kml"  # a KML without a polygon keeps its message
    ok.write_text(
        f"<kml><Placemark><LineString><coordinates>{ring}</coordinates></LineString>"
        "</Placemark></kml>"
    )
    assert "expected a KML Polygon" in _one_line(
        *run_cli(capsys, "plan", ok, "--spacing", "20")[::2], ok
    )
