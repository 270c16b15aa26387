"""Benchmark: one plan of a traced field against its vertices and spacing, time and peak memory,
this tree beside a baseline commit in the same run (issue 21).

Each measurement runs in its own subprocess (``python benchmarks/scale.py --worker ...`` with
``PYTHONPATH`` at the code measured): it builds the field (vertices written by the parent, so
both codes plan the same field), plans a small field first (imports, numba's compiled kernels
loaded or compiled), then times ``plan_region(field, spacing, decompose_area=False,
angle=0.3, offset=1.0)`` (the plan the certified search evaluates) with ``time.process_time``
and the wall clock, and reports its peak RSS (``resource.getrusage``, the whole process:
imports included). The baseline is ``git archive``-d from ``--baseline`` (default: the commit
this work started from) into a temporary directory; a baseline run over ``--timeout`` seconds
is stopped and reported as ``> timeout``, and larger fields of that series are not tried.

Usage::

    python benchmarks/scale.py                  # vertices 50 .. 5000, 0 and 10 holes
    python benchmarks/scale.py --part spacing   # 2000 vertices + 10 holes, spacing 1/10 .. 1/500
    python benchmarks/scale.py --quick          # CI size: 50, 200, 500 vertices
    python benchmarks/scale.py --part cover --vertices 200 2000 --timeout 60
                                                # the certified search, model only
    python benchmarks/scale.py --part area      # plan_area end to end (the default: certified
                                                # region search), per stage, 50 .. 5000 vertices
    python benchmarks/scale.py --part area-spacing  # the same, 2000 vertices + 10 holes,
                                                # spacing 1/10 .. 1/500 of the diameter
    python benchmarks/scale.py --part time --vertices 2000 --holes 10 --baseline-src /tmp/b/src
                                                # plan_area with the time objective (5 m/s,
                                                # 10 s a turn): the certified search over plans

The ``time`` part runs ``plan_area(shell, 10, crs=None, holes=..., speed=5, turn_time=10)``
(the certified cover search, every layout it evaluates a real plan), counts the plans made
(``plan_region``'s tour step), times the plan's stages (cells, lanes, the tour's order, its
lane-by-lane refinement, driving with routing, assembly) and prints the estimate made before
planning (``estimate_work(..., speed=5, turn_time=10)``), the gap, the fitness (mission time,
s) and a hash of the waypoints, so that the two trees' plans can be compared. Its baseline is a
``src`` folder (``--baseline-src``) or a commit (``--baseline``, default :data:`TIME_BASELINE`).

The ``area`` parts time ``boustro.mission.plan_area(shell, spacing, crs=None, holes=...)`` (Eq. 1,
the certified region search with its work budget, coverage measured with shapely) and its
stages (``choose_sweep``, the certified searches, lanes, tour and routing, path, assembly:
the functions :mod:`boustro.mission.region_certified` calls, wrapped with a CPU timer), print
the estimate made before planning (``estimate_work``) beside the measured time, and fit the
growth exponent of every stage over the sizes (least squares of ``log time`` on ``log n``).
Their baseline is :data:`AREA_BASELINE`.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tarfile
import tempfile
import time
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
BASELINE = "42b81be"  # main when issue 21's work started
AREA_BASELINE = "8882b43"  # main before the vectorised trace and links (parts area*)
TIME_BASELINE = "bc75ccd"  # main before the twelfth round (OR-Tools matrix, compiled moves)
#: The plan's stages in :mod:`boustro.plan.region` timed by part ``time``.
PLAN_STAGES = ("_plan_cells", "_plan_lanes", "_orders", "refine_tour", "_drive", "_assemble")
STAGES = (
    "choose_sweep",
    "_cells_for_sweep",
    "_certify",
    "_plan_lanes",
    "_plan_tour",
    "_drive_plan",
    "_assemble_plan",
)
VERTICES = (50, 200, 500, 1000, 2000, 5000)
QUICK_VERTICES = (50, 200, 500)
HOLES = (0, 10)
SPACING_FRACTIONS = (10, 50, 100, 250, 500)


def worker(path: str, spacing: float, part: str) -> None:
    """Plan the field in ``path`` (npz: shell, hole_0, ...), or run the certified search's
    model-only run on it (``part == "cover"``), and print one JSON line."""
    import resource

    from boustro.geometry import Polygon
    from boustro.geometry.region import Region
    from boustro.optimize.cover import CoverCost, cover_optimum
    from boustro.plan.region import plan_region

    data = np.load(path)
    shell = data["shell"]
    holes = [data[k] for k in sorted(data.files) if k.startswith("hole_")]
    region = Region(Polygon(shell), [Polygon(h) for h in holes])
    kw = {"decompose_area": False, "angle": 0.3, "offset": 1.0, "speed": 5.0, "turn_time": 10.0}
    warm = Region(Polygon(data["warm_shell"]), [Polygon(data["warm_hole"])])
    cost = CoverCost.time(5.0, 10.0)
    plan_region(warm, 10.0, **kw)
    if part == "cover":
        cover_optimum(warm, 10.0, cost, None, n_angles=4)
    t0, w0 = time.process_time(), time.perf_counter()
    out: dict = {}
    if part == "cover":
        res = cover_optimum(region, spacing, cost, None)
        out = {"value": res.fitness, "lower": res.info["lower_bound"], "lanes": ""}
        out["gap"] = res.info["gap"] / res.fitness
    else:
        plan = plan_region(region, spacing, **kw)
        out = {"lanes": plan.stats.n_transects, "path_length": plan.stats.path_length}
        out["blocked"] = sum("no connecting move" in n for n in plan.notes)
    out["cpu"], out["wall"] = time.process_time() - t0, time.perf_counter() - w0
    # VmHWM: this program's peak since exec (ru_maxrss inherits the forking parent's peak)
    hwm = [line for line in open("/proc/self/status") if line.startswith("VmHWM:")]
    peak_kb = int(hwm[0].split()[1]) if hwm else resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    out["rss_mb"] = peak_kb / 1024
    print(json.dumps(out))


def _time_stage(module, name: str, stages: dict, calls: dict | None = None) -> None:
    """Replace ``module.name`` by a wrapper adding its CPU time to ``stages[name]`` (and its
    calls to ``calls[name]``)."""
    f = getattr(module, name)

    def g(*a, **k):
        if calls is not None:
            calls[name] = calls.get(name, 0) + 1
        t = time.process_time()
        try:
            return f(*a, **k)
        finally:
            stages[name] = stages.get(name, 0.0) + time.process_time() - t

    setattr(module, name, g)


def area_worker(path: str, spacing: float) -> None:
    """``plan_area`` on the field in ``path`` (npz as :func:`worker`'s), timed per stage."""
    from boustro.mission import estimate_work, plan_area
    from boustro.mission import region_certified as rc

    data = np.load(path)
    shell = data["shell"]
    holes = [data[k] for k in sorted(data.files) if k.startswith("hole_")]
    plan_area(data["warm_shell"], 10.0, crs=None, holes=[data["warm_hole"]])
    stages: dict[str, float] = {}
    for name in STAGES:
        _time_stage(rc, name, stages)
    est = estimate_work(shell, spacing, crs=None, holes=holes)
    t0, w0 = time.process_time(), time.perf_counter()
    m = plan_area(shell, spacing, crs=None, holes=holes)
    out = {"cpu": time.process_time() - t0, "wall": time.perf_counter() - w0}
    out.update(stages=stages, estimate=est.seconds, lanes=m.plan.stats.n_transects)
    out["gap"] = m.optimum.info.get("gap", m.optimum.gap)
    out["converged"] = bool(m.optimum.info.get("converged"))
    out["cells"] = len(m.plan.cells)
    out["covered"] = m.coverage.covered_share if m.coverage is not None else None
    out["path_length"] = m.plan.stats.path_length
    hwm = [line for line in open("/proc/self/status") if line.startswith("VmHWM:")]
    out["rss_mb"] = int(hwm[0].split()[1]) / 1024
    print(json.dumps(out))


def time_worker(path: str, spacing: float) -> None:
    """``plan_area`` with the time objective on the field in ``path``: CPU, plans, stages."""
    import hashlib

    import boustro.plan.region as pr
    from boustro.mission import estimate_work, plan_area

    data = np.load(path)
    shell = data["shell"]
    holes = [data[k] for k in sorted(data.files) if k.startswith("hole_")]
    kw = {"crs": None, "speed": 5.0, "turn_time": 10.0}
    plan_area(data["warm_shell"], 10.0, holes=[data["warm_hole"]], **kw)
    stages: dict[str, float] = {}
    calls: dict[str, int] = {}
    for name in PLAN_STAGES:
        _time_stage(pr, name, stages, calls)
    est = estimate_work(shell, spacing, holes=holes, **kw)
    t0, w0 = time.process_time(), time.perf_counter()
    m = plan_area(shell, spacing, holes=holes, **kw)
    out = {"cpu": time.process_time() - t0, "wall": time.perf_counter() - w0}
    info = m.optimum.info
    out.update(
        stages=stages, plans=calls.get("_plan_cells", 0), estimate=est.seconds, kind=est.kind
    )
    out.update(lanes=m.plan.stats.n_transects, fitness=float(m.optimum.fitness))
    gap = info.get("gap")
    out["gap"] = None if gap is None else float(gap) / float(m.optimum.fitness)
    out["converged"] = bool(info.get("converged") or info.get("certified"))
    out["covered"] = m.coverage.covered_share if m.coverage is not None else None
    out["path_length"] = m.plan.stats.path_length
    out["hash"] = hashlib.sha1(np.ascontiguousarray(m.plan.waypoints).tobytes()).hexdigest()[:10]
    hwm = [line for line in open("/proc/self/status") if line.startswith("VmHWM:")]
    out["rss_mb"] = int(hwm[0].split()[1]) / 1024
    print(json.dumps(out))


def time_main(args: argparse.Namespace) -> None:
    """Part ``time``: one row per size, this tree beside the baseline (each in a subprocess,
    the baseline first), then this tree's stages."""
    load = os.getloadavg()[0]
    print(f"# plan_area, time objective, {datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC, "
          f"load {load:.1f}")  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        base = None
        if args.baseline_src:
            base = Path(args.baseline_src)
        elif not args.no_baseline:
            base = _baseline_src(args.baseline or TIME_BASELINE, tmp)
        holes = args.holes if args.holes is not None else [10]
        rows = [(n, h) for h in holes for n in (args.vertices or (500, 1000, 2000))]
        print("| vertices | holes | lanes | estimate | plans | this tree | baseline | speed-up "
              "| same plan |")  # fmt: skip
        print("|---:|---:|---:|---:|---:|---|---|---:|---|")
        done = []
        for n, h in rows:
            field = _field_file(tmp, n, h)
            old = None
            if base is not None:
                old = _run(base, field, args.spacing, timeout=600.0, part="time")
            new = _run(ROOT / "src", field, args.spacing, timeout=600.0, part="time")
            ratio = "" if old is None or new is None else f"{old['cpu'] / new['cpu']:.2f}x"
            same = ""
            if old is not None and new is not None:
                same = "yes" if old["hash"] == new["hash"] else (
                    f"no: {new['fitness']:.1f} s vs {old['fitness']:.1f} s")  # fmt: skip
            if new is None:
                print(f"| {n} | {h} | | | | > 600 s | | | |", flush=True)
                continue
            base_cell = "-" if base is None else _time_cell(old, 600)
            head = f"| {n} | {h} | {new['lanes']} | {new['estimate']:.3g} s | {new['plans']} | "
            print(f"{head}{_time_cell(new, 600)} | {base_cell} | {ratio} | {same} |", flush=True)
            done.append((n, h, new))
        print()
        print("| vertices | holes | plans | " + " | ".join(PLAN_STAGES) + " | rest (search) |")
        print("|---:|---:|---:|" + "---:|" * (len(PLAN_STAGES) + 1))
        for n, h, r in done:
            cells = " | ".join(f"{r['stages'].get(name, 0.0):.2f}" for name in PLAN_STAGES)
            rest = r["cpu"] - sum(r["stages"].values())
            print(f"| {n} | {h} | {r['plans']} | {cells} | {rest:.2f} |")


def _time_cell(res: dict | None, timeout: float) -> str:
    if res is None:
        return f"> {timeout:g} s"
    cert = "certified" if res["converged"] else f"gap {res['gap']:.3g}"
    return f"{res['cpu']:.1f} s, {res['rss_mb']:.0f} MB, {cert}"


def _field_file(tmp: Path, n: int, holes: int) -> Path:
    from boustro.geometry.traced import traced_field

    r = traced_field(n, holes)
    warm = traced_field(60, 1, seed=1)
    arrays = {"shell": r.shell.vertices, "warm_shell": warm.shell.vertices}
    arrays["warm_hole"] = warm.holes[0].vertices
    for i, h in enumerate(r.holes):
        arrays[f"hole_{i:03d}"] = h.vertices
    path = tmp / f"field_{n}_{holes}.npz"
    np.savez(path, **arrays)
    return path


def _run(src: Path, field: Path, spacing: float, timeout: float, part: str) -> dict | None:
    env = {**os.environ, "PYTHONPATH": str(src)}
    cmd = [sys.executable, __file__, "--worker", str(field), "--spacing", str(spacing)]
    cmd += ["--part", part]
    try:
        out = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None
    if out.returncode != 0:
        raise RuntimeError(out.stderr.strip().splitlines()[-1])
    return json.loads(out.stdout.strip().splitlines()[-1])


def _baseline_src(commit: str, tmp: Path) -> Path:
    archive = tmp / "base.tar"
    subprocess.run(
        ["git", "-C", str(ROOT), "archive", "-o", str(archive), commit, "src"], check=True
    )
    with tarfile.open(archive) as tar:
        tar.extractall(tmp / "base", filter="data")
    return tmp / "base" / "src"


def _cell(res: dict | None, timeout: float) -> str:
    if res is None:
        return f"> {timeout:g} s"
    gap = f", gap {res['gap']:.2%}" if "gap" in res else ""
    return f"{res['cpu']:.2f} s, {res['rss_mb']:.0f} MB{gap}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--part",
        choices=("vertices", "spacing", "cover", "area", "area-spacing", "time"),
        default="vertices",
    )
    ap.add_argument("--vertices", type=int, nargs="+", help="sizes (parts vertices, cover)")
    ap.add_argument("--quick", action="store_true", help="50, 200, 500 vertices only")
    ap.add_argument("--baseline", help="commit compared against (default: BASELINE, AREA_BASELINE)")
    ap.add_argument("--no-baseline", action="store_true")
    ap.add_argument("--baseline-src", help="part time: the baseline's src folder (no archive)")
    ap.add_argument("--holes", type=int, nargs="+", help="part time: holes (default 10)")
    ap.add_argument("--timeout", type=float, default=15.0, help="seconds a baseline run may take")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    ap.add_argument("--spacing", type=float, default=10.0, help="metres (part vertices)")
    args = ap.parse_args()
    if args.worker:
        if args.part == "time":
            time_worker(args.worker, args.spacing)
        elif args.part.startswith("area"):
            area_worker(args.worker, args.spacing)
        else:
            worker(args.worker, args.spacing, args.part)
        return
    sys.path.insert(0, str(ROOT / "src"))
    if args.part == "time":
        time_main(args)
        return
    if args.part.startswith("area"):
        area_main(args)
        return
    load = os.getloadavg()[0]
    print(f"# scale benchmark, {datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC, load {load:.1f}")
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        base = None if args.no_baseline else _baseline_src(args.baseline or BASELINE, tmp)
        if args.part in ("vertices", "cover"):
            sizes = QUICK_VERTICES if args.quick else VERTICES
            if args.part == "cover":
                sizes = (200, 500)
            sizes = tuple(args.vertices or sizes)
            rows = [(n, h, args.spacing) for h in HOLES for n in sizes]
        else:
            from boustro.geometry.traced import traced_field

            diameter = traced_field(2000, 10).diameter
            rows = [(2000, 10, diameter / f) for f in SPACING_FRACTIONS]
        what = "certificate" if args.part == "cover" else "lanes"
        print(f"| vertices | holes | spacing (m) | {what} | this tree | baseline | speed-up |")
        print("|---:|---:|---:|---:|---|---|---:|")
        gave_up: set[int] = set()
        for n, h, s in rows:
            field = _field_file(tmp, n, h)
            new = _run(ROOT / "src", field, s, timeout=600.0, part=args.part)
            old = None
            tried = base is not None and h not in gave_up
            if tried:
                old = _run(base, field, s, timeout=args.timeout, part=args.part)
                if old is None:
                    gave_up.add(h)
            ratio = "" if old is None or new is None else f"{old['cpu'] / new['cpu']:.1f}x"
            lanes = "" if new is None else new["lanes"]
            if args.part == "cover" and new is not None:
                lanes = f"gap {new['gap']:.2%}"
            base_cell = _cell(old, args.timeout) if tried else "-"
            print(
                f"| {n} | {h} | {s:.3g} | {lanes} | {_cell(new, 600)} | {base_cell} | {ratio} |",
                flush=True,
            )


