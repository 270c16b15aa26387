"""Benchmark (issue 6): plan the shipped field end to end; boustro's plan against the usual lanes.

1. Time planning the embedded 3.6 ha field end to end in one process: read the file, project it
   to UTM, optimise (the default method of :func:`boustro.geo.plan_area`, or ``--method``),
   build the coverage-guaranteed path, check coverage, write GeoJSON. The first run pays for
   pyproj's and shapely's first use; the median of the warm runs is the steady state. The wall
   time of the whole ``boustro plan`` command (interpreter start and imports included) is
   measured too.
2. Compare, at the same spacing, boustro's plan (optimised angle and offset, coverage-guaranteed
   segments) with the usual practice at the SAME angle: the first lane half a spacing inside the
   extreme edge, the others every spacing, segments = the lanes' chords. Reported: covered share
   of the area (exact, shapely; footprint = the strip of width ``spacing`` around each lane),
   transect count, path length (transects and connecting moves, no run-ins). On the shipped
   field and on 100 random convex polygons (Valtr, 3-12 vertices, diameter 100-400 m, spacing
   10 m, planar metres).

    python benchmarks/plan_field.py [--method grid] [--polygons 100] [--spacing 10]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

from boustro.errors import NoTransectError
from boustro.formats import write_mission
from boustro.geo import DEFAULT_METHOD, METHOD_OPTIONS, plan_area
from boustro.geometry import Polygon, random_convex_polygon
from boustro.io import EMBEDDED_FIELD, read_area
from boustro.optimize import optimize
from boustro.plan import build_plan, coverage, edge_offset, nearly_convex


def field_path() -> str:
    from importlib import resources

    return str(resources.files("boustro") / "data" / EMBEDDED_FIELD)


def end_to_end(path: str, spacing: float, method: str, out: str) -> tuple[float, object]:
    t0 = time.perf_counter()
    area = read_area(path)
    mission = plan_area(area, spacing, method=method)
    write_mission(mission, out)
    return time.perf_counter() - t0, mission


def compare(
    poly, spacing: float, method: str, start=None, region=None
) -> dict[str, tuple[float, int, float]]:
    """(covered share of region, transects, path length) for boustro's plan and the usual one."""

    opt = optimize(poly, spacing, method=method, **METHOD_OPTIONS.get(method, {}))
    usual_offset = edge_offset(poly, spacing, opt.angle)
    layouts = {
        "boustro": (opt.offset, "guaranteed"),
        "usual": (usual_offset, "chords"),
        "usual+guarantee": (usual_offset, "guaranteed"),
    }
    out = {}
    for name, (offset, layout) in layouts.items():
        try:
            plan = build_plan(poly, spacing, opt.angle, offset, layout=layout, start=start)
        except NoTransectError:  # a sliver narrower than half a spacing: no lane at all
            out[name] = (0.0, 0, 0.0)
            continue
        out[name] = (
            coverage(plan, region).covered_share,
            plan.stats.n_transects,
            plan.stats.path_length,
        )
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--method", default=DEFAULT_METHOD, help="optimiser (default: %(default)s)")
    parser.add_argument("--spacing", type=float, default=10.0, help="metres (default 10)")
    parser.add_argument("--polygons", type=int, default=100, help="random polygons (100)")
    parser.add_argument("--repeat", type=int, default=5, help="warm end-to-end runs (5)")
    args = parser.parse_args()

    path = field_path()
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "plan.geojson")
        first, mission = end_to_end(path, args.spacing, args.method, out)
        warm = [end_to_end(path, args.spacing, args.method, out)[0] for _ in range(args.repeat)]
        t0 = time.perf_counter()
        subprocess.run(
            [
                sys.executable,
                "-m",
                "boustro.cli",
                "-q",
                "plan",
                path,
                "--spacing",
                str(args.spacing),
                "--method",
                args.method,
                "--out",
                out,
            ],
            check=True,
            capture_output=True,
        )
        command = time.perf_counter() - t0
    s = mission.stats
    print(f"shipped field: {s.area:.0f} m2, spacing {args.spacing:g} m, method {args.method}")
    print(
        f"  end to end in-process (read, project, optimise, plan, coverage, write GeoJSON): "
        f"first {first:.3f} s, warm median {statistics.median(warm):.3f} s "
        f"(min {min(warm):.3f}, max {max(warm):.3f}; optimiser {mission.optimum.seconds:.3f} s "
        f"of the last run)"
    )
    print(f"  load average during the run: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    print(
        f"  whole command 'python -m boustro.cli plan ...' incl. start-up/imports: {command:.2f} s"
    )

    # -- boustro vs the usual practice ---------------------------------------------------------
    proj = mission.projection
    field = Polygon(proj.to_plan(mission.area.ring))
    hull, _ = nearly_convex(field, 0.5 * proj.scale_min)
    s_plan = args.spacing * proj.scale_min
    rows = {}
    res = compare(hull, s_plan, args.method, proj.to_plan(mission.area.ring[0]), field)
    print("\nshipped field (planned on its convex hull, coverage of the field):")
    print(f"  {'plan':<16} {'covered':>10} {'transects':>9} {'path m':>9}")
    for name, (cov, n, length) in res.items():
        print(f"  {name:<16} {100 * cov:>9.4f}% {n:>9d} {length / proj.scale:>9.1f}")
    rows["field"] = res

    rng = np.random.default_rng(2024)
    polys = []
    for _ in range(args.polygons):
        p = random_convex_polygon(rng, int(rng.integers(3, 13)))
        polys.append(p.scaled(float(rng.uniform(100, 400)), origin=(0.0, 0.0)))
    t0 = time.perf_counter()
    results = [compare(p, args.spacing, args.method) for p in polys]
    elapsed = time.perf_counter() - t0
    print(
        f"\n{args.polygons} random convex polygons (diameter 100-400 m, spacing "
        f"{args.spacing:g} m; {elapsed:.1f} s):"
    )
    print(
        f"  {'plan':<16} {'covered: mean':>14} {'min':>9} {'max':>9} {'transects':>10} "
        f"{'path m':>9}"
    )
    for name in ("boustro", "usual", "usual+guarantee"):
        cov = np.array([r[name][0] for r in results])
        n = np.array([r[name][1] for r in results])
        length = np.array([r[name][2] for r in results])
        print(
            f"  {name:<16} {100 * cov.mean():>13.3f}% {100 * cov.min():>8.3f}% "
            f"{100 * cov.max():>8.3f}% {n.mean():>10.2f} {length.mean():>9.1f}"
        )
    empty = sum(r["usual"][1] == 0 for r in results)
    print(f"  usual practice places no lane at all on {empty} sliver polygon(s) (counted as 0)")
    full = sum(r["usual"][0] >= 1 - 1e-9 for r in results)
    extra = np.mean([r["boustro"][1] - r["usual"][1] for r in results])
    ratios = [r["boustro"][2] / r["usual"][2] - 1 for r in results if r["usual"][1]]
    longer = float(np.median(ratios))
    print(
        f"  usual practice fully covers {full}/{len(results)} polygons; boustro all of them "
        f"({sum(r['boustro'][0] >= 1 - 1e-9 for r in results)}/{len(results)}), with "
        f"{extra:+.2f} transects on average and a median {100 * longer:+.1f}% path length (where "
        "the usual practice has lanes)"
    )


if __name__ == "__main__":
    main()
