"""The certified Eq. 1 optimum beside the paper's 200-point grid, in one run (issue 21).

Three ways to optimise each problem, interleaved problem by problem (rotating their order, so a
change of the machine's load hits all alike), CPU time of this process per call
(``time.process_time``):

* ``grid-200``: the paper's 14 x 14 grid (``optimize(..., method="grid", **GRID_200)``), and
  ``grid_search``: the same called directly (as ``benchmarks/learned.py`` does);
* ``certified``: ``optimize(..., method="global")`` (the certified optimum, as ``plan_area``
  calls it) with the compiled kernels (``BOUSTRO_COMPILED=1``);
* ``certified (numpy)``: the same optimiser on its numpy path (``BOUSTRO_COMPILED=0``), the code
  path of the certified optimum before the kernels (7ccb731).

Part 1, the paper's random polygons (the protocol of ``benchmarks/global_opt.py``: 3-9 vertices,
Valtr, spacing uniform in (0.01, 1/3) of the diameter, a = b = 0.5, seed 0). Part 2, the batch's
path (issue 18): ``plan_area(ring, 10.0, crs=None)`` with its default method on random convex
fields of 4-12 vertices, 50-300 m across. Both paths' results are compared (fitness, upper
bound, evaluations). Cold start: a fresh process's first certified optimum with the kernels
(numba imported and the kernels read from its on-disk cache).

``--no-numpy`` leaves the numpy path out of part 1 (and agreement): the grid and the certified
optimum alone, interleaved; the numpy path's 13 ms between two calls evicts the caches of both
(the certified optimum's mean ratio to the grid was 1.25x with it and 1.04x without,
2026-11-27, load 5).

Usage: python benchmarks/exact_speed.py [--polygons 1000] [--fields 300] [--seed 0] [--quick]
[--no-numpy]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import torch

from boustro import optimize as opt
from boustro.geometry import Polygon, random_convex_polygon
from boustro.mission import plan_area


def problems(count: int, seed: int) -> list[tuple[Polygon, float]]:
    """The paper's protocol, as benchmarks/global_opt.py draws it."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        polygon = random_convex_polygon(rng, int(rng.integers(3, 10)))
        out.append((polygon, float(rng.uniform(0.01, 1 / 3)) * polygon.diameter))
    return out


def fields(count: int, seed: int) -> list[np.ndarray]:
    """Convex rings of 4-12 vertices, 50-300 m across, in metres."""
    rng = np.random.default_rng(seed)
    return [
        random_convex_polygon(rng, int(rng.integers(4, 13))).vertices * rng.uniform(50, 300)
        for _ in range(count)
    ]


def with_env(value: str, fn: Callable[[], Any]) -> Callable[[], Any]:
    def run() -> Any:
        os.environ["BOUSTRO_COMPILED"] = value
        return fn()

    return run


def interleaved(cases: list, runners: dict[str, Callable[[Any], Any]]) -> dict[str, dict]:
    """Per method: results and CPU seconds per case, methods in rotating order."""
    names = list(runners)
    out: dict[str, dict] = {name: {"result": [], "cpu": []} for name in names}
    for i, case in enumerate(cases):
        for k in range(len(names)):
            name = names[(i + k) % len(names)]
            start = time.process_time()
            result = runners[name](case)
            out[name]["cpu"].append(time.process_time() - start)
            out[name]["result"].append(result)
        if (i + 1) % 200 == 0:
            print(f"#   {i + 1}/{len(cases)}", file=sys.stderr, flush=True)
    return out


def table(data: dict[str, dict], baseline: str) -> None:
    base = np.array(data[baseline]["cpu"])
    print(
        f"{'method':<18} {'mean ms':>8} {'median ms':>9} {'p95 ms':>8} {'max ms':>8} "
        f"{'mean / ' + baseline:>18} {'median ratio':>12}"
    )
    for name, d in data.items():
        cpu = np.array(d["cpu"]) * 1e3
        ratio = float(cpu.mean() / (base.mean() * 1e3))
        per = float(np.median(cpu / (base * 1e3)))
        print(
            f"{name:<18} {cpu.mean():>8.3f} {np.median(cpu):>9.3f} "
            f"{np.percentile(cpu, 95):>8.3f} {cpu.max():>8.2f} {ratio:>18.2f} {per:>12.2f}"
        )


