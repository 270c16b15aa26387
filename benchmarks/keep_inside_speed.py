"""Benchmark (issue 16, item 4): the time objective with ``--keep-inside`` against a baseline
commit, measured in the same run.

Each case is planned as ``boustro plan --speed 5 --turn-time 10 --keep-inside`` would
(:func:`boustro.mission.plan_area`), once with this tree and once with the baseline's
``src`` (``--baseline``, e.g. a ``git archive`` of 1158b53), each in a fresh process, the two
interleaved; the CPU time of the planning call (``time.process_time``, the machine is shared),
the mission time, the certificate's gap, coverage (shapely, on the area itself) and the path
outside are printed with the ratio of CPU times, whether the two paths are the same (a hash
of the waypoints' bytes) and the plans the final search made (``info["plans"]``; the layouts
its screen skipped, ``info["screened"]``, in brackets: the one grid's search, or the kept
decomposition's whole plan).

Cases: a three-lobed 200-vertex star 1000 m across at 36 lanes (``benchmarks/estimate.py``'s),
Fields2Cover's ``test.json`` (embedded, 10 m), ``--random N`` seeded random concave areas with
1-3 holes (``benchmarks/mission_time.py``'s, ~300 m, 10 m) and, with ``--data``, Fields2Cover's
``test_2_cell.json`` and ``test1.xml`` fields (10 m). The plans' mission times must be equal or
shorter (``time ratio``).

    git archive 374f05c src | tar -x -C /tmp/base
    python benchmarks/keep_inside_speed.py --baseline /tmp/base/src [--data F2C/data] \
        [--random 6] [--only star random_0]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
SRC = os.path.join(os.path.dirname(HERE), "src")

CHILD = r"""
import hashlib, json, os, sys, time
sys.path.insert(0, {here!r})
from keep_inside_speed import keep_inside_case
import numpy as np
from boustro.mission import plan_area
area, spacing, kw = keep_inside_case({case!r}, {data!r})
t0 = time.process_time()
m = plan_area(area, spacing, speed=5.0, turn_time=10.0, keep_inside=True, **kw)
cpu = time.process_time() - t0
s = m.summary()
print(json.dumps(dict(cpu=cpu, decomposed=m.optimum.method.startswith("decomposed"),
                      time=m.stats.duration, gap=s.get("gap"),
                      covered=s.get("covered_share"), outside=s.get("outside_length_m", 0.0),
                      lanes=s["n_transects"], method=s["method"],
                      plans=m.optimum.info.get("plans"),
                      screened=m.optimum.info.get("screened", 0),
                      path=hashlib.sha256(np.ascontiguousarray(m.waypoints).tobytes())
                      .hexdigest()[:12])))
"""


def keep_inside_case(case: str, data: str = "") -> tuple[object, float, dict]:
    """The area, spacing and ``plan_area`` keywords of a case (``star``, ``test.json``,
    ``random_N``, ``<file>#<i>`` of Fields2Cover's ``data``), in the child's tree."""
    import numpy as np
    from estimate import star

    from boustro.geometry.region import random_region
    from boustro.io import embedded_field, read_areas

    if case == "star":
        return star(200), 1000 / 36, {"crs": None}
    if case == "test.json":
        return embedded_field(), 10.0, {}
    if case.startswith("random_"):
        rng = np.random.default_rng(0)
        for _ in range(int(case[7:]) + 1):
            r = random_region(rng, int(rng.integers(6, 16)), int(rng.integers(1, 4)), roughness=0.5)
        k = 300.0 / r.diameter
        return r.shell.vertices * k, 10.0, {"crs": None, "holes": [h.vertices * k for h in r.holes]}
    name, index = case.split("#")
    return read_areas(os.path.join(data, name))[int(index) - 1], 10.0, {}


def run_child(src: str, case: str, data: str, child: str | None = None) -> dict:
    """The last line of JSON the script ``child`` (default :data:`CHILD`; formatted with
    ``here``, ``case``, ``data``) prints, run with ``src`` on the path."""
    env = {**os.environ, "PYTHONPATH": src}
    code = (CHILD if child is None else child).format(here=HERE, case=case, data=data or "")
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", required=True, help="the baseline's src folder")
    ap.add_argument("--data", help="Fields2Cover's data/ folder")
    ap.add_argument("--random", type=int, default=0, help="random areas with holes (seed 0)")
    ap.add_argument("--only", nargs="*", help="case names (star, test_2_cell.json#1, ...)")
    args = ap.parse_args()
    cases = ["star", "test.json"] + [f"random_{i}" for i in range(args.random)]
    if args.data:
        cases += ["test_2_cell.json#1", "test_2_cell.json#2", "test1.xml#1"]
    if args.only:
        cases = [c for c in cases if c in args.only]
    print(
        "| case | baseline: time s / gap s / CPU s | this tree: time s / gap s / CPU s | "
        "covered | outside m | time ratio | same path | CPU ratio | plans: baseline / this tree "
        "(+ screened) |"
    )
    print("|---|---|---|---:|---:|---:|---|---:|---|")
    for src in (args.baseline, SRC):  # numba's caches filled: no compilation timed
        run_child(src, "random_0", args.data)
    for case in cases:
        base = run_child(args.baseline, case, args.data)
        new = run_child(SRC, case, args.data)
        print(
            f"| {case} | {base['time']:.1f} / {base['gap'] or 0:.1f} / {base['cpu']:.1f} | "
            f"{new['time']:.1f} / {new['gap'] or 0:.1f} / {new['cpu']:.1f} | "
            f"{100 * (new['covered'] or 0):.6f}% | {new['outside']:.3g} | "
            f"{new['time'] / base['time']:.4f}{' (cells)' if new['decomposed'] else ''} | "
            f"{'yes' if new['path'] == base['path'] else 'no'} | "
            f"x{new['cpu'] / base['cpu']:.2f} | "
            f"{base['plans']} / {new['plans']} (+{new['screened']}) |",
            flush=True,
        )


if __name__ == "__main__":
    main()
