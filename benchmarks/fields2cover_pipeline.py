"""Benchmark (issue 16): Fields2Cover's own pipeline beside boustro's time-objective plans.

Issue 16 asks for missions no longer than Fields2Cover's at 100% coverage where Fields2Cover
leaves gaps. This script runs Fields2Cover itself (its C++ library through its SWIG Python
module) with the pipeline its tutorials document, and boustro on the same planar areas:

* ``f2c``: no headland; swaths by ``SG_BruteForce`` at its default 1-degree step over the angle
  minimising ``OBJ_NSwath`` (the swath count), robot ``Robot(10, 10)`` (width and coverage width
  10 m); the route ``RP_Boustrophedon``; no turn planner: straight moves from each swath's end to
  the next swath's start (Dubins and Reeds-Shepp off, as boustro's plans here). The variants
  ``OBJ_SwathLength`` (the other tutorial objective) and ``RP_Snake`` (the complete-flow
  tutorial's route) are also flown, and the shortest of the four missions is reported as
  ``f2c best``. ``f2c lengthened``: the first pipeline's swaths each lengthened along its line
  to the ends of the part of its strip in the area it lies in (what a flat-ended footprint must
  reach where the boundary is slanted to the swaths), the same order: how much of boustro's
  longer missions is the price of covering the swath ends. ``f2c completed``: each of the four
  plans lengthened so, and a swath added on the next line of its own grid beyond each outermost
  swath whose strip still meets the area there (the slivers beside it), flown against that
  swath just before or after it (the shorter path); the shortest of the four: Fields2Cover's
  plan made to cover the area as far as its angle and grid can (100% on fields without holes;
  beside holes, parts of strips that hold no swath stay uncovered, so a plan covering those
  too would be longer still). OR-tools' route
  (``RP_RoutePlannerBase``) is not run (see below).
* ``boustro``: ``plan_area(ring, 10, crs=None, holes=..., speed=5, turn_time=10)`` (the time
  objective), and the same with ``keep_inside=True``; with ``--eq1`` also with
  ``fitness=SmithFitness()`` (Eq. 1, boustro's default objective when no speed is given).

Both tools' missions are measured by the same code from the flown path: its length (every
waypoint, straight moves between them), the turns (``passes - 1``: F2C's swaths; boustro's
lanes, passes around holes and boundary passes, ``PlanStats.n_turns``) and the mission time
``CoverCost.time(5, 10).of(length, turns)`` (path / 5 m/s + 10 s a turn); the length outside the
area or inside a hole by :func:`boustro.plan.outside.outside_length`. Coverage of the original
area is measured with shapely: F2C's swaths buffered by half the coverage width with flat ends
(what F2C's own ``Swath::areaCovered`` does), boustro's plans with their own footprint
(``Mission.coverage``). The CPU time of each tool's planning is ``time.process_time``.

Fields: Fields2Cover's demo fields (``--data``: ``test.json``, ``test1.xml``,
``test_2_cell.json``'s two fields; ``test_ring.json`` is a 10 x 10 unit-test ring and
``Envelope.xml``/``envelope1.xml`` hold ``test1.xml``'s parcel again), read by Fields2Cover's
``Parser`` and projected by its ``Transform.transformToUTM`` (its complete-flow tutorial), then
given to both tools as the same planar coordinates (metres, F2C's local frame); and ``--random
N`` of ``benchmarks/mission_time.py``'s random concave areas with 1-3 holes (~300 m).

How Fields2Cover was obtained (2026-11-28; nothing of it is committed here): its 2.1.0 sdist
from PyPI (``pip download fields2cover==2.1.0 --no-deps --no-binary :all:``), built with CMake
3.25 / GCC 12 on Debian 12 against Debian's GDAL 3.6.2, GEOS 3.11, Eigen, TinyXML2, Boost
headers and SWIG 4.1.0 (``BUILD_SHARED_LIBS=OFF``, Release); its FetchContent dependencies from
snapshots of their GitHub repositories at the commits its CMake pins (steering_functions
13e3f56, matplotplusplus 5d01eb3 without its high-resolution world map, whose source file was
missing from the snapshot), nlohmann/json at 3.11.3; OR-tools has neither a Debian package nor
headers in its PyPI wheel and its release tarball is not reachable here, so the local copy was
patched to build without it: its CMake's OR-tools lookup removed and
``RoutePlannerBase::computeBestRoute`` throwing, everything else Fields2Cover's code unchanged
(the Python tests of Fields2Cover's repository: 104 pass, the one of ``RoutePlannerBase`` fails
as expected). The Python module was installed outside the project's venv; put its folder on
the path::

    PYTHONPATH=src:/work/f2c_venv/f2c_py python benchmarks/fields2cover_pipeline.py \\
        --data <Fields2Cover>/data --random 20
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import time
from typing import Any

import mission_time as mt
import numpy as np

from boustro.mission import plan_area
from boustro.objectives import SmithFitness
from boustro.optimize.cover import CoverCost
from boustro.plan.outside import outside_length

SPACING = mt.SPACING
SPEED = mt.SPEED
TURN_TIME = mt.TURN_TIME
FILES = (("test.json", "json"), ("test1.xml", "gml"), ("test_2_cell.json", "json"))


def _import_f2c() -> Any:
    try:
        import fields2cover
    except ImportError as err:
        sys.exit(
            f"fields2cover is not importable ({err}): build Fields2Cover's Python module "
            "(see this script's docstring) and put its folder on PYTHONPATH"
        )
    return fields2cover


# -- the areas --------------------------------------------------------------------------------
def _xy(points: Any) -> np.ndarray:
    """``(N, 2)`` the points of an F2C LinearRing or LineString."""
    return np.array(
        [[points.getGeometry(j).getX(), points.getGeometry(j).getY()] for j in range(points.size())]
    )


def _rings_of_cell(cell: Any) -> list[np.ndarray]:
    return [_xy(cell.getGeometry(i)) for i in range(cell.size())]


def _f2c_fields(f2c: Any, data: str) -> list[tuple[str, np.ndarray, list[np.ndarray]]]:
    """Fields2Cover's demo fields as F2C reads them, in UTM metres (its local frame)."""
    out = []
    for name, kind in FILES:
        path = os.path.join(data, name)
        if not os.path.exists(path):
            continue
        fields = f2c.Fields()
        if kind == "gml":
            f2c.Parser.importGml(path, fields)
        else:
            f2c.Parser.importJson(path, fields)
        for i in range(fields.size()):
            field = fields[i]
            if not field.getCRS():
                field.setEPSGCoordSystem(4326)  # GeoJSON without a crs: WGS 84 (F2C's tests)
            f2c.Transform.transformToUTM(field)
            cells = field.getField()
            for k in range(cells.size()):
                rings = _rings_of_cell(cells.getGeometry(k))
                out.append((f"f2c {name}#{i + 1}", rings[0], rings[1:]))
    return out


