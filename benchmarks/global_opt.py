"""Benchmark the certified global optimiser against the other optimisers, in one run.

Protocol (the paper's, as in ``benchmarks/optimizers.py``): N seeded random convex polygons,
3-9 vertices (Valtr's algorithm), spacing uniform in (0.01, 1/3) of the polygon's diameter;
Eq. 1 with a = b = 0.5.

Eq. 1 rows: every method whose name is registered in ``boustro.optimize.METHODS`` at run time
among ``grid`` (the paper's 14 x 14 grid, GRID_200), ``gradient`` and ``hybrid`` (their
defaults), called as ``optimize.optimize(polygon, spacing, method=...)``, and ``global``
(``boustro.global_opt.global_optimum``, tol 1e-6). For each: mean and worst gap of its EXACT
fitness to the global optimum's fitness (``global fitness - method fitness``; the global
optimum is certified within ``gap`` of the true optimum), the share of polygons where it is
within 1e-6 of it, and median / p95 / max time per polygon (wall; CPU in brackets). For the
global method also the certified gap (``upper_bound - fitness``): max and the share <= 1e-6.

Fewest-transects rows: the exact optimum (``fewest_transects_optimum``: the minimum-width
direction, closed form) against brute force over angles at 1 and 0.1 degree steps (the usual
practice of coverage planners), all with the same count ``ceil(width / spacing)``: mean count,
polygons where the brute force needs more transects than the exact optimum, and time.

Targets (issue 5): global certified gap <= 1e-6 on every polygon; median time <= 20 ms and p95
<= 200 ms per polygon.

Usage: python benchmarks/global_opt.py [--polygons 1000] [--seed 0] [--quick] [--out FILE]
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

from boustro import optimize as opt
from boustro.geometry import Polygon, random_convex_polygon
from boustro.global_opt import fewest_transects_optimum, global_optimum
from boustro.objectives import coverage_count

Runner = Callable[[Polygon, float], opt.OptimizeResult]


def problems(count: int, seed: int) -> list[tuple[Polygon, float]]:
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        polygon = random_convex_polygon(rng, int(rng.integers(3, 10)))
        out.append((polygon, float(rng.uniform(0.01, 1 / 3)) * polygon.diameter))
    return out


def eq1_methods() -> dict[str, Runner]:
    """The Eq. 1 optimisers present at run time, by row name."""
    rows: dict[str, Runner] = {}
    if "grid" in opt.METHODS:
        rows["grid-200"] = lambda p, s: opt.optimize(p, s, method="grid", **opt.GRID_200)
    for name in ("gradient", "hybrid"):
        if name in opt.METHODS:
            rows[name] = lambda p, s, name=name: opt.optimize(p, s, method=name)
    rows["global"] = lambda p, s: global_optimum(p, s)
    return rows


def brute_force_count(polygon: Polygon, spacing: float, step_deg: float) -> tuple[int, float]:
    """Fewest transects over angles ``0, step, 2 step, ... < 180`` degrees, and the angle."""
    v = polygon.vertices - polygon.centre
    theta = np.deg2rad(np.arange(0.0, 180.0, step_deg))
    h = v[:, 1] * np.cos(theta)[:, None] - v[:, 0] * np.sin(theta)[:, None]
    widths = h.max(axis=1) - h.min(axis=1)
    counts = np.ceil(widths / spacing - 1e-12 * np.maximum(1.0, widths / spacing))
    k = int(np.argmin(counts))
    return int(counts[k]), float(theta[k])


def timed(fn: Callable[[], object]) -> tuple[object, float, float]:
    start, start_cpu = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - start, time.process_time() - start_cpu


def ms(values: list[float]) -> tuple[float, float, float]:
    arr = np.array(values) * 1e3
    return float(np.median(arr)), float(np.percentile(arr, 95)), float(arr.max())


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--polygons", type=int, default=1000, help="number of polygons (1000)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the polygons (0)")
    parser.add_argument("--quick", action="store_true", help="50 polygons (a smoke test)")
    parser.add_argument("--threads", type=int, default=1, help="torch threads (1)")
    parser.add_argument("--out", default=None, help="write per-polygon results to this JSON file")
    args = parser.parse_args(argv)
    if args.threads:
        torch.set_num_threads(args.threads)
    count = 50 if args.quick else args.polygons
    cases = problems(count, args.seed)
    rows = eq1_methods()
    print(
        f"# {count} polygons, seed {args.seed}; methods run: {', '.join(rows)}; "
        f"torch {torch.__version__}, {torch.get_num_threads()} threads, "
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, load average "
        f"{os.getloadavg()[0]:.2f}",
        flush=True,
    )
    warm_polygon, warm_spacing = problems(1, args.seed + 1)[0]
    results: dict[str, dict[str, list]] = {}
    t_all = time.perf_counter()
    for name, run in rows.items():
        run(warm_polygon, warm_spacing)
        data: dict[str, list] = {"fitness": [], "seconds": [], "cpu": [], "gap": []}
        for i, (polygon, spacing) in enumerate(cases):
            res, wall, cpu = timed(lambda p=polygon, s=spacing, run=run: run(p, s))
            assert isinstance(res, opt.OptimizeResult)
            data["fitness"].append(res.fitness)
            data["seconds"].append(wall)
            data["cpu"].append(cpu)
            data["gap"].append(res.gap)
            if (i + 1) % 100 == 0:
                print(
                    f"#   {name} {i + 1}/{count} ({time.perf_counter() - t_all:.0f} s)",
                    file=sys.stderr,
                    flush=True,
                )
        results[name] = data

    best = np.array(results["global"]["fitness"])
    certified = np.array(results["global"]["gap"], dtype=float)
    print()
    print("Eq. 1 (a = b = 0.5): gap = global fitness - method fitness (the global optimum is")
    print("certified within its gap of the true optimum); times per polygon, wall (CPU)")
    header = (
        f"{'method':<10} {'mean gap':>10} {'worst gap':>10} {'within 1e-6':>11} "
        f"{'median ms':>14} {'p95 ms':>14} {'max ms':>16}"
    )
    print(header)
    print("-" * len(header))
    summary: dict[str, dict[str, float]] = {}
    for name, data in results.items():
        gap = best - np.array(data["fitness"])
        med, p95, mx = ms(data["seconds"])
        cmed, cp95, cmx = ms(data["cpu"])
        summary[name] = {
            "mean_gap": float(gap.mean()),
            "worst_gap": float(gap.max()),
            "within_1e-6": float(np.mean(gap <= 1e-6)),
            "median_ms": med,
            "p95_ms": p95,
            "max_ms": mx,
            "cpu_median_ms": cmed,
            "cpu_p95_ms": cp95,
            "cpu_max_ms": cmx,
            "best_beats_global_by": float(-gap.min()),
        }
        print(
            f"{name:<10} {gap.mean():>10.6f} {gap.max():>10.6f} {np.mean(gap <= 1e-6):>11.1%} "
            f"{med:>6.1f} ({cmed:>5.1f}) {p95:>6.1f} ({cp95:>5.1f}) {mx:>7.1f} ({cmx:>6.1f})"
        )
    beaten = max(v["best_beats_global_by"] for k, v in summary.items() if k != "global")
    if beaten > 0:
        print(f"another method beat the global answer by {beaten:.2e} (within its certified gap?)")
    else:
        print(f"no method beat the global answer (the closest was {-beaten:.2e} below it)")
    s_global = summary["global"]
    print(
        f"global certified gap: max {certified.max():.2e}, share <= 1e-6 "
        f"{np.mean(certified <= 1e-6):.1%}"
    )
    ok_gap = bool(np.all(certified <= 1e-6))
    ok_med, ok_p95 = s_global["median_ms"] <= 20.0, s_global["p95_ms"] <= 200.0
    print(
        f"target certified gap <= 1e-6 on every polygon: {'PASS' if ok_gap else 'MISS'}; "
        f"median <= 20 ms: {s_global['median_ms']:.1f} ms {'PASS' if ok_med else 'MISS'}; "
        f"p95 <= 200 ms: {s_global['p95_ms']:.1f} ms {'PASS' if ok_p95 else 'MISS'}"
    )

    # fewest transects: exact vs brute force over angles
    exact_n, exact_t = [], []
    brute: dict[str, tuple[list[int], list[float]]] = {"1 deg": ([], []), "0.1 deg": ([], [])}
    for polygon, spacing in cases:
        res, wall, _ = timed(
            lambda polygon=polygon, spacing=spacing: fewest_transects_optimum(polygon, spacing)
        )
        assert isinstance(res, opt.OptimizeResult)
        exact_n.append(int(res.fitness))
        exact_t.append(wall)
        assert int(res.fitness) == coverage_count(res.info["width"], spacing)
        for label, step in (("1 deg", 1.0), ("0.1 deg", 0.1)):
            (n, _), wall_b, _ = timed(
                lambda polygon=polygon, spacing=spacing, step=step: brute_force_count(
                    polygon, spacing, step
                )
            )  # type: ignore[misc]
            brute[label][0].append(n)
            brute[label][1].append(wall_b)
    exact_arr = np.array(exact_n)
    print()
    print("Fewest transects with full coverage (count = ceil(width / spacing)):")
    header = (
        f"{'method':<18} {'mean count':>10} {'worse':>6} {'extra':>6} {'max extra':>9} "
        f"{'median ms':>9} {'p95 ms':>8} {'max ms':>8}"
    )
    print(header)
    print("-" * len(header))
    fewest: dict[str, dict[str, float]] = {}
    for label, counts, times in [("exact (min width)", exact_n, exact_t)] + [
        (f"brute force {k}", v[0], v[1]) for k, v in brute.items()
    ]:
        arr = np.array(counts)
        extra = arr - exact_arr
        med, p95, mx = ms(times)
        fewest[label] = {
            "mean_count": float(arr.mean()),
            "polygons_worse": int(np.sum(extra > 0)),
            "total_extra": int(extra.sum()),
            "max_extra": int(extra.max()),
            "min_extra": int(extra.min()),
            "median_ms": med,
            "p95_ms": p95,
            "max_ms": mx,
        }
        print(
            f"{label:<18} {arr.mean():>10.3f} {np.sum(extra > 0):>6d} {extra.sum():>6d} "
            f"{extra.max():>9d} {med:>9.3f} {p95:>8.3f} {mx:>8.3f}"
        )
    print(f"# load average at the end {os.getloadavg()[0]:.2f}")
    if args.out:
        with open(args.out, "w", encoding="utf-8") as fh:
            json.dump(
                {
                    "polygons": count,
                    "seed": args.seed,
                    "methods": list(rows),
                    "summary": summary,
                    "fewest_transects": fewest,
                    "spacing_fraction": [s / p.diameter for p, s in cases],
                    "vertices": [len(p) for p, _ in cases],
                    "per_polygon": results,
                },
                fh,
                indent=1,
                allow_nan=False,
                default=lambda x: None if isinstance(x, float) and not math.isfinite(x) else x,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
