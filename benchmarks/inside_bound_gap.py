"""Benchmark (issue 16, item 4): the certificate of ``--keep-inside`` plans against a baseline
commit, measured in the same run: per field the mission time, the gap (the plan less the
search's lower bound, seconds and % of the plan), whether it is certified and the planning CPU
(``time.process_time``), for the baseline's ``src`` (``--baseline``) and this tree, each in a
fresh process, the two interleaved.

Cases as ``benchmarks/keep_inside_speed.py``'s (``test.json``, ``random_N``, Fields2Cover's
``test_2_cell.json#1`` ... with ``--data``), planned as ``boustro plan --speed 5 --turn-time
10 --keep-inside`` would. Keep a run under two minutes on a shared machine: ``--only``/
``--first`` select the cases.

    git archive f49f694 src | tar -x -C /tmp/base11
    python benchmarks/inside_bound_gap.py --baseline /tmp/base11/src --data F2C/data \\
        --random 20 [--first 4] [--skip 4] [--moves-decide all]

``--moves-decide`` sets this tree's ``boustro.optimize.cover.search.MOVES_DECIDE`` (what the
keep-inside search decides by with the moves on top of its passes; docs/mission_time.md).
"""

from __future__ import annotations

import argparse
import os
import statistics

from keep_inside_speed import run_child

HERE = os.path.dirname(os.path.abspath(__file__))
SRC = os.path.join(os.path.dirname(HERE), "src")

CHILD = r"""
import hashlib, json, sys, time
import numpy as np
sys.path.insert(0, {here!r})
from keep_inside_speed import keep_inside_case
from boustro.mission import plan_area
#SETUP
area, spacing, kw = keep_inside_case({case!r}, {data!r})
t0 = time.process_time()
m = plan_area(area, spacing, speed=5.0, turn_time=10.0, keep_inside=True, **kw)
cpu = time.process_time() - t0
s = m.summary()
print(json.dumps(dict(cpu=cpu, time=m.stats.duration, gap=s.get("gap") or 0.0,
                      certified=bool(s.get("certified")), method=s["method"],
                      path=hashlib.sha256(np.ascontiguousarray(m.waypoints).tobytes())
                      .hexdigest()[:12])))
"""


def _run(src: str, case: str, data: str, setup: str = "") -> dict:
    return run_child(src, case, data, CHILD.replace("#SETUP", setup))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", required=True, help="the baseline's src folder")
    ap.add_argument("--data", help="Fields2Cover's data/ folder")
    ap.add_argument("--random", type=int, default=0, help="random areas with holes (seed 0)")
    ap.add_argument("--only", nargs="*", help="case names (test.json, random_3, ...)")
    ap.add_argument("--skip", type=int, default=0, help="leave out the first N cases")
    ap.add_argument("--first", type=int, default=0, help="only N cases (after --skip)")
    ap.add_argument("--warm", action="store_true", help="plan random_0 once per tree first")
    ap.add_argument(
        "--moves-decide",
        help="this tree's optimize.cover.search.MOVES_DECIDE (certificate, boxes, all)",
    )
    args = ap.parse_args()
    setup = ""
    if args.moves_decide:
        setup = "import boustro.optimize.cover.search as _s\n"
        setup += f"_s.MOVES_DECIDE = {args.moves_decide!r}"
    cases = ["test.json"]
    if args.data:
        cases += ["test_2_cell.json#1", "test_2_cell.json#2"]
    cases += [f"random_{i}" for i in range(args.random)]
    if args.only:
        cases = [c for c in cases if c in args.only]
    cases = cases[args.skip :]
    if args.first:
        cases = cases[: args.first]
    if args.warm:  # numba's caches filled: no compilation timed
        for src in (args.baseline, SRC):
            _run(src, "random_0", args.data)
    print(
        "| case | baseline: time s / gap s (%) / cert / CPU s | this tree: time s / gap s (%) / "
        "cert / CPU s | gap ratio | CPU ratio | same path |"
    )
    print("|---|---|---|---:|---:|---|")
    ratios = []
    for case in cases:
        base = _run(args.baseline, case, args.data)
        new = _run(SRC, case, args.data, setup)

        def cell(r: dict) -> str:
            pct = 100 * r["gap"] / r["time"]
            return (
                f"{r['time']:.1f} / {r['gap']:.1f} ({pct:.1f}%) / "
                f"{'yes' if r['certified'] else 'no'} / {r['cpu']:.1f}"
            )

        ratio = new["gap"] / base["gap"] if base["gap"] else float("nan")
        ratios.append(ratio)
        print(
            f"| {case} | {cell(base)} | {cell(new)} | {ratio:.3f} | "
            f"x{new['cpu'] / base['cpu']:.2f} | {'yes' if new['path'] == base['path'] else 'NO'} |",
            flush=True,
        )
    good = [r for r in ratios if r == r]
    if good:
        print(f"median gap ratio {statistics.median(good):.3f} over {len(good)} cases")


if __name__ == "__main__":
    main()
