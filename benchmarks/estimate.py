"""Benchmark (issues 20 and 21): calibrating the planning-time estimate of ``boustro plan``.

Plans convex areas (Valtr's random polygons) and concave ones (a three-lobed star with
traced-like noise) of 10..2000 vertices at spacings giving about 10..150 lanes across, planar,
through :func:`boustro.mission.plan_area`, and prints for each case the estimate's features
(:func:`boustro.mission.estimate_work`: lanes, vertices), the estimated and the measured time.
Times are CPU (``time.process_time``). ``--objective time`` (``--keep-inside``) measures the
plan-level objective's rows (the cover search). With ``--fit`` it fits the coefficients of the
model in :mod:`boustro.mission.estimate` (least squares on the logarithm of the time) and
prints them and the error.

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
from boustro.mission.estimate import COST_MODEL, estimate_seconds


def star(n: int, seed: int = 0) -> np.ndarray:
    """A three-lobed star of ``n`` vertices, about 1000 m across, with traced-like noise."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    r = 500 * (0.65 + 0.35 * np.cos(3 * t)) * (1 + 0.004 * rng.standard_normal(n))
    return np.stack([r * np.cos(t), r * np.sin(t)], axis=1)


def convex(n: int, seed: int = 0) -> np.ndarray:
    """A random convex polygon of ``n`` vertices, 1000 m across."""
    return random_convex_polygon(np.random.default_rng(seed), n).vertices * 1000.0


def measure(kind: str, n: int, lanes: int, **objective) -> dict:
    """``objective``: ``speed``, ``turn_time``, ``keep_inside`` (a plan-level objective)."""
    ring = convex(n) if kind == "convex" else star(n)
    spacing = 1000.0 / lanes
    est = estimate_work(ring, spacing, crs=None, **objective)
    t0 = time.process_time()
    plan_area(ring, spacing, crs=None, check_coverage=False, force=True, **objective)
    seconds = time.process_time() - t0
    return {
        "shape": kind,
        "vertices": n,
        "lanes": round(est.lanes, 1),
        "kind": est.kind,
        "work": est.work,
        "estimated_s": round(est.seconds, 3),
        "measured_s": round(seconds, 3),
        "keep_inside": bool(objective.get("keep_inside")),
    }


def _powers(x: np.ndarray, log_c1: float, beta: float, log_c2: float, alpha: float):
    n, lanes, a = x
    return np.log(a + np.exp(log_c1) * lanes**beta + np.exp(log_c2) * n**alpha)


def fit(rows: list[dict]) -> dict[str, tuple[float, ...]]:
    """Least squares on the logarithm of the time: ``b`` of ``a + b W`` (the median of
    ``(T - a) / W``), and ``c1, beta, c2, alpha`` of ``a + c1 L^beta + c2 n^alpha``."""
    from scipy.optimize import curve_fit

    model = dict(COST_MODEL)
    for kind, (a, *_rest) in COST_MODEL.items():
        sel = [r for r in rows if r["kind"] == kind]
        if len(sel) < 5:
            continue
        t = np.array([r["measured_s"] for r in sel])
        if kind == "certified":
            work = np.array([r["work"] for r in sel])
            model[kind] = (a, float(np.median(np.maximum(t - a, 1e-3) / work)))
        else:
            n = np.array([r["vertices"] for r in sel], float)
            lanes = np.array([r["lanes"] for r in sel], float)
            x = np.stack([n, lanes, np.full_like(n, a)])
            p, _ = curve_fit(_powers, x, np.log(t), p0=(-6.0, 1.0, -12.0, 2.0), maxfev=20000)
            model[kind] = (a, float(np.exp(p[0])), float(p[1]), float(np.exp(p[2])), float(p[3]))
        print(f"{kind}: fitted {[float(f'{c:.3g}') for c in model[kind]]} on {len(sel)} cases")
    return model


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="10,30,50,200,1000,2000")
    ap.add_argument("--lanes", default="10,40,150")
    ap.add_argument("--fit", action="store_true")
    ap.add_argument("--rows", help="fit and compare the JSON rows of an earlier run's output")
    ap.add_argument(
        "--objective",
        choices=("default", "time"),
        default="default",
        help="time: --speed 5 --turn-time 10 (the cover search's rows)",
    )
    ap.add_argument("--keep-inside", action="store_true", help="with --objective time")
    ap.add_argument(
        "--max-product", type=float, default=1e5, help="skip cases with vertices x lanes above"
    )
    args = ap.parse_args()
    if args.rows:
        with open(args.rows) as f:
            rows = [json.loads(line) for line in f if line.startswith("{")]
        for r in rows:
            r["estimated_s"] = estimate_seconds(r["kind"], r["vertices"], r["lanes"], r["work"])
        report(rows, fit(rows) if args.fit else COST_MODEL)
        return
    rows = []
    objective: dict = {}
    if args.objective == "time":
        objective = dict(speed=5.0, turn_time=10.0, keep_inside=args.keep_inside)
    plan_area(convex(10), 100.0, crs=None, **objective)  # warm up (imports, kernels)
    plan_area(star(50), 100.0, crs=None, **objective)
    for kind in ("convex", "concave"):
        for n in map(int, args.sizes.split(",")):
            for lanes in map(int, args.lanes.split(",")):
                if n * lanes > args.max_product:
                    continue
                row = measure(kind, n, lanes, **objective)
                rows.append(row)
                print(json.dumps(row), flush=True)
    report(rows, fit(rows) if args.fit else COST_MODEL)


def report(rows: list[dict], model: dict[str, tuple[float, ...]]) -> None:
    """The ratio estimate / measured of ``model`` over ``rows``, per row of the model."""
    saved = dict(COST_MODEL)
    COST_MODEL.update(model)
    try:
        for kind in model:
            sel = [r for r in rows if r["kind"] == kind]
            if not sel:
                continue
            ratios = np.array(
                [
                    estimate_seconds(kind, r["vertices"], r["lanes"], r["work"]) / r["measured_s"]
                    for r in sel
                ]
            )
            print(
                f"{kind} {model[kind]}: estimate / measured over {len(sel)} cases "
                f"{ratios.min():.2f}..{ratios.max():.2f} (median {np.median(ratios):.2f}; "
                f"rms of log10 {math.sqrt(np.mean(np.log10(ratios) ** 2)):.2f})"
            )
    finally:
        COST_MODEL.clear()
        COST_MODEL.update(saved)


if __name__ == "__main__":
    main()
