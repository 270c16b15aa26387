"""Plans for concave areas and areas with holes: check, cells, lanes, tour, assemble."""

from __future__ import annotations

import contextlib
import dataclasses
import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any, Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._memo import bytes_key, remember
from ..errors import InvalidParameterError, InvalidPolygonError, NoTransectError
from ..geometry import Polygon
from ..geometry.region import Region, as_region
from ..models import check_spacing
from ..optimize import OptimizeResult
from ..optimize.problem import _progress_bar
from .cell_order import solve_order
from .cells import _TOL, _check_float
from .inside import inside_layout
from .lane_tour import refine_best, refine_tour
from .lanes import Lanes, region_lanes
from .outside import outside_length
from .region_opt import _cells_for_sweep, _estimate, choose_sweep, optimize_region
from .routing import Router, router_for
from .tour import (
    _boundary_pass,
    _chain_pass,
    _chains,
    _Driver,
    _hole_pass,
    _orders,
    _Pass,
    _Path,
)
from .types import Layout, Plan, PlanCell, PlanStats

__all__ = ["PlanOptions", "plan_region"]


# -- plans ------------------------------------------------------------------------------------
@dataclass(frozen=True)
class PlanOptions:
    """The options of :func:`plan_region`, checked (plan units; see its arguments)."""

    spacing: float
    reach: float
    turnaround: float = 0.0
    nadir_gap: float = 0.0
    turn_time: float = 0.0
    ground_scale: float = 1.0
    speed: float | None = None
    layout: Layout = "guaranteed"
    decompose_area: bool | Literal["auto"] = "auto"
    min_width: float = 0.0
    sweep: float | None = None
    angle: float | None = None
    offset: float | None = None
    fitness: Any = None
    n_angles: int = 90
    n_offsets: int = 16
    start: ArrayLike | None = None
    hole_passes: bool = True
    area: float | None = None
    merge_angle: float = math.radians(15.0)
    keep_inside: bool = False
    cells: tuple[tuple[Region, OptimizeResult], ...] | None = None
    order: str = "heuristic"


class _Cells(NamedTuple):
    """Step 2: the cells (or the whole area) and their optima (``None``: the given grid)."""

    regions: list[Region]
    optima: list[OptimizeResult | None]


class _CellLanes(NamedTuple):
    """Step 3: every cell with its grid and its lanes."""

    cells: list[PlanCell]
    lanes: list[Lanes]
    boundary: list[NDArray[np.float64]] | None = None  # keep_inside: the boundary passes
    uncovered: float = 0.0  # keep_inside: the area they could not cover (plan units)


