"""A CRS named in an input file never makes PROJ open a file; every pyproj error is one line.

A CRS from a file (GeoJSON ``crs`` member, GML ``srsName``) is an authority code or a WKT naming
no file; anything else is refused before pyproj sees it. ``--crs`` on the command line may be
any pyproj input, and PROJ's failures on it are one line (exit 2), never a traceback.
"""

from __future__ import annotations

import json

import pyproj
import pytest

from boustro.errors import InvalidParameterError, PolygonFileError
from boustro.io import area_from_json, area_from_kml, area_from_text
from boustro.io.crs import parse_crs, projection_for
from boustro.io.file_crs import crs_from_file

from .conftest import run_cli

RING = [[5.0, 52.0], [5.003, 52.0], [5.003, 52.002], [5.0, 52.002], [5.0, 52.0]]
RD_RING = [[155000, 463000], [155300, 463000], [155300, 463200], [155000, 463200]]
GRID = "/nonexistent-boustro-grid/ntv2_0.gsb"  # a path that is never there

GEOG = (
    'GEOGCRS["x",DATUM["WGS 84",ELLIPSOID["WGS 84",6378137,298.257223563]],'
    'CS[ellipsoidal,2],AXIS["lon",east],AXIS["lat",north],ANGLEUNIT["degree",0.0174532925199433]]'
)
HOSTILE = {
    "proj-nadgrids": f"+proj=longlat +datum=WGS84 +nadgrids={GRID}",
    "proj-geoidgrids": f"+proj=longlat +ellps=WGS84 +geoidgrids={GRID} +type=crs",
    "proj-init": f"+init={GRID}:4326",
    "proj-no-plus": f"proj=longlat nadgrids={GRID}",
    "grid-list": f"+proj=longlat +datum=WGS84 +nadgrids=@{GRID}",
    "wkt2-parameterfile": (
        f'BOUNDCRS[SOURCECRS[{GEOG}],TARGETCRS[{GEOG}],ABRIDGEDTRANSFORMATION["t",'
        f'METHOD["NTv2"],PARAMETERFILE["Latitude and longitude difference file","{GRID}"]]]'
    ),
    "wkt1-extension": (
        'PROJCS["x",GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563]],'
        'PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433]],PROJECTION["Mercator_1SP"],'
        'UNIT["metre",1],'
        f'EXTENSION["PROJ4","+proj=merc +datum=WGS84 +nadgrids={GRID}"]]'
    ),
    "projjson": json.dumps({"type": "GeographicCRS", "name": GRID}),
    "bare-path": GRID,
}


@pytest.fixture
def pyproj_never_sees(monkeypatch):
    """Fail the test if pyproj is asked to build a CRS or transformation naming ``GRID``."""
    seen: list[str] = []

    def guard(real):
        def call(*args, **kwargs):
            text = " ".join(str(a) for a in (*args, *kwargs.values()) if isinstance(a, str))
            if "nonexistent-boustro-grid" in text:
                seen.append(text)
                pytest.fail(f"pyproj was asked about a refused CRS: {text[:200]}")
            return real(*args, **kwargs)

        return call

    monkeypatch.setattr(pyproj.CRS, "from_user_input", guard(pyproj.CRS.from_user_input))
    monkeypatch.setattr(pyproj.CRS, "__init__", guard(pyproj.CRS.__init__))
    monkeypatch.setattr(pyproj.Transformer, "from_crs", guard(pyproj.Transformer.from_crs))
    return seen


def _one_line(code: int, err: str) -> str:
    lines = [line for line in err.strip().splitlines() if line]
    assert code == 2, err
    assert "Traceback" not in err and len(lines) == 1, err
    return lines[0]


@pytest.mark.parametrize("name", sorted(HOSTILE))
def test_a_hostile_crs_in_a_geojson_file_is_refused_before_pyproj(
    capsys, tmp_path, pyproj_never_sees, name
):
    area = tmp_path / "lake.geojson"
    crs = {"type": "name", "properties": {"name": HOSTILE[name]}}
    area.write_text(json.dumps({"type": "Polygon", "coordinates": [RING], "crs": crs}))
    out = tmp_path / "x.geojson"
    code, _, err = run_cli(capsys, "plan", area, "--spacing", "20", "--out", out)
    line = _one_line(code, err)
    assert str(area) in line and "--crs" in line and "refused" in line
    assert not out.exists()
    assert pyproj_never_sees == []


@pytest.mark.parametrize("name", ["proj-nadgrids", "wkt2-parameterfile", "bare-path"])
def test_a_hostile_gml_srs_name_is_refused_before_pyproj(pyproj_never_sees, name):
    pos = " ".join(f"{x} {y}" for x, y in RING)
    gml = (
        '<gml:Polygon xmlns:gml="http://www.opengis.net/gml/3.2" '
        f'srsName="{_xml_attr(HOSTILE[name])}">'
        f"<gml:exterior><gml:LinearRing><gml:posList>{pos}</gml:posList></gml:LinearRing>"
        "</gml:exterior></gml:Polygon>"
    )
    with pytest.raises(PolygonFileError, match=r"area\.gml: the file's CRS .* --crs"):
        area_from_text(gml, "area.gml")


def _xml_attr(text: str) -> str:
    return text.replace("&", "&amp;").replace('"', "&quot;").replace("<", "&lt;")


