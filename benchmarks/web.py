"""Benchmark (issue 19): the time from the last edit to the drawn plan in the browser.

Starts ``boustro serve`` on a free port of 127.0.0.1, drives the system's headless Chromium
(Playwright, ``/usr/bin/chromium``) and, for each field, makes an edit (the spacing, alternately
10 and 12 m) and reads the page's own measure: ``performance.now()`` from the edit (the input
event) to the frame after the plan's layers are drawn (debounce, request, planning, JSON,
drawing). The baseline, measured in the same requests, is the server's planning time (its
``Server-Timing`` header: reading the request, :func:`boustro.mission.plan_area`, the answer):
the difference is what the page, HTTP and drawing add to planning. Fields: the embedded 3.6 ha
field, and a 1000-vertex smooth convex boundary (300 x 210 m, as a GPS trace), which the
certified optimiser refuses for its work and the hybrid plans.

    python benchmarks/web.py [--repeats 7] [--screenshots docs]

``--screenshots DIR`` also saves ``web-draw.png`` (the example field planned) and
``web-error.png`` (a bow-tie's error) into DIR.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import socket
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking"]


def traced_field(n: int = 1000) -> np.ndarray:
    t = np.linspace(0, 2 * math.pi, n, endpoint=False)
    lon = 5.66 + 150 * np.cos(t) / (111_320 * math.cos(math.radians(51.99)))
    return np.column_stack([lon, 51.99 + 105 * np.sin(t) / 111_320])


def until(page, expression: str, timeout: float = 300.0) -> None:
    end = time.monotonic() + timeout
    while not page.evaluate(expression):
        if time.monotonic() > end:
            raise TimeoutError(expression)
        time.sleep(0.01)


def edit(page, spacing: float) -> tuple[float, float]:
    """An edit; the page's time from it to the drawn plan and the server's planning time, s."""
    seq = page.evaluate("window.boustro.planSeq")
    page.fill("#spacing", f"{spacing:g}")
    until(page, f"window.boustro.planSeq > {seq}")
    total, server = page.evaluate("[boustro.timings.at(-1), boustro.serverTimings.at(-1)]")
    return float(total) / 1000, float(server) / 1000


def drop(page, name: str, text: str) -> None:
    seq = page.evaluate("window.boustro.planSeq")
    page.evaluate(
        """([name, text]) => { const dt = new DataTransfer(); dt.items.add(new File([text], name));
        document.getElementById("map").dispatchEvent(new DragEvent("drop",
        {dataTransfer: dt, bubbles: true})); }""",
        [name, text],
    )
    until(page, f"window.boustro.planSeq > {seq}")


def measure(page, repeats: int) -> tuple[list[float], list[float]]:
    """Edits (spacing 12, 10, 12, ...): the page's times and the server's planning times."""
    got = [edit(page, 12.0 if k % 2 == 0 else 10.0) for k in range(repeats)]
    return [t for t, _ in got], [s for _, s in got]


def row(name: str, browser: list[float], server: list[float]) -> str:
    b, p = statistics.median(browser), statistics.median(server)
    return (
        f"| {name} | {b * 1000:.0f} ms | {p * 1000:.0f} ms | {(b - p) * 1000:.0f} ms | "
        f"{b / p:.2f} | {len(browser)} |"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--traced-repeats", type=int, default=2)
    ap.add_argument("--screenshots", metavar="DIR")
    args = ap.parse_args()
    from playwright.sync_api import sync_playwright

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    cmd = [sys.executable, "-m", "boustro", "-q", "serve", "--port", str(port)]
    server = subprocess.Popen(cmd, env=env, stderr=subprocess.DEVNULL)
    try:
        with sync_playwright() as p:
            chromium = p.chromium.launch(executable_path="/usr/bin/chromium", args=ARGS)
            page = chromium.new_page(viewport={"width": 1200, "height": 760})
            for _ in range(240):
                try:
                    page.goto(f"http://127.0.0.1:{port}/")
                    break
                except Exception:
                    time.sleep(0.25)
            until(page, "window.boustro && window.boustro.ready === true")
            page.click("#example")
            until(page, "window.boustro.planSeq > 0")
            emb = measure(page, args.repeats)
            if args.screenshots:
                edit(page, 10.0)
                page.screenshot(path=str(Path(args.screenshots) / "web-draw.png"))
            ring = traced_field()
            coords = [*ring.tolist(), ring[0].tolist()]
            drop(page, "traced.geojson", json.dumps({"type": "Polygon", "coordinates": [coords]}))
            traced = measure(page, args.traced_repeats)
            if args.screenshots:
                page.click("#clear")
                page.click("#draw")
                box = page.locator("#map").bounding_box()
                for x, y in [(300, 200), (650, 550), (650, 200), (300, 550), (300, 200)]:
                    page.mouse.click(box["x"] + x, box["y"] + y)
                until(page, "window.boustro.errorSeq > 0")
                page.screenshot(path=str(Path(args.screenshots) / "web-error.png"))
            chromium.close()
    finally:
        server.terminate()
        server.wait(timeout=20)
    load = os.getloadavg()[0]
    print(f"edit -> drawn plan in headless Chromium (load average {load:.1f}):\n")
    print("| field | edit -> drawn, median | planning in the server | the rest | ratio | edits |")
    print("|---|---:|---:|---:|---:|---:|")
    print(row("embedded 3.6 ha, 19 vertices (target 300 ms)", *emb))
    print(row("1000-vertex traced boundary (target 2 s)", *traced))


if __name__ == "__main__":
    main()
