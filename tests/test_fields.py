"""Every field in a file: ``read_areas`` and ``boustro plan`` over several fields, each output
format holding or splitting them, read back by its real reader."""

from __future__ import annotations

import csv
import json
from dataclasses import replace

import numpy as np
import pytest

from boustro.cli import main
from boustro.errors import PolygonFileError
from boustro.io import embedded_field, read_area, read_areas
from boustro.io.formats._fields import field_path, safe_name
from boustro.io.formats.kml import to_kml
from boustro.mission import plan_area

NORTH = [[5.0, 52.0], [5.002, 52.0], [5.002, 52.001], [5.0, 52.001], [5.0, 52.0]]
SOUTH = [[5.0, 51.99], [5.003, 51.99], [5.0035, 51.991], [5.0, 51.9915], [5.0, 51.99]]
HOLE = [[5.001, 51.9903], [5.0015, 51.9903], [5.0015, 51.9906], [5.001, 51.9906], [5.001, 51.9903]]


def _feature(props, coords, **extra):
    geom = {"type": "Polygon", "coordinates": coords}
    return {"type": "Feature", "properties": props, "geometry": geom, **extra}


def _coords(ring):
    return " ".join(f"{x},{y}" for x, y in ring)


@pytest.fixture()
def collection(tmp_path):
    path = tmp_path / "farm.geojson"
    doc = {
        "type": "FeatureCollection",
        "features": [
            _feature({"name": "North"}, [NORTH]),
            {
                "type": "Feature",
                "properties": {},
                "geometry": {"type": "Point", "coordinates": [5, 52]},
            },
            _feature({}, [SOUTH, HOLE], id="s-7"),
        ],
    }
    path.write_text(json.dumps(doc))
    return path


def test_feature_collection_gives_every_polygon_with_its_name(collection):
    areas = read_areas(collection)
    assert [a.name for a in areas] == ["North", "s-7"]  # the point is not a field
    np.testing.assert_allclose(areas[0].ring, NORTH[:-1])
    np.testing.assert_allclose(areas[1].ring, SOUTH[:-1])
    assert len(areas[1].holes) == 1 and areas[0].holes == ()
    assert all(a.crs == "EPSG:4326" for a in areas)


def test_multipolygon_parts_are_fields(tmp_path):
    path = tmp_path / "parts.geojson"
    geom = {"type": "MultiPolygon", "coordinates": [[NORTH], [SOUTH]]}
    path.write_text(json.dumps(geom))
    assert [a.name for a in read_areas(path)] == ["field 1", "field 2"]
    path.write_text(
        json.dumps({"type": "Feature", "properties": {"name": "Farm"}, "geometry": geom})
    )
    assert [a.name for a in read_areas(path)] == ["Farm part 1", "Farm part 2"]
    assert read_area(path).name == "Farm"  # read_area keeps the first polygon only


def test_kml_placemarks_are_fields(tmp_path):
    path = tmp_path / "farm.kml"
    path.write_text(
        '<?xml version="1.0"?><kml xmlns="http://www.opengis.net/kml/2.2"><Document>'
        "<name>farm</name>"
        f"<Placemark><name>Wheat</name><Polygon><outerBoundaryIs><LinearRing><coordinates>"
        f"{_coords(NORTH)}</coordinates></LinearRing></outerBoundaryIs></Polygon></Placemark>"
        f"<Placemark><name>Barley</name><Polygon><outerBoundaryIs><LinearRing><coordinates>"
        f"{_coords(SOUTH)}</coordinates></LinearRing></outerBoundaryIs><innerBoundaryIs>"
        f"<LinearRing><coordinates>{_coords(HOLE)}</coordinates></LinearRing></innerBoundaryIs>"
        "</Polygon></Placemark></Document></kml>"
    )
    areas = read_areas(path)
    assert [a.name for a in areas] == ["Wheat", "Barley"]
    assert len(areas[1].holes) == 1
    np.testing.assert_allclose(areas[1].ring, SOUTH[:-1])


def _gml_polygon(ring, srs=""):
    pos = " ".join(f"{x} {y}" for x, y in ring)
    return (
        f"<gml:Polygon{srs}><gml:exterior><gml:LinearRing><gml:posList>{pos}</gml:posList>"
        "</gml:LinearRing></gml:exterior></gml:Polygon>"
    )


