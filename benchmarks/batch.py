"""Benchmark (issue 18): fields per second of ``boustro.batch`` against a loop of ``boustro plan``.

Random fields in a GeoPackage (EPSG:28992, metres): convex ones (Valtr, 4-10 vertices, diameter
150-500 m, 2-20 ha) and concave ones with lobes and bays (``random_region``: 12-24 vertices, 0-1
holes, diameter 300-600 m), planned at 15 m spacing with the defaults of ``boustro plan``
(certified optimum, coverage-guaranteed lanes, coverage checked). Measured, wall time:

* the command loop: ``boustro -q plan FIELD.geojson --spacing 15 --out plan.geojson``, one
  command per field, on ``--commands`` fields (half before the batch runs, half after, so both
  see the same load), extrapolated to fields/s = 1 / mean seconds per command;
* ``boustro.batch`` on 1 process (in-process), 2 local processes and a 2-worker Dask
  ``LocalCluster`` (2 processes of 1 thread), each over the same fields into a fresh
  GeoPackage. The cluster and the local fork server (which imports boustro once, then forks
  the workers) are started before the clock, and their start-up printed.

Printed: fields/s, the ratio to the command loop, the CPU per field (this process's CPU plus
each field's planning CPU on its worker, the ``cpu_seconds`` column) and its ratio to a
command's CPU, and the scaling efficiency of 2 workers (rate / (2 x the 1-process rate)). On a
shared machine the wall-clock numbers depend on the share of the CPU this run gets (Linux gives
each session an equal share, whatever its number of processes); the CPU ratio does not.

    python benchmarks/batch.py            # 10 000 convex and 1 000 concave fields
    python benchmarks/batch.py --quick    # 200 and 20 (about 2 minutes on a loaded machine)

``--baseline SRC`` (another checkout's ``src``, e.g. ``git archive 7ccb731 src | tar -x -C
/tmp/base``) measures instead the before/after of the worker's own cost: the CPU per convex
field of ``plan_chunk`` in one process (one torch thread, the first 5 fields excluded), this
tree and SRC alternately in fresh subprocesses, ``--repeats`` times each, and their ratio (the
CPU of a process does not depend on the machine's load as much as its wall time does).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np
import pyogrio.raw
import shapely

import boustro
from boustro.geometry import random_convex_polygon
from boustro.geometry.region import random_region

SPACING = 15.0
CRS = "EPSG:28992"


def convex_fields(rng: np.random.Generator, n: int) -> list:
    out = []
    for _ in range(n):
        poly = random_convex_polygon(rng, int(rng.integers(4, 11)))
        size = rng.uniform(150, 500)
        x, y = rng.uniform([100_000, 400_000], [200_000, 500_000])
        out.append(shapely.Polygon(poly.vertices * size + [x, y]))
    return out


def concave_fields(rng: np.random.Generator, n: int) -> list:
    out = []
    for _ in range(n):
        region = random_region(rng, int(rng.integers(12, 25)), int(rng.integers(0, 2)),
                               roughness=float(rng.uniform(0.3, 0.6)))  # fmt: skip
        size = rng.uniform(150, 300)  # radius about 1: diameter 300-600 m
        x, y = rng.uniform([100_000, 400_000], [200_000, 500_000])
        shell = region.shell.vertices * size + [x, y]
        holes = [h.vertices * size + [x, y] for h in region.holes]
        out.append(shapely.Polygon(shell, holes))
    return out


def write_fields(path: str, geoms: list) -> None:
    wkb = np.array([shapely.to_wkb(g) for g in geoms], dtype=object)
    names = np.array([f"field {i}" for i in range(len(geoms))], dtype=object)
    pyogrio.raw.write(path, wkb, [names], ["name"], crs=CRS, geometry_type="Polygon",
                      driver="GPKG")  # fmt: skip


def command_seconds(geoms: list, folder: str) -> list[tuple[float, float]]:
    """``(wall, CPU)`` seconds of one ``boustro plan`` command per field (each its own GeoJSON
    file; CPU from the reaped child's rusage)."""
    import pyproj

    to_lonlat = pyproj.Transformer.from_crs(CRS, "EPSG:4326", always_xy=True)
    times = []
    for i, g in enumerate(geoms):
        ring = np.column_stack(to_lonlat.transform(*np.asarray(g.exterior.coords).T))
        doc = {"type": "Polygon", "coordinates": [ring.tolist()]}
        path = os.path.join(folder, f"cmd{i}.geojson")
        with open(path, "w") as fh:
            json.dump(doc, fh)
        cmd = [sys.executable, "-m", "boustro", "-q", "plan", path, "--spacing", str(SPACING),
               "--out", os.path.join(folder, "cmd-plan.geojson")]  # fmt: skip
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True)
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
        times.append((wall, cpu))
    return times


_WORKER_CPU = """
import sys, time
import torch
from boustro.batch.options import PlanOptions
from boustro.batch.source import read_source
from boustro.batch.worker import Job, plan_chunk
torch.set_num_threads(1)
source = read_source(sys.argv[1])
job = Job(PlanOptions(spacing=float(sys.argv[2])), source.crs, False, 28992, None)
plan_chunk(source.features[:5], job)
c0 = time.process_time()
plan_chunk(source.features[5:], job)
print(1000 * (time.process_time() - c0) / (len(source.features) - 5))
"""


