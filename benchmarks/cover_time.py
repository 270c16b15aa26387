"""Benchmark (issue 17's target): planning time of a 100-vertex field with the time objective.

Fields: the lobed, concave traced field of 100 vertices (``traced_field(100)``, 59 lanes) and a
regular 100-gon of radius 500 m (100 lanes); spacing 10 m, 5 m/s, 10 s per turn, without a
vehicle and with a tractor (``Vehicle(turn_radius=6)``, Dubins turns). Each case runs in a fresh
process (``python -c``), which plans it twice: the first plan pays the first calls (numba kernels
loaded from their on-disk cache, first use of the decomposition's models), the second is a warm
process's time. CPU time of the planning process (``time.process_time``); imports apart.

With ``--baseline SRC`` (a source tree of another version, e.g. ``git archive 7ccb731 src | tar
-x -C /tmp/base`` then ``--baseline /tmp/base/src``) each case also runs on it, interleaved with
today's, and the ratio of the warm times is printed with whether both found the same plan.

    python benchmarks/cover_time.py [--baseline /tmp/base/src] [--repeat 1]
"""

from __future__ import annotations

import argparse
import os

from _child import run_child

SRC = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "src")

_CASE = """
import json, math, sys, time
t0 = time.process_time()
import numpy as np
from boustro.geometry.traced import traced_field
from boustro.mission import plan_area
from boustro.vehicle import Vehicle
imports = time.process_time() - t0
field, radius = sys.argv[1], float(sys.argv[2])
if field == "traced":
    r = traced_field(100)
    ring, holes = r.shell.vertices, [h.vertices for h in r.holes]
else:
    t = np.linspace(0, 2 * math.pi, 100, endpoint=False)
    ring, holes = 500 * np.c_[np.cos(t), np.sin(t)], []
vehicle = Vehicle(turn_radius=radius) if radius > 0 else None
cpu = []
for _ in range(2):
    t0 = time.process_time()
    m = plan_area(ring, 10.0, crs=None, holes=holes, speed=5.0, turn_time=10.0,
                  vehicle=vehicle, check_coverage=False)
    cpu.append(time.process_time() - t0)
info = m.optimum.info
print(json.dumps({"imports": imports, "first": cpu[0], "warm": cpu[1],
                  "time": m.stats.duration, "fitness": m.optimum.fitness, "gap": info["gap"],
                  "plans": info["plans"], "lanes": m.plan.stats.n_transects,
                  "method": m.optimum.method}))
"""

CASES = (("traced", 0.0), ("traced", 6.0), ("100-gon", 0.0), ("100-gon", 6.0))


def _run(src: str, field: str, radius: float) -> dict:
    return run_child(src, _CASE, field, str(radius))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--baseline", help="src/ of the version to compare with")
    ap.add_argument("--repeat", type=int, default=1, help="runs per case (the least is kept)")
    args = ap.parse_args()
    print(f"load: {os.getloadavg()[0]:.2f} (1 min average), {os.cpu_count()} CPUs")
    head = "| field | vehicle | lanes | mission s | gap | plans | first plan s | warm s |"
    rule = "|---|---|---|---|---|---|---|---|"
    if args.baseline:
        head += " baseline warm s | speed-up | same plan |"
        rule += "---|---|---|"
    print(head)
    print(rule)
    for field, radius in CASES:
        runs, base = [], []
        for _ in range(max(1, args.repeat)):
            if args.baseline:
                base.append(_run(args.baseline, field, radius))
            runs.append(_run(SRC, field, radius))
        r = min(runs, key=lambda x: x["warm"])
        row = (
            f"| {field} | {'R ' + format(radius, 'g') + ' m' if radius else 'none'} | "
            f"{r['lanes']} | {r['time']:.1f} | {100 * r['gap'] / r['fitness']:.2f}% | "
            f"{r['plans']} | {min(x['first'] for x in runs):.2f} | {r['warm']:.2f} |"
        )
        if base:
            b = min(base, key=lambda x: x["warm"])
            same = abs(b["fitness"] - r["fitness"]) <= 1e-9 * abs(b["fitness"])
            row += f" {b['warm']:.2f} | {b['warm'] / r['warm']:.1f}x | {'yes' if same else 'NO'} |"
        print(row, flush=True)


if __name__ == "__main__":
    main()
