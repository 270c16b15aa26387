"""CPU of ``plan_area`` on concave areas and areas with holes: the default (the certified Eq. 1
optimum over segments, :mod:`boustro.mission.region_certified`) against ``method="grid"`` (the
grid search, the baseline before the certified search) measured in the same run, best of two
interleaved repeats of ``time.process_time``; the first (compiling) call is excluded.

    PYTHONPATH=src python benchmarks/region_certified.py [name ...]
"""

from __future__ import annotations

import logging
import math
import sys
import time

import numpy as np

from boustro.geometry.region import random_region
from boustro.mission import plan_area

Case = tuple[list, list, float]


def _noisy_field(seed: int = 2, n: int = 400, noise: float = 0.3) -> tuple[list, list]:
    """A traced 200 x 100 m field with two 12-gon ponds of radius 5 (the review's)."""
    rng = np.random.default_rng(seed)
    w, h = 200.0, 100.0
    pts = []
    for u in np.linspace(0, 2 * (w + h), n, endpoint=False) + 0.37:
        z = noise * rng.standard_normal()
        if u < w:
            pts.append((u, z))
        elif u < w + h:
            pts.append((w + z, u - w))
        elif u < 2 * w + h:
            pts.append((w - (u - w - h), h + z))
        else:
            pts.append((z, h - (u - 2 * w - h)))
    t = np.linspace(0, 2 * math.pi, 12, endpoint=False)
    ponds = [np.c_[30 + 40 * j + 5 * np.cos(t), 50 + 5 * np.sin(t)].tolist() for j in range(2)]
    return pts, ponds


def _comb(k: int = 5, size: float = 10.0) -> list:
    """Teeth of width 1, gaps of width 1, height 3 above a base of height 1 (times ``size``)."""
    pts = [(0, 0), (2 * k - 1, 0)]
    for i in range(k):
        right = 2 * (k - 1 - i) + 1
        pts += [(right, 4), (right - 1, 4)]
        if right - 1 > 0:
            pts += [(right - 1, 1), (right - 2, 1)]
    return [(x * size, y * size) for x, y in pts]


def cases() -> dict[str, Case]:
    u_shape = [(0, 0), (90, 0), (90, 60), (65, 60), (65, 20), (25, 20), (25, 60), (0, 60)]
    out: dict[str, Case] = {
        "L+pond 4m": (
            [(0, 0), (60, 0), (60, 20), (25, 20), (25, 50), (0, 50)],
            [[(5, 5), (15, 5), (15, 15), (5, 15)]],
            4.0,
        ),
        "U 10m": (u_shape, [], 10.0),
        "U 1m": (u_shape, [], 1.0),
        "ring 40m 7m": (
            [(0, 0), (40, 0), (40, 40), (0, 40)],
            [[(10, 10), (30, 10), (30, 30), (10, 30)]],
            7.0,
        ),
        "comb 5m": (_comb(), [], 5.0),
    }
    for seed in (5, 6, 7):
        rng = np.random.default_rng(seed)
        r = random_region(rng, int(rng.integers(15, 40)), int(rng.integers(1, 3)))
        out[f"random{seed}"] = (
            (r.shell.vertices * 100).tolist(),
            [(h.vertices * 100).tolist() for h in r.holes],
            10.0 * r.diameter,
        )
    ring, ponds = _noisy_field()
    out["noisy field 10m"] = (ring, ponds, 10.0)
    return out


def _cpu(case: Case, method: str | None) -> tuple[float, dict]:
    ring, holes, spacing = case
    t = time.process_time()
    m = plan_area(ring, spacing, crs=None, holes=holes, method=method)
    return time.process_time() - t, m.summary()


def main(names: list[str]) -> None:
    logging.disable(logging.WARNING)
    all_cases = cases()
    _cpu(all_cases["L+pond 4m"], None)  # compile
    _cpu(all_cases["L+pond 4m"], "grid")
    print(f"{'area':<16} {'certified s':>11} {'grid s':>8} {'ratio':>6} {'gap':>9} lanes")
    for name in names or list(all_cases):
        best = {None: math.inf, "grid": math.inf}
        for _ in range(2):
            for method in (None, "grid"):
                dt, summary = _cpu(all_cases[name], method)
                best[method] = min(best[method], dt)
                if method is None:
                    s = summary
        gap = s["gap"]
        print(
            f"{name:<16} {best[None]:>11.3f} {best['grid']:>8.3f} "
            f"{best[None] / best['grid']:>6.1f} {'-' if gap is None else f'{gap:.1e}':>9} "
            f"{s['n_transects']}",
            flush=True,
        )


if __name__ == "__main__":
    main(sys.argv[1:])
