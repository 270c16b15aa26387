"""Optimising a region: per-cell optima, the sweep direction, merging cells of similar angle."""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..errors import InvalidPolygonError, NoTransectError
from ..geometry import Polygon
from ..geometry.region import Region, as_region
from ..models import check_spacing
from ..models.region import segment_moments
from ..objectives import objective_sign
from ..objectives.smith import SmithFitness
from ..optimize import OptimizeResult, grid_search
from ..optimize.region_grid import evaluate_region_grid
from .cells import Decomposition, decompose

__all__ = [
    "SWEEP_SEARCH",
    "choose_sweep",
    "optimize_region",
]


SWEEP_SEARCH = {"n_angles": 36, "n_offsets": 6, "refine": 1}


def _estimate(
    cells: Sequence[Region], optima: Sequence[OptimizeResult], spacing: float
) -> tuple[float, float]:
    """``(turns, lane length)`` estimated from each cell's line segments at its optimum: one
    turn per segment, plus one per cell to reach it, minus one."""
    turns, length = -1.0, 0.0
    for cell, opt in zip(cells, optima, strict=True):
        frame = cell.frame
        n, s1, _ = segment_moments(
            frame.to_normalised(cell.edges),
            [opt.angle],
            [opt.offset / frame.scale],
            spacing / frame.scale,
            tiny=1e-12,
        )
        turns += float(n[0]) + 1.0
        length += float(s1[0]) * frame.scale
    return turns, length


def _cells_for_sweep(
    region: Region,
    spacing: float,
    sweep: float,
    *,
    min_width: float,
    merge_angle: float,
    options: dict[str, Any],
) -> tuple[list[Region], list[OptimizeResult]]:
    dec = decompose(region, sweep, min_width=min_width)
    _, cells, optima = _merge_by_angle(dec, region.diameter, spacing, merge_angle, **options)
    return cells, optima


def choose_sweep(
    region: Region | Polygon | ArrayLike,
    spacing: float,
    *,
    candidates: Sequence[float] | None = None,
    n_candidates: int = 6,
    min_width: float | None = None,
    merge_angle: float = math.radians(15.0),
    fitness: Any = None,
) -> tuple[float, tuple[float, float]]:
    """The sweep direction whose decomposition promises the fewest turns.

    For each candidate the area is decomposed (:func:`decompose`), every cell optimised on a
    coarse grid (:data:`SWEEP_SEARCH`), neighbours with similar angles merged, and the plan's
    turns and lane length estimated from the cells' line segments at their optima. Candidates
    (radians): ``n_candidates`` directions over 180 degrees and those of the 2 longest edges.

    Returns:
        ``(sweep, (estimated turns, estimated lane length))`` of the best candidate.
    """
    r = as_region(region)
    s = check_spacing(spacing, extent=r.diameter)
    min_width = 2 * s if min_width is None else float(min_width)
    if candidates is None:
        e = r.edges
        d = e[:, 1] - e[:, 0]
        longest = np.argsort(-np.linalg.norm(d, axis=1))[:2]
        edge_angles = np.arctan2(d[longest, 1], d[longest, 0]) % math.pi
        candidates = list(np.arange(n_candidates) * math.pi / n_candidates) + list(edge_angles)
    options = dict(SWEEP_SEARCH, fitness=fitness)
    best: tuple[tuple[float, float], float] | None = None
    for angle in candidates:
        try:
            cells, optima = _cells_for_sweep(
                r, s, float(angle), min_width=min_width, merge_angle=merge_angle, options=options
            )
        except InvalidPolygonError:  # a cell that rounding made invalid: skip this sweep
            continue
        key = _estimate(cells, optima, s)
        if best is None or key < best[0]:
            best = (key, float(angle) % math.pi)
    if best is None:
        return 0.0, (math.inf, math.inf)
    return best[1], best[0]


