"""Benchmark the optimisers against a dense exact grid on random convex polygons.

For each of N seeded random convex polygons (3-9 vertices, Valtr's algorithm as in the paper;
spacing uniform in (0.01, 1/3) of the polygon's diameter), every method's answer (its EXACT
fitness) is compared with the best value of a dense reference grid (3600 angles x 200 offsets,
exact model) and with the paper's 200-sample grid search. Times per polygon, after one warm-up
call of each method (the first torch optimizer costs about a second of imports): wall time and
CPU time of this process. The work is many small tensor operations, so it runs on one torch
thread by default (``--threads``): extra intra-op threads only add overhead here, and on a
shared, busy machine they spin and multiply the wall time; the CPU time is the steadier measure.

Rows:
  grid-200         grid_search(**GRID_200): the paper's 14 x 14 grid
  gradient-paper   the paper's gradient descent: SGD, momentum 0.8, 200 steps, one random start
                   (seeded per polygon), no screening, no zoom, no early stopping
  gradient         gradient_descent() defaults: Adam, 8 starts screened from 1024, annealed
                   temperature 50 -> 200, early stopping, exact zoom
  hybrid           hybrid() defaults: 42 x 28 grid, 3 starts, 30 Adam steps, exact zoom
  hybrid-200       hybrid() on the paper's 14 x 14 grid
  --extra ablations: hybrid without the zoom, the zoom without gradient steps, the smooth closed
  form as the guide (if boustro.smooth is present)

Targets (issue 3): gradient-paper mean (fitness - grid-200) >= -0.136 (the paper's finding);
hybrid mean gap to the reference < 0.005 with a median time < 50 ms per polygon.

Usage: python benchmarks/optimizers.py [--polygons 200] [--seed 0] [--quick] [--extra]
       [--threads 1] [--out results.json] [--reference-cache reference.json]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import sys
import time
from collections.abc import Callable

import numpy as np
import torch

from boustro.geometry import Polygon, random_convex_polygon
from boustro.optimize import GRID_200, OptimizeResult, gradient_descent, grid_search, hybrid

Method = Callable[[Polygon, float, int], OptimizeResult]


def problems(count: int, seed: int) -> list[tuple[Polygon, float]]:
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        polygon = random_convex_polygon(rng, int(rng.integers(3, 10)))
        out.append((polygon, float(rng.uniform(0.01, 1 / 3)) * polygon.diameter))
    return out


def methods(extra: bool) -> dict[str, Method]:
    rows: dict[str, Method] = {
        "grid-200": lambda p, s, i: grid_search(p, s, **GRID_200),
        "gradient-paper": lambda p, s, i: gradient_descent(
            p,
            s,
            optimizer="sgd",
            momentum=0.8,
            steps=200,
            starts=1,
            screen=0,
            zoom_levels=0,
            patience=None,
            seed=i,
        ),
        "gradient": lambda p, s, i: gradient_descent(p, s, seed=i),
        "hybrid": lambda p, s, i: hybrid(p, s),
        "hybrid-200": lambda p, s, i: hybrid(p, s, **GRID_200),
    }
    if extra:
        rows["hybrid-no-zoom"] = lambda p, s, i: hybrid(p, s, zoom_levels=0)
        rows["grid+zoom (0 steps)"] = lambda p, s, i: hybrid(p, s, steps=0)
        try:
            from boustro.smooth import SmoothModel
        except ImportError:  # pragma: no cover - the smooth closed form is another module
            pass
        else:
            rows["hybrid-smooth"] = lambda p, s, i: hybrid(p, s, model=SmoothModel())
    return rows


def summarise(
    gaps: np.ndarray, vs_grid: np.ndarray, times: np.ndarray, cpu: np.ndarray
) -> dict[str, float]:
    return {
        "mean_gap": float(gaps.mean()),
        "worst_gap": float(gaps.max()),
        "within_1e-3": float(np.mean(gaps <= 1e-3)),
        "mean_vs_grid200": float(vs_grid.mean()),
        "worst_vs_grid200": float(vs_grid.min()),
        "median_ms": float(np.median(times) * 1e3),
        "p95_ms": float(np.percentile(times, 95) * 1e3),
        "cpu_median_ms": float(np.median(cpu) * 1e3),
        "cpu_p95_ms": float(np.percentile(cpu, 95) * 1e3),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--polygons", type=int, default=200, help="number of polygons (200)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the polygons (0)")
    parser.add_argument(
        "--quick",
        action="store_true",
        help="20 polygons and a 720 x 100 reference grid (a smoke test, not the benchmark)",
    )
    parser.add_argument("--extra", action="store_true", help="ablation rows too")
    parser.add_argument(
        "--only", default=None, metavar="NAMES", help="comma-separated rows to run (default: all)"
    )
    parser.add_argument("--threads", type=int, default=1, help="torch threads (1)")
    parser.add_argument("--out", default=None, help="write per-polygon results to this JSON file")
    parser.add_argument(
        "--reference-cache",
        default=None,
        metavar="FILE",
        help="reuse the dense reference values stored in FILE for the same polygons and grid "
        "(computed and stored there if absent)",
    )
    args = parser.parse_args(argv)
    if args.threads:
        torch.set_num_threads(args.threads)
    count = 20 if args.quick else args.polygons
    ref_grid = (720, 100) if args.quick else (3600, 200)
    cases = problems(count, args.seed)
    rows = methods(args.extra or args.only is not None)
    if args.only is not None:
        wanted = [name.strip() for name in args.only.split(",")]
        unknown = sorted(set(wanted) - set(rows))
        if unknown:
            parser.error(f"unknown rows {unknown}; expected some of {sorted(rows)}")
        rows = {name: rows[name] for name in wanted}
    print(
        f"# {count} polygons, seed {args.seed}, reference grid {ref_grid[0]} x {ref_grid[1]}; "
        f"torch {torch.__version__}, {torch.get_num_threads()} threads, "
        f"{platform.processor() or platform.machine()}, load average "
        f"{os.getloadavg()[0]:.2f}",
        flush=True,
    )

    key = {"polygons": count, "seed": args.seed, "reference_grid": list(ref_grid)}
    cached = None
    if args.reference_cache and os.path.exists(args.reference_cache):
        with open(args.reference_cache, encoding="utf-8") as fh:
            stored = json.load(fh)
        if {k: stored.get(k) for k in key} == key:
            cached = stored["reference"]
            print(f"# reference values from {args.reference_cache}", flush=True)
    t0 = time.perf_counter()
    reference = [] if cached is None else list(cached)
    for i, (polygon, spacing) in enumerate(cases if cached is None else []):
        ref = grid_search(polygon, spacing, n_angles=ref_grid[0], n_offsets=ref_grid[1])
        reference.append(ref.fitness)
        if (i + 1) % 20 == 0:
            print(
                f"#   reference {i + 1}/{count} ({time.perf_counter() - t0:.0f} s)",
                file=sys.stderr,
                flush=True,
            )
    if args.reference_cache and cached is None:
        with open(args.reference_cache, "w", encoding="utf-8") as fh:
            json.dump({**key, "reference": reference}, fh)
    reference_arr = np.array(reference)
    grid200 = np.array([grid_search(p, s, **GRID_200).fitness for p, s in cases])

    warm_polygon, warm_spacing = problems(1, args.seed + 1)[0]
    results: dict[str, dict[str, object]] = {}
    for name, method in rows.items():
        method(warm_polygon, warm_spacing, 0)
        fitness, times, cpu = [], [], []
        for i, (polygon, spacing) in enumerate(cases):
            start, start_cpu = time.perf_counter(), time.process_time()
            result = method(polygon, spacing, i)
            times.append(time.perf_counter() - start)
            cpu.append(time.process_time() - start_cpu)
            fitness.append(result.fitness)
        values = np.array(fitness)
        stats = summarise(reference_arr - values, values - grid200, np.array(times), np.array(cpu))
        results[name] = {"summary": stats, "fitness": fitness, "seconds": times, "cpu": cpu}
        print(f"#   {name} done", file=sys.stderr, flush=True)

    print()
    print("gap = reference - fitness (> 0: worse than the dense grid; < 0: better than it);")
    print("vs grid-200 = fitness - grid-200 fitness; times per polygon, wall and CPU")
    header = (
        f"{'method':<20} {'mean gap':>9} {'worst gap':>9} {'gap<=1e-3':>9} "
        f"{'vs grid-200':>11} {'worst vs':>9} {'median ms':>9} {'p95 ms':>8} "
        f"{'cpu med':>8} {'cpu p95':>8}"
    )
    print(header)
    print("-" * len(header))
    for name, data in results.items():
        st = data["summary"]
        assert isinstance(st, dict)
        print(
            f"{name:<20} {st['mean_gap']:>9.5f} {st['worst_gap']:>9.5f} "
            f"{st['within_1e-3']:>9.1%} {st['mean_vs_grid200']:>+11.5f} "
            f"{st['worst_vs_grid200']:>+9.5f} {st['median_ms']:>9.1f} {st['p95_ms']:>8.1f} "
            f"{st['cpu_median_ms']:>8.1f} {st['cpu_p95_ms']:>8.1f}"
        )
    print()
    if "gradient-paper" in results:
        st = results["gradient-paper"]["summary"]
        assert isinstance(st, dict)
        ok = st["mean_vs_grid200"] >= -0.136
        print(
            f"target gradient-paper mean vs grid-200 >= -0.136: {st['mean_vs_grid200']:+.5f} "
            f"{'PASS' if ok else 'MISS'}"
        )
    if "hybrid" in results:
        st = results["hybrid"]["summary"]
        assert isinstance(st, dict)
        ok_gap, ok_time = st["mean_gap"] < 0.005, st["median_ms"] < 50
        print(
            f"target hybrid mean gap < 0.005: {st['mean_gap']:.5f} "
            f"{'PASS' if ok_gap else 'MISS'}; median time < 50 ms: {st['median_ms']:.1f} ms "
            f"wall {'PASS' if ok_time else 'MISS'} ({st['cpu_median_ms']:.1f} ms CPU)"
        )
    print(f"# load average at the end {os.getloadavg()[0]:.2f}")
    if args.out:
        with open(args.out, "w", encoding="utf-8") as fh:
            json.dump(
                {
                    "polygons": count,
                    "seed": args.seed,
                    "reference_grid": ref_grid,
                    "reference": reference,
                    "grid200": grid200.tolist(),
                    "spacing_fraction": [s / p.diameter for p, s in cases],
                    "vertices": [len(p) for p, _ in cases],
                    "methods": results,
                },
                fh,
                indent=1,
                allow_nan=False,
                default=lambda x: None if isinstance(x, float) and not math.isfinite(x) else x,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