def test_gml_parcels_are_fields(tmp_path):
    a = [(100000, 400000), (100200, 400000), (100200, 400100), (100000, 400100)]
    b = [(100300, 400000), (100500, 400000), (100500, 400150), (100300, 400150)]
    path = tmp_path / "parcels.gml"
    path.write_text(
        '<wfs:FeatureCollection xmlns:wfs="http://www.opengis.net/wfs/2.0" '
        'xmlns:gml="http://www.opengis.net/gml/3.2" xmlns:p="urn:example">'
        '<wfs:member><p:Parcel gml:id="parcel.1"><p:geom>'
        + _gml_polygon(a, ' srsName="EPSG:28992"')
        + "</p:geom></p:Parcel></wfs:member>"
        '<wfs:member><p:Parcel gml:id="parcel.2"><p:name>Meadow</p:name><p:geom>'
        '<gml:MultiSurface srsName="EPSG:28992"><gml:surfaceMember>'
        + _gml_polygon(b)
        + "</gml:surfaceMember></gml:MultiSurface></p:geom></p:Parcel></wfs:member>"
        "</wfs:FeatureCollection>"
    )
    areas = read_areas(path)
    assert [x.name for x in areas] == ["parcel.1", "Meadow"]
    assert [x.crs for x in areas] == ["EPSG:28992", "EPSG:28992"]  # the MultiSurface's srsName
    np.testing.assert_allclose(areas[1].ring, b)


def test_wkt_multipolygon_and_geometry_collection(tmp_path):
    path = tmp_path / "fields.wkt"
    path.write_text(
        "SRID=28992;MULTIPOLYGON (((0 0, 10 0, 10 10, 0 10, 0 0)), "
        "((20 0, 30 0, 30 10, 20 10, 20 0), (22 2, 24 2, 24 4, 22 4, 22 2)))"
    )
    areas = read_areas(path)
    assert [a.name for a in areas] == ["field 1", "field 2"]
    assert [len(a.holes) for a in areas] == [0, 1] and areas[0].crs == "EPSG:28992"
    path.write_text(
        "GEOMETRYCOLLECTION (POINT (1 1), POLYGON ((0 0, 10 0, 10 10, 0 10, 0 0)), "
        "MULTIPOLYGON (((20 0, 30 0, 30 10, 20 10, 20 0)), ((40 0, 50 0, 45 9, 40 0))))"
    )
    areas = read_areas(path)
    assert [len(a.ring) for a in areas] == [4, 4, 3]
    np.testing.assert_allclose(areas[2].ring, [(40, 0), (50, 0), (45, 9)])


def test_a_geometry_collection_with_one_polygon_reads_as_its_polygon(tmp_path):
    # QA: a GEOMETRYCOLLECTION holding one polygon (and a point) was refused ("expected a WKT
    # POLYGON or MULTIPOLYGON, got GEOMETRYCOLLECTION"), and read_area refused any collection
    path = tmp_path / "gc.wkt"
    path.write_text("GEOMETRYCOLLECTION (POINT (1 1), POLYGON ((0 0, 10 0, 10 10, 0 10, 0 0)))")
    (area,) = read_areas(path, crs="planar")
    assert area.name == "gc" and area.crs == "planar"
    np.testing.assert_allclose(area.ring, [(0, 0), (10, 0), (10, 10), (0, 10)])
    np.testing.assert_array_equal(read_area(path, crs="planar").ring, area.ring)
    path.write_text(
        "GEOMETRYCOLLECTION (POLYGON ((0 0, 10 0, 10 10, 0 0)), POLYGON ((20 0, 30 0, 25 9, 20 0)))"
    )
    np.testing.assert_allclose(read_area(path, crs="planar").ring, [(0, 0), (10, 0), (10, 10)])
    path.write_text("GEOMETRYCOLLECTION (POINT (1 1))")
    with pytest.raises(PolygonFileError, match="no polygon in the GEOMETRYCOLLECTION"):
        read_areas(path)


