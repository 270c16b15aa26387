"""The JSON API of ``boustro serve``, in-process (Starlette's test client): the answer is the
``boustro plan --json`` object, every export format is read back by a real reader, every area
format is read from an upload, and bad input is one 4xx line, never a trace."""

from __future__ import annotations

import copy
import csv
import io
import json
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

import numpy as np
import pytest

from boustro.io import embedded_field
from boustro.io.formats import FORMATS
from boustro.mission import plan_area
from boustro.web import MAX_BODY_BYTES, MAX_VERTICES, create_app
from boustro.web import api as web_api
from boustro.web import app as web_app
from boustro.web import server as web_server
from boustro.web.recent import RecentPlans

from .conftest import run_cli
from .test_formats import assert_qgc_plan
from .test_read_formats import KML, PLAN

testclient = pytest.importorskip("starlette.testclient")
DATA = Path(__file__).parent / "data"
BOW_TIE = {"type": "Polygon", "coordinates": [[[5, 52], [5.01, 52.01], [5.01, 52], [5, 52.01]]]}
OPTIONS = {"spacing": 10, "altitude": 35, "speed": 3, "turn_time": 6, "turnaround": 4}


@pytest.fixture(scope="module")
def client():
    with testclient.TestClient(create_app(), base_url="http://127.0.0.1:8000") as c:
        yield c


@pytest.fixture(scope="module")
def embedded(client):
    return client.get("/api/embedded").json()


@pytest.fixture(scope="module")
def mission():
    """The mission the API must give for the embedded field with :data:`OPTIONS`."""
    return plan_area(embedded_field(), 10.0, altitude=35, speed=3, turn_time=6, turnaround=4)


def _error(response, status=400) -> str:
    assert response.status_code == status, response.text
    message = response.json()["error"]
    assert "\n" not in message and "Traceback" not in message
    return message


# -- the page ----------------------------------------------------------------------------------
def test_the_page_and_its_files_are_served_from_the_package(client):
    page = client.get("/")
    assert page.status_code == 200 and "text/html" in page.headers["content-type"]
    assert "default-src 'self'" in page.headers["content-security-policy"]
    scripts = [s for s in page.text.split('src="')[1:]]
    assert [s.split('"')[0] for s in scripts] == [
        "/static/leaflet/leaflet.js",
        "/static/planning.js",
        "/static/app.js",
    ]
    assert "http" not in page.text  # nothing fetched from elsewhere (no CDN)
    # the page names its icon (an empty data: URL, which the policy allows): without one the
    # browser asked for /favicon.ico and logged a 404 in the console at every load
    assert (
        '<link rel="icon" href="data:,">' in page.text
        and "data:" in page.headers["content-security-policy"].split("img-src")[1].split(";")[0]
    )
    leaflet = client.get("/static/leaflet/leaflet.js")
    assert leaflet.status_code == 200 and "Leaflet 1.9.4" in leaflet.text[:200]
    assert "BSD 2-Clause" in client.get("/static/leaflet/LICENSE").text
    for name in ("app.js", "planning.js"):
        js = client.get(f"/static/{name}").text
        assert "fetch(" in js and "https://" not in js and "http://" not in js


def test_config_lists_every_format_objective_and_limit(client):
    config = client.get("/api/config").json()
    assert set(config["formats"]) == set(FORMATS)
    assert "smith" in config["objectives"] and "fewest-transects" in config["objectives"]
    assert config["limits"]["vertices"] == MAX_VERTICES and config["tiles"] is None


def test_an_other_host_name_is_refused(client):
    assert client.get("/", headers={"host": "attacker.example"}).status_code == 400


