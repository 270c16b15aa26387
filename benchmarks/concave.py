"""Benchmark (issue 7): concave areas with holes, single-angle plans against decomposed plans.

For every area, three plans at the same spacing, all coverage-guaranteed (lanes cut at the
boundary and at the holes, passes around the holes that cut lanes, connecting moves around
obstacles; :func:`boustro.decompose.plan_region`):

* ``single``: one angle and offset for the whole area (grid search over the exact per-segment
  fitness, Eq. 1 over segments),
* ``auto``: the planner's default: decomposed into cells when the estimate says that pays,
* ``cells``: always decomposed (the best sweep direction of the candidates).

Reported: number of turns (connecting moves between passes), path length, covered share of the
area (exact, shapely), planning time (``plan_region``: decomposition, optimisation of every
cell, lanes, ordering, routing; the coverage check is timed apart).

Areas:

1. random concave regions with holes (:func:`boustro.regions.random_region`: star-shaped
   shells with lobes and bays, 30-100 vertices, 0-3 convex holes), diameter about 300 m,
   spacing 10 m, planar metres;
2. strongly concave shapes (L, U, V, T, comb, two crossing strips), spacing 1/30 of the diameter;
3. the real field shipped with the package (3.6 ha, nearly convex) planned exactly as a concave
   area, and the same field with three ponds (holes) added, spacing 10 m;
4. the timing target: a field with 100 vertices and 3 holes planned in under 2 s.

    python benchmarks/concave.py [--quick] [--seed 0] [--count 20] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
import time
from typing import Any

import numpy as np
import shapely

from boustro.decompose import plan_region
from boustro.geo import plan_area, projection_for
from boustro.io import embedded_field
from boustro.plan import coverage
from boustro.regions import Region, random_region

MODES = {"single": False, "auto": "auto", "cells": True}


def run(region: Region, spacing: float, mode: str, n_angles: int) -> dict[str, Any]:
    t0, c0 = time.perf_counter(), time.process_time()
    plan = plan_region(region, spacing, decompose_area=MODES[mode], n_angles=n_angles)
    seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
    t1 = time.perf_counter()
    cov = coverage(plan).covered_share
    check = time.perf_counter() - t1
    return {
        "turns": plan.stats.n_turns,
        "cells": plan.stats.n_cells,
        "path": plan.stats.path_length,
        "lanes": plan.stats.transect_length,
        "covered": cov,
        "seconds": seconds,
        "cpu_seconds": cpu,
        "coverage_seconds": check,
    }


def arm(angle: float, length: float, width: float, x0=0.0, y0=0.0) -> shapely.Polygon:
    u = np.array([math.cos(angle), math.sin(angle)])
    n = np.array([-u[1], u[0]])
    o = np.array([x0, y0])
    return shapely.Polygon(
        [
            o + a * u + b * n
            for a, b in [(0, -width / 2), (length, -width / 2), (length, width / 2), (0, width / 2)]
        ]
    )


def shapes() -> dict[str, Region]:
    def union(*parts: shapely.Polygon) -> Region:
        return Region(np.asarray(shapely.union_all(parts).exterior.coords)[:-1])

    return {
        "L": Region([(0, 0), (10, 0), (10, 3), (3, 3), (3, 10), (0, 10)]),
        "U": Region([(0, 0), (10, 0), (10, 10), (7, 10), (7, 3), (3, 3), (3, 10), (0, 10)]),
        "V": union(arm(math.radians(20), 10, 2.5), arm(math.radians(100), 10, 2.5)),
        "T": union(shapely.box(0, 8, 12, 10), shapely.box(5, 0, 7, 9)),
        "comb": Region(
            [
                (0, 0),
                (12, 0),
                (12, 8),
                (10, 8),
                (10, 2),
                (8, 2),
                (8, 8),
                (6, 8),
                (6, 2),
                (4, 2),
                (4, 8),
                (2, 8),
                (2, 2),
                (0, 2),
            ]
        ),
        "cross": union(
            arm(0, 12, 2, -6, 0),
            arm(math.radians(70), 12, 2, -6 * math.cos(1.22), -6 * math.sin(1.22)),
        ),
        "L+hole": Region(
            [(0, 0), (10, 0), (10, 3), (3, 3), (3, 10), (0, 10)], [[(1, 4), (2, 4), (2, 6), (1, 6)]]
        ),
    }


def field_regions() -> dict[str, Region]:
    area = embedded_field()
    proj = projection_for(area.ring, area.crs)
    ring = proj.to_plan(area.ring)
    centre = ring.mean(axis=0)
    rng = np.random.default_rng(1)

    def pond(offset: tuple[float, float], radius: float, n: int) -> np.ndarray:
        a = np.sort(rng.uniform(0, 2 * math.pi, n))
        r = radius * rng.uniform(0.7, 1.0, n)
        return centre + np.array(offset) + np.stack([r * np.cos(a), r * np.sin(a)], axis=1)

    ponds = [pond((-40, 30), 14, 9), pond((45, -20), 10, 7), pond((5, -60), 8, 6)]
    return {"field": Region(ring), "field+3 ponds": Region(ring, ponds)}


def summarise(rows: list[dict[str, Any]], label: str) -> dict[str, Any]:
    out: dict[str, Any] = {"areas": len(rows)}
    for mode in MODES:
        turns = [r[mode]["turns"] for r in rows]
        path = [r[mode]["path"] for r in rows]
        out[mode] = {
            "turns_mean": statistics.fmean(turns),
            "path_mean": statistics.fmean(path),
            "covered_min": min(r[mode]["covered"] for r in rows),
            "seconds_median": statistics.median(r[mode]["seconds"] for r in rows),
            "seconds_max": max(r[mode]["seconds"] for r in rows),
            "cells_mean": statistics.fmean(r[mode]["cells"] for r in rows),
        }
    for mode in ("auto", "cells"):
        out[f"{mode}_vs_single"] = {
            "fewer_turns": sum(r[mode]["turns"] < r["single"]["turns"] for r in rows),
            "more_turns": sum(r[mode]["turns"] > r["single"]["turns"] for r in rows),
            "turns_ratio_mean": statistics.fmean(
                r[mode]["turns"] / max(r["single"]["turns"], 1) for r in rows
            ),
            "path_ratio_mean": statistics.fmean(
                r[mode]["path"] / r["single"]["path"] for r in rows
            ),
        }
    print(f"\n== {label}: {len(rows)} areas")
    print(
        f"{'mode':8s} {'turns':>8s} {'path':>10s} {'cells':>6s} {'covered min':>12s} "
        f"{'t median':>9s} {'t max':>7s}"
    )
    for mode in MODES:
        m = out[mode]
        print(
            f"{mode:8s} {m['turns_mean']:8.1f} {m['path_mean']:10.1f} {m['cells_mean']:6.2f} "
            f"{m['covered_min']:12.9f} {m['seconds_median']:8.2f}s {m['seconds_max']:6.2f}s"
        )
    for mode in ("auto", "cells"):
        c = out[f"{mode}_vs_single"]
        print(
            f"{mode} vs single: fewer turns on {c['fewer_turns']}, more on {c['more_turns']}; "
            f"turns x{c['turns_ratio_mean']:.3f}, path x{c['path_ratio_mean']:.3f} (mean ratios)"
        )
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    p.add_argument("--quick", action="store_true", help="fewer areas, for a smoke test")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--count", type=int, default=20, help="random regions (default 20)")
    p.add_argument("--json", metavar="FILE", help="write the results as JSON")
    args = p.parse_args(argv)
    count = 4 if args.quick else args.count
    n_angles = 45 if args.quick else 90
    results: dict[str, Any] = {"seed": args.seed, "quick": args.quick}

    rng = np.random.default_rng(args.seed)
    rows = []
    for _ in range(count):
        region = random_region(
            rng,
            int(rng.integers(30, 101)),
            int(rng.integers(0, 4)),
            roughness=float(rng.uniform(0.3, 0.6)),
        ).map(lambda v: 150.0 * v)
        rows.append({m: run(region, 10.0, m, n_angles) for m in MODES})
        print(".", end="", file=sys.stderr, flush=True)
    results["random"] = summarise(rows, "random concave regions with holes (300 m, spacing 10 m)")

    shape_rows = []
    print("\n== strongly concave shapes (spacing = diameter / 30)")
    for name, region in shapes().items():
        row = {m: run(region, region.diameter / 30, m, n_angles) for m in MODES}
        shape_rows.append(row)
        print(
            f"{name:8s} turns single {row['single']['turns']:3d}, auto {row['auto']['turns']:3d} "
            f"({row['auto']['cells']} cells), cells {row['cells']['turns']:3d} "
            f"({row['cells']['cells']}); path auto/single "
            f"{row['auto']['path'] / row['single']['path']:.3f}; covered min "
            f"{min(row[m]['covered'] for m in MODES):.9f}"
        )
    results["shapes"] = summarise(shape_rows, "strongly concave shapes")

    print("\n== the shipped field (spacing 10 m)")
    field_rows = {}
    for name, region in field_regions().items():
        row = {m: run(region, 10.0, m, n_angles) for m in MODES}
        field_rows[name] = row
        for m in MODES:
            r = row[m]
            print(
                f"{name:14s} {m:7s} turns {r['turns']:3d}, cells {r['cells']}, path "
                f"{r['path']:7.1f} m, covered {r['covered']:.9f}, {r['seconds']:.2f} s"
            )
    results["field"] = field_rows

    # The timing target: 100 vertices and 3 holes, diameter ~300 m, spacing 10 m.
    print("\n== timing: 100 vertices, 3 holes (planning; target < 2 s)")
    timing: dict[str, list[float]] = {m: [] for m in MODES}
    cpu: dict[str, list[float]] = {m: [] for m in MODES}
    e2e, e2e_cpu = [], []
    repeats = 3 if args.quick else 10
    trng = np.random.default_rng(args.seed + 1)
    for _ in range(repeats):
        region = random_region(trng, 100, 3).map(lambda v: 150.0 * v)
        for m in MODES:
            r = run(region, 10.0, m, 90)
            timing[m].append(r["seconds"])
            cpu[m].append(r["cpu_seconds"])
        t0, c0 = time.perf_counter(), time.process_time()
        plan_area(region.shell.vertices, 10.0, crs=None, holes=[h.vertices for h in region.holes])
        e2e.append(time.perf_counter() - t0)
        e2e_cpu.append(time.process_time() - c0)
    timing["plan_area_with_coverage"], cpu["plan_area_with_coverage"] = e2e, e2e_cpu
    results["timing"] = {
        m: {
            "median": statistics.median(v),
            "max": max(v),
            "cpu_median": statistics.median(cpu[m]),
            "cpu_max": max(cpu[m]),
        }
        for m, v in timing.items()
    }
    print("(wall time on a shared machine; CPU time of this process beside it)")
    for m, v in results["timing"].items():
        print(
            f"{m:24s} wall median {v['median']:.2f} s, max {v['max']:.2f} s; "
            f"cpu median {v['cpu_median']:.2f} s, max {v['cpu_max']:.2f} s"
        )
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(results, fh, indent=2)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
