"""Measurement (issue 21): can a certificate on a SIMPLIFIED boundary carry over to the real one?
On issue 21's traced field (``traced_field(2000, 10)``, 10 m) the boundary is simplified by
GEOS (Douglas-Peucker, topology kept) at ``--tolerances`` metres; per tolerance: the edges, the
Hausdorff distance ``h`` to the real area (densified), and at ``--layouts`` random layouts the
per-segment Eq. 1 of the real area minus that of the simplified one (a proven bound on it at
every layout would carry a certificate over), and how often the real value lies outside the
values of the simplified area eroded and dilated by ``h`` (the bracket of an inner and an outer
simplification: usable only if Eq. 1 were monotone in the segments); with ``--certify``, the
simplified area's own certified optimum (``smith_bb_region``, CPU by ``time.process_time``).

    PYTHONPATH=src python benchmarks/region_simplify.py [--tolerances 0.3 1 2] [--certify]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np


def _edges(poly) -> np.ndarray:  # type: ignore[no-untyped-def]
    out = []
    for ring in [poly.exterior, *poly.interiors]:
        c = np.asarray(ring.coords)[:-1]
        out.append(np.c_[c, np.roll(c, -1, axis=0)])
    return np.concatenate(out).reshape(-1, 2, 2)


def main() -> None:
    import shapely

    from boustro.geometry.region import Region
    from boustro.geometry.traced import traced_field
    from boustro.optimize.region_grid import evaluate_region_grid
    from boustro.optimize.smith_bb.region import smith_bb_region

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--tolerances", type=float, nargs="+", default=[0.3, 0.6, 1.0, 2.0])
    ap.add_argument("--layouts", type=int, default=4000)
    ap.add_argument("--spacing", type=float, default=10.0)
    ap.add_argument("--certify", action="store_true")
    args = ap.parse_args()
    print(f"load: {os.getloadavg()}")
    region = traced_field(2000, 10)
    f = region.frame
    s = args.spacing / f.scale
    poly = shapely.Polygon(region.shell.vertices, [h.vertices for h in region.holes])
    rng = np.random.default_rng(0)
    theta = rng.uniform(0.0, np.pi, args.layouts)
    d = rng.uniform(0.0, s, args.layouts)

    def value(p) -> np.ndarray:  # type: ignore[no-untyped-def]
        e = (_edges(p) - f.centre) / f.scale
        return evaluate_region_grid(e, theta, d, s, pairs=True)

    real = value(poly)
    print(f"real: {len(_edges(poly))} edges, best of {args.layouts} layouts {np.nanmax(real):.4f}")
    print(f"{'tol m':>6} {'edges':>5} {'h m':>5} {'min':>8} {'median':>8} {'max':>8} "
          f"{'|d|>.01':>7} {'outside':>7}  certified optimum of the simplified area")  # fmt: skip
    for tol in args.tolerances:
        simple = poly.simplify(tol, preserve_topology=True)
        h = shapely.hausdorff_distance(poly, simple, densify=0.05)
        diff = real - value(simple)
        inner, outer = value(simple.buffer(-h)), value(simple.buffer(h))
        outside = (real > np.fmax(inner, outer) + 1e-9) | (real < np.fmin(inner, outer) - 1e-9)
        row = (f"{tol:>6.2f} {len(_edges(simple)):>5} {h:>5.2f} {np.nanmin(diff):>+8.4f} "
               f"{np.nanmedian(diff):>+8.4f} {np.nanmax(diff):>+8.4f} "
               f"{np.nanmean(np.abs(diff) > 0.01):>7.2f} {np.mean(outside):>7.2f}")  # fmt: skip
        if args.certify:
            area = Region(np.asarray(simple.exterior.coords)[:-1],
                          holes=[np.asarray(r.coords)[:-1] for r in simple.interiors])  # fmt: skip
            t = time.process_time()
            res = smith_bb_region(area, args.spacing, max_work=4e7)
            cpu = time.process_time() - t
            # its layout on the real area: the offset from the real shell's vertex mean
            n = np.array([-np.sin(res.angle), np.cos(res.angle)])
            off = (res.offset + n @ (area.frame.centre - f.centre)) / f.scale
            there = evaluate_region_grid(
                (_edges(poly) - f.centre) / f.scale,
                np.array([res.angle]),
                np.array([off]),
                s,
                pairs=True,
            )
            row += (f"  {res.fitness:.5f} (gap {res.gap:.1e}, {res.info['boxes']} boxes, "
                    f"{cpu:.2f} s; real area there {float(there[0]):.5f})")  # fmt: skip
        print(row, flush=True)


if __name__ == "__main__":
    main()
