"""Benchmark (issue 19): the time from the last edit to the drawn plan in the browser.

Starts ``boustro serve`` on a free port of 127.0.0.1, drives the system's headless Chromium
(Playwright, ``/usr/bin/chromium``) and, for each field, makes edits (the spacing, alternately
12 and 10 m) and reads the page's own measure: ``performance.now()`` from the edit to the frame
after the plan's layers are drawn (the wait before asking, the request, planning, JSON,
drawing). Two kinds of edit: *typed* (the value typed into the field: an ``input`` event, which
the page plans after a pause for more keys) and *committed* (typed, then Enter: a ``change``
event, planned at once). Beside it, in the same requests, the server's planning time (the
``plan`` entry of its ``Server-Timing`` header), and for this tree's page where the time went
(``window.boustro.phases``: the wait, HTTP, the server's steps, reading, drawing, the frame).

The baseline, ``--baseline SRC`` (a ``src`` folder of another checkout, e.g. the branch's base
extracted with ``git archive``), runs a second server and page from that tree, edit for edit
interleaved with this one, so both see the same load. Fields: the embedded 3.6 ha field, and a
1000-vertex smooth convex boundary (300 x 210 m, as a GPS trace), which the certified
optimiser refuses for its work and the hybrid plans.

    python benchmarks/web.py [--repeats 7] [--baseline /tmp/base/src] [--screenshots docs]

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
        time.sleep(0.005)


def edit(page, spacing: float, commit: bool) -> dict:
    """An edit; the page's ms from it to the drawn plan, the server's planning ms, and (this
    tree's page) where they went."""
    seq = page.evaluate("window.boustro.planSeq")
    page.fill("#spacing", f"{spacing:g}")
    if commit:
        page.press("#spacing", "Enter")
    until(page, f"window.boustro.planSeq > {seq}")
    total, server, phases = page.evaluate(
        "[boustro.timings.at(-1), boustro.serverTimings.at(-1), (boustro.phases || []).at(-1)]"
    )
    return {"total": float(total), "plan": float(server), "phases": phases}


def drop(page, name: str, text: str) -> None:
    seq = page.evaluate("window.boustro.planSeq")
    page.evaluate(
        """([name, text]) => { const dt = new DataTransfer(); dt.items.add(new File([text], name));
        document.getElementById("map").dispatchEvent(new DragEvent("drop",
        {dataTransfer: dt, bubbles: true})); }""",
        [name, text],
    )
    until(page, f"window.boustro.planSeq > {seq}")


def start_server(src: Path) -> tuple[subprocess.Popen, int]:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    env = {**os.environ, "PYTHONPATH": str(src)}
    cmd = [sys.executable, "-m", "boustro", "-q", "serve", "--port", str(port)]
    return subprocess.Popen(cmd, env=env, stderr=subprocess.DEVNULL, cwd="/"), port


def open_page(chromium, port: int):
    page = chromium.new_page(viewport={"width": 1200, "height": 760})
    for _ in range(240):
        try:
            page.goto(f"http://127.0.0.1:{port}/")
            break
        except Exception:
            time.sleep(0.25)
    until(page, "window.boustro && window.boustro.ready === true")
    return page


def measure(pages: dict, repeats: int, commit: bool) -> dict[str, list[dict]]:
    """Edits (spacing 12, 10, 12, ...), interleaved over the pages: each page's results."""
    got: dict[str, list[dict]] = {name: [] for name in pages}
    if commit:  # the field's value committed once, so that Enter after a new value changes it
        for page in pages.values():
            page.press("#spacing", "Enter")
    order = list(pages)
    for _ in range(repeats):
        for name in order:
            page = pages[name]
            spacing = 10.0 if page.input_value("#spacing") == "12" else 12.0  # a change
            got[name].append(edit(page, spacing, commit))
        order.reverse()  # each tree first in turn
    return got


def median(values) -> float:
    return statistics.median(values)


def row(name: str, got: list[dict]) -> str:
    b, p = median(g["total"] for g in got), median(g["plan"] for g in got)
    return f"| {name} | {b:.0f} ms | {p:.0f} ms | {b - p:.0f} ms | {len(got)} |"


def phases_row(name: str, got: list[dict]) -> str:
    ph = [g["phases"] for g in got if g["phases"]]
    if not ph:
        return f"| {name} | (no phases: an older page) |"
    cols = [
        median(p["wait"] for p in ph),
        median(p["http"] for p in ph),
        median(p["server"].get("parse", 0) for p in ph),
        median(p["server"].get("plan", 0) for p in ph),
        median(p["server"].get("answer", 0) + p["server"].get("encode", 0) for p in ph),
        median(p["read"] for p in ph),
        median(p["draw"] for p in ph),
        median(p["frame"] for p in ph),
        median(p["total"] for p in ph),
    ]
    return f"| {name} | " + " | ".join(f"{c:.1f}" for c in cols) + " |"


def run(args: argparse.Namespace) -> dict[str, dict[str, list[dict]]]:
    from playwright.sync_api import sync_playwright

    trees = {"this tree": ROOT / "src"}
    if args.baseline:
        trees["baseline"] = Path(args.baseline).resolve()
    servers = {name: start_server(src) for name, src in trees.items()}
    results: dict[str, dict[str, list[dict]]] = {}
    try:
        with sync_playwright() as p:
            chromium = p.chromium.launch(executable_path="/usr/bin/chromium", args=ARGS)
            pages = {name: open_page(chromium, port) for name, (_, port) in servers.items()}
            for page in pages.values():
                page.click("#example")
                until(page, "window.boustro.planSeq > 0")
            for commit in (False, True):
                kind = "committed" if commit else "typed"
                results[f"embedded, {kind}"] = measure(pages, args.repeats, commit)
            if args.screenshots:
                edit(pages["this tree"], 10.0, True)
                pages["this tree"].screenshot(path=str(Path(args.screenshots) / "web-draw.png"))
            ring = traced_field()
            coords = [*ring.tolist(), ring[0].tolist()]
            for page in pages.values():
                drop(
                    page, "traced.geojson", json.dumps({"type": "Polygon", "coordinates": [coords]})
                )
            results["1000 vertices, committed"] = measure(pages, args.traced_repeats, True)
            if args.screenshots:
                page = pages["this tree"]
                page.click("#clear")
                page.click("#draw")
                box = page.locator("#map").bounding_box()
                for x, y in [(300, 200), (650, 550), (650, 200), (300, 550), (300, 200)]:
                    page.mouse.click(box["x"] + x, box["y"] + y)
                until(page, "window.boustro.errorSeq > 0")
                page.screenshot(path=str(Path(args.screenshots) / "web-error.png"))
            chromium.close()
    finally:
        for server, _ in servers.values():
            server.terminate()
            server.wait(timeout=20)
    return results


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--traced-repeats", type=int, default=2)
    ap.add_argument("--baseline", metavar="SRC", help="the src folder of a baseline checkout")
    ap.add_argument("--screenshots", metavar="DIR")
    args = ap.parse_args()
    before = os.getloadavg()[0]
    results = run(args)
    print(
        f"edit -> drawn plan in headless Chromium (load average {before:.1f} before, "
        f"{os.getloadavg()[0]:.1f} after):\n"
    )
    print(
        "| field, edit, tree | edit -> drawn, median | planning in the server | the rest | edits |"
    )
    print("|---|---:|---:|---:|---:|")
    for field, got in results.items():
        for tree, values in got.items():
            print(row(f"{field}, {tree}", values))
    print("\nwhere the time went, this tree's page (medians, ms):\n")
    print(
        "| field, edit | wait | HTTP | parse | plan | answer+encode | read | draw | frame | total |"
    )
    print("|---|" + "---:|" * 9)
    for field, got in results.items():
        print(phases_row(field, got["this tree"]))


if __name__ == "__main__":
    main()
