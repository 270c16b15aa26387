"""Step 2 for a concave area or one with holes under Eq. 1 (the default objective): the
certified optimum over the segments (:func:`~boustro.optimize.smith_bb.region.smith_bb_region`)
of the whole area and, where a decomposition promises fewer turns, of each cell.

The decomposition is chosen as :func:`boustro.plan.plan_region` chooses it (its sweep
candidates, cells and merging scored on the coarse grid), but the whole area's estimate and the
final cells' angles and offsets are the certified optima; the cells are planned at those
optima. The plan's certificate (:func:`_combined`): ``certified`` when every cell's search
converged, its ``gap`` the largest of the cells' gaps (the plan's fitness is their area-weighted
mean); it holds for the cells as chosen: the choice of cells itself is not certified.
The grid (``--method grid``/``region-grid``) stays the baseline.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..errors import InvalidPolygonError
from ..geometry.region import Region
from ..objectives import SmithFitness
from ..optimize import OptimizeResult
from ..optimize.smith_bb.region import smith_bb_region
from ..plan import Plan
from ..plan.region import _assemble as _assemble_plan
from ..plan.region import _Cells, _check_options, _plan_lanes, _plan_tour, _Stages
from ..plan.region import _drive as _drive_plan
from ..plan.region_opt import _cells_for_sweep, _estimate, choose_sweep, optimize_region
from .defaults import DEFAULT_METHOD, REGION_OPTIONS, SCALE_METHOD, log

__all__ = ["certified_applies", "plan_certified"]

#: Cells narrower than this many spacings are merged, and neighbours whose angles differ by
#: less than this are merged (as :func:`plan_region`'s defaults).
MIN_WIDTH_SPACINGS = 2.0
MERGE_ANGLE = math.radians(15.0)
#: On an area of at most this many vertices the grid's optimum is the search's first incumbent
#: (the grid costs seconds beyond).
GRID_FALLBACK_VERTICES = 300
#: The note of a plan of several cells (``--json``'s ``notes``).
CELLS_NOTE = (
    "certificate for these cells fixed: each cell is at its own certified optimum, the plan's "
    "gap is the largest cell's; the choice of cells is not certified"
)


def certified_applies(method: str | None, fitness: Any, angle: float | None) -> bool:
    """Whether a concave area is planned by the certified region search: the default (or
    ``certified-bb``) method, Eq. 1 with its default (weighted) statistics, no fixed angle."""
    if method not in (None, DEFAULT_METHOD, SCALE_METHOD) or angle is not None:
        return False
    return fitness is None or (
        type(fitness) is SmithFitness and getattr(fitness, "statistics", "weighted") == "weighted"
    )


def _certify(region: Region, spacing: float, fitness: Any, progress: bool) -> OptimizeResult:
    """The certified optimum. On an area of at most :data:`GRID_FALLBACK_VERTICES` vertices
    the grid's optimum (``region-grid``, cheap there) is computed first and given to the search
    as its first incumbent (it prunes boxes from the start, and where the search stops on its
    budget the grid's layout is among the candidates scored at the end). An area no wider than
    the spacing gets the grid's single lane along its diameter (Eq. 1 is undefined there)."""
    if spacing >= region.diameter:
        return optimize_region(region, spacing, fitness=fitness, **REGION_OPTIONS)
    seeds: list[tuple[float, float]] = []
    if len(region.vertices) <= GRID_FALLBACK_VERTICES:
        grid = optimize_region(region, spacing, fitness=fitness, **REGION_OPTIONS)
        if math.isfinite(grid.fitness):
            seeds.append((grid.angle, grid.offset))
    res = smith_bb_region(region, spacing, fitness=fitness, progress=progress, incumbents=seeds)
    if not res.info.get("converged"):
        log.warning(
            "the certified optimum of a %d-vertex area stopped at gap %.3g (%s)",
            len(region.vertices),
            res.gap,
            res.info.get("stopped", "not converged"),
        )
    return res


class _Whole:
    """The whole area's certified optimum, computed when first asked (not at all when
    ``decompose=True`` forces cells that the decomposition finds)."""

    def __init__(self, region: Region, spacing: float, fitness: Any, progress: bool) -> None:
        self.args = (region, spacing, fitness, progress)
        self.result: OptimizeResult | None = None

    def __call__(self) -> OptimizeResult:
        if self.result is None:
            self.result = _certify(*self.args)
        return self.result


def _cells(
    r: Region,
    s: float,
    whole: _Whole,
    decompose: bool | None,
    sweep: float | None,
    fitness: Any,
    progress: bool,
) -> tuple[list[Region], list[OptimizeResult]]:
    """The whole area, or the cells of the best sweep with their certified optima where they
    promise fewer turns (or on a tie less lane length) than the whole area's optimum (always
    with ``decompose=True``, the whole area then searched only if no cells come out)."""
    if decompose is False or r.is_convex:
        return [r], [whole()]
    min_width = MIN_WIDTH_SPACINGS * s
    if sweep is None:
        sweep, estimate = choose_sweep(r, s, min_width=min_width, merge_angle=MERGE_ANGLE,
                                       fitness=fitness)  # fmt: skip
        if decompose is None and not estimate < _estimate([r], [whole()], s):
            return [r], [whole()]
    options = {**REGION_OPTIONS, "fitness": fitness}
    try:
        regions, _ = _cells_for_sweep(
            r, s, sweep, min_width=min_width, merge_angle=MERGE_ANGLE, options=options
        )
    except InvalidPolygonError as exc:
        log.info("the decomposition failed (%s); the area is planned as one cell", exc)
        return [r], [whole()]
    if len(regions) < 2:
        return [r], [whole()]
    optima = [_certify(c, s, fitness, progress) for c in regions]
    if decompose or _estimate(regions, optima, s) < _estimate([r], [whole()], s):
        return regions, optima
    return [r], [whole()]


def _combined(plan: Plan, optima: list[OptimizeResult], s: float) -> OptimizeResult:
    """One result for the plan: the largest cell's layout, the area-weighted fitness of the
    cells (a single-lane cell, NaN fitness and no bound, left out) and as its gap the LARGEST
    of the cells' gaps (each cell is within it of its own certified optimum), ``converged``
    only when every cell's search converged. The choice of cells is not certified: the
    certificate is for the cells fixed (``info["cells_fixed"]``)."""
    if len(optima) == 1:
        return optima[0]
    areas = np.array([c.region.area for c in plan.cells])
    values = np.array([o.fitness for o in optima], dtype=np.float64)
    scored = np.isfinite(values)
    w = areas * scored
    fitness = float(np.dot(w, np.where(scored, values, 0.0)) / w.sum()) if w.any() else math.nan
    gaps = [o.gap for o in optima if math.isfinite(o.fitness)]
    main = int(np.argmax(areas))
    info: dict[str, Any] = {"cells": len(optima), "cells_fixed": True}
    upper = None
    if gaps and all(g is not None for g in gaps) and math.isfinite(fitness):
        gap = max(float(g) for g in gaps if g is not None)
        upper = fitness + gap  # >= the area-weighted mean of the cells' upper bounds
        info["gap"] = gap
        info["converged"] = all(bool(o.info.get("converged")) for o in optima if o.gap is not None)
    return OptimizeResult(
        angle=plan.cells[main].angle,
        offset=plan.cells[main].offset,
        fitness=fitness,
        spacing=s,
        method="decomposed",
        evaluations=int(sum(o.evaluations for o in optima)),
        seconds=float(sum(o.seconds for o in optima)),
        upper_bound=upper,
        info=info,
    )


def plan_certified(
    region: Region,
    spacing: float,
    path: dict[str, Any],
    *,
    fitness: Any,
    layout: str,
    start: Any,
    decompose: bool | None,
    sweep: float | None,
    progress: bool = False,
    keep_inside: bool = False,
) -> tuple[Plan, OptimizeResult]:
    """``(plan, optimum)``: a concave area or one with holes (plan frame) planned at certified
    optima of Eq. 1 over segments (module docstring); ``path``: the options of the path
    (:func:`boustro.mission.steps.plan_concave`'s), ``sweep`` in degrees, ``start`` ``None``
    for the shortest tour. The options are checked before any work; the stages are
    :func:`plan_region`'s (its bar with ``progress``)."""
    opts = _check_options(
        region, spacing, decompose_area=decompose is not False, sweep=None, angle=None,
        offset=None, fitness=None, n_angles=REGION_OPTIONS["n_angles"],
        n_offsets=REGION_OPTIONS["n_offsets"], layout=layout, start=start, hole_passes=True,
        min_width=None, merge_angle=MERGE_ANGLE, keep_inside=keep_inside, order="heuristic",
        **path)  # fmt: skip
    sweep_rad = None if sweep is None else math.radians(float(sweep))
    notes: list[str] = []
    bar = _Stages(progress)
    with bar.stage("optimising the cells"):
        whole = _Whole(region, opts.spacing, fitness, progress)
        cells, optima = _cells(region, opts.spacing, whole, decompose, sweep_rad, fitness,
                               progress)  # fmt: skip
    if len(cells) > 1:
        notes.append(CELLS_NOTE)
    with bar.stage("lanes"):
        lanes = _plan_lanes(region, _Cells(cells, list(optima)), opts)
    with bar.stage("tour and routing"):
        tour = _plan_tour(region, lanes, opts, notes)
    with bar.stage("path"):
        driven = _drive_plan(tour, lanes, opts)
    bar.close()
    plan = _assemble_plan(region, lanes, tour, driven, opts, notes)
    return plan, _combined(plan, optima, opts.spacing)