# -- optimising a region ----------------------------------------------------------------------
def optimize_region(
    region: Region | Polygon | ArrayLike,
    spacing: float,
    *,
    n_angles: int = 90,
    n_offsets: int = 16,
    refine: int = 2,
    fitness: Any = None,
) -> OptimizeResult:
    """Grid search of angle and offset for any region with the exact per-segment fitness.

    A convex polygon goes to :func:`boustro.optimize.grid_search` (closed-form chords); any
    other region is scored by :func:`boustro.regions.evaluate_region_grid` on an
    ``n_angles x n_offsets`` grid, then ``refine`` times on a 9 x 9 grid zoomed (by 4) around
    the best point. A region narrower than the spacing in every direction gets the single lane
    through its vertex mean along its diameter.

    Returns:
        :class:`~boustro.optimize.OptimizeResult` in the region's units (offset from the shell's
        vertex mean), method ``"region-grid"`` (or ``"grid"`` for a convex polygon).
    """
    t0 = time.perf_counter()
    r = as_region(region)
    s = check_spacing(spacing, extent=r.diameter)
    fitness = SmithFitness() if fitness is None else fitness
    sign = objective_sign(fitness)
    if s >= r.diameter:
        v = r.shell.vertices
        dif = v[:, None] - v[None]
        i, j = np.unravel_index(int(np.argmax(np.einsum("ijk,ijk->ij", dif, dif))), dif.shape[:2])
        angle = math.atan2(*(v[j] - v[i])[::-1]) % math.pi
        return OptimizeResult(angle, 0.0, math.nan, s, "single-lane", 0, time.perf_counter() - t0)
    if r.is_convex:
        try:
            return grid_search(r.shell, s, n_angles=n_angles, n_offsets=n_offsets, fitness=fitness)
        except NoTransectError:
            pass
    frame = r.frame
    edges = frame.to_normalised(r.edges)
    s_n = s / frame.scale
    angles = np.arange(n_angles) * (math.pi / n_angles)
    offsets = np.arange(n_offsets) * (s_n / n_offsets)
    values = evaluate_region_grid(edges, angles, offsets, s_n, fitness=fitness)
    evaluations = values.size
    i, j = np.unravel_index(int(np.argmax(sign * values)), values.shape)
    best = (float(values[i, j]), float(angles[i]), float(offsets[j]))
    da, do = math.pi / n_angles, s_n / n_offsets
    for _ in range(int(refine)):
        a = best[1] + np.linspace(-da, da, 9)
        o = best[2] + np.linspace(-do, do, 9)
        vals = evaluate_region_grid(edges, a, o, s_n, fitness=fitness)
        evaluations += vals.size
        i, j = np.unravel_index(int(np.argmax(sign * vals)), vals.shape)
        if sign * vals[i, j] > sign * best[0]:
            best = (float(vals[i, j]), float(a[i]), float(o[j]))
        da, do = da / 4, do / 4
    if not math.isfinite(best[0]):
        raise NoTransectError(f"no transect crosses the area at spacing {s:g}")
    angle, offset = best[1], best[2]
    turns = math.floor(angle / math.pi)
    angle -= turns * math.pi
    if turns % 2:
        offset = -offset
    offset = math.fmod(offset, s_n) % s_n
    return OptimizeResult(
        angle=angle,
        offset=offset * frame.scale,
        fitness=best[0],
        spacing=s,
        method="region-grid",
        evaluations=int(evaluations),
        seconds=time.perf_counter() - t0,
        info={"n_angles": n_angles, "n_offsets": n_offsets, "refine": int(refine)},
    )


def _angle_gap(a: float, b: float) -> float:
    d = abs(a - b) % math.pi
    return min(d, math.pi - d)


def _merge_by_angle(
    dec: Decomposition,
    diameter: float,
    spacing: float,
    merge_angle: float,
    **options: Any,
) -> tuple[list[list[int]], list[Region], list[OptimizeResult]]:
    """Optimise every cell; then repeatedly merge the two neighbouring cells (longest shared
    boundary first) whose angles differ by less than ``merge_angle`` and optimise the union."""
    groups = [[k] for k in range(len(dec.cells))]
    regions = list(dec.cells)
    optima = [optimize_region(c, spacing, **options) for c in regions]
    refused: set[tuple[tuple[int, ...], tuple[int, ...]]] = set()
    while len(groups) > 1:
        best = None
        for i in range(len(groups)):
            for j in range(i + 1, len(groups)):
                shared = float(dec.shared[np.ix_(groups[i], groups[j])].sum())
                if shared <= 0 or (tuple(groups[i]), tuple(groups[j])) in refused:
                    continue
                if _angle_gap(optima[i].angle, optima[j].angle) >= merge_angle:
                    continue
                if best is None or shared > best[0]:
                    best = (shared, i, j)
        if best is None:
            break
        _, i, j = best
        try:
            union = dec.union(groups[i] + groups[j], diameter)
        except InvalidPolygonError:
            refused.add((tuple(groups[i]), tuple(groups[j])))
            continue
        groups[i] = groups[i] + groups[j]
        regions[i] = union
        optima[i] = optimize_region(union, spacing, **options)
        del groups[j], regions[j], optima[j]
    return groups, regions, optima