def agreement(fast: list, slow: list) -> str:
    df = max(abs(a.fitness - b.fitness) for a, b in zip(fast, slow, strict=True))
    du = max(abs(a.upper_bound - b.upper_bound) for a, b in zip(fast, slow, strict=True))
    same = sum(a.evaluations == b.evaluations for a, b in zip(fast, slow, strict=True))
    gaps = np.array([a.gap for a in fast])
    conv = all(a.info["converged"] for a in fast)
    return (
        f"compiled vs numpy: max |fitness diff| {df:.1e}, max |upper bound diff| {du:.1e}, "
        f"same evaluations on {same}/{len(fast)}; certified gap max {gaps.max():.2e} "
        f"(all converged: {conv})"
    )


def cold_start() -> str:
    code = (
        "import time; t = time.process_time(); w = time.perf_counter();"
        "from boustro.optimize.exact import global_optimum;"
        "global_optimum([(0, 0), (4, 0), (5, 3), (1, 2)], 0.5);"
        "print(time.process_time() - t, time.perf_counter() - w)"
    )
    env = dict(os.environ, BOUSTRO_COMPILED="1", PYTHONPATH=os.pathsep.join(sys.path))
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    if out.returncode != 0:
        return f"cold start failed: {out.stderr.strip()[-200:]}"
    cpu, wall = (float(x) for x in out.stdout.split())
    return (
        f"cold start (fresh process, import + first certified optimum with the kernels, numba "
        f"cache warm): {cpu:.2f} s CPU, {wall:.2f} s wall"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--polygons", type=int, default=1000)
    parser.add_argument("--fields", type=int, default=300)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--quick", action="store_true", help="100 polygons, 30 fields")
    parser.add_argument(
        "--no-numpy", action="store_true", help="part 1 without the certified optimum's numpy path"
    )
    args = parser.parse_args(argv)
    torch.set_num_threads(1)
    n_poly, n_fields = (100, 30) if args.quick else (args.polygons, args.fields)
    print(f"# {time.strftime('%Y-%m-%d %H:%M')} load average {os.getloadavg()}", flush=True)
    print(f"# {cold_start()}", flush=True)
    cases = problems(n_poly, args.seed)

    def certified(case: tuple[Polygon, float]) -> Any:
        return opt.optimize(case[0], case[1], method="global")

    runners: dict[str, Callable[[Any], Any]] = {
        "grid-200": lambda c: opt.optimize(c[0], c[1], method="grid", **opt.GRID_200),
        "grid_search": lambda c: opt.grid_search(c[0], c[1], **opt.GRID_200),
        "certified": lambda c: with_env("1", lambda: certified(c))(),
        "certified (numpy)": lambda c: with_env("0", lambda: certified(c))(),
    }
    if args.no_numpy:
        del runners["certified (numpy)"]
    warm = problems(1, args.seed + 1)[0]
    for run in runners.values():  # compile / load everything first
        run(warm)
    data = interleaved(cases, runners)
    print(f"\nPart 1: {n_poly} random polygons (3-9 vertices), CPU per polygon")
    table(data, "grid-200")
    if not args.no_numpy:
        print(agreement(data["certified"]["result"], data["certified (numpy)"]["result"]))
    best = np.array([r.fitness for r in data["certified"]["result"]])
    grid = np.array([r.fitness for r in data["grid-200"]["result"]])
    print(f"grid-200 below the certified optimum: mean {np.mean(best - grid):.4f}, "
          f"worst {np.max(best - grid):.4f}")  # fmt: skip
    print(f"# load average {os.getloadavg()}", flush=True)

    rings = fields(n_fields, args.seed)
    plans: dict[str, Callable[[Any], Any]] = {
        "certified": lambda r: with_env("1", lambda: plan_area(r, 10.0, crs=None))(),
        "certified (numpy)": lambda r: with_env("0", lambda: plan_area(r, 10.0, crs=None))(),
    }
    for run in plans.values():
        run(rings[0])
    mdata = interleaved(rings, plans)
    print(f"\nPart 2: plan_area(ring, 10.0, crs=None) on {n_fields} convex fields "
          "(4-12 vertices, 50-300 m), CPU per field")  # fmt: skip
    table(mdata, "certified (numpy)")
    lanes = [
        (a.stats.n_transects, b.stats.n_transects)
        for a, b in zip(
            mdata["certified"]["result"], mdata["certified (numpy)"]["result"], strict=False
        )
    ]
    same = sum(x == y for x, y in lanes)
    print(f"same number of lanes on {same}/{len(lanes)} fields")
    print(f"# load average {os.getloadavg()}")
    os.environ.pop("BOUSTRO_COMPILED", None)
    return 0


if __name__ == "__main__":
    sys.exit(main())
