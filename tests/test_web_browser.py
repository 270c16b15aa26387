"""The page of ``boustro serve`` in a REAL headless browser: the system's Chromium
(``/usr/bin/chromium``; ``.ci/run`` installs Debian's ``chromium`` when it is absent) driven by
Playwright, against the real server (uvicorn) in a subprocess on 127.0.0.1.

Draw a polygon by mouse events, see the lanes, change the spacing, download the ``.plan`` and
check it, drop a KML file, see the error of a bow-tie; and the time from the last edit to the
drawn plan on the embedded field and on a 1000-vertex field (printed; ``benchmarks/web.py``
measures it with repeats)."""

from __future__ import annotations

import json
import math
import os
import socket
import statistics
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import numpy as np
import pytest

from boustro.geometry.traced import traced_field
from boustro.mission import plan_area

from .test_formats import assert_qgc_plan
from .test_read_formats import KML

sync_api = pytest.importorskip("playwright.sync_api")
CHROMIUM = os.environ.get("BOUSTRO_CHROMIUM", "/usr/bin/chromium")
ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-dev-shm-usage",
]
ROOT = Path(__file__).resolve().parents[1]


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture(scope="module")
def server():
    port = _free_port()
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    proc = subprocess.Popen(
        [sys.executable, "-m", "boustro", "-q", "serve", "--port", str(port)],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    url = f"http://127.0.0.1:{port}"
    try:
        for _ in range(240):
            try:
                urllib.request.urlopen(url + "/api/config", timeout=2).read()
                break
            except OSError:
                assert proc.poll() is None, proc.stderr.read().decode() if proc.stderr else ""
                time.sleep(0.25)
        else:
            pytest.fail("the server did not start in 60 s")
        yield url
    finally:
        proc.terminate()
        proc.wait(timeout=20)


@pytest.fixture(scope="module")
def browser():
    if not os.path.exists(CHROMIUM):
        pytest.fail(f"{CHROMIUM} is missing: apt-get install chromium (.ci/run does)")
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS, headless=True)
        yield b
        b.close()


@pytest.fixture
def page(browser, server):
    context = browser.new_context(viewport={"width": 1200, "height": 800}, accept_downloads=True)
    pg = context.new_page()
    errors: list[str] = []
    pg.on("pageerror", lambda exc: errors.append(str(exc)))
    pg.goto(server + "/")
    _until(pg, "window.boustro && window.boustro.ready === true")
    yield pg
    context.close()
    assert not errors, errors


def _until(page, expression: str, timeout: float = 60_000) -> None:
    """Poll ``expression`` in the page until it is true (``page.wait_for_function`` evaluates
    a string, which the page's Content-Security-Policy forbids, as it should)."""
    end = time.monotonic() + timeout / 1000
    while not page.evaluate(expression):
        if time.monotonic() > end:
            state = page.evaluate(
                "[window.boustro.inFlight, document.getElementById('error').textContent]"
            )
            pytest.fail(f"timed out waiting for {expression} (in flight, error: {state})")
        time.sleep(0.02)


def _wait_plan(page, seq: int, timeout: float = 60_000) -> None:
    _until(page, f"window.boustro.planSeq > {seq}", timeout)


def _lanes(page) -> int:
    return page.locator("path.lane").count()


def _draw(page, points) -> None:
    """Click 'Draw area', click each point of the map (pixels), click the first to close."""
    page.click("#draw")
    box = page.locator("#map").bounding_box()
    for x, y in [*points, points[0]]:
        page.mouse.move(box["x"] + x, box["y"] + y)
        page.mouse.click(box["x"] + x, box["y"] + y)


def _set(page, selector: str, value: str) -> int:
    seq = page.evaluate("window.boustro.planSeq")
    page.fill(selector, value)
    return seq


def _drop(page, name: str, text: str) -> None:
    """Drop a file on the map as a user drags one from the desktop."""
    page.evaluate(
        """([name, text]) => {
            const dt = new DataTransfer();
            dt.items.add(new File([text], name));
            const map = document.getElementById("map");
            map.dispatchEvent(new DragEvent("dragover", {dataTransfer: dt, bubbles: true}));
            map.dispatchEvent(new DragEvent("drop", {dataTransfer: dt, bubbles: true}));
        }""",
        [name, text],
    )