def test_one_field_reads_as_read_area(tmp_path):
    path = tmp_path / "one.geojson"
    path.write_text(json.dumps(_feature({}, [NORTH], id="x")))
    (area,) = read_areas(path)
    ref = read_area(path)
    assert area.name == ref.name == "one" and area.source == ref.source
    np.testing.assert_array_equal(area.ring, ref.ring)
    with pytest.raises(PolygonFileError, match="no such file"):
        read_areas(tmp_path / "missing.geojson")
    bad = tmp_path / "bad.wkt"
    bad.write_text("MULTIPOLYGON (((0 0, 1 0, 1 1, 0 0)), ((5 5, 6 5)))")
    with pytest.raises(PolygonFileError, match="polygon 2"):  # counted from 1, as --field
        read_areas(bad)


# -- the command ----------------------------------------------------------------------------
def _plan(args, capsys):
    assert main(["-q", "plan", *args, "--spacing", "10"]) == 0
    return capsys.readouterr().out


def test_json_is_a_list_of_one_plan_per_field(collection, capsys):
    out = json.loads(_plan([str(collection), "--json"], capsys))
    assert isinstance(out, list) and [o["name"] for o in out] == ["North", "s-7"]
    for o, area in zip(out, read_areas(collection), strict=True):
        ref = plan_area(area, 10.0)
        assert o["n_transects"] == ref.stats.n_transects
        assert o["path_length_m"] == pytest.approx(ref.stats.path_length)
    assert out[1]["holes"] == 1 and "holes" not in out[0]
    one = json.loads(_plan(["--json"], capsys))  # the embedded field: one object, as before
    assert isinstance(one, dict) and one["name"] == embedded_field().name


@pytest.mark.parametrize("pick,name", [("s-7", "s-7"), ("1", "North"), ("2", "s-7")])
def test_field_picks_one_by_name_or_index(collection, capsys, pick, name):
    out = json.loads(_plan([str(collection), "--json", "--field", pick], capsys))
    assert isinstance(out, dict) and out["name"] == name


