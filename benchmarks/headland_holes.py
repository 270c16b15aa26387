"""Benchmark (task "tidy", item 1): headlands around many holes near the boundary, this tree
against a baseline's ``src`` measured in the same run.

A 200 m deep field ``70 N + 50`` m long with ``N`` holes 20 m square, 25 m from its long side
(a corridor too narrow for the second pass at 10 m), planned as ``boustro plan --spacing 10
--headland 2 --angle 0`` would (:func:`boustro.mission.plan_area`, a fixed angle so that the
headland's share shows), once with each tree in a fresh process, the two interleaved. Printed:
the CPU time (``time.process_time``, the machine is shared) of the whole plan and of
``add_headland`` in it, coverage (shapely, the whole field), the path's length, and the ratios
of this tree's CPU times to the baseline's.

    git archive fff0927 src | tar -x -C /tmp/base
    python benchmarks/headland_holes.py --baseline /tmp/base/src [--holes 5 10 20 40]
"""

from __future__ import annotations

import argparse
import os

from _child import run_child

HERE = os.path.dirname(os.path.abspath(__file__))
SRC = os.path.join(os.path.dirname(HERE), "src")

CHILD = r"""
import json, time
from boustro.mission import plan_area, pipeline
n = {n}
pitch = 70.0
holes = [[(50 + i * pitch, 25), (70 + i * pitch, 25), (70 + i * pitch, 45), (50 + i * pitch, 45)]
         for i in range(n)]
width = n * pitch + 50
spent = []
add_headland = pipeline.add_headland
def timed(*args, **kwargs):
    t = time.process_time()
    out = add_headland(*args, **kwargs)
    spent.append(time.process_time() - t)
    return out
pipeline.add_headland = timed
t0 = time.process_time()
m = plan_area([(0, 0), (width, 0), (width, 200), (0, 200)], 10.0, crs=None, holes=holes,
              headland=2, angle=0.0)
cpu = time.process_time() - t0
s = m.summary()
print(json.dumps(dict(cpu=cpu, headland=spent[0], covered=m.coverage.covered_share,
                      path=s["path_length_m"], headland_m=s["headland_length_m"])))
"""


def run(src: str, n: int) -> dict:
    return run_child(src, CHILD.format(n=n))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", required=True, help="the baseline's src directory")
    parser.add_argument("--holes", type=int, nargs="+", default=[5, 10, 20, 40])
    args = parser.parse_args()
    load = os.getloadavg()[0]
    print(f"load average {load:.2f}")
    print(
        "| holes | baseline plan s | baseline headland s | plan s | headland s | headland ratio "
        "| uncovered share (baseline / this) | path km (baseline / this) |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for n in args.holes:
        base = run(args.baseline, n)
        this = run(SRC, n)
        print(
            f"| {n} | {base['cpu']:.2f} | {base['headland']:.2f} | {this['cpu']:.2f} | "
            f"{this['headland']:.2f} | {this['headland'] / base['headland']:.2f} | "
            f"{1 - base['covered']:.1e} / {1 - this['covered']:.1e} | "
            f"{base['path'] / 1000:.1f} / {this['path'] / 1000:.1f} |"
        )


if __name__ == "__main__":
    main()