def test_draw_plan_change_spacing_and_download_the_plan(page, tmp_path):
    _draw(page, [(500, 250), (800, 260), (820, 520), (520, 560)])
    _wait_plan(page, 0)
    assert page.evaluate("window.boustro.outer.length") == 4
    before = _lanes(page)
    assert before >= 5  # a field of ~ 290 m across at 10 m
    assert "certified optimum" in page.inner_text("#summary")
    seq = _set(page, "#spacing", "20")
    _wait_plan(page, seq)
    after = _lanes(page)
    assert 0 < after < before
    assert page.locator("#progress").is_hidden() and page.locator("#error").is_hidden()
    with page.expect_download() as info:
        page.click("#downloads button[data-format=plan]")
    path = tmp_path / info.value.suggested_filename
    info.value.save_as(path)
    assert path.suffix == ".plan"
    ring = [[lng, lat] for lat, lng in page.evaluate("window.boustro.outer")]
    mission = plan_area(np.array(ring), 20.0, altitude=50.0, turn_time=0.0, turnaround=0.0)
    assert_qgc_plan(json.loads(path.read_text()), mission)
    assert mission.stats.n_transects == after


def test_drop_a_kml_file(page):
    _drop(page, "field.kml", KML.format(name="dropped field"))
    _wait_plan(page, 0)
    outer = page.evaluate("window.boustro.outer")
    np.testing.assert_allclose(
        outer, [[52.0, 5.0], [52.0, 5.003], [52.002, 5.003], [52.002, 5.0]], atol=1e-12
    )
    assert _lanes(page) > 0 and "dropped field" in page.inner_text("#summary")
    assert "field.kml" in page.inner_text("#hint")


def test_a_bow_tie_shows_its_error(page):
    page.click("#example")
    _wait_plan(page, 0)
    errors = page.evaluate("window.boustro.errorSeq")
    _draw(page, [(450, 250), (800, 550), (800, 250), (450, 550)])
    _until(page, f"window.boustro.errorSeq > {errors}")
    text = page.inner_text("#error")
    assert page.locator("#error").is_visible() and "Self-intersection at" in text
    assert "Traceback" not in text and _lanes(page) == 0


def test_a_hole_is_drawn_and_avoided(page):
    _draw(page, [(300, 200), (700, 200), (700, 600), (300, 600)])
    _wait_plan(page, 0)
    seq = page.evaluate("window.boustro.planSeq")
    page.click("#hole")
    box = page.locator("#map").bounding_box()
    for x, y in [(450, 350), (550, 350), (550, 450), (450, 450), (450, 350)]:
        page.mouse.click(box["x"] + x, box["y"] + y)
    _wait_plan(page, seq)
    assert page.evaluate("window.boustro.holes.length") == 1
    assert "lanes" in page.inner_text("#summary") and page.locator("#error").is_hidden()


def test_keep_inside_and_a_vehicle_from_the_form(page):
    bodies: list = []
    page.on(
        "request",
        lambda r: bodies.append(r.post_data_json) if r.url.endswith("/api/plan") else None,
    )
    page.click("#example")
    _wait_plan(page, 0)
    assert "outside the area" in page.inner_text("#summary")
    seq = page.evaluate("window.boustro.planSeq")
    page.check("#keep_inside")
    _wait_plan(page, seq)
    assert bodies[-1]["options"]["keep_inside"] is True
    assert "0.0 m of the path" in page.inner_text("#summary")
    seq = _set(page, "#turn_radius", "6")
    page.press("#turn_radius", "Enter")
    _wait_plan(page, seq)
    assert bodies[-1]["options"]["turn_radius"] == 6 and page.locator("#error").is_hidden()


