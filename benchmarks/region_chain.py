"""Benchmark (issue 16 item 2, issue 21): the certified per-segment Eq. 1 (``smith_bb_region``)
with the chain bound against a baseline tree (default ``/work/main/src``, the bound before it),
each in its own subprocess, interleaved (best of ``--repeats``, ``time.process_time``, the
first compiling call excluded): gap, converged, boxes and CPU per area.

Areas: the rectilinear ones of ``benchmarks/region_certified.py`` (the L with a pond, the U, the
square ring, the comb, three random areas, the noisy traced field), the L of the docs (7 x 6.1,
arms 2.3 and 2.9, spacing 0.7), ``--random N`` random concave areas with holes (as
``benchmarks/eq1_region.py``: 10-60 vertices, 1-2 holes, spacing 1/10 of the diameter) and,
with ``--big``, issue 21's traced field (2000 vertices, 10 holes, 10 m).

    PYTHONPATH=src python benchmarks/region_chain.py [--baseline /work/main/src] [--random 10]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time


def _areas(n_random: int, big: bool) -> dict:
    import numpy as np

    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import region_certified

    from boustro.geometry import Polygon
    from boustro.geometry.region import Region, random_region
    from boustro.geometry.traced import traced_field

    out = {
        name: (Region(Polygon(ring), [Polygon(h) for h in holes]), spacing)
        for name, (ring, holes, spacing) in region_certified.cases().items()
    }
    out["L 0.7"] = (Region(Polygon([(0, 0), (7, 0), (7, 2.3), (2.9, 2.3), (2.9, 6.1), (0, 6.1)])),
                    0.7)  # fmt: skip
    rng = np.random.default_rng(0)
    for i in range(n_random):
        r = random_region(rng, int(rng.integers(10, 61)), int(rng.integers(1, 3)))
        out[f"random #{i}"] = (r, 0.1 * r.diameter)
    if big:
        out["traced 2000+10"] = (traced_field(2000, 10), 10.0)
    return out


def _worker(n_random: int, big: bool, repeats: int) -> None:
    from boustro.optimize.smith_bb.region import smith_bb_region

    areas = _areas(n_random, big)
    first = next(iter(areas.values()))
    smith_bb_region(*first)  # compile / load the kernels
    for name, (region, spacing) in areas.items():
        best = float("inf")
        for _ in range(repeats):
            t = time.process_time()
            res = smith_bb_region(region, spacing)
            best = min(best, time.process_time() - t)
        row = {"area": name, "cpu": best, "gap": res.gap, "converged": res.info["converged"],
               "boxes": res.info["boxes"], "fitness": res.fitness}  # fmt: skip
        print(json.dumps(row), flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--baseline", default="/work/main/src", help="src folder of the baseline")
    ap.add_argument("--random", type=int, default=10)
    ap.add_argument("--big", action="store_true")
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        _worker(args.random, args.big, args.repeats)
        return
    here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "src")
    cmd = [sys.executable, os.path.abspath(__file__), "--worker", "--random", str(args.random),
           "--repeats", str(args.repeats)] + (["--big"] if args.big else [])  # fmt: skip
    print(f"load: {os.getloadavg()}")
    runs = {}
    for label, src in (("base", args.baseline), ("new", here), ("base2", args.baseline)):
        env = dict(os.environ, PYTHONPATH=os.path.abspath(src))
        out = subprocess.run(cmd, capture_output=True, text=True, check=True, env=env).stdout
        runs[label] = {r["area"]: r for r in map(json.loads, out.splitlines())}
    print(f"{'area':<16} {'base gap':>9} {'new gap':>9} {'conv':>10} {'base s':>7} {'new s':>7} "
          f"{'ratio':>6} {'boxes':>13}")  # fmt: skip
    for name, new in runs["new"].items():
        base = runs["base"][name]
        cpu = min(base["cpu"], runs["base2"][name]["cpu"])
        conv = str(base["converged"])[0] + "->" + str(new["converged"])[0]
        print(f"{name:<16} {base['gap']:>9.2e} {new['gap']:>9.2e} {conv:>10} {cpu:>7.3f} "
              f"{new['cpu']:>7.3f} {new['cpu'] / cpu:>6.2f} "
              f"{base['boxes']:>6}/{new['boxes']:<6}")  # fmt: skip


if __name__ == "__main__":
    main()