def _random_fields(n: int, seed: int) -> list[tuple[str, np.ndarray, list[np.ndarray]]]:
    """``benchmarks/mission_time.py``'s random concave areas with holes (same names, seeds)."""
    return [
        (name, np.asarray(area[0]), [np.asarray(h) for h in area[1]])
        for name, area, _ in mt._fields(None, n, seed)
        if name.startswith("random")
    ]


# -- one measure for both tools ---------------------------------------------------------------
def _shapely_area(ring: np.ndarray, holes: list[np.ndarray]) -> Any:
    import shapely

    return shapely.Polygon(ring, holes)


def _path_length(path: np.ndarray) -> float:
    return float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum())


def _measure(path: np.ndarray, passes: int, lanes: int, area: Any) -> dict[str, float]:
    """Length, turns, mission time and length outside of a flown path (straight between its
    waypoints), the same for both tools."""
    length = _path_length(np.asarray(path, dtype=np.float64))
    turns = max(passes - 1, 0)
    return {
        "lanes": lanes,
        "turns": turns,
        "length": length,
        "time": CoverCost.time(SPEED, TURN_TIME).of(length, turns),
        "outside": outside_length(path, area),
    }


# -- Fields2Cover -----------------------------------------------------------------------------
def _f2c_cell(f2c: Any, ring: np.ndarray, holes: list[np.ndarray]) -> Any:
    cell = f2c.Cell()
    for r in [ring, *holes]:
        pts = [f2c.Point(float(x), float(y)) for x, y in r]
        if not np.array_equal(r[0], r[-1]):
            pts.append(f2c.Point(float(r[0, 0]), float(r[0, 1])))
        cell.addRing(f2c.LinearRing(f2c.VectorPoint(pts)))
    return cell


