"""Step 2 of a mission: the projected area optimised and planned (convex, or cells and lanes)."""

from __future__ import annotations

import dataclasses
import inspect
import math
from typing import Any, NamedTuple

import numpy as np

from ..errors import InvalidParameterError, ProblemTooLargeError
from ..geometry.region import Region
from ..objectives import ShortestPath, SmithFitness
from ..optimize import OptimizeResult, optimize
from ..optimize.fixed_angle import optimize_offset
from ..optimize.methods import resolve_method
from ..plan import Coverage, Plan, build_plan, coverage
from ..plan.cells import _frame
from ..plan.outside import outside_length
from ..plan.region import plan_region
from .defaults import (
    DEFAULT_METHOD,
    FALLBACK_METHOD,
    METHOD_OPTIONS,
    REGION_OPTIONS,
    SCALE_METHOD,
    log,
)
from .project import Frame
from .region_certified import certified_applies, plan_certified

__all__ = ["Planned", "main_cell", "plan_concave", "plan_convex", "region_optimum"]


class Planned(NamedTuple):
    """Step 2: the plan (plan frame), its optimum and its coverage."""

    plan: Plan
    optimum: OptimizeResult
    coverage: Coverage | None


def _path_options(frame: Frame, turnaround: float, speed: Any, turn_time: float) -> dict:
    """The options of the path that both planners take, scaled to the plan frame."""
    proj, sensor = frame.proj, frame.sensor
    return {
        "turnaround": float(turnaround) * proj.scale_max,
        "reach": sensor.reach * proj.scale_min,
        "nadir_gap": sensor.nadir_gap * proj.scale_max,
        "ground_scale": proj.scale,
        "speed": speed,
        "turn_time": turn_time,
        "area": frame.ground_area,
    }


def plan_convex(
    frame: Frame,
    *,
    method: str | None,
    fitness: Any,
    options: dict[str, Any] | None,
    layout: str,
    turnaround: float,
    speed: float | None,
    turn_time: float,
    check_coverage: bool,
    angle: float | None = None,
    progress: bool = False,
    keep_inside: bool = False,
) -> Planned:
    """A convex area (or the hull of a nearly convex one): optimise, then build the plan; at a
    fixed ``angle`` (radians, plan frame) only the offset is optimised (:func:`optimize_offset`).
    With ``keep_inside`` the optimum's lanes are planned inside the area itself (not its hull)
    by :func:`plan_region`."""
    s_plan = frame.sensor.spacing * frame.proj.scale_min
    if angle is not None:
        optimum = optimize_offset(frame.poly, s_plan, angle, fitness=fitness)
    else:
        optimum = _optimize_convex(frame, s_plan, method, fitness, options, progress)
    if keep_inside:
        planned = _convex_inside(frame, optimum, s_plan, layout, turnaround, speed, turn_time)
        cov = coverage(planned.plan, frame.surveyed) if check_coverage else None
        return planned._replace(coverage=cov)
    plan = build_plan(
        frame.poly,
        s_plan,
        optimum.angle,
        optimum.offset,
        layout=layout,  # type: ignore[arg-type]
        start=frame.start,
        **_path_options(frame, turnaround, speed, turn_time),
    )
    if frame.poly is not frame.surveyed:  # the hull was planned: measured on the area itself
        plan = _with_outside(plan, frame.surveyed)
    cov = coverage(plan, frame.surveyed) if check_coverage else None
    return Planned(plan, optimum, cov)


def _with_outside(plan: Plan, area: Any) -> Plan:
    """The plan with its ``outside_length`` measured against the area (not its hull)."""
    outside = outside_length(plan.waypoints, area) / plan.ground_scale
    return dataclasses.replace(plan, stats=dataclasses.replace(plan.stats, outside_length=outside))


def _convex_inside(
    frame: Frame,
    optimum: OptimizeResult,
    s_plan: float,
    layout: str,
    turnaround: float,
    speed: Any,
    turn_time: float,
) -> Planned:
    """The convex optimum's grid planned with ``keep_inside`` over the area itself (the offset
    moved from the hull's vertex mean to the area's)."""
    area = Region(frame.surveyed)
    _, n = _frame(optimum.angle)
    offset = optimum.offset + float((frame.poly.centre - area.centre) @ n)
    plan = plan_region(
        area,
        s_plan,
        decompose_area=False,
        angle=optimum.angle,
        offset=offset,
        layout=layout,  # type: ignore[arg-type]
        start=frame.start,
        keep_inside=True,
        **_path_options(frame, turnaround, speed, turn_time),
    )
    cell = dataclasses.replace(plan.cells[0], fitness=optimum.fitness, optimum=optimum)
    return Planned(dataclasses.replace(plan, cells=(cell,)), optimum, None)


