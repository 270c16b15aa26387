"""Benchmark (issue 16, item 4): what keeping the path inside the area costs.

Every area is planned twice at the same spacing with the optimiser's own angle and offset
(default planner, :func:`boustro.plan.plan_region`; the shipped field through
:func:`boustro.mission.plan_area`): as today (lanes reach past the boundary) and with
``keep_inside=True``. Reported for both: path length, turns (connecting moves between
passes), the path outside the area or in a hole (shapely), the covered share of the area
itself (shapely), planning CPU time (``time.process_time``: the machine is shared); and the
ratios keep-inside / today measured in the same run.

Areas: the shipped field (3.6 ha, 10 m), an L-shape and an L with two holes (4 m), a lake-like
shore with an island (12 m), a 1 m wide square ring (1 m), and ``--count`` random concave
regions with holes (:func:`boustro.geometry.region.random_region`, 24-60 vertices, 0-3 holes,
diameter about 2, spacing 0.05-0.1).

    python benchmarks/keep_inside.py [--count 20] [--seed 0]
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

import numpy as np

from boustro.geometry.region import Region, random_region
from boustro.io import embedded_field
from boustro.mission import plan_area
from boustro.plan import coverage
from boustro.plan.region import plan_region


def _lake() -> Region:
    th = np.linspace(0, 2 * math.pi, 80, endpoint=False)
    r = 100 * (1 + 0.3 * np.sin(3 * th) + 0.12 * np.cos(7 * th + 1))
    return Region(np.stack([r * np.cos(th), r * np.sin(th)], 1), [[(10, 10), (30, 12), (25, 30)]])


def _named() -> list[tuple[str, Region, float]]:
    ell = [(0, 0), (60, 0), (60, 20), (25, 20), (25, 50), (0, 50)]
    holes = [[(5, 5), (15, 5), (15, 15), (5, 15)], [(40, 5), (48, 9), (44, 14)]]
    ring = [(0, 0), (10, 0), (10, 10), (0, 10)], [[(1, 1), (9, 1), (9, 9), (1, 9)]]
    return [
        ("L-shape", Region(ell), 4.0),
        ("L + 2 holes", Region(ell, holes), 4.0),
        ("lake + island", _lake(), 12.0),
        ("1 m square ring", Region(*ring), 1.0),
    ]


def _one(region: Region, spacing: float, keep: bool) -> dict[str, float]:
    c0 = time.process_time()
    plan = plan_region(region, spacing, keep_inside=keep)
    cpu = time.process_time() - c0
    return {
        "path": plan.stats.path_length,
        "turns": plan.stats.n_turns,
        "outside": plan.stats.outside_length,
        "covered": coverage(plan).covered_share,
        "cpu": cpu,
    }


def _field(keep: bool) -> dict[str, float]:
    c0 = time.process_time()
    m = plan_area(embedded_field(), 10.0, keep_inside=keep)
    cpu = time.process_time() - c0
    return {
        "path": m.stats.path_length,
        "turns": m.stats.n_turns,
        "outside": m.stats.outside_length,
        "covered": m.coverage.covered_share,
        "cpu": cpu,
    }


def _row(name: str, today: dict[str, float], inside: dict[str, float]) -> str:
    return (
        f"| {name} | {today['path']:.1f} / {today['turns']} / {today['outside']:.1f} | "
        f"{inside['path']:.1f} / {inside['turns']} / {inside['outside']:.3g} | "
        f"x{inside['path'] / today['path']:.3f} | {100 * inside['covered']:.6f}% | "
        f"{today['cpu']:.2f} / {inside['cpu']:.2f} |"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--count", type=int, default=20)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    print(
        "| area | today: path / turns / outside | keep-inside: path / turns / outside | "
        "path ratio | covered (keep-inside) | CPU s today / keep-inside |"
    )
    print("|---|---|---|---:|---:|---|")
    print(_row("shipped field (10 m)", _field(False), _field(True)))
    for name, region, spacing in _named():
        print(
            _row(f"{name} ({spacing:g})", _one(region, spacing, False), _one(region, spacing, True))
        )
    rng = np.random.default_rng(args.seed)
    ratios, covered, outside, cpu_in, cpu_out = [], [], [], [], []
    for _ in range(args.count):
        region = random_region(rng, int(rng.integers(24, 61)), int(rng.integers(0, 4)))
        spacing = float(rng.uniform(0.05, 0.1))
        today, inside = _one(region, spacing, False), _one(region, spacing, True)
        ratios.append(inside["path"] / today["path"])
        covered.append(inside["covered"])
        outside.append(today["outside"] / today["path"])
        cpu_in.append(inside["cpu"])
        cpu_out.append(today["cpu"])
    if ratios:
        print(
            f"| {args.count} random regions (median; min-max) | outside "
            f"{100 * statistics.median(outside):.1f}% of the path | outside 0 | "
            f"x{statistics.median(ratios):.3f} ({min(ratios):.3f}-{max(ratios):.3f}) | "
            f"min {100 * min(covered):.6f}% | {statistics.median(cpu_out):.2f} / "
            f"{statistics.median(cpu_in):.2f} (max {max(cpu_in):.2f}) |"
        )


if __name__ == "__main__":
    main()
