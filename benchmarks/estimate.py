"""Benchmark (issues 20 and 21): calibrating the planning-time estimate of ``boustro plan``.

Plans convex areas (Valtr's random polygons) and concave ones (a three-lobed star with
traced-like noise) of 10..2000 vertices at spacings giving about 10..150 lanes across, planar,
through :func:`boustro.mission.plan_area`, and prints for each case the estimate's features
(:func:`boustro.mission.estimate_work`: lanes, vertices), the estimated and the measured time.
With ``--fit`` it fits the coefficients of the model in :mod:`boustro.mission.estimate`
(least squares on the logarithm of the time) and prints them and the error.

    python benchmarks/estimate.py [--sizes 10,50,200,1000,2000] [--lanes 10,40,150] [--fit]
"""

from __future__ import annotations

import argparse
import json
import math
import time

import numpy as np

from boustro.geometry.random import random_convex_polygon
from boustro.mission import estimate_work, plan_area
from boustro.mission.estimate import COST_MODEL


def star(n: int, seed: int = 0) -> np.ndarray:
    """A three-lobed star of ``n`` vertices, about 1000 m across, with traced-like noise."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    r = 500 * (0.65 + 0.35 * np.cos(3 * t)) * (1 + 0.004 * rng.standard_normal(n))
    return np.stack([r * np.cos(t), r * np.sin(t)], axis=1)


def convex(n: int, seed: int = 0) -> np.ndarray:
    """A random convex polygon of ``n`` vertices, 1000 m across."""
    return random_convex_polygon(np.random.default_rng(seed), n).vertices * 1000.0


def measure(kind: str, n: int, lanes: int) -> dict:
    ring = convex(n) if kind == "convex" else star(n)
    spacing = 1000.0 / lanes
    est = estimate_work(ring, spacing, crs=None)
    t0 = time.perf_counter()
    plan_area(ring, spacing, crs=None, check_coverage=False, force=True)
    seconds = time.perf_counter() - t0
    return {
        "shape": kind,
        "vertices": n,
        "lanes": round(est.lanes, 1),
        "kind": est.kind,
        "work": est.work,
        "estimated_s": round(est.seconds, 3),
        "measured_s": round(seconds, 3),
    }


def fit(rows: list[dict]) -> None:
    """Least squares of the model's rows: ``b`` of ``a + b W`` (the median of ``(T - a) / W``),
    and ``c, alpha, beta`` of ``a + c n^alpha L^beta`` on ``log(T - a)``."""
    for kind, (a, *_rest) in COST_MODEL.items():
        sel = [r for r in rows if r["kind"] == kind and r["measured_s"] > a]
        if len(sel) < 3:
            continue
        t = np.array([r["measured_s"] for r in sel]) - a
        if kind == "certified":
            coef = [a, float(np.median(t / np.array([r["work"] for r in sel])))]
        else:
            n = np.log([r["vertices"] for r in sel])
            lanes = np.log([r["lanes"] for r in sel])
            x = np.stack([np.ones_like(n), n, lanes], axis=1)
            (logc, alpha, beta), *_ = np.linalg.lstsq(x, np.log(t), rcond=None)
            coef = [a, float(np.exp(logc)), float(alpha), float(beta)]
        print(f"{kind}: fitted {[float(f'{c:.3g}') for c in coef]} on {len(sel)} cases")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="10,30,50,200,1000,2000")
    ap.add_argument("--lanes", default="10,40,150")
    ap.add_argument("--fit", action="store_true")
    ap.add_argument(
        "--max-product", type=float, default=1e5, help="skip cases with vertices x lanes above"
    )
    args = ap.parse_args()
    rows = []
    plan_area(convex(10), 100.0, crs=None)  # warm up (imports, compiled kernels)
    plan_area(star(50), 100.0, crs=None)
    for kind in ("convex", "concave"):
        for n in map(int, args.sizes.split(",")):
            for lanes in map(int, args.lanes.split(",")):
                if n * lanes > args.max_product:
                    continue
                row = measure(kind, n, lanes)
                rows.append(row)
                print(json.dumps(row), flush=True)
    if args.fit:
        fit(rows)
    ratios = [r["estimated_s"] / r["measured_s"] for r in rows if r["measured_s"] > 0]
    print(
        f"model {COST_MODEL}: estimate / measured over {len(ratios)} cases: "
        f"{min(ratios):.2f}..{max(ratios):.2f} (median {float(np.median(ratios)):.2f}); "
        f"log10 error rms {math.sqrt(np.mean(np.log10(ratios) ** 2)):.2f}"
    )


if __name__ == "__main__":
    main()