def _optimize_convex(
    frame: Frame,
    s_plan: float,
    method: str | None,
    fitness: Any,
    options: dict[str, Any] | None,
    progress: bool = False,
) -> OptimizeResult:
    """The optimum by ``method`` (default: certified by the event method; where it would take
    too long, Eq. 1 by the certified branch and bound :data:`SCALE_METHOD` and any other
    objective by the hybrid); with ``progress`` the optimiser's bars on stderr where it has
    them (``progress`` parameter)."""
    chosen = method or DEFAULT_METHOD
    opts = dict(METHOD_OPTIONS.get(chosen, {}))
    if progress and "progress" in inspect.signature(resolve_method(chosen)).parameters:
        opts["progress"] = True
    opts.update(options or {})
    try:
        return optimize(frame.poly, s_plan, method=chosen, fitness=fitness, **opts)
    except ProblemTooLargeError as exc:
        if method is not None:
            raise
        weighted = type(fitness) is SmithFitness and fitness.statistics == "weighted"
        if fitness is None or weighted:  # Eq. 1 (weighted statistics): certified at scale
            log.info("%s; planning with the certified branch and bound (%s)", exc, SCALE_METHOD)
            return optimize(
                frame.poly, s_plan, method=SCALE_METHOD, fitness=fitness, progress=progress
            )
        if isinstance(fitness, ShortestPath):  # needs exact chords: no other optimiser has them
            raise ProblemTooLargeError(
                f"{exc}; the shortest-path objective is optimised by the certified event method "
                "only: plan this area with the default objective or --objective time"
            ) from exc
        log.warning("%s; planning with the hybrid optimiser instead", exc)
        return optimize(
            frame.poly, s_plan, method=FALLBACK_METHOD, fitness=fitness, progress=progress
        )


def plan_concave(
    frame: Frame,
    *,
    method: str | None,
    fitness: Any,
    options: dict[str, Any] | None,
    layout: str,
    turnaround: float,
    speed: float | None,
    turn_time: float,
    check_coverage: bool,
    decompose: bool | None,
    sweep: float | None,
    angle: float | None = None,
    progress: bool = False,
    keep_inside: bool = False,
) -> Planned:
    """A concave area or one with holes: cells, lanes and a tour. Eq. 1 by default: the
    certified optimum over the segments of the area and of each cell (:func:`plan_certified`);
    other objectives and ``method="grid"``/``"region-grid"``: :func:`plan_region`'s grid. At a
    fixed ``angle`` one grid over the whole area, its offset optimised (:func:`optimize_offset`)."""
    if method not in (None, DEFAULT_METHOD, SCALE_METHOD, "grid", "region-grid"):
        raise InvalidParameterError(
            f"method {method!r} optimises convex areas only; a concave area or one with "
            "holes is optimised by the certified search over its segments (leave --method "
            "out) or by grid search (--method grid)"
        )
    s_plan = frame.sensor.spacing * frame.proj.scale_min
    if certified_applies(method, fitness, angle):
        plan, optimum = plan_certified(
            frame.region,  # type: ignore[arg-type]
            s_plan,
            _path_options(frame, turnaround, speed, turn_time),
            fitness=fitness,
            layout=layout,
            start=frame.start if frame.given_start else None,
            decompose=decompose,
            sweep=sweep,
            progress=progress,
            keep_inside=keep_inside,
        )
        cov = coverage(plan, frame.region) if check_coverage else None
        return Planned(plan, optimum, cov)
    opts = dict(REGION_OPTIONS)
    opts.update({k: v for k, v in (options or {}).items() if k in ("n_angles", "n_offsets")})
    fixed = None
    if angle is not None:
        fixed = optimize_offset(frame.region, s_plan, angle, fitness=fitness)  # type: ignore[arg-type]
        decompose = False
    plan = plan_region(
        frame.region,  # type: ignore[arg-type]
        s_plan,
        decompose_area="auto" if decompose is None else bool(decompose),
        sweep=None if sweep is None else math.radians(float(sweep)),
        angle=None if fixed is None else fixed.angle,
        offset=None if fixed is None else fixed.offset,
        fitness=fitness,
        layout=layout,  # type: ignore[arg-type]
        start=frame.start if frame.given_start else None,  # None: the shortest tour
        **_path_options(frame, turnaround, speed, turn_time),
        **opts,
        keep_inside=keep_inside,
        progress=progress,
    )
    if fixed is None:
        optimum = region_optimum(plan, s_plan)
    else:  # the one cell carries the fixed angle's optimum
        cell = dataclasses.replace(plan.cells[0], fitness=fixed.fitness, optimum=fixed)
        plan, optimum = dataclasses.replace(plan, cells=(cell,)), fixed
    cov = coverage(plan, frame.region) if check_coverage else None
    return Planned(plan, optimum, cov)


def main_cell(plan: Plan) -> int:
    return max(range(len(plan.cells)), key=lambda i: plan.cells[i].region.area)


def region_optimum(plan: Plan, spacing: float) -> OptimizeResult:
    """One :class:`OptimizeResult` for a plan of cells: the largest cell's angle and offset,
    the area-weighted mean of the cells' fitness, the evaluations and time of all of them."""
    cells = plan.cells
    results = [c.optimum for c in cells if c.optimum is not None]
    areas = np.array([c.region.area for c in cells])
    values = np.array([c.fitness for c in cells])
    ok = np.isfinite(values)
    fitness = float(np.sum(values[ok] * areas[ok]) / np.sum(areas[ok])) if ok.any() else math.nan
    main = cells[main_cell(plan)]
    method = "region-grid" if len(cells) == 1 else "decomposed"
    return OptimizeResult(
        angle=main.angle,
        offset=main.offset,
        fitness=fitness,
        spacing=spacing,
        method=method,
        evaluations=int(sum(r.evaluations for r in results)),
        seconds=float(sum(r.seconds for r in results)),
        info={"cells": len(cells)},
    )