def worker_cpu(geoms: list, folder: str, baseline: str, repeats: int) -> None:
    """CPU ms per field of ``plan_chunk`` in one process: this tree and ``baseline``, interleaved
    (each in a fresh subprocess, so both see the same load)."""
    fields = os.path.join(folder, "worker-cpu.gpkg")
    write_fields(fields, geoms)
    here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "src")
    found: dict[str, list[float]] = {"this tree": [], "baseline": []}
    for _ in range(repeats):
        for label, src in (("baseline", baseline), ("this tree", here)):
            env = {**os.environ, "PYTHONPATH": os.path.abspath(src)}
            done = subprocess.run([sys.executable, "-c", _WORKER_CPU, fields, str(SPACING)],
                                  env=env, capture_output=True, text=True, check=True)  # fmt: skip
            found[label].append(float(done.stdout.split()[-1]))
    this, base = (float(np.median(found[k])) for k in ("this tree", "baseline"))
    print(f"  worker CPU per convex field ({len(geoms) - 5} fields, median of {repeats}): this "
          f"tree {this:.2f} ms {[round(x, 2) for x in found['this tree']]}, baseline "
          f"{base:.2f} ms {[round(x, 2) for x in found['baseline']]}: {base / this:.3f}x "
          f"(load {os.getloadavg()[0]:.1f})", flush=True)  # fmt: skip


def run_set(name: str, geoms: list, folder: str, client) -> dict[str, tuple[float, float]]:
    """``{run: (fields/s wall, CPU seconds per field)}``; the CPU is this process's plus each
    field's planning on its worker (the ``cpu_seconds`` column: worker start-up and transfer
    not counted)."""
    fields = os.path.join(folder, f"{name}.gpkg")
    write_fields(fields, geoms)
    rates = {}
    for label, kwargs in (
        ("1 process", dict(workers=1)),
        ("2 processes", dict(workers=2)),
        ("LocalCluster, 2 workers", dict(client=client, chunk_size=8)),
    ):
        out = os.path.join(folder, f"{name}-{len(rates)}.gpkg")
        t0, c0 = time.perf_counter(), time.process_time()
        result = boustro.batch(fields, out, spacing=SPACING, **kwargs)
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        assert result.planned + result.failed == len(geoms)
        if label != "1 process":
            _, _, _, data = pyogrio.raw.read(out, layer="fields", columns=["cpu_seconds"])
            cpu += float(np.nansum(data[0]))
        rates[label] = (len(geoms) / wall, cpu / len(geoms))
        print(f"  {name:8s} {label:24s} {len(geoms):6d} fields {wall:8.1f} s "
              f"{len(geoms) / wall:8.2f} fields/s, {1000 * cpu / len(geoms):6.1f} ms CPU/field "
              f"({result.failed} failed; load {os.getloadavg()[0]:.1f})", flush=True)  # fmt: skip
    return rates


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="200 convex, 20 concave fields")
    parser.add_argument("--convex", type=int, default=None)
    parser.add_argument("--concave", type=int, default=None)
    parser.add_argument("--commands", type=int, default=20, help="boustro plan commands timed")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--baseline", metavar="SRC", help="another checkout's src: worker CPU")
    parser.add_argument("--repeats", type=int, default=3, help="of the --baseline comparison")
    args = parser.parse_args()
    n_convex = args.convex or (200 if args.quick else 10_000)
    n_concave = args.concave or (20 if args.quick else 1_000)
    rng = np.random.default_rng(args.seed)
    convex, concave = convex_fields(rng, n_convex), concave_fields(rng, n_concave)
    from distributed import Client, LocalCluster

    print(f"{time.strftime('%Y-%m-%d %H:%M')}, load average at start: {os.getloadavg()}")
    with tempfile.TemporaryDirectory() as folder:
        if args.baseline is not None:
            worker_cpu(convex[:300], folder, args.baseline, args.repeats)
            return
        half = args.commands // 2
        cmd = command_seconds(convex[:half], folder)
        t0 = time.perf_counter()
        with (
            LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                         dashboard_address=None) as cluster,
            Client(cluster) as client,
        ):  # fmt: skip
            print(f"  LocalCluster started in {time.perf_counter() - t0:.1f} s (not counted)")
            warm = os.path.join(folder, "warm.gpkg")
            write_fields(warm, convex[:2])
            t0 = time.perf_counter()  # the local fork server: started once per process
            boustro.batch(warm, os.path.join(folder, "warm-out.gpkg"), spacing=SPACING, workers=2)
            print(f"  local fork server started in {time.perf_counter() - t0:.1f} s (not counted)")
            results = {
                "convex": run_set("convex", convex, folder, client),
                "concave": run_set("concave", concave, folder, client),
            }
        cmd += command_seconds(convex[half : args.commands], folder)
    wall = float(np.mean([w for w, _ in cmd]))
    cpu = float(np.mean([c for _, c in cmd]))
    print(f"load average at end: {os.getloadavg()}")
    print(
        f"\nboustro plan command loop: {len(cmd)} commands timed (on convex fields), mean "
        f"{wall:.2f} s wall, {cpu:.2f} s CPU: {1 / wall:.3f} fields/s, extrapolated\n"
    )
    print("| fields | run | fields/s | vs command loop | CPU ms/field | vs loop, CPU | "
          "scaling efficiency |")  # fmt: skip
    print("|---|---|---:|---:|---:|---:|---:|")
    for name, rates in results.items():
        one = rates["1 process"][0]
        count = n_convex if name == "convex" else n_concave
        for label, (rate, per_field) in rates.items():
            eff = "" if label == "1 process" else f"{rate / (2 * one):.0%}"
            print(
                f"| {count} {name} | {label} | {rate:.1f} | {rate * wall:.0f}x | "
                f"{1000 * per_field:.0f} | {cpu / per_field:.0f}x | {eff} |"
            )


if __name__ == "__main__":
    main()