# -- planning ----------------------------------------------------------------------------------
def test_the_answer_is_the_command_line_json_plus_geojson(client, embedded, capsys):
    answer = client.post("/api/plan", json={"area": embedded, "options": OPTIONS}).json()
    argv = ["plan", "--spacing", "10", "--altitude", "35", "--speed", "3", "--turn-time", "6"]
    code, out, _ = run_cli(capsys, "-q", *argv, "--turnaround", "4", "--json")
    assert code == 0
    cli = json.loads(out)
    assert set(answer) == set(cli) | {"geojson"}
    for key, value in cli.items():
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            assert answer[key] == pytest.approx(value, rel=1e-12), key
        else:
            assert answer[key] == value, key
    assert answer["objective"] == "time"  # a speed given: mission time, as on the command line
    assert answer["n_transects"] == cli["n_transects"] and answer["covered_share"] == pytest.approx(
        1.0
    )
    assert answer["certified"] and answer["gap"] <= 1e-3 * answer["duration_s"]
    roles = [f["properties"]["role"] for f in answer["geojson"]["features"]]
    assert roles.count("transect") == answer["n_transects"] and "path" in roles


def test_options_reach_the_planner(client, embedded):
    def plan(**options):
        body = {"area": embedded, "options": {"spacing": 10, **options}}
        response = client.post("/api/plan", json=body)
        assert response.status_code == 200, response.text
        return response.json()

    assert plan(spacing=20)["n_transects"] < plan()["n_transects"]
    assert plan(bearing=0)["bearing_deg"] == pytest.approx(0.0, abs=1e-6)
    assert plan(angle=30)["angle_deg"] == pytest.approx(30.0, abs=1e-6)
    fewest = plan(objective="fewest-transects")
    assert fewest["n_transects"] <= 19 and fewest["objective"] == "fewest-transects"
    assert plan(objective="fewest_transects")["n_transects"] == fewest["n_transects"]  # as --json
    camera = plan(spacing=None, camera=[13.2, 8.8, 5472], altitude=80)
    assert camera["spacing_m"] == pytest.approx(36.0) and "camera" in camera["sensor"]
    swath = plan(spacing=None, swath=20, overlap=10, nadir_gap=2)
    assert swath["spacing_m"] == pytest.approx(8.1) and swath["nadir_gap_m"] == 2
    chords = plan(layout="chords", method="hybrid")
    assert chords["layout"] == "chords" and chords["method"] == "hybrid"
    start = embedded["features"][0]["geometry"]["coordinates"][0][5]
    first = plan(start=start)["geojson"]["features"][1]["geometry"]["coordinates"][0]
    far = plan()["geojson"]["features"][1]["geometry"]["coordinates"][0]
    assert np.hypot(*np.subtract(first, start)) < np.hypot(*np.subtract(far, start))


def test_vehicle_headland_and_keep_inside_reach_the_planner(client, embedded):
    def plan(**options):
        body = {"area": embedded, "options": {"spacing": 10, **options}}
        response = client.post("/api/plan", json=body)
        assert response.status_code == 200, response.text
        return response.json()

    assert plan()["outside_length_m"] > 0
    assert plan(keep_inside=True)["outside_length_m"] == pytest.approx(0.0, abs=1e-6)
    tractor = plan(turn_radius=6, reverse=True, headland=1)
    assert tractor["vehicle"]["turn_radius_m"] == 6 and tractor["vehicle"]["reverse"] is True
    assert tractor["headland_passes"] == 1 and tractor["covered_share"] >= 1 - 1e-9
    expected = plan_area(embedded_field(), 10.0, keep_inside=True).summary()
    assert plan(keep_inside=True)["path_length_m"] == pytest.approx(expected["path_length_m"])


