"""Benchmark (issue 16): the certified fastest mission against a 1-degree brute force.

Fields: Fields2Cover's public demo fields (``data/`` of github.com/Fields2Cover/Fields2Cover; not
committed here: give the folder with ``--data``; the embedded field is its ``test.json`` and is
always run) and seeded random concave polygons with holes (``random_region``, ~300 m across).
Spacing 10 m, 5 m/s, 10 s per turn. For each field:

* ``time``: ``plan_area(..., speed, turn_time)``: the time objective (the default with a speed),
  certified search over every angle and offset, the decomposed plan when it is faster;
* ``eq1``: the same with ``fitness=SmithFitness()``: the paper's fitness (today's default plan);
* ``brute``: the baseline (b) of the issue: every whole degree, lanes centred on the area
  (the first half a spacing inside its extreme, as Fields2Cover's swaths), the
  coverage-guaranteed lanes flown by the same planner, the fastest angle kept;
* ``keep-inside`` (with ``--keep-inside``): the time objective with ``keep_inside=True`` (lanes
  end inside, moves follow the inside, boundary passes), its ratio to the same brute force
  (whose path leaves the area).

Printed per set: the median and worst ratio of mission time to the brute force's (measured in
the same run), the share certified, the median gap, lanes, coverage (shapely, the original
boundary), path outside the area, and planning CPU time (``time.process_time``), warm: the
compiled kernels are built by an untimed plan of a random area with holes (and the embedded
field) first, so the first fields' CPU is not the compiler's (after a source change numba's
on-disk cache is rebuilt: 15-19 s on the first two fields otherwise).

    python benchmarks/mission_time.py --data F2C/data [--random 100] [--keep-inside]
"""

from __future__ import annotations

import argparse
import hashlib
import os
import statistics
import time

import numpy as np

from boustro.geometry.region import Region, random_region
from boustro.io import embedded_field, read_areas
from boustro.mission import _as_area, _project, _Sensor, _sensor_spacing, plan_area
from boustro.mission.cover import _planner
from boustro.mission.steps import _path_options
from boustro.objectives import SmithFitness
from boustro.optimize.cover import centred_offsets

SPACING = 10.0
SPEED = 5.0
TURN_TIME = 10.0
FILES = ("test_2_cell.json", "test1.xml")


def _fields(data: str | None, n_random: int, seed: int) -> list[tuple[str, object, str | None]]:
    out: list[tuple[str, object, str | None]] = [("f2c test.json", embedded_field(), "auto")]
    if data:
        for name in FILES:
            path = os.path.join(data, name)
            if os.path.exists(path):
                for i, area in enumerate(read_areas(path)):
                    out.append((f"f2c {name}#{i + 1}", area, "auto"))
    rng = np.random.default_rng(seed)
    for i in range(n_random):
        r = random_region(rng, int(rng.integers(6, 16)), int(rng.integers(1, 4)), roughness=0.5)
        out.append((f"random {i}", _scaled(r), None))
    return out


def _scaled(r: Region) -> tuple[np.ndarray, list[np.ndarray]]:
    """A random region's shell and holes scaled to 300 m across."""
    k = 300.0 / r.diameter
    return r.shell.vertices * k, [h.vertices * k for h in r.holes]


def _plan(area, crs, **kw):
    if isinstance(area, tuple):
        ring, holes = area
        return plan_area(ring, SPACING, crs=None, holes=holes, **kw)
    return plan_area(area, SPACING, **kw)


