"""The command line's start: ``boustro --help`` and ``boustro plan`` as whole processes.

Each command runs as ``python -m boustro ...`` in a fresh process with one tree's ``src`` on
``PYTHONPATH`` (this tree's, and ``--base`` for a baseline), the trees interleaved, ``--repeat``
times each after one warm-up run per tree (numba's disk cache filled, files in the page cache).
Reports per command and tree the median wall time and the median CPU time of the child (user +
system, ``os.wait4``). Whether torch is imported is tested in ``tests/test_architecture.py``.

    python benchmarks/cli_start.py --base /path/to/other/src [--field FILE --spacing M] [--repeat 5]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parents[1] / "src"


def _measure(src: str, argv: list[str]) -> tuple[float, float]:
    """``(wall s, child CPU s)`` of one ``python -m boustro argv``."""
    env = {**os.environ, "PYTHONPATH": src}
    t0 = time.perf_counter()
    proc = subprocess.Popen(
        [sys.executable, "-m", "boustro", *argv],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    wall = time.perf_counter() - t0
    if proc.returncode:
        raise RuntimeError(f"{argv} with {src}: exit status {proc.returncode}")
    return wall, usage.ru_utime + usage.ru_stime


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", required=True, help="the baseline tree's src folder")
    ap.add_argument("--field", help="an area file for a second plan (e.g. Fields2Cover's)")
    ap.add_argument("--spacing", default="10")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    out = tempfile.mkdtemp()
    commands = {
        "--help": ["--help"],
        "plan (embedded)": ["-q", "plan", "--out", f"{out}/a.geojson"],
        "plan --keep-inside": ["-q", "plan", "--keep-inside", "--out", f"{out}/b.kml"],
    }
    if args.field:
        commands["plan FIELD"] = ["-q", "plan", args.field, "--spacing", args.spacing,
                                  "--out", f"{out}/c.geojson"]  # fmt: skip
    trees = {"base": args.base, "this": str(HERE)}
    print(f"load {os.getloadavg()[0]:.2f}; {args.repeat} runs each, after one warm-up")
    for name, argv in commands.items():
        for src in trees.values():
            _measure(src, argv)  # warm: numba's cache, the page cache
        times: dict[str, list[tuple[float, float]]] = {t: [] for t in trees}
        for _ in range(args.repeat):
            for tree, src in trees.items():
                times[tree].append(_measure(src, argv))
        for tree, rows in times.items():
            wall = statistics.median(r[0] for r in rows)
            cpu = statistics.median(r[1] for r in rows)
            print(f"{name:20s} {tree:5s} wall {wall:6.3f} s  CPU {cpu:6.3f} s")
    print(f"load {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