def test_holes_and_several_fields(client):
    outer = [[5, 52], [5.004, 52], [5.004, 52.003], [5, 52.003], [5, 52]]
    hole = [[5.001, 52.001], [5.002, 52.001], [5.002, 52.002], [5.001, 52.002], [5.001, 52.001]]
    square = {"type": "Polygon", "coordinates": [outer, hole]}
    answer = client.post("/api/plan", json={"area": square, "options": {"spacing": 20}}).json()
    assert answer["holes"] == 1 and answer["covered_share"] == pytest.approx(1.0)
    feature = {"type": "Feature", "properties": {"name": "a"}, "geometry": square}
    other = copy.deepcopy(feature)
    other["properties"]["name"] = "b"
    other["geometry"]["coordinates"] = [[[x + 0.01, y] for x, y in outer]]
    both = {"type": "FeatureCollection", "features": [feature, other]}
    answers = client.post("/api/plan", json={"area": both, "options": {"spacing": 20}}).json()
    assert [a["name"] for a in answers] == ["a", "b"]
    picked = {"spacing": 20, "field": "b"}
    assert client.post("/api/plan", json={"area": both, "options": picked}).json()["name"] == "b"
    csv_text = client.post(
        "/api/export", json={"area": both, "options": {"spacing": 20}, "format": "csv"}
    ).text
    assert {row["field"] for row in csv.DictReader(io.StringIO(csv_text))} == {"a", "b"}
    refused = client.post(
        "/api/export", json={"area": both, "options": {"spacing": 20}, "format": "plan"}
    )
    assert "options.field" in _error(refused)


def test_the_estimate(client, embedded):
    est = client.post("/api/estimate", json={"area": embedded, "options": {"spacing": 10}}).json()
    (field,) = est["fields"]
    assert 0 < field["seconds"] < est["limit_seconds"] and "19 vertices" in field["text"]


# -- every export format, read back by a real reader -----------------------------------------
def _export(client, embedded, fmt, **options):
    body = {"area": embedded, "options": {**OPTIONS, **options}, "format": fmt}
    response = client.post("/api/export", json=body)
    assert response.status_code == 200, response.text
    assert response.headers["content-disposition"].startswith("attachment; filename=")
    return response


def test_every_format_is_exported_and_read_back(client, embedded, mission, tmp_path):
    pyogrio = pytest.importorskip("pyogrio")
    gpxpy = pytest.importorskip("gpxpy")
    fastkml = pytest.importorskip("fastkml.kml")
    mavwp = pytest.importorskip("pymavlink.mavwp")
    lonlat = mission.waypoints_lonlat
    got = {}
    for fmt in FORMATS:
        response = _export(client, embedded, fmt)
        path = tmp_path / response.headers["content-disposition"].split('"')[1]
        path.write_bytes(response.content)
        got[fmt] = path
    assert got["plan"].name == "test_parcel.plan"
    doc = json.loads(got["geojson"].read_text())
    path = next(f for f in doc["features"] if f["properties"]["role"] == "path")
    np.testing.assert_allclose(path["geometry"]["coordinates"], lonlat, atol=1e-12)
    geometries = pyogrio.raw.read(got["geojson"])[2]  # GDAL reads every feature
    assert len(geometries) == len(doc["features"])
    kml = next(iter(fastkml.KML.from_string(got["kml"].read_bytes()).features))
    placemarks = {f.name: f for f in kml.features if hasattr(f, "geometry")}
    np.testing.assert_allclose(np.array(placemarks["Path"].geometry.coords)[:, :2], lonlat)
    (route,) = gpxpy.parse(got["gpx"].read_text()).routes
    np.testing.assert_allclose([[p.longitude, p.latitude] for p in route.points], lonlat)
    rows = list(csv.DictReader(got["csv"].open(newline="")))
    np.testing.assert_array_equal([[float(r["lon"]), float(r["lat"])] for r in rows], lonlat)
    assert_qgc_plan(json.loads(got["plan"].read_text()), mission, speed=3.0)
    loader = mavwp.MAVWPLoader()
    assert loader.load(str(got["wpl"])) == len(lonlat) + 2  # home, speed, the waypoints


