"""Benchmark (issues 20 and 21): validating a ring with GEOS against the old all-pairs check.

For rings of 100, 1000, 8000 and 20000 vertices, valid (a three-lobed star with traced-like
noise) and self-crossing (the same ring with two far-apart vertices swapped), the time to build
a :class:`boustro.geometry.Polygon` (every check: duplicates, collinear vertices, simplicity,
area, diameter) and the process's peak memory beyond the input, each case in a fresh process
(``resource.getrusage``). The baseline is the landed code before this change: the same
constructor with the all-pairs numpy simplicity test and the all-pairs diameter, kept here
(:func:`old_polygon`) only as the baseline. Cases the baseline cannot finish on this machine
(memory ~ 80 * n^2 bytes) are skipped with the estimate.

    python benchmarks/validity.py [--sizes 100,1000,8000,20000] [--small]

``--small`` also times both checks on valid rings of 3..50 vertices (in-process, many repeats):
the reason for keeping one path, GEOS, for every size.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import time

import numpy as np

from boustro.errors import InvalidPolygonError
from boustro.geometry import RELATIVE_TOLERANCE, Polygon
from boustro.geometry import polygon as polygon_module
from boustro.geometry.polygon import _cross

#: Largest baseline case run: its all-pairs arrays need about 80 * n^2 bytes at peak (8000:
#: 5.2 GB measured; 20000 would need ~32 GB, more than this 24 GB machine has).
BASELINE_LIMIT = 8000


def ring(n: int, crossing: bool) -> np.ndarray:
    rng = np.random.default_rng(n)
    angles = np.linspace(0, 2 * math.pi, n, endpoint=False) + rng.uniform(0, 0.5 / n, n)
    radii = 1.0 + 0.2 * np.cos(3 * angles) + 1e-3 * rng.random(n)
    v = np.stack([radii * np.cos(angles), radii * np.sin(angles)], axis=1)
    if crossing:
        v[[n // 10, n // 2]] = v[[n // 2, n // 10]]
    return v


# -- the baseline: the landed check before GEOS (git history of src/boustro/geometry/polygon.py)
def _first_self_intersection(v, tol, scale):
    n = len(v)
    p, q = v, np.roll(v, -1, axis=0)
    i, j = np.triu_indices(n, k=2)
    keep = ~((i == 0) & (j == n - 1))
    i, j = i[keep], j[keep]
    if len(i) == 0:
        return None
    p1, p2, q1, q2 = p[i], q[i], p[j], q[j]

    def orient(a, b, c):
        d = _cross(b - a, c - a)
        on_line = np.abs(d) <= tol * scale * np.linalg.norm(b - a, axis=1)
        return np.where(on_line, 0.0, np.sign(d))

    d1, d2 = orient(q1, q2, p1), orient(q1, q2, p2)
    d3, d4 = orient(p1, p2, q1), orient(p1, p2, q2)
    proper = (d1 * d2 <= 0) & (d3 * d4 <= 0)
    collinear = (d1 == 0) & (d2 == 0)
    direction = p2 - p1
    t = lambda x: np.einsum("ij,ij->i", x - p1, direction)  # noqa: E731
    lo, hi = np.minimum(t(q1), t(q2)), np.maximum(t(q1), t(q2))
    length2 = np.einsum("ij,ij->i", direction, direction)
    overlap = (hi >= -tol * length2) & (lo <= length2 * (1 + tol))
    hit = np.where(collinear, overlap, proper)
    if np.any(hit):
        k = int(np.argmax(hit))
        return int(i[k]), int(j[k])
    return None


def _old_ring_problem(v, tol):
    """The old check behind the new one's interface (``tol`` is RELATIVE_TOLERANCE * extent)."""
    hit = _first_self_intersection(v, RELATIVE_TOLERANCE, tol / RELATIVE_TOLERANCE)
    return None if hit is None else f"the polygon is self-intersecting: edges {hit}"


def _old_diameter(v):
    diffs = v[:, None, :] - v[None, :, :]
    return float(np.sqrt(np.max(np.einsum("ijk,ijk->ij", diffs, diffs))))


def old_polygon(vertices) -> Polygon:
    """The landed constructor: today's Polygon with the all-pairs test and diameter put back
    (everything else identical), the baseline."""
    saved = polygon_module.ring_problem, polygon_module._diameter
    polygon_module.ring_problem, polygon_module._diameter = _old_ring_problem, _old_diameter
    try:
        return Polygon(vertices)
    finally:
        polygon_module.ring_problem, polygon_module._diameter = saved


def _case(which: str, n: int, crossing: bool) -> dict:
    """One measurement, in this (fresh) process."""
    import resource

    v = ring(n, crossing)
    check = Polygon if which == "new" else old_polygon
    check([(0, 0), (1, 0), (1, 1), (0, 1)])  # warm: imports (shapely) are not the check's cost
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    start = time.perf_counter()
    try:
        check(v)
        refused = False
    except InvalidPolygonError:
        refused = True
    seconds = time.perf_counter() - start
    peak = (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before) / 1024
    return {"seconds": seconds, "peak_mb": peak, "refused": refused}


def _run(which: str, n: int, crossing: bool) -> dict:
    code = (
        "import json, sys; sys.path.insert(0, 'benchmarks'); import validity; "
        f"print(json.dumps(validity._case({which!r}, {n}, {crossing})))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def _small() -> None:
    print("\nsmall valid rings (in-process, median of 200): n, old ms, GEOS ms, old/GEOS")
    for n in (3, 4, 6, 10, 20, 50):
        v = ring(n, False) if n > 4 else np.array([(0, 0), (1, 0), (1, 1), (0, 1)][:n], float)
        times = {}
        for which, check in (("old", old_polygon), ("new", Polygon)):
            check(v)
            runs = []
            for _ in range(200):
                t0 = time.perf_counter()
                check(v)
                runs.append(time.perf_counter() - t0)
            times[which] = float(np.median(runs)) * 1e3
        print(f"{n:>3} {times['old']:.4f} {times['new']:.4f} {times['old'] / times['new']:.1f}x")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="100,1000,8000,20000")
    ap.add_argument("--small", action="store_true")
    args = ap.parse_args()
    print("n, ring, old s, old MB, new s, new MB, time old/new, memory old/new, both refused")
    for n in (int(s) for s in args.sizes.split(",")):
        for crossing in (False, True):
            new = _run("new", n, crossing)
            kind = "crossing" if crossing else "valid"
            if n > BASELINE_LIMIT:
                gb = 80 * n * n / 1e9
                print(
                    f"{n:>6} {kind:<8} (old: not run, ~{gb:.0f} GB) {new['seconds']:.4f} s "
                    f"{new['peak_mb']:.1f} MB refused={new['refused']}"
                )
                continue
            old = _run("old", n, crossing)
            print(
                f"{n:>6} {kind:<8} {old['seconds']:.4f} {old['peak_mb']:.1f} "
                f"{new['seconds']:.4f} {new['peak_mb']:.1f} "
                f"{old['seconds'] / new['seconds']:.0f}x "
                f"{old['peak_mb'] / max(new['peak_mb'], 0.1):.0f}x "
                f"{old['refused'] == new['refused'] == crossing}",
                flush=True,
            )
    if args.small:
        _small()


if __name__ == "__main__":
    main()