class _Tour(NamedTuple):
    """Step 4: the passes (chains of lanes, hole passes), their order and driving options."""

    passes: list[_Pass]
    order: list[int]
    choice: list[int]
    router: Router
    solver: str | None = None  # how the order was found (None: greedy + 2-opt, not reported)


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
    keep_inside: bool = False,
    progress: bool | None = False,
    cells: Sequence[tuple[Region, OptimizeResult]] | None = None,
    order: str = "heuristic",
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
        keep_inside: no part of the path leaves the area or enters a hole: lanes are cut at
            the boundary, connecting moves follow the inside, and boundary passes (the contour
            half a spacing inside the edge, and patches over corners and thin parts) cover what
            the cut lanes leave (:mod:`boustro.plan.inside`; guaranteed layout; run-ins end at
            the boundary; no ``nadir_gap``). The passes replace the passes around holes.
        progress: a tqdm bar on stderr over the stages (optimisation of the cells, lanes,
            tour and routing, path); ``None``: if stderr is a terminal.
        cells: the cells to plan, each with its optimum (angle, offset from the cell's vertex
            mean), instead of deciding and optimising them (a decomposition chosen by the
            caller, e.g. :mod:`boustro.mission.decomposed`).
        order: how the passes are ordered: ``"heuristic"`` (default: greedy + 2-opt) or
            ``"auto"``, ``"exact"``, ``"or-tools"`` (:func:`boustro.plan.cell_order.solve_order`;
            the solver used is the plan's ``order_solver``).

    Returns:
        a :class:`~boustro.plan.Plan` with ``region``, ``cells``, per-transect angles and
        roles; its ``polygon`` is the shell.

    Raises:
        InvalidParameterError: bad parameters. NoTransectError: nothing to plan.

    Example:
        >>> from boustro.plan import coverage
        >>> u_shape = [(0, 0), (9, 0), (9, 9), (6, 9), (6, 3), (3, 3), (3, 9), (0, 9)]
        >>> plan = plan_region(u_shape, 1.0)
        >>> plan.stats.n_transects, round(coverage(plan).covered_share, 4)
        (12, 1.0)
    """
    r = as_region(region)
    opts = _check_options(
        r,
        spacing,
        decompose_area=decompose_area,
        sweep=sweep,
        angle=angle,
        offset=offset,
        fitness=fitness,
        n_angles=n_angles,
        n_offsets=n_offsets,
        layout=layout,
        start=start,
        turnaround=turnaround,
        reach=reach,
        nadir_gap=nadir_gap,
        hole_passes=hole_passes,
        ground_scale=ground_scale,
        speed=speed,
        turn_time=turn_time,
        area=area,
        min_width=min_width,
        merge_angle=merge_angle,
        keep_inside=keep_inside,
        cells=None if cells is None else tuple(cells),
        order=order,
    )
    notes: list[str] = []
    bar = _Stages(progress)
    with bar.stage("optimising the cells"):
        chosen = _plan_cells(r, opts, notes)
    with bar.stage("lanes"):
        cell_lanes = _plan_lanes(r, chosen, opts)
    with bar.stage("tour and routing"):
        tour = _plan_tour(r, cell_lanes, opts, notes)
    with bar.stage("path"):
        path = _drive(tour, cell_lanes, opts)
    bar.close()
    return _assemble(r, cell_lanes, tour, path, opts, notes)


class _Stages:
    """A bar over the named stages of :func:`plan_region` (nothing when not shown)."""

    def __init__(self, progress: bool | None) -> None:
        self.bar = _progress_bar(4, progress, "plan", unit="stage")

    @contextlib.contextmanager
    def stage(self, name: str) -> Iterator[None]:
        if self.bar is not None:
            self.bar.set_postfix_str(name)
        yield
        if self.bar is not None:
            self.bar.update(1)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


# -- step 1: check ----------------------------------------------------------------------------
def _check_options(r: Region, spacing: float, **kw: Any) -> PlanOptions:
    """The options checked, in the order the errors are reported."""
    s = check_spacing(spacing, extent=r.diameter)
    reach = s / 2 if kw["reach"] is None else _check_float("reach", kw["reach"])
    if reach < s / 2 * (1 - 1e-12):
        raise InvalidParameterError(
            f"reach must be >= spacing / 2 = {s / 2:g} for the bands to tile the area, "
            f"got {reach:g}"
        )
    turnaround = _check_float("turnaround", kw["turnaround"], 0.0)
    nadir_gap = _check_float("nadir_gap", kw["nadir_gap"], 0.0)
    turn_time = _check_float("turn_time", kw["turn_time"], 0.0)
    ground_scale = _check_float("ground_scale", kw["ground_scale"])
    if ground_scale <= 0:
        raise InvalidParameterError(f"ground_scale must be > 0, got {kw['ground_scale']!r}")
    speed = kw["speed"]
    if speed is not None and _check_float("speed", speed) <= 0:
        raise InvalidParameterError(f"speed must be > 0, got {speed!r}")
    layout = kw["layout"]
    if layout not in ("guaranteed", "chords"):
        raise InvalidParameterError(f"layout must be 'guaranteed' or 'chords', got {layout!r}")
    if nadir_gap > 0 and r.n_holes and kw["hole_passes"] and layout == "guaranteed":
        raise InvalidParameterError(
            "a nadir gap is not supported with holes: the passes around holes would not cover "
            "their own blind strip"
        )
    if kw["decompose_area"] not in (True, False, "auto"):
        raise InvalidParameterError(
            f"decompose_area must be True, False or 'auto', got {kw['decompose_area']!r}"
        )
    if kw["keep_inside"] not in (True, False):
        raise InvalidParameterError(f"keep_inside must be True or False, got {kw['keep_inside']!r}")
    if kw["keep_inside"] and nadir_gap > 0:
        raise InvalidParameterError(
            "keep_inside (--keep-inside) does not take a nadir gap: the boundary passes would "
            "not cover their own blind strip"
        )
    if kw["order"] not in ("heuristic", "auto", "exact", "or-tools"):
        raise InvalidParameterError(
            f"order must be 'heuristic', 'auto', 'exact' or 'or-tools', got {kw['order']!r}"
        )
    min_width = kw["min_width"]
    min_width = 2 * s if min_width is None else _check_float("min_width", min_width, 0.0)
    kw.update(
        spacing=s,
        reach=reach,
        turnaround=turnaround,
        nadir_gap=nadir_gap,
        turn_time=turn_time,
        ground_scale=ground_scale,
        min_width=min_width,
    )
    return PlanOptions(**kw)


# -- step 2: cells ----------------------------------------------------------------------------
def _plan_cells(r: Region, opts: PlanOptions, notes: list[str]) -> _Cells:
    """The cells and their optima: the whole area, or its decomposition where that promises
    fewer turns (or on a tie less lane length); a given ``angle`` is planned as it is."""
    s = opts.spacing
    options = {"n_angles": opts.n_angles, "n_offsets": opts.n_offsets, "fitness": opts.fitness}
    whole = _Cells([r], [None])
    if opts.cells is not None:
        return _Cells([c for c, _ in opts.cells], [o for _, o in opts.cells])
    if opts.angle is not None:
        return whole
    optima: list[OptimizeResult | None] = [optimize_region(r, s, **options)]
    whole = _Cells([r], optima)
    if not opts.decompose_area or r.is_convex:
        return whole
    if opts.sweep is None:
        sweep_angle, estimate = choose_sweep(
            r, s, min_width=opts.min_width, merge_angle=opts.merge_angle, fitness=opts.fitness
        )
    else:
        sweep_angle, estimate = _check_float("sweep", opts.sweep), (-math.inf, -math.inf)
    single = _estimate([r], optima, s)  # type: ignore[arg-type]
    if not (opts.decompose_area is True or estimate < single):
        return whole
    try:
        cell_regions, cells_opt = _cells_for_sweep(
            r,
            s,
            sweep_angle,
            min_width=opts.min_width,
            merge_angle=opts.merge_angle,
            options=options,
        )
    except InvalidPolygonError as exc:
        notes.append(f"the decomposition failed ({exc}); the area is planned as one cell")
        return whole
    if len(cell_regions) > 1 and (
        opts.decompose_area is True or _estimate(cell_regions, cells_opt, s) < single
    ):
        return _Cells(cell_regions, list(cells_opt))
    return whole  # one cell after all: the whole area, as planned without decomposition


# -- step 3: lanes ----------------------------------------------------------------------------
def _plan_lanes(r: Region, cells: _Cells, opts: PlanOptions) -> _CellLanes:
    """The lanes of every cell at its angle and offset (the optimum, or the given grid); with
    ``keep_inside`` (the guaranteed layout) cut inside the area, with its boundary passes."""
    out = _laid_lanes(r, cells, opts)
    if opts.keep_inside and opts.layout == "guaranteed":
        cut, boundary, uncovered = inside_layout(r, out.lanes, opts.spacing, opts.reach)
        counted = [
            dataclasses.replace(c, n_transects=len(ls.k))
            for c, ls in zip(out.cells, cut, strict=True)
        ]
        return _CellLanes(counted, cut, boundary, uncovered)
    return out


def _laid_lanes(r: Region, cells: _Cells, opts: PlanOptions) -> _CellLanes:
    """The lanes of every cell at its angle and offset, as laid (not cut inside the area)."""
    out = _CellLanes([], [])
    for cell, opt in zip(cells.regions, cells.optima, strict=True):
        if opt is None:
            cell_angle = _check_float("angle", opts.angle)
            cell_offset = 0.0 if opts.offset is None else _check_float("offset", opts.offset)
            value = math.nan
        else:
            cell_angle, cell_offset, value = opt.angle, opt.offset, opt.fitness
        lanes = _region_lanes(cell, cell_angle, cell_offset, r.holes, opts)
        out.lanes.append(lanes)
        out.cells.append(PlanCell(cell, cell_angle, cell_offset, value, len(lanes.k), opt))
    if sum(len(lanes.k) for lanes in out.lanes) == 0:
        raise NoTransectError(f"no lane crosses the area at spacing {opts.spacing:g}")
    return out


#: :func:`region_lanes` results kept for ``keep_inside`` plans (keyed by every number it
#: reads): a search's screen (:func:`~boustro.plan.region_floor.plan_floor`) lays a layout's
#: lanes, and the plan of a layout that passes it lays the same again.
LANES_CACHE = 8
_LANES: dict[bytes, Lanes] = {}


def _region_lanes(
    cell: Region, angle: float, offset: float, holes: Sequence[Polygon], opts: PlanOptions
) -> Lanes:
    """:func:`region_lanes` of the cell (the area's ``holes`` avoided), from the cache of the
    last :data:`LANES_CACHE` calls with ``keep_inside`` (the arrays are the same, never
    written: :func:`~boustro.plan.inside.inside_layout` cuts new ones)."""

    def lay() -> Lanes:
        return region_lanes(
            cell, opts.spacing, angle, offset, reach=opts.reach, holes=holes, layout=opts.layout
        )

    if not opts.keep_inside:
        return lay()
    rings = [cell.shell.vertices, *(h.vertices for h in cell.holes), *(h.vertices for h in holes)]
    parts = [np.ascontiguousarray(v, dtype=np.float64).tobytes() for v in rings]
    numbers = [len(cell.holes), len(holes), opts.spacing, angle, offset, opts.reach]
    parts.append(np.array(numbers, dtype=np.float64).tobytes())
    return remember(_LANES, bytes_key(parts) + opts.layout.encode(), LANES_CACHE, lay)


# -- step 4: tour -----------------------------------------------------------------------------
def _plan_tour(r: Region, cl: _CellLanes, opts: PlanOptions, notes: list[str]) -> _Tour:
    """Chains of lanes and hole passes, ordered from the start (or where the tour is shortest)."""
    tol = _TOL * r.diameter
    passes: list[_Pass] = []
    for ci, lanes in enumerate(cl.lanes):
        for chain in _chains(lanes, tol):
            passes.append(_chain_pass(lanes, chain, ci))
    cut = set().union(*(lanes.cut for lanes in cl.lanes))
    if opts.keep_inside:
        passes += [_boundary_pass(line) for line in cl.boundary or []]
        if cl.uncovered > 0:
            notes.append(
                f"{cl.uncovered / opts.ground_scale**2:.6g} m2 near the boundary is not covered: "
                "more slivers than boundary patches allowed"
            )
    elif opts.layout == "guaranteed" and opts.hole_passes:
        passes += [_hole_pass(r.holes[hi]) for hi in _flown_holes(cl.lanes, opts)]
    elif cut and opts.layout == "guaranteed":
        notes.append(
            f"{len(cut)} hole(s) cut lanes and hole passes are off: the area along their edges "
            "is not fully covered"
        )
    router = router_for(r, 0.0 if opts.keep_inside else float(max(opts.reach, opts.turnaround)))
    start = opts.start
    if start is None:
        start_pt = r.shell.vertices[0]
    else:
        start_pt = np.asarray(start, dtype=np.float64).reshape(-1)
        if start_pt.shape != (2,) or not np.all(np.isfinite(start_pt)):
            raise InvalidParameterError(f"start must be a finite (x, y) pair, got {start!r}")
    forced = start is not None
    solver: str | None = None  # greedy + 2-opt, not reported
    if opts.order == "heuristic":
        tours = _orders(passes, start_pt, router, force_start=forced)
    else:
        order, choice, solver, said = solve_order(
            passes, start_pt, router, force_start=forced, solver=opts.order
        )
        tours = [(order, choice)]
        notes.extend(said)
    run = (opts.turnaround, opts.keep_inside)  # the lanes' run-ins and run-outs
    passes, order, choice = refine_best(passes, tours, start_pt, router, forced, *run, refine_tour)
    return _Tour(passes, order, choice, router, solver)


def _flown_holes(lanes: Sequence[Lanes], opts: PlanOptions) -> list[int]:
    """The holes (indices into the area's, ascending) whose pass a plan without ``keep_inside``
    flies (:func:`_plan_tour`): every hole that cuts one of ``lanes``, with the guaranteed
    layout and hole passes on; none otherwise. Also the rings of
    :func:`~boustro.plan.region_floor.plan_floor`'s floor of such a plan."""
    if opts.keep_inside or opts.layout != "guaranteed" or not opts.hole_passes:
        return []
    return sorted(set().union(*(ls.cut for ls in lanes)))


# -- step 5: drive ----------------------------------------------------------------------------
def _drive(tour: _Tour, cl: _CellLanes, opts: PlanOptions) -> _Path:
    """The waypoints of the tour: every pass in order, joined by connecting moves."""
    driver = _Driver(tour.router, opts.turnaround, opts.keep_inside)
    for pi, oi in zip(tour.order, tour.choice, strict=True):
        p = tour.passes[pi]
        _, _, pts, _ = p.options[oi]
        if p.kind == "chain":
            driver.chain(pts, p.angle, p.cell, cl.lanes[p.cell].origin)
        elif p.kind == "boundary":
            driver.boundary(pts)
        else:
            driver.hole(pts)
    return driver.result()


# -- step 6: assemble -------------------------------------------------------------------------
#: The start of a plan's note on a move the router found no way for inside the area (it flies
#: the straight line, through a hole or outside the area).
BLOCKED_NOTE = "no connecting move inside the area"
#: The start of a keep-inside plan's note on a path that leaves the area (never seen).
OUTSIDE_NOTE = "keep_inside: "


def _assemble(
    r: Region, cl: _CellLanes, tour: _Tour, path: _Path, opts: PlanOptions, notes: list[str]
) -> Plan:
    """The :class:`Plan` with its statistics (ground units) and notes."""
    tr = path.transects
    lane_role = np.array(path.roles) == "lane"
    transect_length = float(np.linalg.norm(tr[:, 1] - tr[:, 0], axis=1)[lane_role].sum())
    path_length = float(np.linalg.norm(np.diff(path.waypoints, axis=0), axis=1).sum())
    n_lanes = int(lane_role.sum())
    n_turns = n_lanes + sum(1 for p in tour.passes if p.kind != "chain") - 1  # passes - 1
    for a, b in path.blocked:
        notes.append(
            f"{BLOCKED_NOTE} from {a.round(3).tolist()} to "
            f"{b.round(3).tolist()}: the straight line is used"
        )
    scale = opts.ground_scale
    outside = outside_length(path.waypoints, r)
    if opts.keep_inside and outside > 0:  # never seen; said rather than hidden
        notes.append(f"{OUTSIDE_NOTE}{outside / scale:.6g} m of the path leaves the area")
    speed = opts.speed
    duration = None if speed is None else path_length / scale / speed + n_turns * opts.turn_time
    cells = cl.cells
    stats = PlanStats(
        n_transects=n_lanes,
        n_turns=n_turns,
        transect_length=transect_length / scale,
        path_length=path_length / scale,
        area=r.area / scale**2 if opts.area is None else float(opts.area),
        speed=speed,
        turn_time=opts.turn_time,
        duration=duration,
        n_cells=len(cells),
        hole_pass_length=path.hole_length / scale,
        outside_length=outside / scale,
        boundary_pass_length=path.boundary_length / scale,
    )
    main = max(range(len(cells)), key=lambda i: cells[i].polygon.area)
    return Plan(
        polygon=r.shell,
        spacing=opts.spacing,
        angle=cells[main].angle,
        offset=cells[main].offset,
        layout=opts.layout,
        reach=float(opts.reach),
        nadir_gap=opts.nadir_gap,
        turnaround=opts.turnaround,
        positions=path.positions,
        transects=tr,
        waypoints=path.waypoints,
        kinds=path.kinds,
        lane=path.lane,
        ground_scale=scale,
        stats=stats,
        region=r,
        cells=tuple(cells),
        transect_angles=path.angles,
        roles=path.roles,
        transect_cells=path.cells,
        notes=tuple(notes),
        keep_inside=opts.keep_inside,
        order_solver=tour.solver,
    )
