"""Benchmark (issues 19, 21): Eq. 1 certified at scale, ``method="certified-bb"``.

Rows (CPU seconds, ``time.process_time``; the machine is shared):

* the 1000-vertex smooth convex field of ``benchmarks/web.py`` (a 300 x 210 m ellipse, 10 m
  spacing) at several ``tol``, beside the hybrid optimiser (what ``plan`` used before) in the
  same run;
* convex fields of 200..5000 vertices at 10 m spacing: a rounded rectangle traced with ``n``
  points (a superellipse, 500 x 360 m, tilted 17 degrees) and the convex hull of
  ``traced_field(n)`` (fewer vertices: the hull of a noisy lobed trace), time, boxes, gap; the
  hybrid beside them up to ``--hybrid-max`` vertices;
* agreement with the event method (``method="global"``) on random convex polygons of 16-40
  vertices: the same optimum within the two gaps, and both times.

    python benchmarks/eq1_scale.py [--quick] [--hybrid-max 1000]
"""

from __future__ import annotations

import argparse
import math
import os
import time

import numpy as np

from boustro.geometry.random import random_convex_polygon
from boustro.geometry.traced import traced_field
from boustro.optimize import optimize
from boustro.optimize.exact import global_optimum
from boustro.optimize.smith_bb import smith_bb


def ellipse(n: int = 1000) -> np.ndarray:
    t = np.linspace(0, 2 * math.pi, n, endpoint=False)
    return np.c_[150 * np.cos(t), 105 * np.sin(t)]


def superellipse(n: int, seed: int = 0) -> np.ndarray:
    t = np.sort(np.random.default_rng(seed).uniform(0, 2 * math.pi, n))
    c, s = np.cos(t), np.sin(t)
    x, y = 250 * np.sign(c) * np.abs(c) ** 0.5, 180 * np.sign(s) * np.abs(s) ** 0.5
    a = math.radians(17)
    return np.c_[x * math.cos(a) - y * math.sin(a), x * math.sin(a) + y * math.cos(a)]


def hull(n: int) -> np.ndarray:
    import shapely

    ring = traced_field(n).shell.vertices
    return np.asarray(shapely.Polygon(ring).convex_hull.exterior.coords)[:-1]


def timed(fn, *args, **kwargs):
    t0 = time.process_time()
    out = fn(*args, **kwargs)
    return out, time.process_time() - t0


def load() -> str:
    return "load " + " ".join(f"{x:.1f}" for x in os.getloadavg())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer sizes and polygons")
    ap.add_argument("--hybrid-max", type=int, default=500)
    args = ap.parse_args()
    print(f"# {time.strftime('%Y-%m-%d %H:%M')} {load()}")
    _, first = timed(smith_bb, [(0, 0), (2, 0), (2, 1), (0, 1)], 0.25)
    print(f"first call (numba compiled or loaded from its cache): {first:.2f} s CPU\n")

    print("## 1000-vertex ellipse, 10 m spacing")
    print("| method | tol | CPU s | boxes | fitness | gap |")
    print("|---|---|---|---|---|---|")
    field = ellipse()
    for tol in (1e-3, 1e-4, 1e-5) if args.quick else (1e-3, 1e-4, 1e-5, 1e-6):
        r, t = timed(smith_bb, field, 10.0, tol=tol)
        print(f"| certified-bb | {tol:g} | {t:.2f} | {r.info['boxes']} | {r.fitness:.7f} "
              f"| {r.gap:.1e} |")  # fmt: skip
    r, t = timed(optimize, field, 10.0, method="hybrid")
    print(f"| hybrid | - | {t:.2f} | - | {r.fitness:.7f} | none |")

    print(f"\n## convex fields, 10 m spacing, tol 1e-4 ({load()})")
    print("| field | vertices | CPU s | boxes | gap | hybrid CPU s | bb - hybrid fitness |")
    print("|---|---|---|---|---|---|---|")
    sizes = (200, 1000, 5000) if args.quick else (200, 500, 1000, 2000, 5000)
    for n in sizes:
        fields = (("superellipse", superellipse(n)), (f"hull of traced_field({n})", hull(n)))
        for name, ring in fields:
            r, t = timed(smith_bb, ring, 10.0, tol=1e-4)
            cells = [name, str(len(ring)), f"{t:.2f}", str(r.info["boxes"]), f"{r.gap:.1e}"]
            if len(ring) <= args.hybrid_max:
                h, th = timed(optimize, ring, 10.0, method="hybrid")
                cells += [f"{th:.2f}", f"{r.fitness - h.fitness:+.1e}"]
            else:
                cells += ["-", "-"]
            print("| " + " | ".join(cells) + " |", flush=True)

    print(f"\n## agreement with the event method, tol 1e-6 ({load()})")
    print("| vertices | spacing / diameter | global | gap | CPU s | certified-bb | gap | CPU s |")
    print("|---|---|---|---|---|---|---|---|")
    rng = np.random.default_rng(21)
    agree = 0
    count = 4 if args.quick else 10
    for _ in range(count):
        p = random_convex_polygon(rng, int(rng.integers(16, 41)))
        s = p.diameter * float(rng.uniform(0.02, 0.1))
        g, tg = timed(global_optimum, p, s)
        b, tb = timed(smith_bb, p, s, tol=1e-6)
        ok = b.fitness >= g.fitness - b.gap - 1e-12 and g.fitness >= b.fitness - g.gap - 1e-12
        agree += ok
        print(f"| {len(p)} | {s / p.diameter:.3f} | {g.fitness:.9f} | {g.gap:.1e} | {tg:.2f} "
              f"| {b.fitness:.9f} | {b.gap:.1e} | {tb:.2f} |", flush=True)  # fmt: skip
    print(f"\nagree within the gaps: {agree}/{count}; {load()}")


if __name__ == "__main__":
    main()
