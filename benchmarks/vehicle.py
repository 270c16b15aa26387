"""Benchmark (issue 17, items 1-2): mission length and time with the vehicle's turns.

On the public demo fields of Fields2Cover (``data/`` of github.com/Fields2Cover/Fields2Cover;
not committed here: give the folder, e.g. a checkout, with ``--data``; the embedded field is
Fields2Cover's ``test.json`` and is always run), at 10 m spacing and a 6 m turn radius (a
tractor), each field is planned with boustro's optimised lanes and:

* ``straight``: the connecting moves of today (straight lines: what a plan without a vehicle
  model flies; a real tractor cannot turn like that, so this is a lower bound, the baseline);
* ``dubins``: Dubins turns (forward only), every other lane where that turns less;
* ``reeds-shepp``: Reeds-Shepp turns (the tractor may reverse);
* ``dubins+headland 2``: two headland passes, lanes in the inner field, Dubins turns inside it.

Reported per field: path length (m), turn length, mission time at 2 m/s plus 5 s per turn, and
the ratio to the baseline's length measured in the same run; the CPU time of planning
(``time.process_time``) and of the turn step alone on a regular 100-gon of radius 500 m.

    python benchmarks/vehicle.py --data /path/to/Fields2Cover/data
"""

from __future__ import annotations

import argparse
import math
import os
import time

import numpy as np

from boustro.io import embedded_field, read_areas
from boustro.mission import plan_area
from boustro.plan import drive_vehicle
from boustro.vehicle import Vehicle

SPACING = 10.0
RADIUS = 6.0
SPEED = 2.0
TURN_TIME = 5.0
#: The distinct real fields of data/ (Envelope.xml and envelope1.xml hold test1.xml's parcel
#: again; test_ring.json is a 10 x 10 unit-test ring, not a field at 10 m spacing).
FILES = ("test_2_cell.json", "test1.xml")


def _fields(data: str | None):
    out = [("test.json (embedded)", embedded_field())]
    if data:
        for name in FILES:
            path = os.path.join(data, name)
            if os.path.exists(path):
                for i, area in enumerate(read_areas(path)):
                    out.append((f"{name}#{i + 1}", area))
    return out


def _row(area, **kw):
    t0 = time.process_time()
    m = plan_area(area, SPACING, speed=SPEED, turn_time=TURN_TIME, **kw)
    cpu = time.process_time() - t0
    s = m.summary()
    kept = sum(int(n.split(" of ")[0]) for n in m.plan.notes if "moves between passes" in n)
    s["kept"] = kept
    return s, cpu


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", help="Fields2Cover's data/ folder")
    args = ap.parse_args()
    dubins = Vehicle(turn_radius=RADIUS)
    rs = Vehicle(turn_radius=RADIUS, reverse=True)
    variants = [
        ("straight", {}),
        ("dubins", {"vehicle": dubins}),
        ("reeds-shepp", {"vehicle": rs}),
        ("dubins+headland 2", {"vehicle": dubins, "headland": 2}),
    ]
    print(f"spacing {SPACING} m, turn radius {RADIUS} m, {SPEED} m/s + {TURN_TIME} s per turn")
    print(
        "| field | area ha | plan | lanes | turns | path m | turn m | time min | "
        "length ratio | covered | straight moves kept | plan CPU s |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name, area in _fields(args.data):
        base = None
        for label, kw in variants:
            try:
                s, cpu = _row(area, **kw)
            except Exception as exc:  # a field the variant cannot plan: say why
                print(f"| {name} | | {label} | {type(exc).__name__}: {exc} | | | | | | | | |")
                continue
            base = s["path_length_m"] if base is None else base
            print(
                f"| {name} | {s['area_m2'] / 1e4:.2f} | {label} | {s['n_transects']} | "
                f"{s['n_turns']} | {s['path_length_m']:.0f} | {s.get('turn_length_m', 0):.0f} | "
                f"{s['duration_s'] / 60:.1f} | {s['path_length_m'] / base:.3f} | "
                f"{s['covered_share']:.6f} | {s['kept']} | {cpu:.2f} |"
            )
    # The turn step alone on a 100-vertex field (Eq. 1's plan), then the time objective's plan.
    ring = 500 * np.stack(
        [
            np.cos(np.linspace(0, 2 * math.pi, 100, endpoint=False)),
            np.sin(np.linspace(0, 2 * math.pi, 100, endpoint=False)),
        ],
        axis=1,
    )
    t0 = time.process_time()
    m = plan_area(ring, SPACING, crs=None, check_coverage=False)
    t_plan = time.process_time() - t0
    t0 = time.process_time()
    turned = drive_vehicle(m.plan, dubins)
    t_turns = time.process_time() - t0
    print(
        f"\n100-gon (r 500 m, {m.plan.stats.n_transects} lanes): plan {t_plan:.2f} s CPU, "
        f"Dubins turns and lane order {t_turns:.3f} s CPU, "
        f"{sum(k == 'turn' for k in turned.kinds)} turn waypoints"
    )
    # The target: the time objective with the vehicle's turns in the search.
    t0 = time.process_time()
    m = plan_area(
        ring, SPACING, crs=None, speed=SPEED, turn_time=TURN_TIME, vehicle=dubins,
        check_coverage=False,
    )  # fmt: skip
    print(
        f"100-gon, time objective with Dubins turns: plan {time.process_time() - t0:.2f} s CPU "
        f"({m.plan.stats.n_transects} lanes, {m.stats.duration / 60:.1f} min, gap "
        f"{100 * m.optimum.info['gap'] / m.optimum.fitness:.2f}%)"
    )


if __name__ == "__main__":
    main()