def _f2c_plan(f2c: Any, cell: Any, objective: str, route: str) -> tuple[list[np.ndarray], float]:
    """Fields2Cover's pipeline: brute-force swaths (1 degree) for ``objective``, sorted by
    ``route``; the swaths' lines in driving order and direction, and the CPU time."""
    t0 = time.process_time()
    robot = f2c.Robot(SPACING, SPACING)
    gen = f2c.SG_BruteForce()
    gen.setStepAngle(math.pi / 180.0)
    obj = f2c.OBJ_NSwath() if objective == "nswath" else f2c.OBJ_SwathLength()
    swaths = gen.generateBestSwaths(obj, robot.getCovWidth(), cell)
    sorter = f2c.RP_Boustrophedon() if route == "boustrophedon" else f2c.RP_Snake()
    swaths = sorter.genSortedSwaths(swaths)
    cpu = time.process_time() - t0
    return [_xy(swaths[i].getPath()) for i in range(swaths.size())], cpu


def _lengthened(p: np.ndarray, q: np.ndarray, area: Any, whole: bool = False) -> np.ndarray:
    """The swath ``p -> q`` lengthened along its line, in its direction, to the ends of the part
    of its strip (the band of the coverage width about the line) in the area that it lies in
    (``whole``: of every part of the strip in the area)."""
    import shapely

    u = (q - p) / np.linalg.norm(q - p)
    n = np.array([-u[1], u[0]])
    far = 10.0 * (area.length + np.linalg.norm(q - p))
    corners = [p - far * u + n * SPACING / 2, q + far * u + n * SPACING / 2]
    corners += [q + far * u - n * SPACING / 2, p - far * u - n * SPACING / 2]
    strip = shapely.intersection(area, shapely.Polygon(corners))
    swath = shapely.LineString([p, q]).buffer(1e-6)
    parts = [g for g in getattr(strip, "geoms", [strip]) if not g.is_empty]
    if not whole:
        parts = [g for g in parts if g.intersects(swath)]
    if not parts:
        return np.array([p, q])
    pts = np.concatenate([shapely.get_coordinates(g) for g in parts])
    s = (pts - p) @ u
    return np.array([p + min(s.min(), 0.0) * u, p + max(s.max(), (q - p) @ u) * u])


def _extended(lines: list[np.ndarray], area: Any) -> list[np.ndarray]:
    """Fields2Cover's swaths each lengthened (:func:`_lengthened`): what its flat-ended
    footprint must reach to cover its strip's part whole where the boundary is slanted to the
    swaths. The slivers beside the outermost swaths stay uncovered; on a line cut by a hole the
    lengthened swaths of both sides may overlap (not merged)."""
    return [_lengthened(x[0], x[-1], area) for x in lines]