def _area_cell(res: dict | None, timeout: float) -> str:
    if res is None:
        return f"> {timeout:g} s"
    cert = "certified" if res["converged"] else f"gap {res['gap']:.3g}"
    return f"{res['cpu']:.2f} s, {res['rss_mb']:.0f} MB, {cert}"


def _exponents(sizes: list[int], runs: list[dict]) -> dict[str, float]:
    """The growth exponent of every stage (and the total): slope of log CPU on log n."""
    out = {}
    names = ["cpu"] + [s for s in STAGES if all(s in r["stages"] for r in runs)]
    for name in names:
        t = np.array([r["cpu"] if name == "cpu" else r["stages"][name] for r in runs])
        if len(sizes) >= 2 and np.all(t > 0):
            out[name] = float(np.polyfit(np.log(sizes), np.log(t), 1)[0])
    return out


def area_main(args: argparse.Namespace) -> None:
    """Parts ``area`` and ``area-spacing``: plan_area end to end, this tree beside the
    baseline, then each stage's CPU and growth exponent (this tree)."""
    from boustro.geometry.traced import traced_field

    load = os.getloadavg()[0]
    print(f"# plan_area at scale, {datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC, load {load:.1f}")
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        base = None if args.no_baseline else _baseline_src(args.baseline or AREA_BASELINE, tmp)
        if args.part == "area":
            sizes = tuple(args.vertices or (QUICK_VERTICES if args.quick else VERTICES))
            rows = [(n, h, args.spacing) for h in HOLES for n in sizes]
        else:
            diameter = traced_field(2000, 10).diameter
            rows = [(2000, 10, diameter / f) for f in SPACING_FRACTIONS]
        head = "| vertices | holes | spacing (m) | lanes | estimate | this tree | baseline |"
        print(head + " speed-up |")
        print("|---:|---:|---:|---:|---:|---|---|---:|")
        warm = _field_file(tmp, 60, 1)  # numba compiles (and caches) each tree's kernels once
        for src in [ROOT / "src"] + ([base] if base is not None else []):
            _run(src, warm, 10.0, timeout=1800.0, part=args.part)
        done: list[tuple[int, int, float, dict]] = []
        gave_up: set[int] = set()
        for n, h, s in rows:
            field = _field_file(tmp, n, h)
            new = _run(ROOT / "src", field, s, timeout=600.0, part=args.part)
            old = None
            tried = base is not None and h not in gave_up
            if tried:
                old = _run(base, field, s, timeout=args.timeout, part=args.part)
                if old is None:
                    gave_up.add(h)
            ratio = "" if old is None or new is None else f"{old['cpu'] / new['cpu']:.1f}x"
            lanes = "" if new is None else new["lanes"]
            est = "" if new is None else f"{new['estimate']:.2g} s"
            base_cell = _area_cell(old, args.timeout) if tried else "-"
            print(
                f"| {n} | {h} | {s:.3g} | {lanes} | {est} | {_area_cell(new, 600)} | "
                f"{base_cell} | {ratio} |",
                flush=True,
            )
            if new is not None:
                done.append((n, h, s, new))
        print()
        print("| vertices | holes | spacing | " + " | ".join(STAGES) + " |")
        print("|---:|---:|---:|" + "---:|" * len(STAGES))
        for n, h, s, r in done:
            cells = " | ".join(f"{r['stages'].get(name, 0.0):.3f}" for name in STAGES)
            print(f"| {n} | {h} | {s:.3g} | {cells} |")
        if args.part == "area":
            for h in HOLES:
                runs = [(n, r) for n, hh, _, r in done if hh == h]
                exps = _exponents([n for n, _ in runs], [r for _, r in runs])
                said = ", ".join(f"{k} {v:.2f}" for k, v in exps.items())
                print(f"growth exponents (CPU ~ n^k), {h} holes: {said}")


if __name__ == "__main__":
    main()
