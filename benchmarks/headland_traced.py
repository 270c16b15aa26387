"""Benchmark (round 13, "headland"): headland passes on a traced (noisy) boundary and on plain
fields, this tree against a baseline's ``src`` measured in the same run.

Fields: a 3000-vertex traced ellipse (500 x 300 m, a random walk of the radius and 0.3 m of
noise per vertex at about 0.7 m spacing: the recipe of the exploratory test that found spikes
to every noise corner; and the same with 5 cm of noise), a 120 x 90 m rectangle, an L (240 x
220 m, a 130 m notch), and Fields2Cover's demo fields (``--data``, e.g. a checkout's ``data/``:
test_2_cell.json and test1.xml; the embedded test.json always). Each is planned as ``boustro
plan --spacing S --headland N`` would (:func:`boustro.mission.plan_area`), once with each tree
in a fresh process, the two interleaved. Printed: the headland's length beside the length of
its rings alone (the passes without spikes), the path's length, coverage measured here with
shapely on the original boundary (flat-ended bands along the lanes, every point within reach of
the headland passes: the footprint model of :mod:`boustro.plan.coverage`), and the CPU time
(``time.process_time``, the machine is shared) of ``add_headland``. Each child plans its field
once before the timed run (numba's cache, shapely's first calls).

    python benchmarks/headland_traced.py --baseline /path/to/base/src [--data DIR]
"""

from __future__ import annotations

import argparse
import os
import subprocess

from _child import run_child

HERE = os.path.dirname(os.path.abspath(__file__))
SRC = os.path.join(os.path.dirname(HERE), "src")

CHILD = r"""
import json, time
import numpy as np
import shapely
from boustro.io import embedded_field, read_areas
from boustro.mission import plan_area, pipeline
from boustro.plan.headland import headland_rings

name, data, spacing, passes = {name!r}, {data!r}, {spacing!r}, {passes!r}
if name.startswith("traced"):
    noise = 0.05 if name == "traced 5cm" else 0.3
    rng = np.random.default_rng(3)
    t = np.linspace(0, 2 * np.pi, 3000, endpoint=False)
    r = 1 + 0.01 * rng.standard_normal(3000).cumsum() / 10
    x = 250 * np.cos(t) * r + noise * rng.standard_normal(3000)
    y = 150 * np.sin(t) * r + noise * rng.standard_normal(3000)
    poly = shapely.Polygon(np.c_[x, y])
    poly = poly if poly.is_valid else poly.buffer(0)  # as the test's recipe
    area, kw = np.asarray(poly.exterior.coords)[:-1], dict(crs=None)
elif name == "rectangle":
    area, kw = [(0, 0), (120, 0), (120, 90), (0, 90)], dict(crs=None)
elif name == "L":
    area, kw = [(0, 0), (240, 0), (240, 90), (110, 90), (110, 220), (0, 220)], dict(crs=None)
elif name == "test.json":
    area, kw = embedded_field(), {{}}
else:
    file, i = name.rsplit("#", 1)
    area, kw = read_areas(data + "/" + file)[int(i) - 1], {{}}
spent = []
add_headland = pipeline.add_headland
def timed(*args, **kwargs):
    t = time.process_time()
    out = add_headland(*args, **kwargs)
    spent.append(time.process_time() - t)
    return out
pipeline.add_headland = timed
plan_area(area, spacing, headland=passes, check_coverage=False, **kw)  # warm
m = plan_area(area, spacing, headland=passes, **kw)
plan = m.plan
proj = m.projection
field = shapely.Polygon(proj.to_plan(m.area.ring), [proj.to_plan(h) for h in m.area.holes])
parts = []
for seg, role in zip(plan.transects, plan.role()):
    line = shapely.LineString(seg)
    if role == "lane":
        parts.append(line.buffer(plan.reach, cap_style="flat"))
    else:
        parts.append(line.buffer(plan.reach, quad_segs=64))
missed = field.difference(shapely.union_all(parts)).area
rings = headland_rings(plan.region, plan.spacing, passes)
ring_m = sum(shapely.LineString(r).length for rs in rings for r in rs) / plan.ground_scale
s = m.summary()
print(json.dumps(dict(cpu=spent[-1], headland_m=s["headland_length_m"], ring_m=ring_m,
                      path=s["path_length_m"], missed=missed / field.area,
                      covered=m.coverage.covered_share)))
"""


def run(src: str, name: str, data: str, spacing: float, passes: int) -> dict:
    return run_child(src, CHILD.format(name=name, data=data, spacing=spacing, passes=passes))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--baseline", required=True, help="a baseline tree's src folder")
    ap.add_argument("--data", default="", help="Fields2Cover's data/ folder")
    args = ap.parse_args()
    cases = [("traced", 15.0, 1), ("traced", 15.0, 2), ("traced 5cm", 15.0, 1)]
    cases += [("rectangle", 10.0, 1), ("rectangle", 10.0, 2), ("L", 10.0, 2)]
    cases.append(("test.json", 10.0, 2))
    if args.data:
        cases += [("test_2_cell.json#1", 10.0, 2), ("test1.xml#1", 10.0, 2)]
    print(
        "| field | spacing, passes | tree | rings m | headland m | headland / rings | path m "
        "| uncovered share (shapely) | add_headland CPU s |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for name, spacing, passes in cases:
        for label, src in (("base", args.baseline), ("this", SRC)):
            try:
                r = run(src, name, args.data, spacing, passes)
            except subprocess.CalledProcessError as exc:
                print(f"| {name} | {spacing:g}, {passes} | {label} | {exc.stderr[-200:]!r} |")
                continue
            print(
                f"| {name} | {spacing:g}, {passes} | {label} | {r['ring_m']:.0f} | "
                f"{r['headland_m']:.0f} | {r['headland_m'] / r['ring_m']:.3f} | {r['path']:.0f} "
                f"| {r['missed']:.1e} | {r['cpu']:.2f} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