def test_a_linked_or_malformed_crs_member_is_refused():
    link = {"type": "link", "properties": {"href": f"file://{GRID}", "type": "proj4"}}
    with pytest.raises(PolygonFileError, match="does not follow links"):
        area_from_json({"type": "Polygon", "coordinates": [RING], "crs": link}, "a.json")
    for crs in ({"type": "name"}, {"type": "name", "properties": {"name": 4326}}, "EPSG:4326"):
        with pytest.raises(PolygonFileError, match=r"a\.json: "):
            area_from_json({"type": "Polygon", "coordinates": [RING], "crs": crs}, "a.json")


@pytest.mark.parametrize(
    ("name", "expected"),
    [
        ("EPSG:28992", "EPSG:28992"),
        ("epsg:28992", "EPSG:28992"),
        ("urn:ogc:def:crs:EPSG::28992", "EPSG:28992"),
        ("urn:ogc:def:crs:EPSG:9.8.15:28992", "EPSG:28992"),
        ("urn:x-ogc:def:crs:EPSG:28992", "EPSG:28992"),
        ("http://www.opengis.net/def/crs/EPSG/0/28992", "EPSG:28992"),
        ("https://www.opengis.net/def/crs/EPSG/0/28992", "EPSG:28992"),
        ("http://www.opengis.net/gml/srs/epsg.xml#28992", "EPSG:28992"),
        ("urn:ogc:def:crs:OGC:1.3:CRS84", "EPSG:4326"),
        ("OGC:CRS84", "EPSG:4326"),
        ("http://www.opengis.net/def/crs/OGC/1.3/CRS84", "EPSG:4326"),
    ],
)
def test_authority_codes_from_a_file_are_accepted(name, expected):
    assert crs_from_file(name) == expected


@pytest.mark.parametrize("name", ["EPSG:28992x", "EPSG:", "/etc/EPSG/28992", "+init=EPSG:28992"])
def test_near_authority_codes_are_refused(name):
    with pytest.raises(PolygonFileError, match="refused"):
        crs_from_file(name, "f")


@pytest.mark.parametrize("version", ["WKT1_GDAL", "WKT2_2019"])
def test_a_wkt_without_files_plans_as_its_epsg_code(capsys, tmp_path, version):
    wkt = pyproj.CRS("EPSG:28992").to_wkt(version)
    assert crs_from_file(wkt) == wkt
    results = []
    for crs in (wkt, "urn:ogc:def:crs:EPSG::28992"):
        area = tmp_path / "rd.geojson"
        member = {"type": "name", "properties": {"name": crs}}
        area.write_text(json.dumps({"type": "Polygon", "coordinates": [RD_RING], "crs": member}))
        code, out, err = run_cli(capsys, "plan", area, "--spacing", "20", "--json")
        assert code == 0, err
        results.append(json.loads(out))
    a, b = results
    assert a["n_transects"] == b["n_transects"] and a["bearing_deg"] == b["bearing_deg"]
    assert a["path_length_m"] == pytest.approx(b["path_length_m"], rel=1e-9)


def test_the_command_line_crs_overrides_a_refused_file_crs(capsys, tmp_path, pyproj_never_sees):
    area = tmp_path / "lake.geojson"
    crs = {"type": "name", "properties": {"name": HOSTILE["proj-nadgrids"]}}
    area.write_text(json.dumps({"type": "Polygon", "coordinates": [RING], "crs": crs}))
    code, _, err = run_cli(capsys, "plan", area, "--crs", "EPSG:4326", "--spacing", "20")
    assert code == 0, err


def test_a_pyproj_failure_on_a_command_line_crs_is_one_line(capsys, tmp_path):
    """PROJ accepts this CRS but cannot build its transformation (the grid is missing)."""
    area = tmp_path / "rd.json"
    area.write_text(json.dumps(RD_RING))
    rd = (
        "+proj=sterea +lat_0=52.15616055555555 +lon_0=5.38763888888889 +k=0.9999079 "
        f"+x_0=155000 +y_0=463000 +ellps=bessel +units=m +nadgrids={GRID} +type=crs"
    )
    out = tmp_path / "x.geojson"
    code, _, err = run_cli(capsys, "plan", area, "--crs", rd, "--spacing", "20", "--out", out)
    line = _one_line(code, err)
    assert "PROJ failed" in line and "coordinate reference system" in line
    assert not out.exists()
    with pytest.raises(InvalidParameterError, match="PROJ failed"):
        projection_for(RD_RING, rd)


def test_an_unparsable_command_line_crs_is_one_line(capsys, tmp_path):
    with pytest.raises(InvalidParameterError, match="unknown coordinate reference system"):
        parse_crs("+proj=nonsense +x=\n2")
    area = tmp_path / "a.json"
    area.write_text(json.dumps(RING))
    code, _, err = run_cli(capsys, "plan", area, "--crs", "+proj=nonsense", "--spacing", "20")
    assert "unknown coordinate reference system" in _one_line(code, err)


def test_ewkt_srid_stays_an_epsg_code():
    area = area_from_text("SRID=28992;POLYGON ((0 0, 10 0, 10 10, 0 0))")
    assert area.crs == "EPSG:28992"
    assert area_from_kml(
        '<gml:Polygon xmlns:gml="http://www.opengis.net/gml" srsName="EPSG:28992">'
        "<gml:exterior><gml:LinearRing><gml:posList>0 0 9 0 9 9 0 0</gml:posList>"
        "</gml:LinearRing></gml:exterior></gml:Polygon>"
    ).crs == ("EPSG:28992")