def _row(area, crs, **kw):
    t0 = time.process_time()
    m = _plan(area, crs, speed=SPEED, turn_time=TURN_TIME, **kw)
    cpu = time.process_time() - t0
    s = m.summary()
    return {
        "time": m.stats.duration,
        "lanes": s["n_transects"],
        "turns": m.stats.n_turns,
        "covered": s.get("covered_share", float("nan")),
        "outside": s.get("outside_length_m", 0.0),
        "certified": bool(s.get("certified")),
        "gap": s.get("gap") if s.get("gap") is not None else float("nan"),
        "cpu": cpu,
        "method": s["method"],
        "path": hashlib.sha256(np.ascontiguousarray(m.waypoints).tobytes()).hexdigest()[:12],
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", help="Fields2Cover's data/ folder")
    ap.add_argument("--random", type=int, default=20, help="random concave areas (default 20)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument(
        "--keep-inside",
        action="store_true",
        help="also plan each field with the time objective and --keep-inside",
    )
    args = ap.parse_args()
    _warm(args.keep_inside)
    rows = []
    for name, area, crs in _fields(args.data, args.random, args.seed):
        timed = _row(area, crs)
        eq1 = _row(area, crs, fitness=SmithFitness())
        brute, brute_cpu = _brute_centred(area, crs)
        inside = _row(area, crs, keep_inside=True) if args.keep_inside else None
        rows.append((name, timed, eq1, brute, brute_cpu, inside))
        print(
            f"{name:24s} time {timed['time']:8.1f} s ({timed['method']}, certified "
            f"{timed['certified']}, gap {timed['gap']:.2f} s, {timed['cpu']:.2f} s CPU, "
            f"{timed['lanes']} lanes, {timed['turns']} turns) | eq1 "
            f"{eq1['time']:8.1f} | brute {brute:8.1f} ({brute_cpu:.1f} s CPU) | time/brute "
            f"{timed['time'] / brute:.4f} covered {timed['covered']:.6f} outside "
            f"{timed['outside']:.0f} m",
            flush=True,
        )
        if inside is not None:
            print(
                f"{'':24s} keep-inside {inside['time']:8.1f} s (certified {inside['certified']}, "
                f"gap {inside['gap']:.2f} s, {inside['cpu']:.2f} s CPU, {inside['lanes']} lanes, "
                f"{inside['turns']} turns) | /brute {inside['time'] / brute:.4f} covered "
                f"{inside['covered']:.6f} outside {inside['outside']:.2f} m",
                flush=True,
            )
    _summary(rows)


def _warm(keep_inside: bool) -> None:
    """Plan a convex field and a concave area with holes once, untimed (the module docstring)."""
    r = random_region(np.random.default_rng(12345), 8, 2, roughness=0.5)
    for area, crs in ((embedded_field(), None), (_scaled(r), None)):
        _plan(area, crs, speed=SPEED, turn_time=TURN_TIME)
        _plan(area, crs, fitness=SmithFitness())
        if keep_inside:
            _plan(area, crs, speed=SPEED, turn_time=TURN_TIME, keep_inside=True)


def _brute_centred(area, crs) -> tuple[float, float]:
    """The brute force of the module docstring: the plan at each whole degree with the first
    lane half a spacing inside the area's extreme (offset from the shell's vertex mean)."""
    t0 = time.process_time()
    if isinstance(area, tuple):
        a_obj = _as_area(area[0], None, area[1])
    else:
        a_obj = area
    sensor = _Sensor(*_sensor_spacing(SPACING))
    frame = _project(a_obj, sensor, 0.5, None, None)
    plan_of = _planner(frame, "guaranteed", _path_options(frame, 0.0, SPEED, TURN_TIME))
    target = frame.poly if frame.region is None else frame.region
    region = target if isinstance(target, Region) else Region(target)
    s = SPACING * frame.proj.scale_min
    angles = np.radians(np.arange(180.0))
    offsets = centred_offsets(region, angles, s, s / 2)
    best = min(plan_of(a, d).stats.duration for a, d in zip(angles, offsets, strict=True))
    return best, time.process_time() - t0


def _summary(rows) -> None:
    for label, pick in (("Fields2Cover", "f2c"), ("random concave with holes", "random")):
        sel = [r for r in rows if r[0].startswith(pick)]
        if not sel:
            continue
        ratio = [r[1]["time"] / r[3] for r in sel]
        eq1 = [r[2]["time"] / r[3] for r in sel]
        print(f"\n{label}: {len(sel)} fields")
        print(
            f"  time objective / brute force: median {statistics.median(ratio):.4f}, worst "
            f"{max(ratio):.4f}, never longer: {sum(x <= 1 + 1e-9 for x in ratio)}/{len(sel)}"
        )
        print(f"  Eq. 1 (today's default) / brute force: median {statistics.median(eq1):.4f}")
        print(
            f"  certified {sum(r[1]['certified'] for r in sel)}/{len(sel)}, median gap "
            f"{_median_gap(sel) * 100:.2f}% (of the one-grid plans; a decomposed plan's cells "
            f"carry theirs), decomposed {sum(r[1]['method'] == 'decomposed-cover' for r in sel)}, "
            f"coverage min {min(r[1]['covered'] for r in sel):.6f}, planning CPU median "
            f"{statistics.median(r[1]['cpu'] for r in sel):.2f} s, max "
            f"{max(r[1]['cpu'] for r in sel):.2f} s"
        )
        ins = [r for r in sel if r[5] is not None]
        if ins:
            k_ratio = [r[5]["time"] / r[3] for r in ins]
            print(
                f"  --keep-inside / brute force (which leaves the area): median "
                f"{statistics.median(k_ratio):.4f}, worst {max(k_ratio):.4f}; certified "
                f"{sum(r[5]['certified'] for r in ins)}/{len(ins)}, median gap "
                f"{statistics.median(_rel_gap(r[5]) for r in ins) * 100:.2f}%, coverage min "
                f"{min(r[5]['covered'] for r in ins):.6f}, outside max "
                f"{max(r[5]['outside'] for r in ins):.3f} m, planning CPU median "
                f"{statistics.median(r[5]['cpu'] for r in ins):.2f} s, max "
                f"{max(r[5]['cpu'] for r in ins):.2f} s"
            )


def _rel_gap(row) -> float:
    return row["gap"] / row["time"] if row["gap"] == row["gap"] else float("inf")


def _median_gap(sel) -> float:
    gaps = [r[1]["gap"] / r[1]["time"] for r in sel if r[1]["gap"] == r[1]["gap"]]
    return statistics.median(gaps) if gaps else float("nan")


if __name__ == "__main__":
    main()
