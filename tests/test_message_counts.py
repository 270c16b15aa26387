"""Locations in messages count from 1, as ``--field INDEX`` does, and name the field (QA 19).

Round 18 left them counting features, polygons, parts, holes and positions from 0
(``two.kml: polygon 1`` was the second field) while ``--field 2`` picked that same field.
"""

from __future__ import annotations

import json

import pytest

from boustro.io import read_areas

from .conftest import run_cli

N = [[5.0, 52.0], [5.002, 52.0], [5.002, 52.001], [5.0, 52.001], [5.0, 52.0]]
S = [[5.0, 51.99], [5.003, 51.99], [5.0035, 51.991], [5.0, 51.9915], [5.0, 51.99]]
BOWTIE = [[5.0, 52.0], [5.002, 52.001], [5.002, 52.0], [5.0, 52.001], [5.0, 52.0]]
INSIDE = [[5.001, 51.9903], [5.0015, 51.9903], [5.0015, 51.9906], [5.001, 51.9906]]
OUTSIDE = [[6.001, 51.9903], [6.0015, 51.9903], [6.0015, 51.9906], [6.001, 51.9906]]


def _feature(name, coords, kind="Polygon"):
    geometry = {"type": kind, "coordinates": coords}
    return {"type": "Feature", "properties": {"name": name}, "geometry": geometry}


def _closed(ring):
    return [*ring, ring[0]]


def _kml(tmp_path):
    def placemark(name, rings):
        co = [" ".join(f"{x},{y}" for x, y in r) for r in rings]
        inner = "".join(
            f"<innerBoundaryIs><LinearRing><coordinates>{c}</coordinates></LinearRing>"
            "</innerBoundaryIs>"
            for c in co[1:]
        )
        return (
            f"<Placemark><name>{name}</name><Polygon><outerBoundaryIs><LinearRing><coordinates>"
            f"{co[0]}</coordinates></LinearRing></outerBoundaryIs>{inner}</Polygon></Placemark>"
        )

    body = placemark("good", [N]) + placemark("holed", [S, _closed(INSIDE), _closed(OUTSIDE)])
    path = tmp_path / "two.kml"
    path.write_text(
        f'<kml xmlns="http://www.opengis.net/kml/2.2"><Document>{body}</Document></kml>'
    )
    return path


def test_sources_count_from_1(tmp_path):
    path = tmp_path / "f.geojson"
    features = [_feature("a", [N]), _feature("b", [[N], [S, _closed(INSIDE)]], "MultiPolygon")]
    path.write_text(json.dumps({"type": "FeatureCollection", "features": features}))
    assert [a.source for a in read_areas(path)] == [
        f"{path}: feature 1",
        f"{path}: feature 2: part 1",
        f"{path}: feature 2: part 2",
    ]
    assert [a.source for a in read_areas(_kml(tmp_path))] == [
        f"{tmp_path / 'two.kml'}: polygon 1",
        f"{tmp_path / 'two.kml'}: polygon 2",
    ]


@pytest.mark.parametrize("ext", ["kml", "gpkg"])
def test_a_failing_field_is_named_and_counted_from_1(capsys, tmp_path, ext):
    path = _kml(tmp_path)
    if ext == "gpkg":  # read by GDAL: feature N is the N-th of the layer
        pyogrio = pytest.importorskip("pyogrio")
        gdf = pyogrio.read_dataframe(path)
        path = tmp_path / "two.gpkg"
        pyogrio.write_dataframe(gdf.rename(columns={"Name": "name"}), path)
    where = "polygon 2" if ext == "kml" else "feature 2"
    said = f"field 'holed' (2 of 2): {path}: {where}: hole 2 lies outside the shell"
    code, _, err = run_cli(capsys, "plan", path, "--spacing", "10")
    assert code == 2 and said in err and err.count("\n") == 1
    for pick in ("holed", "2"):  # one field: named all the same
        code, _, err = run_cli(capsys, "plan", path, "--spacing", "10", "--field", pick)
        said = f"boustro: error: field 'holed': {path}: {where}: hole 2 lies outside the shell"
        assert code == 2 and err.startswith(said), err


@pytest.mark.parametrize(
    ("text", "said"),
    [
        ("MULTIPOLYGON (((0 0, 1 0, 1 1, 0 0)), ((5 5, 6 5)))", "polygon 2: a polygon needs"),
        ("POLYGON ((0 0, 9 0, 9 9, 0 0), (1 1, 2 1, x 2))", "hole 1: position 3 must be two"),
    ],
)
def test_wkt_counts_from_1(tmp_path, text, said):
    path = tmp_path / "bad.wkt"
    path.write_text(text)
    with pytest.raises(Exception, match=said):
        read_areas(path)


def test_geojson_positions_and_the_feature_used_count_from_1(tmp_path, caplog):
    from boustro.errors import PolygonFileError
    from boustro.io import area_from_json

    with pytest.raises(PolygonFileError, match="position 2 must be a list"):
        area_from_json({"type": "Polygon", "coordinates": [[[0, 0], "x", [1, 1], [0, 0]]]})
    doc = {"type": "FeatureCollection", "features": [_feature("a", [N]), _feature("b", [S])]}
    area_from_json(doc, "f.geojson")
    assert "only the first (feature 1) is used" in caplog.text


def test_the_page_names_a_failing_field_as_plan_does():
    pytest.importorskip("starlette")
    from boustro.errors import BoustroError
    from boustro.web import plan_request

    doc = {
        "type": "FeatureCollection",
        "features": [_feature("good", [N]), _feature("bad", [BOWTIE])],
    }
    with pytest.raises(BoustroError, match=r"^field 'bad' \(2 of 2\): area: feature 2: the shell"):
        plan_request({"area": doc, "options": {"spacing": 20, "field": None}})
    with pytest.raises(BoustroError, match=r"^field 'bad': area: feature 2: the shell"):
        plan_request({"area": doc, "options": {"spacing": 20, "field": "bad"}})


def test_one_field_named_after_its_file_is_not_named_again(capsys, tmp_path):
    path = tmp_path / "bowtie.geojson"
    path.write_text(json.dumps({"type": "Polygon", "coordinates": [BOWTIE]}))
    code, _, err = run_cli(capsys, "plan", path, "--spacing", "10")
    assert code == 2 and err.startswith(f"boustro: error: {path}: the shell:"), err
