"""Benchmark (issue 16 item 2, issue 21): the certified mission time's gap on concave areas with
holes, this tree beside a baseline commit in the same run.

The fields of ``benchmarks/mission_time.py`` (Fields2Cover's demo fields with ``--data``, the
embedded field, seeded random concave areas with holes; 10 m spacing, 5 m/s, 10 s a turn),
planned by ``plan_area(..., speed, turn_time)`` (the time objective's certified search over real
plans; ``decompose=False`` so that the gap is the one-grid search's). Each code runs in its own
subprocess (``PYTHONPATH`` at the code measured, the baseline ``git archive``-d), each field
twice and the second timed (``time.process_time``), so compilation and imports are excluded.
Printed per field: mission time, gap (% of the time), certified, planning CPU, for both codes;
then medians.

    python benchmarks/tour_bound.py --data /path/to/Fields2Cover/data --random 8
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BASELINE = "1158b53"  # main before the tour's 1-tree (issue 16 item 2, third round)


def worker(data: str | None, n_random: int) -> None:
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from mission_time import SPEED, TURN_TIME, _fields, _plan

    for name, area, crs in _fields(data, n_random, 0):
        kw = {"speed": SPEED, "turn_time": TURN_TIME, "decompose": False}
        _plan(area, crs, **kw)
        t0 = time.process_time()
        m = _plan(area, crs, **kw)
        cpu = time.process_time() - t0
        s = m.summary()
        row = {"name": name, "time": m.stats.duration, "gap": s.get("gap"), "cpu": cpu}
        row["certified"] = bool(s.get("certified"))
        print(json.dumps(row), flush=True)


def _run(src: Path, args: argparse.Namespace) -> list[dict]:
    env = {**os.environ, "PYTHONPATH": str(src)}
    cmd = [sys.executable, __file__, "--worker", "--random", str(args.random)]
    if args.data:
        cmd += ["--data", args.data]
    out = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True)
    return [json.loads(line) for line in out.stdout.splitlines() if line.startswith("{")]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", help="Fields2Cover's data/ folder")
    ap.add_argument("--random", type=int, default=8, help="random concave areas (default 8)")
    ap.add_argument("--baseline", default=BASELINE, help="commit compared against")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        worker(args.data, args.random)
        return
    with tempfile.TemporaryDirectory() as tmp:
        archive = Path(tmp) / "base.tar"
        subprocess.run(
            ["git", "-C", str(ROOT), "archive", "-o", str(archive), args.baseline, "src"],
            check=True,
        )
        with tarfile.open(archive) as tar:
            tar.extractall(Path(tmp) / "base", filter="data")
        base = _run(Path(tmp) / "base" / "src", args)
        new = _run(ROOT / "src", args)
    print(f"load: {os.getloadavg()[0]:.1f}; baseline {args.baseline}")
    print(f"{'field':24s} {'time (base / new) s':>22s} {'gap % (base / new)':>20s} "
          f"{'certified':>11s} {'CPU s (base / new)':>20s}")  # fmt: skip
    for b, n in zip(base, new, strict=True):
        print(
            f"{n['name']:24s} {b['time']:10.1f} / {n['time']:9.1f} "
            f"{100 * b['gap'] / b['time']:9.2f} / {100 * n['gap'] / n['time']:8.2f} "
            f"{str(b['certified'])[0]:>5s} / {str(n['certified'])[0]:3s} "
            f"{b['cpu']:9.2f} / {n['cpu']:8.2f}"
        )
    for label, pick in (("Fields2Cover", "f2c"), ("random concave with holes", "random")):
        rows = [(b, n) for b, n in zip(base, new, strict=True) if b["name"].startswith(pick)]
        if not rows:
            continue
        gb = statistics.median(b["gap"] / b["time"] for b, _ in rows) * 100
        gn = statistics.median(n["gap"] / n["time"] for _, n in rows) * 100
        cb = sum(b["cpu"] for b, _ in rows)
        cn = sum(n["cpu"] for _, n in rows)
        longer = sum(n["time"] > b["time"] * (1 + 1e-9) for b, n in rows)
        print(
            f"{label}: {len(rows)} fields, median gap {gb:.2f}% -> {gn:.2f}%, certified "
            f"{sum(b['certified'] for b, _ in rows)} -> {sum(n['certified'] for _, n in rows)}, "
            f"CPU {cb:.1f} s -> {cn:.1f} s ({cn / cb:.2f}x), plans longer than the baseline's: "
            f"{longer}"
        )


if __name__ == "__main__":
    main()