def test_a_download_of_the_plan_just_answered_is_not_planned_again(embedded, monkeypatch):
    calls = []
    real = web_api.plan_area
    monkeypatch.setattr(web_api, "plan_area", lambda *a, **k: calls.append(1) or real(*a, **k))
    body = {"area": embedded, "options": {"spacing": 10, "altitude": 40}}
    with testclient.TestClient(create_app(), base_url="http://127.0.0.1") as c:
        planned = c.post("/api/plan", json=body)
        steps = [part.split(";")[0] for part in planned.headers["server-timing"].split(", ")]
        assert planned.status_code == 200 and steps == ["parse", "plan", "answer", "encode"]
        assert len(calls) == 1
        # the same area and options (in another order), plus a format: the plan answered
        same = {"format": "plan", "options": {"altitude": 40, "spacing": 10}, "area": embedded}
        kept = c.post("/api/export", json=same)
        assert kept.status_code == 200 and len(calls) == 1
        other = {**body, "options": {"spacing": 12, "altitude": 40}, "format": "plan"}
        assert c.post("/api/export", json=other).status_code == 200 and len(calls) == 2
    assert kept.content == web_api.export_request({**body, "format": "plan"})[0]  # planned anew
    assert len(calls) == 3


def test_a_bad_export_is_refused_whether_its_plan_is_kept_or_not(embedded):
    body = {"area": embedded, "options": {"spacing": 10}}
    with testclient.TestClient(create_app(), base_url="http://127.0.0.1") as c:
        assert c.post("/api/plan", json=body).status_code == 200
        bad = {**body, "format": "kml", "bogus": 1}
        for _ in range(2):
            answer = c.post("/api/export", json=bad)
            assert answer.status_code == 400 and "bogus" in answer.json()["error"]


def test_recent_plans_keep_the_last_few():
    recent = RecentPlans(size=2)
    bodies = [{"area": {"type": "Polygon", "n": k}, "options": {"spacing": 10}} for k in range(3)]
    for k, body in enumerate(bodies):
        recent.put(body, [k])  # type: ignore[list-item]
    assert recent.get(bodies[0]) is None and recent.get(bodies[2]) == [2] and len(recent) == 2
    assert recent.get({**bodies[1], "format": "kml"}) == [1]
    assert recent.get({"area": float("nan")}) is None and recent.get([]) is None


def test_a_mission_format_without_an_altitude_says_so(client, embedded):
    body = {"area": embedded, "options": {"spacing": 10}, "format": "plan"}
    assert "altitude" in _error(client.post("/api/export", json=body))
    body["format"] = "shapefile"
    assert "format must be one of" in _error(client.post("/api/export", json=body))


# -- every area format, uploaded -------------------------------------------------------------
def _read(client, name, data, **params):
    return client.post(
        "/api/read",
        params={"name": name, **params},
        content=data if isinstance(data, bytes) else data.encode(),
        headers={"content-type": "application/octet-stream"},
    )


def _ring(response):
    assert response.status_code == 200, response.text
    features = response.json()["features"]
    return features, np.array(features[0]["geometry"]["coordinates"][0])


def test_a_file_is_read_while_a_plan_runs(client):
    # Opening a file on the page while a plan runs (another client's, or the page's own long
    # one) waited for the plan lock: the page showed nothing, neither a bar nor the field, for
    # up to the plan's 60 s. Reading plans nothing, so it does not queue behind plans.
    import threading

    answer: list = []
    with web_app._PLAN_LOCK:  # a plan running
        reader = threading.Thread(target=lambda: answer.append(_read(client, "f.kml", KML)))
        reader.start()
        reader.join(timeout=10)
        read_during_the_plan = not reader.is_alive()
    reader.join()
    assert read_during_the_plan, "the upload waited for the running plan"
    assert answer[0].status_code == 200, answer[0].text