def test_unknown_field_is_one_line_naming_the_fields(collection, capsys):
    assert main(["plan", str(collection), "--spacing", "10", "--field", "East"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "'North'" in err and "'s-7'" in err


def test_a_failing_field_is_named_and_nothing_is_written(tmp_path, capsys):
    path = tmp_path / "two.geojson"
    bowtie = [[5.0, 52.0], [5.002, 52.001], [5.002, 52.0], [5.0, 52.001], [5.0, 52.0]]
    doc = {"type": "FeatureCollection", "features": [_feature({"name": "Good"}, [NORTH])]}
    doc["features"].append(_feature({"name": "Bowtie"}, [bowtie]))
    path.write_text(json.dumps(doc))
    out = tmp_path / "m.geojson"
    assert main(["plan", str(path), "--spacing", "10", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "field 'Bowtie' (2 of 2)" in err and "'Good'" not in err
    assert not out.exists()
    assert main(["-q", "plan", str(path), "--spacing", "10", "--field", "Good"]) == 0


def _two_missions(collection):
    return [plan_area(a, 10.0, altitude=30.0) for a in read_areas(collection)]


def test_geojson_holds_every_field_read_by_gdal(collection, tmp_path, capsys):
    pyogrio = pytest.importorskip("pyogrio")
    out = tmp_path / "m.geojson"
    _plan([str(collection), "--altitude", "30", "--out", str(out)], capsys)
    meta, _, _, values = pyogrio.raw.read(out)
    props = dict(zip(meta["fields"], values, strict=True))
    for m in _two_missions(collection):
        mine = props["field"] == m.name
        assert int(np.sum(mine & (props["role"] == "waypoint"))) == len(m.waypoints)
        assert int(np.sum(mine & (props["role"] == "transect"))) == len(m.transects)
        assert int(np.sum(mine & (props["role"] == "area"))) == 1
    assert [s["name"] for s in json.loads(out.read_text())["boustro"]] == ["North", "s-7"]


def test_kml_has_a_folder_per_field_read_by_fastkml(collection, tmp_path, capsys):
    kml = pytest.importorskip("fastkml.kml")
    out = tmp_path / "m.kml"
    _plan([str(collection), "--altitude", "30", "--out", str(out)], capsys)
    doc = next(iter(kml.KML.from_string(out.read_bytes()).features))
    folders = {f.name: f for f in doc.features}
    missions = _two_missions(collection)
    assert list(folders) == [m.name for m in missions]
    for m in missions:
        marks = {f.name: f for f in folders[m.name].features if hasattr(f, "geometry")}
        path = np.array(marks["Path"].geometry.coords)[:, :2]
        np.testing.assert_allclose(path, m.waypoints_lonlat, atol=1e-9, rtol=0)


def test_a_kml_boustro_wrote_reads_back_with_its_fields_names(collection, tmp_path, capsys):
    """The area's placemark was named 'Area' (the field's name on the Document or Folder):
    read back, every field was 'Area' and ``--field North`` failed on boustro's own KML."""
    two, one = tmp_path / "m.kml", tmp_path / "one.kml"
    _plan([str(collection), "--out", str(two)], capsys)
    _plan([str(collection), "--field", "s-7", "--out", str(one)], capsys)
    assert [a.name for a in read_areas(two)] == ["North", "s-7"]
    assert [a.name for a in read_areas(one)] == ["s-7"] and read_area(one).name == "s-7"
    for path, pick in ((two, "North"), (two, "s-7"), (one, "s-7")):
        out = json.loads(_plan([str(path), "--field", pick, "--json"], capsys))
        ref = plan_area(read_areas(collection)[1 if pick == "s-7" else 0], 10.0)
        assert out["name"] == pick and out["n_transects"] == ref.stats.n_transects
    # a field without a name keeps the placemark's old name.
    unnamed = plan_area(read_areas(collection)[0], 10.0)
    assert "<name>Area</name>" in to_kml(replace(unnamed, name=""))


def test_gpx_has_a_route_per_field_read_by_gpxpy(collection, tmp_path, capsys):
    gpxpy = pytest.importorskip("gpxpy")
    out = tmp_path / "m.gpx"
    _plan([str(collection), "--altitude", "30", "--out", str(out)], capsys)
    gpx = gpxpy.parse(out.read_text())
    missions = _two_missions(collection)
    assert [r.name for r in gpx.routes] == [m.name for m in missions]
    for route, track, m in zip(gpx.routes, gpx.tracks, missions, strict=True):
        xy = np.array([[p.longitude, p.latitude] for p in route.points])
        np.testing.assert_allclose(xy, m.waypoints_lonlat, atol=1e-9, rtol=0)
        assert len(track.segments) == len(m.transects)


def test_csv_has_a_field_column(collection, tmp_path, capsys):
    out = tmp_path / "m.csv"
    _plan([str(collection), "--out", str(out)], capsys)
    rows = list(csv.DictReader(out.open()))
    for m in _two_missions(collection):
        mine = [r for r in rows if r["field"] == m.name]
        assert [int(r["seq"]) for r in mine] == list(range(len(m.waypoints)))
        xy = np.array([[float(r["lon"]), float(r["lat"])] for r in mine])
        np.testing.assert_allclose(xy, m.waypoints, atol=1e-12, rtol=0)


def test_plan_and_waypoints_and_plot_are_one_file_per_field(collection, tmp_path, capsys):
    mavwp = pytest.importorskip("pymavlink.mavwp")
    pytest.importorskip("matplotlib")
    missions = _two_missions(collection)
    args = [str(collection), "--altitude", "30", "--json"]
    out = json.loads(_plan([*args, "--out", str(tmp_path / "m.plan")], capsys))
    assert [o["written"] for o in out] == [
        [str(tmp_path / "m-North.plan")],
        [str(tmp_path / "m-s-7.plan")],
    ]
    for m in missions:
        doc = json.loads((tmp_path / f"m-{m.name}.plan").read_text())
        nav = [i for i in doc["mission"]["items"] if i["command"] == 16]
        assert len(nav) == len(m.waypoints)
    _plan(
        [*args, "--out", str(tmp_path / "m.waypoints"), "--plot", str(tmp_path / "p.png")], capsys
    )
    for m in missions:
        loader = mavwp.MAVWPLoader()
        assert (
            loader.load(str(tmp_path / f"m-{m.name}.waypoints")) == len(m.waypoints) + 1
        )  # home + waypoints
        assert (tmp_path / f"p-{m.name}.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not (tmp_path / "m.waypoints").exists() and not (tmp_path / "p.png").exists()


def test_file_names_are_safe_and_distinct():
    assert safe_name("../North field: 2") == "North_field_2"
    assert safe_name("///") == "field"
    assert (
        safe_name("日本 畑") == "日本_畑"
    )  # letters of any script kept (QA: "Feld Lärche" was "Feld_L_rche")
    taken: set[str] = set()
    assert field_path("out/m.plan", "a/b", taken) == "out/m-a_b.plan"
    assert field_path("out/m.plan", "a b", taken) == "out/m-a_b-2.plan"
    # QA round 18: a 300-character name was "File name too long" after every field was planned
    long = [safe_name(x * 300) for x in ("N", "畑")] + [safe_name("N" * 299 + "M")]
    assert all(len(n.encode()) <= 109 for n in long) and len(set(long)) == 3
    assert long[0].startswith("N" * 100 + "-") and long[1].startswith("畑" * 33 + "-")


def test_a_field_with_a_long_name_is_written(tmp_path, capsys):
    doc = {"type": "FeatureCollection", "features": []}
    for name in ("N" * 300, "N" * 299 + "M"):
        doc["features"].append(_feature({"name": name}, [NORTH]))
    path = tmp_path / "long.geojson"
    path.write_text(json.dumps(doc))
    out = tmp_path / "m.plan"
    assert main(["plan", str(path), "--spacing", "10", "--altitude", "30", "--out", str(out)]) == 0
    assert len(list(tmp_path.glob("m-*.plan"))) == 2


def test_fields_with_a_fixed_angle(collection, capsys):
    out = json.loads(_plan([str(collection), "--json", "--angle", "45"], capsys))
    assert [o["angle_deg"] for o in out] == pytest.approx([45.0, 45.0])
    assert [o["method"] for o in out] == ["exact-offset", "region-offset-grid"]


def test_kml_multigeometry_parts_and_duplicate_names(tmp_path, capsys):
    poly = "<Polygon><outerBoundaryIs><LinearRing><coordinates>{}</coordinates></LinearRing>"
    poly += "</outerBoundaryIs></Polygon>"
    path = tmp_path / "dup.kml"
    path.write_text(
        '<kml xmlns="http://www.opengis.net/kml/2.2"><Document>'
        "<Placemark><name>Farm</name><MultiGeometry>"
        + poly.format(_coords(NORTH))
        + poly.format(_coords(SOUTH))
        + "</MultiGeometry></Placemark><Placemark><name>Farm part 1</name>"
        + poly.format(_coords(SOUTH))
        + "</Placemark><Placemark>"
        + poly.format(_coords(NORTH))
        + "</Placemark></Document></kml>"
    )
    areas = read_areas(path)
    assert [a.name for a in areas] == ["Farm part 1", "Farm part 2", "Farm part 1", "field 4"]
    assert main(["plan", str(path), "--spacing", "10", "--field", "Farm part 1"]) == 2
    err = capsys.readouterr().err
    assert "2 fields have that name" in err and err.count("\n") == 1
    out = json.loads(_plan([str(path), "--field", "3", "--json"], capsys))
    assert out["name"] == "Farm part 1" and out["area_m2"] > 20000  # the southern one


def test_field_shows_only_its_own_reading_warnings(tmp_path, capsys, caplog):
    """QA round 13: ``--field`` printed the warnings of every feature of the file (here the
    open ring of the other field), not only the picked one's."""
    path = tmp_path / "two.geojson"
    doc = {"type": "FeatureCollection", "features": [_feature({"name": "Good"}, [NORTH])]}
    doc["features"].append(_feature({"name": "Open"}, [SOUTH[:-1]]))
    path.write_text(json.dumps(doc))
    assert main(["plan", str(path), "--spacing", "10", "--field", "Good"]) == 0
    assert "not closed" not in caplog.text
    caplog.clear()
    assert main(["plan", str(path), "--spacing", "10", "--field", "Open"]) == 0
    assert caplog.text.count("feature 2: the ring is not closed") == 1


def test_unknown_field_shows_no_field_warnings_before_its_error(tmp_path, capsys, caplog):
    """QA round 15: ``--field`` naming no field printed every field's reading warnings (the
    open ring of each) before its one-line error."""
    path = tmp_path / "two.geojson"
    doc = {"type": "FeatureCollection", "features": [_feature({"name": "Open"}, [SOUTH[:-1]])]}
    doc["features"].append(_feature({"name": "Good"}, [NORTH]))
    path.write_text(json.dumps(doc))
    assert main(["plan", str(path), "--spacing", "10", "--field", "Nope"]) == 2
    assert "not closed" not in caplog.text
    assert "no field of that name" in capsys.readouterr().err
