"""Benchmark (issue 21): how far the certified per-segment Eq. 1 (``smith_bb_region``) is from
certifying the 2000-vertex traced field with 10 holes (``traced_field(2000, 10)``, 10 m): gap,
upper bound, fitness, boxes and CPU (``time.process_time``) against the work budget, for this
tree and a baseline tree (``--baseline``: a ``src`` folder), each in its own subprocess,
interleaved (base, new, base again: the lesser CPU of the two base runs), the first compiling
call excluded and timed apart, and each process's peak RSS. Targets of issue 21: certified
(gap <= 1e-4) in 5 s.

    git archive f49f694 src | tar -x -C /tmp/base   # the tree before (the strips: 11th round)
    PYTHONPATH=src python benchmarks/region_big.py --baseline /tmp/base/src [--budgets 0 1e7 4e7]
        [--vertices 1000]

A budget of 0 runs the default settings (``max_work=None``: since the twelfth round the region
search doubles its budget while the gap shrinks, up to 8x; an explicit budget is a hard limit).

``--fractions 10 20 50 100 200 500`` sweeps the spacing instead (issue 21's benchmark against
spacing): the spacing is the field's diameter over each fraction (``--spacing`` is ignored), one
row per spacing and budget, with its lines across (diameter / spacing) and the count that
``region_splits.NODE_LINES`` is compared with (``range``: ``lines_range``, about the
circumscribed diameter over the spacing, plus 6; above 200 the boxes keep the pooled split
bound); ``--once`` runs each tree once (base, new) instead of base, new, base again.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time


def _worker(budgets: list[float], n: int, holes: int, spacings: list[float]) -> None:
    """Rows of JSON: the first call's CPU, one row per spacing and budget, the peak RSS.
    ``spacings``: user units, or negative for the diameter over ``-spacing``."""
    from boustro.geometry.traced import traced_field
    from boustro.optimize.smith_bb.kernel import lines_range
    from boustro.optimize.smith_bb.region import smith_bb_region

    region = traced_field(n, holes)
    spacings = [s if s > 0 else region.diameter / -s for s in spacings]
    xy = region.frame.to_normalised(region.vertices)
    t = time.process_time()
    smith_bb_region(region, spacings[0], max_work=1e5)  # compile / load the kernels
    print(json.dumps({"first": time.process_time() - t}), flush=True)
    for spacing in spacings:
        for budget in budgets:
            t = time.process_time()
            res = smith_bb_region(region, spacing, max_work=budget or None)  # 0: the default
            row = {"budget": budget, "cpu": time.process_time() - t, "gap": res.gap,
                   "upper": res.upper_bound, "fitness": res.fitness, "boxes": res.info["boxes"],
                   "converged": res.info["converged"], "spacing": spacing,
                   "lines": region.diameter / spacing,
                   "range": lines_range(xy, spacing / region.frame.scale)[1]}  # fmt: skip
            print(json.dumps(row), flush=True)
    # peak resident memory of the whole process (imports, all budgets), kilobytes on Linux
    print(json.dumps({"rss": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss}), flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--baseline", default="/work/main/src", help="src folder of the baseline")
    ap.add_argument("--budgets", type=float, nargs="+", default=[0, 1e7, 2e7, 4e7, 8e7])
    ap.add_argument("--vertices", type=int, default=2000)
    ap.add_argument("--holes", type=int, default=10)
    ap.add_argument("--spacing", type=float, default=10.0)
    ap.add_argument("--fractions", type=float, nargs="+", help="spacings: the diameter over each")
    ap.add_argument("--once", action="store_true", help="each tree once (base, new)")
    ap.add_argument("--spacings", type=float, nargs="+", help=argparse.SUPPRESS)
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        _worker(args.budgets, args.vertices, args.holes, args.spacings)
        return
    spacings = [-f for f in args.fractions] if args.fractions else [args.spacing]
    here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "src")
    cmd = [sys.executable, os.path.abspath(__file__), "--worker", "--vertices",
           str(args.vertices), "--holes", str(args.holes), "--spacings", *map(str, spacings),
           "--budgets", *map(str, args.budgets)]  # fmt: skip
    print(f"load: {os.getloadavg()}")
    runs: dict[str, list[dict]] = {}
    trees = [("base", args.baseline), ("new", here), ("base2", args.baseline)]
    for label, src in trees[: 2 if args.once else 3]:
        env = dict(os.environ, PYTHONPATH=os.path.abspath(src))
        out = subprocess.run(cmd, capture_output=True, text=True, check=True, env=env).stdout
        runs[label] = [json.loads(line) for line in out.splitlines()]
    print(f"first call (compile or load): base {runs['base'][0]['first']:.2f} s, "
          f"new {runs['new'][0]['first']:.2f} s")  # fmt: skip
    runs.setdefault("base2", runs["base"])
    rss = {k: v.pop()["rss"] / 1024 for k, v in runs.items() if k != "base2" or not args.once}
    print(f"peak RSS of a process (all budgets): base {max(rss['base'], rss.get('base2', 0)):.0f} "
          f"MB, new {rss['new']:.0f} MB")  # fmt: skip
    print(f"{'spacing':>8} {'lines':>6} {'range':>6} {'budget':>8} {'base gap':>9} {'new gap':>9} "
          f"{'base ub':>8} {'new ub':>8} {'base fit':>9} {'new fit':>9} {'base s':>7} "
          f"{'new s':>7} {'boxes':>13} certified")  # fmt: skip
    for base, base2, new in zip(runs["base"][1:], runs["base2"][1:], runs["new"][1:], strict=True):
        cpu = min(base["cpu"], base2["cpu"])
        label = f"{new['budget']:>8.0e}" if new["budget"] else " default"
        print(f"{new['spacing']:>8.3g} {new['lines']:>6.0f} {new['range']:>6} {label} "
              f"{base['gap']:>9.2e} {new['gap']:>9.2e} {base['upper']:>8.4f} {new['upper']:>8.4f} "
              f"{base['fitness']:>9.5f} {new['fitness']:>9.5f} {cpu:>7.2f} {new['cpu']:>7.2f} "
              f"{base['boxes']:>6}/{new['boxes']:<6} "
              f"{base['converged']}/{new['converged']}")  # fmt: skip


if __name__ == "__main__":
    main()
