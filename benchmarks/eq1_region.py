"""Benchmark (issues 16 item 2, 21): the certified Eq. 1 optimum over the segments of concave
areas and areas with holes (``smith_bb_region``) beside the region grid (``region-grid``, what
``plan`` used before), CPU seconds (``time.process_time``) measured in the same run.

Rows:

* random concave areas with holes (``random_region``, 10-60 vertices, 1-2 holes, spacing 1/10
  of the diameter): the optimiser alone, certified against the 90 x 16 grid with two zooms;
* Fields2Cover's demo fields (``--data``: its ``data/`` folder, read, never copied) and
  ``test_ring.json``-like areas: ``plan_area`` at 10 m (one grid, ``decompose=False``), default
  (certified) against ``--method grid``;
* issue 21's traced field (``traced_field(2000, 10)``, spacing 10 m): the certified search alone,
  in a subprocess for its peak memory (the grid took 2 min 28 s and 5.8 GB there, issue 21;
  ``--grid-big`` runs it here too).

The first call compiles the numba kernels (about 25 s of CPU in a cold process with the chain
bound, cached on disk after); it is made before any timing.

    python benchmarks/eq1_region.py [--data /path/to/Fields2Cover/data] [--random 10]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time

import numpy as np

from boustro.geometry.region import random_region
from boustro.geometry.traced import traced_field
from boustro.io import read_areas
from boustro.mission import plan_area
from boustro.optimize.smith_bb.region import smith_bb_region
from boustro.plan.region_opt import optimize_region

FILES = ("test1.xml", "test_2_cell.json", "test_ring.json")


def _random(n: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    ratios, gaps, better = [], [], 0
    print("random concave areas with holes (optimiser alone)")
    print(f"{'vertices':>8} {'holes':>5} {'grid s':>8} {'cert s':>8} {'ratio':>6} {'fit-grid':>10} "
          f"{'gap':>9} conv")  # fmt: skip
    for _ in range(n):
        r = random_region(rng, int(rng.integers(10, 61)), int(rng.integers(1, 3)))
        s = 0.1 * r.diameter
        t0 = time.process_time()
        grid = optimize_region(r, s)
        t1 = time.process_time()
        cert = smith_bb_region(r, s)
        t2 = time.process_time()
        ratios.append((t2 - t1) / (t1 - t0))
        gaps.append(cert.gap)
        better += cert.fitness > grid.fitness + 1e-12
        print(f"{len(r.vertices):>8} {r.n_holes:>5} {t1 - t0:>8.3f} {t2 - t1:>8.3f} "
              f"{ratios[-1]:>6.2f} {cert.fitness - grid.fitness:>10.2e} {cert.gap:>9.2e} "
              f"{cert.info['converged']}")  # fmt: skip
    print(f"median CPU ratio certified/grid {np.median(ratios):.2f}; certified better on "
          f"{better}/{n}; largest gap {max(gaps):.2e}\n")  # fmt: skip


def _field_rows(data: str) -> None:
    print("Fields2Cover demo fields: plan_area, 10 m, one grid")
    print(f"{'field':<24} {'grid s':>7} {'cert s':>7} {'fit grid':>9} {'fit cert':>9} "
          f"{'gap':>9} certified")  # fmt: skip
    for name in FILES:
        path = os.path.join(data, name)
        if not os.path.exists(path):
            continue
        for i, area in enumerate(read_areas(path)):
            kw: dict = {"decompose": False}
            spacing = 10.0
            if name == "test_ring.json":  # planar (a 10 m ring with an 8 m hole): 1 m
                spacing, kw["crs"], kw["holes"] = 1.0, None, area.holes
                area = area.ring
            t0 = time.process_time()
            grid = plan_area(area, spacing, method="grid", **kw).summary()
            t1 = time.process_time()
            cert = plan_area(area, spacing, **kw).summary()
            t2 = time.process_time()
            gap = cert["gap"] if cert["gap"] is not None else float("nan")
            print(f"{name + '#' + str(i + 1):<24} {t1 - t0:>7.2f} {t2 - t1:>7.2f} "
                  f"{grid['fitness']:>9.5f} {cert['fitness']:>9.5f} {gap:>9.2e} "
                  f"{cert['certified']}")  # fmt: skip
    print()


def _big_worker(grid: bool) -> None:
    r = traced_field(2000, 10)
    smith_bb_region(traced_field(50, 1), 10.0)  # compile / load the kernels
    t0 = time.process_time()
    res = smith_bb_region(r, 10.0)
    t1 = time.process_time()
    out = {"cert_s": t1 - t0, "gap": res.gap, "converged": res.info["converged"],
           "boxes": res.info["boxes"], "fitness": res.fitness}  # fmt: skip
    if grid:
        g = optimize_region(r, 10.0)
        out.update(grid_s=time.process_time() - t1, grid_fitness=g.fitness)
    out["peak_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(json.dumps(out))


def _big(grid: bool) -> None:
    cmd = [sys.executable, __file__, "--big-worker"] + (["--grid-big"] if grid else [])
    res = json.loads(subprocess.run(cmd, capture_output=True, text=True, check=True).stdout)
    print("issue 21's traced field, 2000 vertices, 10 holes, 10 m (subprocess)")
    print(json.dumps(res))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", help="Fields2Cover's data/ folder")
    ap.add_argument("--random", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--no-big", action="store_true")
    ap.add_argument("--grid-big", action="store_true")
    ap.add_argument("--big-worker", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.big_worker:
        _big_worker(args.grid_big)
        return
    print(f"load: {os.getloadavg()}")
    smith_bb_region(random_region(np.random.default_rng(0), 12, 1), 0.2)  # compile first
    if args.random:
        _random(args.random, args.seed)
    if args.data:
        _field_rows(args.data)
    if not args.no_big:
        _big(args.grid_big)


if __name__ == "__main__":
    main()