def test_a_committed_edit_is_planned_at_once_and_one_that_changes_nothing_not_at_all(page):
    plans: list[str] = []
    page.on("request", lambda r: plans.append(r.url) if r.url.endswith("/api/plan") else None)
    page.click("#example")
    _wait_plan(page, 0)
    seq = _set(page, "#spacing", "12")  # typed: planned after a pause for more keys
    _wait_plan(page, seq)
    typed = page.evaluate("window.boustro.phases.at(-1)")
    assert typed["wait"] >= 59 and typed["server"]["plan"] > 0
    seq = _set(page, "#spacing", "14")
    page.press("#spacing", "Enter")  # committed: planned at once
    _wait_plan(page, seq)
    committed = page.evaluate("window.boustro.phases.at(-1)")
    assert committed["wait"] < 59 and len(plans) == 3
    assert set(committed["server"]) == {"parse", "plan", "answer", "encode"}
    seq = page.evaluate("window.boustro.planSeq")
    page.press("#spacing", "Enter")  # nothing changed: nothing planned
    page.dispatch_event("#layout", "change")
    time.sleep(0.3)
    assert page.evaluate("window.boustro.planSeq") == seq and len(plans) == 3
    page.select_option("#layout", "chords")  # a choice: planned at once
    _wait_plan(page, seq)
    assert page.evaluate("window.boustro.phases.at(-1).wait") < 59 and len(plans) == 4


def _field_geojson(n: int) -> str:
    """A 1000-vertex field: a smooth convex boundary (as a GPS trace), 300 x 210 m."""
    t = np.linspace(0, 2 * math.pi, n, endpoint=False)
    lat0 = 51.99
    x, y = 150 * np.cos(t), 105 * np.sin(t)
    lon = 5.66 + x / (111_320 * math.cos(math.radians(lat0)))
    lat = lat0 + y / 111_320
    ring = np.column_stack([lon, lat]).tolist()
    return json.dumps({"type": "Polygon", "coordinates": [[*ring, ring[0]]]})


def _timed_edit(page, spacing: str, timeout: float) -> float:
    seq = _set(page, "#spacing", spacing)
    _wait_plan(page, seq, timeout)
    return float(page.evaluate("window.boustro.timings.at(-1)"))


def test_time_from_the_last_edit_to_the_drawn_plan(page):
    page.click("#example")
    _wait_plan(page, 0)
    embedded = [_timed_edit(page, s, 30_000) for s in ("12", "10", "12", "10", "12")]
    seq = page.evaluate("window.boustro.planSeq")
    _drop(page, "traced.geojson", _field_geojson(1000))
    _wait_plan(page, seq, 240_000)
    assert page.evaluate("window.boustro.outer.length") == 1000
    traced = [page.evaluate("window.boustro.timings.at(-1)"), _timed_edit(page, "12", 240_000)]
    print(
        f"\nedit -> drawn plan: embedded field median {statistics.median(embedded):.0f} ms "
        f"({', '.join(f'{t:.0f}' for t in embedded)}); 1000-vertex field "
        f"{', '.join(f'{t / 1000:.2f}' for t in traced)} s (targets 300 ms, 2 s)"
    )
    # The targets are reported, not asserted (a loaded 2-core machine); these bounds catch a
    # page that stalls or plans twice.
    assert statistics.median(embedded) < 5_000 and max(traced) < 200_000


def _traced_geojson(n: int, holes: int) -> str:
    """A concave traced field (:func:`boustro.geometry.traced.traced_field`) with holes, as
    longitude/latitude."""
    region = traced_field(n, holes)
    lat0 = 51.99

    def lonlat(xy) -> list:
        xy = np.asarray(xy, dtype=float)
        lon = 5.66 + xy[:, 0] / (111_320 * math.cos(math.radians(lat0)))
        ring = np.column_stack([lon, lat0 + xy[:, 1] / 111_320]).tolist()
        return [*ring, ring[0]]

    rings = [lonlat(region.shell.vertices), *(lonlat(h.vertices) for h in region.holes)]
    return json.dumps({"type": "Polygon", "coordinates": rings})


def test_a_long_plan_shows_its_progress(page):
    page.click("#example")
    _wait_plan(page, 0)
    seq = page.evaluate("window.boustro.planSeq")
    _drop(page, "traced.geojson", _traced_geojson(2000, 10))
    # a long plan: the progress bar fills over the estimate before planning, which it names
    _until(page, "document.getElementById('progress-text').textContent.includes('estimated')")
    assert page.locator("#progress").is_visible()
    assert "2120 vertices" in page.inner_text("#progress-text")
    _wait_plan(page, seq, 240_000)
    assert page.locator("#progress").is_hidden()
    assert page.evaluate("window.boustro.outer.length") == 2000