def test_files_read_at_once_leave_the_warnings_of_the_process_as_they_were(client, tmp_path):
    # Reads run at once since /api/read left the plan lock; GDAL's reader recorded warnings
    # with warnings.catch_warnings, whose enter/exit on two threads interleaved left a finished
    # read's list as the process's printer: every later warning of the server went into it.
    import threading
    import warnings

    pyogrio = pytest.importorskip("pyogrio")
    import shapely

    path = tmp_path / "f.gpkg"
    wkb = np.array([shapely.to_wkb(shapely.box(5.0, 52.0, 5.003, 52.002))], dtype=object)
    pyogrio.raw.write(str(path), wkb, [np.array(["a"], dtype=object)], ["name"],
                      crs="EPSG:4326", driver="GPKG", geometry_type="Polygon")  # fmt: skip
    data = path.read_bytes()
    filters, printer = list(warnings.filters), warnings._showwarnmsg_impl  # type: ignore[attr-defined]
    codes: list[int] = []

    def reads() -> None:
        codes.extend(_read(client, "f.gpkg", data).status_code for _ in range(15))

    readers = [threading.Thread(target=reads) for _ in range(4)]
    for reader in readers:
        reader.start()
    for reader in readers:
        reader.join()
    assert codes == [200] * 60
    assert warnings._showwarnmsg_impl is printer  # type: ignore[attr-defined]
    assert warnings.filters == filters


def test_every_area_format_is_read_from_an_upload(client):
    square = [[5.0, 52.0], [5.003, 52.0], [5.003, 52.002], [5.0, 52.002], [5.0, 52.0]]
    geojson = json.dumps({"type": "Polygon", "coordinates": [square]})
    kml = KML.format(name="kml field")
    kmz = io.BytesIO()
    with zipfile.ZipFile(kmz, "w") as zf:
        zf.writestr("doc.kml", kml)
    wkt = "POLYGON ((5 52, 5.003 52, 5.003 52.002, 5 52.002, 5 52))"
    for name, data in [
        ("f.geojson", geojson),
        ("f.kml", kml),
        ("f.kmz", kmz.getvalue()),
        ("f.wkt", wkt),
        ("m.plan", json.dumps(PLAN)),
    ]:
        features, ring = _ring(_read(client, name, data))
        np.testing.assert_allclose(ring, square, atol=1e-12, err_msg=name)
    assert [f["properties"]["name"] for f in features] == ["survey 2", "geofence 1"]
    assert _ring(_read(client, "f.kml", kml))[0][0]["properties"]["name"] == "kml field"
    features, ring = _ring(_read(client, "Envelope.xml", (DATA / "Envelope.xml").read_bytes()))
    assert features[0]["properties"]["crs"] == "EPSG:4258"
    assert 4.25 < ring[:, 0].min() < ring[:, 0].max() < 4.27 and 51.78 < ring[:, 1].min() < 51.8
    rd = "POLYGON ((155000 463000, 155200 463000, 155200 463150, 155000 463150, 155000 463000))"
    _, ring = _ring(_read(client, "rd.wkt", rd, crs="EPSG:28992"))
    assert 5.38 < ring[0, 0] < 5.39 and 52.15 < ring[0, 1] < 52.16  # Amersfoort, lon/lat


def test_an_upload_is_read_in_a_temporary_directory_only(client, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    scratch = tmp_path / "scratch"
    scratch.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(scratch))
    wkt = "POLYGON ((5 52, 5.003 52, 5.003 52.002, 5 52.002, 5 52))"
    assert _read(client, "../../etc/evil.wkt", wkt).status_code == 200
    assert _read(client, "broken.kml", "<kml>").status_code == 400
    assert [p.name for p in tmp_path.iterdir()] == ["scratch"] and not any(scratch.iterdir())


def test_a_bad_upload_names_the_upload_not_the_temporary_file(client):
    message = _error(_read(client, "mine.kml", "<kml><Document></Document></kml>"))
    assert "mine.kml" in message and "boustro-web-" not in message


# -- bad input: one 4xx line -----------------------------------------------------------------
def test_a_bow_tie_is_refused_with_the_reason(client):
    message = _error(client.post("/api/plan", json={"area": BOW_TIE, "options": {"spacing": 10}}))
    assert "self-intersecting" in message.lower() and "Self-intersection at" in message
    assert "try options.repair" in message
    repaired = {"spacing": 10, "repair": True}
    assert "options.repair splits the area into 2 polygons" in _error(
        client.post("/api/plan", json={"area": BOW_TIE, "options": repaired})
    )


