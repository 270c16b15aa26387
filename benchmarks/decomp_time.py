"""Benchmark (issue 16 item 3): the decomposition chosen by mission time on thin and concave
shapes, against one grid and the best whole degree, measured in the same run.

Shapes (planar, metres; 5 m/s, 10 s per turn): the 1 m wide square ring (10 x 10, 8 x 8 hole,
spacing 1), an L-shape (100 x 100 minus 70 x 70, spacing 10), a U, a T, a frame with two holes
and seeded random concave polygons with holes (~300 m across, spacing 10). For each:

* ``plan``: ``plan_area(..., speed, turn_time)``: the time objective, the decomposed plan when
  it is faster than the certified one grid;
* ``one grid``: the same with ``decompose=False``;
* ``brute``: every whole degree, lanes laid from the area's edge, the fastest kept.

Printed: mission times, their ratios, lanes, the order's solver and planning CPU time
(``time.process_time``) of ``plan`` and of ``one grid``.

    python benchmarks/decomp_time.py [--random 10]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from boustro.geometry.region import Region, random_region
from boustro.mission import _as_area, _project, _Sensor, _sensor_spacing, plan_area
from boustro.mission.cover import _planner
from boustro.mission.steps import _path_options
from boustro.optimize.cover import centred_offsets

SPEED = 5.0
TURN_TIME = 10.0

SHAPES = [
    ("ring 1 m", [(0, 0), (10, 0), (10, 10), (0, 10)], [[(1, 1), (1, 9), (9, 9), (9, 1)]], 1.0),
    ("L-shape", [(0, 0), (100, 0), (100, 30), (30, 30), (30, 100), (0, 100)], [], 10.0),
    (
        "U-shape",
        [(0, 0), (120, 0), (120, 120), (90, 120), (90, 30), (30, 30), (30, 120), (0, 120)],
        [],
        10.0,
    ),
    (
        "T-shape",
        [(0, 80), (0, 110), (150, 110), (150, 80), (90, 80), (90, 0), (60, 0), (60, 80)],
        [],
        10.0,
    ),
    (
        "frame, 2 holes",
        [(0, 0), (200, 0), (200, 100), (0, 100)],
        [[(20, 20), (90, 20), (90, 80), (20, 80)], [(110, 20), (180, 20), (180, 80), (110, 80)]],
        10.0,
    ),
]


def _brute(shell, holes, spacing) -> float:
    area = _as_area(np.asarray(shell, float), None, [np.asarray(h, float) for h in holes])
    frame = _project(area, _Sensor(*_sensor_spacing(spacing)), 0.5, None, None)
    plan_of = _planner(frame, "guaranteed", _path_options(frame, 0.0, SPEED, TURN_TIME))
    region = frame.region if frame.region is not None else Region(frame.poly)
    angles = np.radians(np.arange(180.0))
    offsets = centred_offsets(region, angles, spacing, spacing / 2)
    return min(plan_of(a, d).stats.duration for a, d in zip(angles, offsets, strict=True))


def _timed(shell, holes, spacing, **kw):
    t0 = time.process_time()
    m = plan_area(shell, spacing, crs=None, holes=holes, speed=SPEED, turn_time=TURN_TIME, **kw)
    return m, time.process_time() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--random", type=int, default=10, help="random concave areas (default 10)")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    shapes = list(SHAPES)
    rng = np.random.default_rng(args.seed)
    for i in range(args.random):
        r = random_region(rng, int(rng.integers(6, 16)), int(rng.integers(1, 4)), roughness=0.5)
        k = 300.0 / r.diameter
        shapes.append(
            (f"random {i}", r.shell.vertices * k, [h.vertices * k for h in r.holes], 10.0)
        )
    _timed(*shapes[0][1:])  # compile the kernels outside the timings
    rows = []
    for name, shell, holes, spacing in shapes:
        m, cpu = _timed(shell, holes, spacing)
        one, cpu_one = _timed(shell, holes, spacing, decompose=False)
        brute = _brute(shell, holes, spacing)
        s = m.summary()
        rows.append(
            (name, m.stats.duration / one.stats.duration, m.stats.duration / brute, cpu, cpu_one)
        )
        print(
            f"{name:16s} plan {m.stats.duration:8.1f} s ({m.stats.n_transects} lanes, "
            f"{s['method']}, order {s.get('cell_order', '-')}) | one grid "
            f"{one.stats.duration:8.1f} s ({one.stats.n_transects} lanes) | brute {brute:8.1f} s | "
            f"plan/one {rows[-1][1]:.4f} plan/brute {rows[-1][2]:.4f} | CPU {cpu:.2f} s "
            f"(one grid {cpu_one:.2f} s)",
            flush=True,
        )
    print(
        f"\nplan / one grid: median {statistics.median(r[1] for r in rows):.4f}, worst "
        f"{max(r[1] for r in rows):.4f}; plan / brute: median "
        f"{statistics.median(r[2] for r in rows):.4f}, worst {max(r[2] for r in rows):.4f}; "
        f"CPU median {statistics.median(r[3] for r in rows):.2f} s (one grid "
        f"{statistics.median(r[4] for r in rows):.2f} s)"
    )


if __name__ == "__main__":
    main()