def _completed(lines: list[np.ndarray], area: Any) -> list[np.ndarray]:
    """:func:`_extended`, and a swath on the next line of Fields2Cover's grid beyond each
    outermost swath whose strip still meets the area there (the slivers), flown against that
    swath just before or just after it (the shorter path): Fields2Cover's plan made to cover
    the area as far as its angle and its own grid of lines can (each strip's parts whole)."""
    import shapely

    out = _extended(lines, area)
    if len(out) < 2:
        return out
    u = (out[0][-1] - out[0][0]) / np.linalg.norm(out[0][-1] - out[0][0])
    n = np.array([-u[1], u[0]])
    covered = shapely.union_all(
        [shapely.LineString(x).buffer(SPACING / 2, cap_style="flat") for x in out]
    )
    left = shapely.difference(area, covered)
    across = [float(x[0] @ n) for x in out]
    for side in (-1.0, 1.0):
        i = int(np.argmin(across)) if side < 0 else int(np.argmax(across))
        a = out[i]
        p, q = a[-1] + side * SPACING * n, a[0] + side * SPACING * n  # flown against ``a``
        extra = _lengthened(p, q, area, whole=True)
        strip = shapely.LineString(extra).buffer(SPACING / 2, cap_style="flat")
        if shapely.intersection(left, strip).area <= 1e-9 * area.area:
            continue
        before = [*out[:i], extra, *out[i:]]
        after = [*out[: i + 1], extra, *out[i + 1 :]]
        out = min(before, after, key=lambda x: _path_length(np.concatenate(x)))
        across = [float(x[0] @ n) for x in out]
    return out


def _f2c_row(lines: list[np.ndarray], area: Any) -> dict[str, float]:
    import shapely

    row = _measure(np.concatenate(lines), len(lines), len(lines), area)
    strips = [shapely.LineString(x).buffer(SPACING / 2, cap_style="flat") for x in lines]
    covered = shapely.intersection(area, shapely.union_all(strips)).area
    row["covered"] = covered / area.area
    return row


# -- boustro ----------------------------------------------------------------------------------
def _boustro_row(ring: np.ndarray, holes: list[np.ndarray], area: Any, **kw: Any) -> dict:
    t0 = time.process_time()
    m = plan_area(ring, SPACING, crs=None, holes=holes, speed=SPEED, turn_time=TURN_TIME, **kw)
    cpu = time.process_time() - t0
    s = m.plan.stats
    lanes = sum(r == "lane" for r in m.plan.role())
    row = _measure(m.waypoints, s.n_turns + 1, lanes, area)
    row["covered"] = m.coverage.covered_share if m.coverage is not None else float("nan")
    row["cpu"] = cpu
    row["own_time"] = float(s.duration)  # boustro's own number, a check of the measure
    return row


# -- the run ----------------------------------------------------------------------------------
def _line(label: str, r: dict) -> str:
    return (
        f"  {label:18s} lanes {r['lanes']:3d} turns {r['turns']:3d} time {r['time']:8.1f} s "
        f"path {r['length']:8.1f} m covered {r['covered'] * 100:7.3f}% outside "
        f"{r['outside']:7.1f} m CPU {r['cpu']:6.2f} s"
    )