def test_nan_and_infinity_are_refused(client, embedded):
    for text in ("NaN", "Infinity", "-Infinity"):
        body = f'{{"area": {json.dumps(embedded)}, "options": {{"spacing": {text}}}}}'
        response = client.post(
            "/api/plan", content=body, headers={"content-type": "application/json"}
        )
        assert "non-finite" in _error(response)
        coords = json.dumps(BOW_TIE).replace("5.01, 52.01", f"{text}, 52.01")
        response = client.post(
            "/api/plan",
            content=f'{{"area": {coords}, "options": {{"spacing": 10}}}}',
            headers={"content-type": "application/json"},
        )
        assert "non-finite" in _error(response)


def test_a_spacing_whose_figures_overflow_is_refused(client, embedded, recwarn):
    """QA round 19: ``spacing: 1e300`` was planned (200) with shapely's overflow warnings in
    the server's log; it is refused as ``boustro plan`` refuses it (one rule, plan_area's)."""
    message = _error(
        client.post("/api/plan", json={"area": embedded, "options": {"spacing": 1e300}})
    )
    assert "spacing 1e+300 is too wide: at most 1e+100" in message
    assert not [w for w in recwarn if "overflow" in str(w.message)]


def test_only_epsg_codes_name_a_crs(client, embedded):
    for crs in ("+proj=utm +zone=31 +datum=WGS84", "+init=/etc/passwd", 'PROJCS["x"]', True):
        body = {"area": embedded, "options": {"spacing": 10, "crs": crs}}
        assert "EPSG code" in _error(client.post("/api/plan", json=body))
    area = copy.deepcopy(embedded)
    area["crs"] = {"type": "name", "properties": {"name": "+proj=longlat +nadgrids=@x.gsb"}}
    assert "EPSG code" in _error(
        client.post("/api/plan", json={"area": area, "options": {"spacing": 10}})
    )
    area["crs"] = {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::4326"}}
    assert client.post("/api/plan", json={"area": area, "options": {"spacing": 10}}).is_success
    area["crs"] = {"type": "name", "properties": {"name": "EPSG:28992"}}  # the member is used
    answer = client.post("/api/plan", json={"area": area, "options": {"spacing": 10}}).json()
    assert answer["crs"] == "EPSG:28992"
    body = {"area": area, "options": {"spacing": 10, "crs": "EPSG:4326"}}  # options win
    assert client.post("/api/plan", json=body).json()["crs"] == "EPSG:4326"
    wkt = "POLYGON ((5 52, 5.003 52, 5.003 52.002, 5 52.002, 5 52))"
    assert "EPSG code" in _error(_read(client, "f.wkt", wkt, crs="+proj=longlat"))


def test_a_huge_request_is_refused_before_it_is_read(client):
    big = b"{" + b" " * MAX_BODY_BYTES + b"}"
    response = client.post("/api/plan", content=big, headers={"content-type": "application/json"})
    assert "over the limit" in _error(response, 413)
    assert "over the limit" in _error(_read(client, "f.kml", big), 413)


def test_too_many_vertices_and_too_much_work_are_refused(client):
    t = np.linspace(0, 2 * np.pi, MAX_VERTICES + 1, endpoint=False)
    ring = np.column_stack([5 + 0.01 * np.cos(t), 52 + 0.01 * np.sin(t)]).tolist()
    body = {"area": {"type": "Polygon", "coordinates": [[*ring, ring[0]]]}, "options": {}}
    body["options"] = {"spacing": 10}
    assert "vertices" in _error(client.post("/api/plan", json=body), 413)
    square = [[5, 52], [5.5, 52], [5.5, 52.5], [5, 52.5], [5, 52]]
    hole = [[5.1, 52.1], [5.2, 52.1], [5.2, 52.2], [5.1, 52.2], [5.1, 52.1]]
    body = {"area": {"type": "Polygon", "coordinates": [square, hole]}, "options": {"spacing": 1}}
    assert "limit" in _error(client.post("/api/plan", json=body), 413)


@pytest.mark.parametrize(
    "body, expected",
    [
        ({"options": {"spacing": 10}}, 'no "area"'),
        (
            {"area": {"type": "Point", "coordinates": [5, 52]}, "options": {"spacing": 10}},
            "Polygon",
        ),
        ({"area": "POLYGON", "options": {"spacing": 10}}, "GeoJSON object"),
        ({"area": BOW_TIE, "options": {"spacing": -1}}, "options.spacing must be > 0"),
        ({"area": BOW_TIE, "options": {"spacing": "ten"}}, "must be a number"),
        ({"area": BOW_TIE, "options": {"spacing": "10"}}, "options.spacing must be a number"),
        ({"area": BOW_TIE, "options": {"spacing": 1, "speed": "5"}}, "options.speed must be"),
        ({"area": BOW_TIE, "options": {"camera": ["13.2", 8.8, 5472]}}, "options.camera must"),
        ({"area": BOW_TIE, "options": {"spacing": 1, "headland": "2"}}, "options.headland must"),
        ({"area": BOW_TIE, "options": {"spacing": 1, "start": ["5", 52]}}, "options.start must"),
        ({"area": BOW_TIE, "options": {}}, "exactly one of options.spacing"),
        ({"area": BOW_TIE, "options": {"spacing": 1, "warp": 9}}, "unknown option(s) 'warp'"),
        ({"area": BOW_TIE, "options": {"spacing": 1, "turn_time": 5}}, "options.turn_time needs"),
        ({"area": BOW_TIE, "options": {"spacing": 1, "layout": "x"}}, "options.layout"),
        ({"area": BOW_TIE, "options": {"spacing": 1, "start": [1]}}, "options.start"),
        (
            {"area": BOW_TIE, "options": {"spacing": 1, "reverse": True}},
            "needs options.turn_radius",
        ),
        ({"area": BOW_TIE, "options": {"spacing": 1, "turn_radius": 0}}, "options.turn_radius"),
        ({"area": BOW_TIE, "options": {"spacing": 1, "headland": 1.5}}, "options.headland"),
        ({"area": BOW_TIE, "options": {"spacing": 1, "keep_inside": 1}}, "options.keep_inside"),
        ({"area": BOW_TIE, "extra": 1}, "unknown member(s) 'extra'"),
        ([1, 2], "JSON object"),
    ],
)
def test_bad_requests_are_one_line(client, body, expected):
    assert expected in _error(client.post("/api/plan", json=body))


def test_malformed_json_and_the_wrong_content_type(client):
    response = client.post("/api/plan", content=b"{", headers={"content-type": "application/json"})
    assert "malformed JSON" in _error(response)
    response = client.post("/api/plan", content=b"{}", headers={"content-type": "text/plain"})
    assert "application/json" in _error(response)


def test_an_unexpected_failure_is_a_500_line_without_a_trace(client, embedded, monkeypatch):
    def boom(body):
        raise RuntimeError("secret internal detail")

    monkeypatch.setattr(web_app, "plan_request", boom)
    response = client.post("/api/plan", json={"area": embedded, "options": {"spacing": 10}})
    assert response.status_code == 500
    assert "secret" not in response.text and "RuntimeError" in response.json()["error"]


# -- the server and the command --------------------------------------------------------------
def test_serve_binds_to_this_machine_by_default(monkeypatch, capsys):
    uvicorn = pytest.importorskip("uvicorn")
    calls = []
    monkeypatch.setattr(uvicorn, "run", lambda app, **kw: calls.append(kw))
    code, _, err = run_cli(capsys, "serve", "--port", "8123")
    assert code == 0 and calls == [{"host": "127.0.0.1", "port": 8123, "log_level": "info"}]
    assert "http://127.0.0.1:8123/" in err
    code, _, err = run_cli(capsys, "serve", "--port", "70000")
    assert code == 2 and "--port" in err
    code, _, err = run_cli(capsys, "serve", "--threads", "0")
    assert code == 2 and "--threads" in err


def test_serve_plans_on_one_torch_thread_and_restores_them(monkeypatch, capsys):
    uvicorn = pytest.importorskip("uvicorn")
    torch = pytest.importorskip("torch")
    during = []
    monkeypatch.setattr(uvicorn, "run", lambda app, **kw: during.append(torch.get_num_threads()))
    before = torch.get_num_threads()
    torch.set_num_threads(2)
    try:
        assert run_cli(capsys, "serve")[0] == 0 and during == [1]
        assert torch.get_num_threads() == 2
        assert run_cli(capsys, "serve", "--threads", "3")[0] == 0 and during == [1, 3]
        assert torch.get_num_threads() == 2
    finally:
        torch.set_num_threads(before)
    code, _, err = run_cli(capsys, "serve", "--port", "70000")
    assert code == 2 and "--port" in err
    code, _, err = run_cli(capsys, "serve", "--tiles", "file:///etc/passwd")
    assert code == 2 and "--tiles must be an http(s) URL" in err


def test_serve_without_the_extra_names_it(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "uvicorn", None)
    code, _, err = run_cli(capsys, "serve")
    assert code == 2 and "pip install 'boustro[web]'" in err
    monkeypatch.setitem(sys.modules, "starlette.applications", None)
    with pytest.raises(ImportError, match=r"boustro\[web\]"):
        web_server.create_app()


def test_a_tile_server_is_allowed_by_the_page_policy():
    app = create_app(tiles="https://{s}.tiles.example/{z}/{x}/{y}.png")
    with testclient.TestClient(app, base_url="http://127.0.0.1") as c:
        assert "https://*.tiles.example" in c.get("/").headers["content-security-policy"]
        assert c.get("/api/config").json()["tiles"].startswith("https://{s}.tiles.example")


def test_import_boustro_loads_no_web_framework():
    names = ("starlette", "uvicorn", "boustro.web")
    code = f"import sys, boustro; print([m for m in {names!r} if m in sys.modules])"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_every_file_of_the_page_is_package_data():
    """The wheel ships the page and Leaflet (checked on pyproject.toml; a wheel build is slow)."""
    import fnmatch
    import re

    root = Path(__file__).resolve().parents[1]
    text = (root / "pyproject.toml").read_text()
    globs = re.findall(r'"([^"]+)"', re.search(r"^boustro = \[(.*)\]$", text, re.M).group(1))
    static = root / "src" / "boustro" / "web" / "static"
    files = [p.relative_to(root / "src" / "boustro").as_posix() for p in static.rglob("*")]
    missing = [f for f in files if (static.parent.parent / f).is_file()]
    missing = [f for f in missing if not any(fnmatch.fnmatch(f, g) for g in globs)]
    assert not missing, missing
    assert "src/boustro/web/static/leaflet/LICENSE" in text  # its licence in the metadata too


def test_a_hole_touching_the_shell_at_a_point_is_planned(client):
    """QA round 13: as ``boustro plan``, a hole touching the shell at one point (valid for
    GEOS) is cut back from it and planned (it was HTTP 400)."""
    outer = [[5, 52], [5.004, 52], [5.004, 52.003], [5, 52.003], [5, 52]]
    hole = [[5.002, 52], [5.0025, 52.001], [5.0015, 52.001], [5.002, 52]]
    square = {"type": "Polygon", "coordinates": [outer, hole]}
    response = client.post("/api/plan", json={"area": square, "options": {"spacing": 20}})
    assert response.status_code == 200, response.text
    assert response.json()["covered_share"] == pytest.approx(1.0)
