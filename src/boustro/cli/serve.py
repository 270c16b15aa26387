"""``boustro serve``: the planner in the browser (the ``boustro[web]`` extra)."""

from __future__ import annotations

import argparse

from ..web import serve
from ..web.server import PLAN_THREADS

__all__ = ["register", "run"]

DETAILS = """\
The page: draw an area on the map (click the vertices, click the first one or double-click to
close it; 'Add hole' draws a hole inside it; drag a vertex to move it), or drop / open a
GeoJSON, KML, KMZ, GML, WKT or QGroundControl .plan file on it. The plan is drawn as you edit
(lanes, the path with its direction, the start, cells) with its summary; the Download buttons
save the mission in every format boustro writes.

The map needs no network: a plain background with a graticule and a scale bar. --tiles URL
adds a tile layer from a tile server (e.g. a private one: https://tiles.example/{z}/{x}/{y}.png).

The JSON API (POST /api/plan with {"area": <GeoJSON>, "options": {"spacing": 10, ...}}) is
described in docs/web.md. The server binds to 127.0.0.1 (this machine only), accepts a CRS only
as an EPSG code, refuses requests over 5 MB, 20000 vertices or an estimated 60 s of work, and
writes nothing but uploaded files, into a temporary directory that it removes.
"""


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "serve",
        help="plan in the browser: a local web page with a map (needs 'boustro[web]')",
        description="Serve a local web page on which to draw or drop an area, see its optimal "
        "plan as you edit and download the mission; and its JSON API.",
        epilog=DETAILS,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--port", type=int, default=8000, help="TCP port (default 8000)")
    p.add_argument(
        "--host",
        default="127.0.0.1",
        help="address to bind (default 127.0.0.1: this machine only; anything else lets other "
        "machines reach the planner, with a warning)",
    )
    p.add_argument("--open", action="store_true", help="open the page in the default browser")
    p.add_argument(
        "--tiles",
        metavar="URL",
        help="tile-server URL template for the map background, {z}/{x}/{y} (default: none, a "
        "plain background with a graticule: no network needed)",
    )
    p.add_argument(
        "--threads",
        type=int,
        default=PLAN_THREADS,
        help=f"torch threads of a plan (default {PLAN_THREADS}: one plan runs at a time and its "
        "tensors are small; more threads only pay on large fields with cores to spare)",
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    serve(
        args.host,
        args.port,
        open_browser=args.open,
        tiles=args.tiles,
        quiet=args.quiet,
        threads=args.threads,
    )
    return 0