def _run_field(
    f2c: Any, name: str, ring: np.ndarray, holes: list[np.ndarray], with_eq1: bool
) -> dict:
    area = _shapely_area(ring, holes)
    cell = _f2c_cell(f2c, ring, holes)
    f2c_rows, completed = {}, {}
    for objective in ("nswath", "swath-length"):
        for route in ("boustrophedon", "snake"):
            lines, cpu = _f2c_plan(f2c, cell, objective, route)
            row = _f2c_row(lines, area)
            row["cpu"] = cpu
            f2c_rows[(objective, route)] = row
            completed[(objective, route)] = _f2c_row(_completed(lines, area), area)
            completed[(objective, route)]["cpu"] = float("nan")
    main = f2c_rows[("nswath", "boustrophedon")]
    full = _f2c_row(_extended(_f2c_plan(f2c, cell, "nswath", "boustrophedon")[0], area), area)
    full["cpu"] = float("nan")
    whole_key = min(completed, key=lambda k: completed[k]["time"])
    whole = completed[whole_key]
    best_key = min(f2c_rows, key=lambda k: f2c_rows[k]["time"])
    timed = _boustro_row(ring, holes, area)
    inside = _boustro_row(ring, holes, area, keep_inside=True)
    eq1 = _boustro_row(ring, holes, area, fitness=SmithFitness()) if with_eq1 else None
    print(f"{name}: {area.area / 1e4:.2f} ha, {len(holes)} holes", flush=True)
    print(_line("f2c nswath+boustr", main))
    print(_line("f2c best of 4", f2c_rows[best_key]) + f" ({best_key[0]}, {best_key[1]})")
    print(_line("f2c lengthened", full))
    print(_line("f2c completed", whole) + f" (best of 4 completed: {whole_key[0]}, {whole_key[1]})")
    print(_line("boustro time", timed) + f" (own {timed['own_time']:.1f} s)")
    print(_line("boustro inside", inside) + f" (own {inside['own_time']:.1f} s)", flush=True)
    row = {"name": name, "f2c": main, "best": f2c_rows[best_key], "full": full, "whole": whole}
    row.update(time=timed, inside=inside)
    if eq1 is not None:
        print(_line("boustro eq1", eq1) + f" (own {eq1['own_time']:.1f} s)", flush=True)
        row["eq1"] = eq1
    return row


def _summary(rows: list[dict]) -> None:
    for label, pick in (("Fields2Cover's fields", "f2c"), ("random concave with holes", "random")):
        sel = [r for r in rows if r["name"].startswith(pick)]
        if not sel:
            continue
        print(f"\n{label}: {len(sel)} areas")
        for key in ("f2c", "best", "full", "whole"):
            print(
                f"  F2C {key:4s}: {_spread(sel, key)}, fewer lanes than boustro time on "
                f"{sum(r[key]['lanes'] < r['time']['lanes'] for r in sel)}/{len(sel)}"
            )
            for b in [x for x in ("time", "inside", "eq1") if x in sel[0]]:
                ratio = [r[b]["time"] / r[key]["time"] for r in sel]
                print(
                    f"    boustro {b:6s} / F2C {key}: median {statistics.median(ratio):.4f}, "
                    f"range {min(ratio):.4f}-{max(ratio):.4f}, no longer on "
                    f"{sum(x <= 1 + 1e-9 for x in ratio)}/{len(sel)}"
                )
        for b in [x for x in ("time", "inside", "eq1") if x in sel[0]]:
            print(
                f"  boustro {b}: {_spread(sel, b)}, CPU median "
                f"{statistics.median(r[b]['cpu'] for r in sel):.2f} s"
            )


def _spread(sel: list[dict], key: str) -> str:
    """The coverage range and the longest path outside of one tool's plans."""
    cov = [r[key]["covered"] * 100 for r in sel]
    out = max(r[key]["outside"] for r in sel)
    return f"covered {min(cov):.3f}-{max(cov):.3f}%, path outside max {out:.1f} m"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", help="Fields2Cover's data/ folder")
    ap.add_argument("--random", type=int, default=7, help="random concave areas (default 7)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument(
        "--eq1",
        action="store_true",
        help="also fly boustro's plan for Eq. 1 (its default objective without a speed)",
    )
    args = ap.parse_args()
    f2c = _import_f2c()
    print(f"Fields2Cover {getattr(f2c, '__version__', '?')} from {os.path.dirname(f2c.__file__)}")
    fields = (_f2c_fields(f2c, args.data) if args.data else []) + _random_fields(
        args.random, args.seed
    )
    rows = [_run_field(f2c, name, ring, holes, args.eq1) for name, ring, holes in fields]
    _summary(rows)


if __name__ == "__main__":
    main()
