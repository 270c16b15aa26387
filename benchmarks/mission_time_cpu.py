"""Planning CPU of the time objective against a baseline tree, interleaved (issue 16).

Two worker processes plan the same fields (:mod:`mission_time`'s: Fields2Cover's ``test.json``,
its concave fields with ``--data``, and seeded random concave areas with holes), one with this
tree's ``src`` and one with the baseline's (e.g. ``git archive fff0927 src | tar -x -C
/tmp/base``), one field at a time each in turn, so that both see the same load. Each worker
compiles its kernels on a small field first (not timed). Per field: ``time.process_time`` of
``plan_area(..., speed, turn_time)`` in each, the missions' times, and the 1-degree brute
force's (``mission_time._brute_centred``, this tree; not with ``--turn-radius``, whose
plans fly the vehicle's turns: ``plan_area(..., vehicle=Vehicle(turn_radius=R,
reverse=...))``, the brute force column then repeats the plan). Printed: the distribution of
CPU (median, max, fields over 5 s), the ratio of CPU to the baseline's, how many plans are
longer than the brute force's, and how many plans have the baseline's waypoints (a hash of
their bytes: a behaviour-preserving change must keep every one).

    python benchmarks/mission_time_cpu.py --baseline /tmp/base/src [--random 30] [--first 0]
        [--data <Fields2Cover>/data] [--turn-radius 8 [--reverse]]

Without ``--baseline`` this tree only (the "base" columns repeat it).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from typing import Any

HERE = os.path.dirname(os.path.abspath(__file__))
SRC = os.path.join(os.path.dirname(HERE), "src")

WORKER = r"""
import json, sys, time
sys.path.insert(0, sys.argv[1])
import mission_time as mt
fields = mt._fields(sys.argv[3] or None, int(sys.argv[2]), 0)
kw = {}
if float(sys.argv[4]) > 0:
    from boustro.vehicle import Vehicle
    kw["vehicle"] = Vehicle(turn_radius=float(sys.argv[4]), reverse=sys.argv[5] == "1")
ring = [(0, 0), (120, 0), (120, 80), (60, 100), (0, 80)]
mt._row((ring, [[(30, 30), (50, 30), (50, 45)]]), None, **kw)  # compile (not timed)
mt._row(([(0, 0), (90, 0), (80, 60)], []), None, **kw)  # a convex one too
print("ready", flush=True)
for line in sys.stdin:
    name, area, crs = fields[int(line)]
    row = mt._row(area, crs, **kw)
    keys = ("time", "cpu", "gap", "lanes", "certified", "path")
    print(json.dumps({k: row[k] for k in keys}), flush=True)
"""


def _worker(
    src: str, n_random: int, data: str | None, radius: float = 0.0, reverse: bool = False
) -> subprocess.Popen[str]:
    env = {**os.environ, "PYTHONPATH": src}
    vehicle = [str(radius), "1" if reverse else "0"]
    p = subprocess.Popen(
        [sys.executable, "-c", WORKER, HERE, str(n_random), data or "", *vehicle],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
        env=env,
    )
    assert p.stdout is not None and p.stdout.readline().strip() == "ready"
    return p


def _ask(p: subprocess.Popen[str], i: int) -> dict[str, float]:
    assert p.stdin is not None and p.stdout is not None
    p.stdin.write(f"{i}\n")
    p.stdin.flush()
    return json.loads(p.stdout.readline())


def _cert(row: dict[str, Any]) -> str:
    return ", certified" if row.get("certified") else ""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--baseline", help="the baseline tree's src folder (none: this tree only)")
    ap.add_argument("--random", type=int, default=30, help="random areas (default 30)")
    ap.add_argument("--first", type=int, default=0, help="the first random area's index")
    ap.add_argument("--no-f2c", action="store_true", help="without Fields2Cover's fields")
    ap.add_argument("--data", help="Fields2Cover's data/ folder: its concave fields too")
    ap.add_argument("--turn-radius", type=float, default=0.0, help="a vehicle's radius, m")
    ap.add_argument("--reverse", action="store_true", help="the vehicle may reverse")
    args = ap.parse_args()
    sys.path.insert(0, HERE)
    import mission_time as mt  # the benchmarks folder is not a package

    n = args.first + args.random
    fields = mt._fields(args.data, n, 0)
    f2c = len(fields) - n  # test.json and the fields of --data
    index = ([] if args.no_f2c else list(range(f2c))) + list(range(f2c + args.first, f2c + n))
    vehicle = (args.turn_radius, args.reverse)
    new = _worker(SRC, n, args.data, *vehicle)
    base = _worker(args.baseline, n, args.data, *vehicle) if args.baseline else None
    rows: list[tuple[Any, ...]] = []
    for i in index:
        name, area, crs = fields[i]
        b = _ask(base, i) if base is not None else None
        t = _ask(new, i)
        if b is None:  # this tree alone: compared with itself
            b = t
        brute = t["time"] if args.turn_radius > 0 else mt._brute_centred(area, crs)[0]
        rows.append((name, t, b, brute))
        print(
            f"{name:20s} new {t['time']:8.1f} s ({t['cpu']:5.2f} s CPU, gap {t['gap']:6.2f}"
            f"{_cert(t)}) | base {b['time']:8.1f} s ({b['cpu']:5.2f} s CPU, gap "
            f"{b['gap']:6.2f}{_cert(b)}) | brute "
            f"{brute:8.1f} | new/brute {t['time'] / brute:.4f} base/brute {b['time'] / brute:.4f}"
            f" | CPU new/base {t['cpu'] / b['cpu']:.2f}"
            f"{'' if t['path'] == b['path'] else ' | PATH DIFFERS'}",
            flush=True,
        )
    for p in (new, base):
        if p is None:
            continue
        assert p.stdin is not None
        p.stdin.close()
        p.wait()
    for label, k in (("new", 1), ("base", 2)):
        cpu = [r[k]["cpu"] for r in rows]
        longer = sum(r[k]["time"] > r[3] * (1 + 1e-9) for r in rows)
        print(
            f"{label}: CPU median {statistics.median(cpu):.2f} s, max {max(cpu):.2f} s, over 5 s "
            f"{sum(c > 5 for c in cpu)}/{len(cpu)}, total {sum(cpu):.1f} s; longer than the "
            f"brute force {longer}/{len(rows)}; time/brute median "
            f"{statistics.median(r[k]['time'] / r[3] for r in rows):.4f}"
        )
    same = sum(r[1]["path"] == r[2]["path"] for r in rows)
    print(f"the same waypoints (a hash of their bytes) as the baseline: {same}/{len(rows)}")
    ratio = [r[1]["cpu"] / r[2]["cpu"] for r in rows]
    print(
        f"CPU new/base: median {statistics.median(ratio):.2f}, max {max(ratio):.2f}; "
        f"time new/base: worst {max(r[1]['time'] / r[2]['time'] for r in rows):.5f}, best "
        f"{min(r[1]['time'] / r[2]['time'] for r in rows):.5f}"
    )


if __name__ == "__main__":
    main()
