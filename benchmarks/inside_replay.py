"""Benchmark (issue 16, tenth round): :func:`boustro.plan.inside.inside_layout` alone, this tree
beside a baseline tree, on the very calls a ``--speed 5 --turn-time 10 --keep-inside`` plan
makes.

Each case (``keep_inside_speed.py``'s star and random areas with holes) is planned once with the
baseline's ``src`` while every ``inside_layout`` call's arguments are recorded (pickled to a
temporary file); each tree then replays them in a fresh process (a first pass, then
``--repeats`` passes with the per-area caches cleared, as a new plan_area finds them; CPU
``time.process_time``, the least of the passes) and hashes what they return (the cut lanes, the
passes' points, what is left uncovered): "same" when the two hashes agree.

    python benchmarks/inside_replay.py --baseline /tmp/base/src [--only star random_0]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
SRC = os.path.join(os.path.dirname(HERE), "src")

RECORD = r"""
import pickle, sys
sys.path.insert(0, {here!r})
from keep_inside_speed import keep_inside_case
import boustro.plan.region as R
from boustro.mission import plan_area
area, spacing, kw = keep_inside_case({case!r})
calls, real = [], R.inside_layout
def record(*args):
    calls.append(args)
    return real(*args)
R.inside_layout = record
plan_area(area, spacing, speed=5.0, turn_time=10.0, keep_inside=True, **kw)
pickle.dump(calls, open({path!r}, "wb"))
"""

REPLAY = r"""
import hashlib, json, pickle, time
import numpy as np
import boustro.plan.inside as I
calls = pickle.load(open({path!r}, "rb"))
def run():
    h = hashlib.sha256()
    for args in calls:
        cut, passes, uncovered = I.inside_layout(*args)
        for ls in cut:
            h.update(np.concatenate([ls.k, ls.c, ls.t0, ls.t1]).tobytes())
        for p in passes:
            h.update(np.ascontiguousarray(p).tobytes())
        h.update(np.float64(uncovered).tobytes())
    return h.hexdigest()[:12]
run()
cpu = []
for _ in range({repeats}):
    I._GEOMETRIES.clear(); I._bands.cache_clear(); I._band.cache_clear()
    t0 = time.process_time()
    digest = run()
    cpu.append(time.process_time() - t0)
print(json.dumps(dict(calls=len(calls), cpu=min(cpu), digest=digest)))
"""


def _python(src: str, code: str) -> str:
    env = {**os.environ, "PYTHONPATH": src}
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    return out.stdout.strip().splitlines()[-1] if out.stdout.strip() else ""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", required=True, help="the baseline's src folder")
    ap.add_argument("--only", nargs="*", default=["star", "random_0", "random_4"])
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    print("| case | calls | baseline CPU s | this tree CPU s | same | CPU ratio |")
    print("|---|---:|---:|---:|---|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        for case in args.only:
            path = os.path.join(tmp, f"{case}.pkl")
            _python(args.baseline, RECORD.format(here=HERE, case=case, path=path))
            code = REPLAY.format(path=path, repeats=args.repeats)
            base = json.loads(_python(args.baseline, code))
            new = json.loads(_python(SRC, code))
            print(
                f"| {case} | {new['calls']} | {base['cpu']:.2f} | {new['cpu']:.2f} | "
                f"{'yes' if base['digest'] == new['digest'] else 'no'} | "
                f"x{new['cpu'] / base['cpu']:.2f} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
