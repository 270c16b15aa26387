"""Plans for concave areas and areas with holes: check, cells, lanes, tour, assemble."""

from __future__ import annotations

import math
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError, InvalidPolygonError, NoTransectError
from ..geometry import Polygon
from ..models import check_spacing
from ..optimize import OptimizeResult
from ..regions import Region, as_region
from .cells import _TOL, _check_float, _frame
from .lanes import Lanes, region_lanes
from .region_opt import _cells_for_sweep, _estimate, choose_sweep, optimize_region
from .routing import Router
from .tour import _chain_pass, _chains, _hole_pass, _order, _Pass
from .types import KINDS, Layout, Plan, PlanCell, PlanStats

__all__ = [
    "plan_region",
]


# -- plans ------------------------------------------------------------------------------------
def _extension_end(
    router: Router, p: NDArray[np.float64], q: NDArray[np.float64]
) -> NDArray[np.float64]:
    """``q``, or the point where ``p -> q`` first enters a hole (run-ins never enter holes)."""
    br, cls = router._pieces(p, q)
    bad = np.flatnonzero(cls == 1)
    if len(bad) == 0:
        return q
    return p + br[bad[0]] * (q - p)


def plan_region(
    region: Region | Polygon | ArrayLike,
    spacing: float,
    *,
    decompose_area: bool | Literal["auto"] = "auto",
    sweep: float | None = None,
    angle: float | None = None,
    offset: float | None = None,
    fitness: Any = None,
    n_angles: int = 90,
    n_offsets: int = 16,
    layout: Layout = "guaranteed",
    start: ArrayLike | None = None,
    turnaround: float = 0.0,
    reach: float | None = None,
    nadir_gap: float = 0.0,
    hole_passes: bool = True,
    ground_scale: float = 1.0,
    speed: float | None = None,
    turn_time: float = 0.0,
    area: float | None = None,
    min_width: float | None = None,
    merge_angle: float = math.radians(15.0),
) -> Plan:
    """Plan a concave area or an area with holes: lanes, hole passes, one connected path.

    Args:
        region: the area (plan units): a :class:`~boustro.regions.Region`, or a polygon.
        spacing: distance between lanes, > 0.
        decompose_area: ``"auto"`` (default): decompose into cells, each with its own
            optimised angle and offset, when that promises fewer turns (or, on a tie, less
            lane length) than one grid over the whole area (:func:`choose_sweep`'s estimate);
            ``True``: always decompose; ``False``: one grid over the whole area.
        sweep: sweep direction of the decomposition (radians); default: the best of
            :func:`choose_sweep`'s candidates.
        angle, offset: with ``decompose_area=False``, plan this grid instead of optimising
            (offset from the shell's vertex mean).
        fitness: the objective of the per-cell (or whole-area) optimisation (default Eq. 1 over
            segments).
        n_angles, n_offsets: grid of :func:`optimize_region`.
        layout: ``"guaranteed"`` (default; with hole passes, every point of the area is within
            ``reach`` of a lane across it or of a hole pass) or ``"chords"``.
        start: the path begins at the entry nearest this point of a chain of lanes (a chain
            starts at its first or last lane's ends); default: where the tour is shortest.
        turnaround: run-in / run-out beyond each lane end (shortened where it would enter a
            hole), plan units.
        reach: half-width of each lane's band (default ``spacing / 2``).
        nadir_gap: blind strip under the vehicle (not supported with hole passes).
        hole_passes: drive around every hole that cuts a lane (guaranteed layout only).
        ground_scale, speed, turn_time, area: as in :func:`boustro.plan.build_plan`.
        min_width: cells narrower than this across the sweep are merged into a neighbour
            (default two spacings), see :func:`decompose`.
        merge_angle: neighbouring cells whose optimised angles differ by less than this
            (radians, default 15 degrees) are merged and optimised again as one cell.

    Returns:
        a :class:`~boustro.plan.Plan` with ``region``, ``cells``, per-transect angles and
        roles; its ``polygon`` is the shell.

    Raises:
        InvalidParameterError: bad parameters. NoTransectError: nothing to plan.
    """
    r = as_region(region)
    s = check_spacing(spacing, extent=r.diameter)
    reach = s / 2 if reach is None else _check_float("reach", reach)
    if reach < s / 2 * (1 - 1e-12):
        raise InvalidParameterError(
            f"reach must be >= spacing / 2 = {s / 2:g} for the bands to tile the area, "
            f"got {reach:g}"
        )
    turnaround = _check_float("turnaround", turnaround, 0.0)
    nadir_gap = _check_float("nadir_gap", nadir_gap, 0.0)
    turn_time = _check_float("turn_time", turn_time, 0.0)
    ground_scale = _check_float("ground_scale", ground_scale)
    if ground_scale <= 0:
        raise InvalidParameterError(f"ground_scale must be > 0, got {ground_scale!r}")
    if speed is not None and _check_float("speed", speed) <= 0:
        raise InvalidParameterError(f"speed must be > 0, got {speed!r}")
    if layout not in ("guaranteed", "chords"):
        raise InvalidParameterError(f"layout must be 'guaranteed' or 'chords', got {layout!r}")
    if nadir_gap > 0 and r.n_holes and hole_passes and layout == "guaranteed":
        raise InvalidParameterError(
            "a nadir gap is not supported with holes: the passes around holes would not cover "
            "their own blind strip"
        )
    tol = _TOL * r.diameter
    notes: list[str] = []

    # Cells and their grids.
    if decompose_area not in (True, False, "auto"):
        raise InvalidParameterError(
            f"decompose_area must be True, False or 'auto', got {decompose_area!r}"
        )
    min_width = 2 * s if min_width is None else _check_float("min_width", min_width, 0.0)
    options = {"n_angles": n_angles, "n_offsets": n_offsets, "fitness": fitness}
    cell_regions: list[Region] = [r]
    optima: list[OptimizeResult | None] = [None]
    if angle is None:
        optima = [optimize_region(r, s, **options)]
    if decompose_area and not r.is_convex and angle is None:
        if sweep is None:
            sweep_angle, estimate = choose_sweep(
                r, s, min_width=min_width, merge_angle=merge_angle, fitness=fitness
            )
        else:
            sweep_angle, estimate = _check_float("sweep", sweep), (-math.inf, -math.inf)
        single = _estimate([r], optima, s)  # type: ignore[arg-type]
        if decompose_area is True or estimate < single:
            try:
                cell_regions, cells_opt = _cells_for_sweep(
                    r, s, sweep_angle, min_width=min_width, merge_angle=merge_angle, options=options
                )
            except InvalidPolygonError as exc:
                notes.append(f"the decomposition failed ({exc}); the area is planned as one cell")
                cell_regions, cells_opt = [r], optima  # type: ignore[assignment]
            if len(cell_regions) > 1 and (
                decompose_area is True or _estimate(cell_regions, cells_opt, s) < single
            ):
                optima = list(cells_opt)
            else:  # one cell after all: the whole area, as planned without decomposition
                cell_regions = [r]
    cells: list[PlanCell] = []
    lanes_by_cell: list[Lanes] = []
    for cell, opt in zip(cell_regions, optima, strict=True):
        if opt is None:
            cell_angle = _check_float("angle", angle)
            cell_offset = 0.0 if offset is None else _check_float("offset", offset)
            value = math.nan
        else:
            cell_angle, cell_offset, value = opt.angle, opt.offset, opt.fitness
        lanes = region_lanes(
            cell, s, cell_angle, cell_offset, reach=reach, holes=r.holes, layout=layout
        )
        lanes_by_cell.append(lanes)
        cells.append(PlanCell(cell, cell_angle, cell_offset, value, len(lanes.k), opt))
    if sum(len(lanes.k) for lanes in lanes_by_cell) == 0:
        raise NoTransectError(f"no lane crosses the area at spacing {s:g}")

    passes: list[_Pass] = []
    for ci, lanes in enumerate(lanes_by_cell):
        for chain in _chains(lanes, tol):
            passes.append(_chain_pass(lanes, chain, ci))
    cut = set().union(*(lanes.cut for lanes in lanes_by_cell))
    if layout == "guaranteed" and hole_passes:
        for hi in sorted(cut):
            passes.append(_hole_pass(r.holes[hi]))
    elif cut and layout == "guaranteed":
        notes.append(
            f"{len(cut)} hole(s) cut lanes and hole passes are off: the area along their edges "
            "is not fully covered"
        )

    router = Router(r, reach=max(reach, turnaround))
    force_start = start is not None
    if start is None:
        start_pt = r.shell.vertices[0]
    else:
        start_pt = np.asarray(start, dtype=np.float64).reshape(-1)
        if start_pt.shape != (2,) or not np.all(np.isfinite(start_pt)):
            raise InvalidParameterError(f"start must be a finite (x, y) pair, got {start!r}")
    order, choice = _order(passes, start_pt, router, force_start=force_start)

    # Waypoints.
    points: list[NDArray[np.float64]] = []
    kinds: list[str] = []
    lane_of: list[int] = []
    transects: list[NDArray[np.float64]] = []
    angles_t: list[float] = []
    roles: list[str] = []
    cells_t: list[int] = []
    positions: list[float] = []
    outside = 0.0
    hole_length = 0.0
    blocked: list[tuple[NDArray[np.float64], NDArray[np.float64]]] = []

    def move_to(target: NDArray[np.float64], next_transect: int) -> None:
        nonlocal outside
        if not points:
            return
        route = router.path(points[-1], target)
        outside += route.outside
        if not route.found:
            blocked.append((points[-1], target))
        for p in route.points[1:-1]:
            points.append(p)
            kinds.append("via")
            lane_of.append(next_transect)

    for pi, oi in zip(order, choice, strict=True):
        p = passes[pi]
        _, _, pts, _ = p.options[oi]
        if p.kind == "chain":
            u, n = _frame(p.angle)
            origin = lanes_by_cell[p.cell].origin
            for j in range(0, len(pts), 2):
                a, b = pts[j], pts[j + 1]
                ti = len(transects)
                d = b - a
                length = float(np.linalg.norm(d))
                direction = d / length if length > 0 else (u if j % 4 == 0 else -u)
                run_in = _extension_end(router, a, a - turnaround * direction) if turnaround else a
                move_to(run_in, ti)
                if turnaround:
                    points.append(run_in)
                    kinds.append("run_in")
                    lane_of.append(ti)
                points += [a, b]
                kinds += ["start", "end"]
                lane_of += [ti, ti]
                if turnaround:
                    points.append(_extension_end(router, b, b + turnaround * direction))
                    kinds.append("run_out")
                    lane_of.append(ti)
                transects.append(np.stack([a, b]))
                angles_t.append(p.angle)
                roles.append("lane")
                cells_t.append(p.cell)
                positions.append(float((a - origin) @ n))
        else:
            ti = len(transects)
            move_to(pts[0], ti)
            for j in range(len(pts) - 1):
                a, b = pts[j], pts[j + 1]
                transects.append(np.stack([a, b]))
                d = b - a
                angles_t.append(math.atan2(d[1], d[0]))
                roles.append("hole")
                cells_t.append(-1)
                positions.append(math.nan)
                hole_length += float(np.linalg.norm(d))
            points.append(pts[0])
            kinds.append("start")
            lane_of.append(ti)
            for j in range(1, len(pts) - 1):
                points.append(pts[j])
                kinds.append("loop")
                lane_of.append(ti + j)
            points.append(pts[-1])
            kinds.append("end")
            lane_of.append(ti + len(pts) - 2)
    assert set(kinds) <= set(KINDS)
    waypoints = np.asarray(points)
    tr = np.asarray(transects)
    lane_role = np.array(roles) == "lane"
    transect_length = float(np.linalg.norm(tr[:, 1] - tr[:, 0], axis=1)[lane_role].sum())
    path_length = float(np.linalg.norm(np.diff(waypoints, axis=0), axis=1).sum())
    n_lanes = int(lane_role.sum())
    n_turns = n_lanes + sum(1 for p in passes if p.kind == "hole") - 1  # passes - 1
    for a, b in blocked:
        notes.append(
            f"no connecting move inside the area from {a.round(3).tolist()} to "
            f"{b.round(3).tolist()}: the straight line is used"
        )
    duration = None if speed is None else path_length / ground_scale / speed + n_turns * turn_time
    stats = PlanStats(
        n_transects=n_lanes,
        n_turns=n_turns,
        transect_length=transect_length / ground_scale,
        path_length=path_length / ground_scale,
        area=r.area / ground_scale**2 if area is None else float(area),
        speed=speed,
        turn_time=turn_time,
        duration=duration,
        n_cells=len(cells),
        hole_pass_length=hole_length / ground_scale,
        outside_length=outside / ground_scale,
    )
    main = max(range(len(cells)), key=lambda i: cells[i].polygon.area)
    return Plan(
        polygon=r.shell,
        spacing=s,
        angle=cells[main].angle,
        offset=cells[main].offset,
        layout=layout,
        reach=float(reach),
        nadir_gap=nadir_gap,
        turnaround=turnaround,
        positions=np.asarray(positions),
        transects=tr,
        waypoints=waypoints,
        kinds=tuple(kinds),
        lane=np.asarray(lane_of, dtype=np.int64),
        ground_scale=ground_scale,
        stats=stats,
        region=r,
        cells=tuple(cells),
        transect_angles=np.asarray(angles_t),
        roles=tuple(roles),
        transect_cells=np.asarray(cells_t, dtype=np.int64),
        notes=tuple(notes),
    )
