"""The mission facade: a survey area planned end to end (project, plan, map back)."""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import (
    InvalidParameterError,
    InvalidPolygonError,
    NonConvexPolygonError,
    ProblemTooLargeError,
    as_number,
)
from .geometry import Polygon
from .geometry.region import Region
from .io.crs import Projection, check_lonlat, parse_crs, projection_for
from .io.read import LONLAT, Area
from .objectives.smith import SmithFitness
from .optimize import OptimizeResult, optimize
from .plan import Coverage, Plan, PlanStats, build_plan, coverage, nearly_convex
from .plan.region import plan_region
from .sensors import SensorSpacing

__all__ = [
    "DEFAULT_HULL_TOLERANCE",
    "DEFAULT_METHOD",
    "FALLBACK_METHOD",
    "METHOD_OPTIONS",
    "REGION_OPTIONS",
    "Mission",
    "plan_area",
]


log = logging.getLogger("boustro")

#: The optimiser :func:`plan_area` uses unless told otherwise, and the options it passes to each
#: method. Switching the default is this one line.
DEFAULT_METHOD = "global"
#: Used instead of the default when the global optimiser would take too long (many vertices at a
#: small spacing; :data:`boustro.global_opt.WORK_LIMIT`).
FALLBACK_METHOD = "hybrid"
METHOD_OPTIONS: dict[str, dict[str, Any]] = {"grid": {"n_angles": 360, "n_offsets": 32}}

#: Deepest pocket (metres) of a nearly convex area that is planned on its convex hull.
DEFAULT_HULL_TOLERANCE = 0.5

#: Grid of the optimiser for concave areas and areas with holes
#: (:func:`boustro.plan.optimize_region`; a cell or the whole area), overridden by
#: ``options``.
REGION_OPTIONS: dict[str, Any] = {"n_angles": 90, "n_offsets": 16}


@dataclass(frozen=True)
class Mission:
    """A plan over a real area: the plan frame's :class:`~boustro.plan.Plan` and its coordinates.

    Attributes:
        name: the area's name.
        area: the area as read (source coordinates).
        projection: source CRS <-> plan frame.
        plan: the plan in the plan frame (its statistics in metres, or planar units).
        optimum: the optimiser's answer, in the plan frame.
        spacing: the spacing asked for, ground metres (planar units for planar input).
        reach, nadir_gap: the band half-width each transect covers and the sensor's blind strip,
            ground metres.
        turnaround: run-in / run-out distance asked for, metres.
        hull_depth: for a nearly convex area planned on its convex hull, the depth of the deepest
            pocket (how far transects may leave the area), metres; 0 for a convex area.
        altitude: mission altitude above the take-off point, metres, if known.
        coverage: coverage of the area (not the hull) by the plan's footprints, or ``None``.
        sensor: description of the sensor the spacing came from, if any.
        waypoints: ``(W, 2)`` in the area's coordinates; ``kinds`` as in the plan.
        transects: ``(T, 2, 2)`` in the area's coordinates, driving order.
        waypoints_lonlat, transects_lonlat, area_lonlat: the same in WGS 84 longitude/latitude,
            ``None`` for planar input.
        bearing: direction of the transects, degrees clockwise from true north in ``[0, 180)``
            (from grid north +y for planar input).
        home, home_lonlat: the take-off / home position: the ``start`` point if given, else the
            first waypoint (area coordinates; WGS 84, ``None`` for planar input).
    """

    name: str
    area: Area
    projection: Projection
    plan: Plan
    optimum: OptimizeResult
    spacing: float
    reach: float
    nadir_gap: float
    turnaround: float
    hull_depth: float
    altitude: float | None
    coverage: Coverage | None
    sensor: str | None
    waypoints: NDArray[np.float64]
    transects: NDArray[np.float64]
    waypoints_lonlat: NDArray[np.float64] | None
    transects_lonlat: NDArray[np.float64] | None
    area_lonlat: NDArray[np.float64] | None
    bearing: float
    home: NDArray[np.float64]
    home_lonlat: NDArray[np.float64] | None
    holes_lonlat: tuple[NDArray[np.float64], ...] = ()

    @property
    def crs(self) -> str | None:
        return self.area.crs

    @property
    def decomposed(self) -> bool:
        """True for a plan over several cells."""
        return len(self.plan.cells) > 1

    def cell_rings(self) -> list[list[NDArray[np.float64]]]:
        """Each cell's rings (outer boundary, then holes) in the area's coordinates."""
        out = []
        for cell in self.plan.cells:
            region = cell.region
            out.append(
                [self.projection.to_source(region.shell.vertices)]
                + [self.projection.to_source(h.vertices) for h in region.holes]
            )
        return out

    @property
    def kinds(self) -> tuple[str, ...]:
        return self.plan.kinds

    @property
    def stats(self) -> PlanStats:
        return self.plan.stats

    def summary(self) -> dict[str, Any]:
        """Plain-JSON summary of the mission (no waypoints), for files and ``--json``."""
        s = self.stats
        out: dict[str, Any] = {
            "name": self.name,
            "crs": self.crs,
            "plan_crs": self.projection.plan_crs,
            "spacing_m": self.spacing,
            "bearing_deg": self.bearing,
            "angle_deg": math.degrees(self.plan.angle),
            "offset": self.plan.offset,
            "method": self.optimum.method,
            "fitness": self.optimum.fitness,
            "layout": self.plan.layout,
            "n_transects": s.n_transects,
            "n_turns": s.n_turns,
            "transect_length_m": s.transect_length,
            "path_length_m": s.path_length,
            "area_m2": s.area,
            "turnaround_m": self.turnaround,
            "hull_depth_m": self.hull_depth,
        }
        if s.duration is not None:
            out.update(speed_m_s=s.speed, turn_time_s=s.turn_time, duration_s=s.duration)
        if self.altitude is not None:
            out["altitude_m"] = self.altitude
        if self.coverage is not None:
            out["covered_share"] = self.coverage.covered_share
            out["overlap_share"] = self.coverage.overlap_share
        if self.nadir_gap:
            out["nadir_gap_m"] = self.nadir_gap
            out["reach_m"] = self.reach
        if self.sensor:
            out["sensor"] = self.sensor
        if self.plan.region is not None:
            out["holes"] = self.plan.region.n_holes
            out["n_cells"] = s.n_cells
            out["cells"] = [
                {
                    "angle_deg": math.degrees(c.angle),
                    "offset": c.offset,
                    "fitness": None if math.isnan(c.fitness) else c.fitness,
                    "n_transects": c.n_transects,
                    "area_m2": c.region.area / self.plan.ground_scale**2,
                }
                for c in self.plan.cells
            ]
            out["hole_pass_length_m"] = s.hole_pass_length
            out["outside_length_m"] = s.outside_length
            if self.plan.notes:
                out["notes"] = list(self.plan.notes)
        return out


def _sensor_spacing(spacing: Any) -> tuple[float, float, float, float | None, str | None]:
    """(spacing, reach, nadir gap, altitude, description) from a number or a sensor."""
    if hasattr(spacing, "spacing") and callable(spacing.spacing):
        spacing = spacing.spacing()
    if isinstance(spacing, SensorSpacing):
        return (
            spacing.spacing,
            spacing.reach,
            spacing.nadir_gap,
            spacing.altitude,
            (spacing.description),
        )
    try:
        s = float(spacing)
    except (TypeError, ValueError):
        raise InvalidParameterError(
            f"spacing must be a number of metres or a sensor, got {spacing!r}"
        ) from None
    if not math.isfinite(s) or s <= 0:
        raise InvalidParameterError(f"spacing must be a finite number > 0, got {spacing!r}")
    return s, s / 2, 0.0, None, None


def plan_area(
    area: Area | ArrayLike,
    spacing: float | SensorSpacing | Any,
    *,
    crs: str | None = LONLAT,
    method: str | None = None,
    fitness: SmithFitness | Any | None = None,
    options: dict[str, Any] | None = None,
    start: ArrayLike | None = None,
    turnaround: float = 0.0,
    speed: float | None = None,
    turn_time: float = 0.0,
    altitude: float | None = None,
    hull_tolerance: float = DEFAULT_HULL_TOLERANCE,
    layout: str = "guaranteed",
    check_coverage: bool = True,
    holes: Sequence[ArrayLike] = (),
    decompose: bool | None = None,
    sweep: float | None = None,
) -> Mission:
    """Plan a survey area end to end: project, optimise, build the path, map it back.

    Args:
        area: an :class:`~boustro.io.Area` (from :func:`boustro.io.read_area`), or an ``(N, 2)``
            ring in ``crs``.
        spacing: metres on the ground (planar units for planar input), or a sensor
            (:class:`~boustro.sensors.Camera`, :class:`~boustro.sensors.Swath`, or their
            :class:`~boustro.sensors.SensorSpacing`).
        crs: CRS of a bare ring (ignored for an :class:`Area`, which carries its own); default
            WGS 84 longitude/latitude, ``None`` for planar.
        method: optimiser (default :data:`DEFAULT_METHOD`), see :func:`boustro.optimize.optimize`;
            ``options`` override :data:`METHOD_OPTIONS`. Concave areas and areas with holes
            are optimised by :func:`boustro.plan.optimize_region` (a grid search with the
            exact per-segment fitness, :data:`REGION_OPTIONS`, ``options`` override it).
        fitness: the objective (default Eq. 1).
        start: ``(x, y)`` in the area's coordinates; the path starts at the corner nearest it
            (default: the area's first vertex).
        turnaround: run-in / run-out distance beyond each transect end, metres.
        speed: ground speed, m/s, for the duration; ``turn_time``: seconds per turn.
        altitude: mission altitude above take-off, metres (default: the camera's, if any).
        hull_tolerance: a concave area without holes whose convex hull reaches at most this many
            metres beyond it is planned on its hull (its pockets are digitising noise), unless
            ``decompose`` is given; a deeper one is planned as a concave area.
        layout: ``"guaranteed"`` (default) or ``"chords"`` (see :func:`boustro.plan.build_plan`).
        check_coverage: compute the covered share with shapely.
        holes: holes of a bare ring (an :class:`Area` carries its own), in ``crs``.
        decompose: for a concave area or one with holes: ``None`` (default) decomposes into
            cells when that promises fewer turns, ``True`` always, ``False`` plans one angle
            with lines cut at the boundary and the holes (:func:`boustro.plan.plan_region`).
            Given, it also turns off the convex-hull rule for nearly convex areas.
        sweep: sweep direction of the decomposition, degrees in the plan frame (default:
            chosen by :func:`boustro.plan.choose_sweep`).

    Raises:
        InvalidPolygonError, NonConvexPolygonError, InvalidParameterError, NoTransectError.

    Example:
        >>> from boustro.io import embedded_field
        >>> mission = plan_area(embedded_field(), 10.0)
        >>> mission.plan.stats.n_transects, round(mission.bearing, 2)
        (19, 68.43)
    """
    area = _as_area(area, crs, holes)
    sensor = _Sensor(*_sensor_spacing(spacing))
    frame = _project(area, sensor, hull_tolerance, decompose, start)
    if frame.region is None:
        planned = _plan_convex(
            frame,
            method=method,
            fitness=fitness,
            options=options,
            layout=layout,
            turnaround=turnaround,
            speed=speed,
            turn_time=turn_time,
            check_coverage=check_coverage,
        )
    else:
        planned = _plan_concave(
            frame,
            method=method,
            fitness=fitness,
            options=options,
            layout=layout,
            turnaround=turnaround,
            speed=speed,
            turn_time=turn_time,
            check_coverage=check_coverage,
            decompose=decompose,
            sweep=sweep,
        )
    return _map_back(frame, planned, altitude=altitude, turnaround=turnaround)


class _Sensor(NamedTuple):
    """The spacing and footprint asked for, on the ground (metres, or planar units)."""

    spacing: float
    reach: float
    nadir_gap: float
    altitude: float | None
    text: str | None


class _Frame(NamedTuple):
    """Step 1: the area projected into the plan frame, with what the plan needs."""

    area: Area
    sensor: _Sensor
    proj: Projection
    ring: NDArray[np.float64]
    holes: list[NDArray[np.float64]]
    surveyed: Polygon
    poly: Polygon
    region: Region | None
    depth: float
    start: NDArray[np.float64]
    given_start: bool
    ground_area: float


class _Planned(NamedTuple):
    """Step 2: the plan (plan frame), its optimum and its coverage."""

    plan: Plan
    optimum: OptimizeResult
    coverage: Coverage | None


def _as_area(area: Area | ArrayLike, crs: str | None, holes: Sequence[ArrayLike]) -> Area:
    """An :class:`Area` with one spelling of its CRS ("EPSG:n", or None for planar)."""
    if not isinstance(area, Area):
        hole_rings = tuple(np.asarray(h, dtype=np.float64) for h in holes)
        return Area(np.asarray(area, dtype=np.float64), parse_crs(crs), "", "<array>", hole_rings)
    return dataclasses.replace(area, crs=parse_crs(area.crs))


# -- step 1: project --------------------------------------------------------------------------
def _project_holes(area: Area, proj: Projection) -> list[NDArray[np.float64]]:
    """The holes in the plan frame, checked."""
    where = area.source
    holes_plan = []
    for i, hole in enumerate(area.holes):
        if proj.geographic:
            check_lonlat(proj.to_lonlat(proj.to_plan(hole)), f"{where}: hole {i}")
        hp = proj.to_plan(hole)
        if not np.all(np.isfinite(hp)):
            raise InvalidPolygonError(f"{where}: hole {i} cannot be projected to {proj.plan_crs}")
        holes_plan.append(hp)
    if holes_plan and proj.geographic:
        # Validate the holes in the file's own coordinates too: a hole edge lying on the shell
        # in the file (touching it) can come out a fraction of a millimetre inside it after the
        # projection, above the tolerance, and would pass; messages then name the file's values.
        try:
            Region(Polygon(area.ring), [np.asarray(h, dtype=np.float64) for h in area.holes])
        except InvalidPolygonError as exc:
            raise InvalidPolygonError(f"{where}: {exc} (in the file's coordinates)") from None
    return holes_plan


def _project(
    area: Area,
    sensor: _Sensor,
    hull_tolerance: float,
    decompose: bool | None,
    start: ArrayLike | None,
) -> _Frame:
    """Project the area, decide convex (possibly its hull) or region, place the start."""
    where = area.source
    proj = projection_for(area.ring, area.crs, where)
    ring_plan = proj.to_plan(area.ring)
    holes_plan = _project_holes(area, proj)
    try:
        surveyed = Polygon(ring_plan)
        region = Region(surveyed, holes_plan) if holes_plan else None
    except InvalidPolygonError as exc:
        raise InvalidPolygonError(f"{where}: {exc}") from None
    k_lo = proj.scale_min
    depth = 0.0
    poly = surveyed
    if region is None and (decompose is None or surveyed.is_convex):
        try:
            poly, depth = nearly_convex(surveyed, float(hull_tolerance) * k_lo)
        except NonConvexPolygonError:
            region = Region(surveyed)
    elif region is None:
        region = Region(surveyed)
    if depth > 0:
        log.debug(
            "the area is not convex, but its convex hull reaches only %.3g m beyond it: "
            "planning the hull",
            depth / k_lo,
        )
    start_plan = ring_plan[0] if start is None else proj.to_plan(np.asarray(start, float))
    if start is not None:
        _warn_far_start(ring_plan, start_plan, k_lo)
    ground_area = proj.ground_area(ring_plan) - sum(proj.ground_area(h) for h in holes_plan)
    return _Frame(
        area=area,
        sensor=sensor,
        proj=proj,
        ring=ring_plan,
        holes=holes_plan,
        surveyed=surveyed,
        poly=poly,
        region=region,
        depth=depth,
        start=start_plan,
        given_start=start is not None,
        ground_area=ground_area,
    )


def _warn_far_start(ring: NDArray[np.float64], start: NDArray[np.float64], k_lo: float) -> None:
    far = float(np.min(np.hypot(*(ring - start).T))) / k_lo
    size = float(np.max(np.hypot(*(ring - ring.mean(axis=0)).T))) * 2 / k_lo
    if far > 10 * size:
        log.warning(
            "the start is %.3g m from the area, %.0f times its size: swapped longitude and "
            "latitude?",
            far,
            far / size,
        )


# -- step 2: plan -----------------------------------------------------------------------------
def _path_options(frame: _Frame, turnaround: float, speed: Any, turn_time: float) -> dict:
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


def _plan_convex(
    frame: _Frame,
    *,
    method: str | None,
    fitness: Any,
    options: dict[str, Any] | None,
    layout: str,
    turnaround: float,
    speed: float | None,
    turn_time: float,
    check_coverage: bool,
) -> _Planned:
    """A convex area (or the hull of a nearly convex one): optimise, then build the plan."""
    s_plan = frame.sensor.spacing * frame.proj.scale_min
    chosen = method or DEFAULT_METHOD
    opts = dict(METHOD_OPTIONS.get(chosen, {}))
    opts.update(options or {})
    try:
        optimum = optimize(frame.poly, s_plan, method=chosen, fitness=fitness, **opts)
    except ProblemTooLargeError as exc:
        if method is not None:
            raise
        log.warning("%s; planning with the hybrid optimiser instead", exc)
        optimum = optimize(frame.poly, s_plan, method=FALLBACK_METHOD, fitness=fitness)
    plan = build_plan(
        frame.poly,
        s_plan,
        optimum.angle,
        optimum.offset,
        layout=layout,  # type: ignore[arg-type]
        start=frame.start,
        **_path_options(frame, turnaround, speed, turn_time),
    )
    cov = coverage(plan, frame.surveyed) if check_coverage else None
    return _Planned(plan, optimum, cov)


def _plan_concave(
    frame: _Frame,
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
) -> _Planned:
    """A concave area or one with holes: cells, lanes and a tour (:func:`plan_region`)."""
    if method not in (None, DEFAULT_METHOD, "grid", "region-grid"):
        raise InvalidParameterError(
            f"method {method!r} optimises convex areas only; a concave area or one with "
            "holes is optimised by grid search over its segments (leave --method out)"
        )
    s_plan = frame.sensor.spacing * frame.proj.scale_min
    opts = dict(REGION_OPTIONS)
    opts.update({k: v for k, v in (options or {}).items() if k in ("n_angles", "n_offsets")})
    plan = plan_region(
        frame.region,  # type: ignore[arg-type]
        s_plan,
        decompose_area="auto" if decompose is None else bool(decompose),
        sweep=None if sweep is None else math.radians(float(sweep)),
        fitness=fitness,
        layout=layout,  # type: ignore[arg-type]
        start=frame.start if frame.given_start else None,  # None: the shortest tour
        **_path_options(frame, turnaround, speed, turn_time),
        **opts,
    )
    optimum = _region_optimum(plan, s_plan)
    cov = coverage(plan, frame.region) if check_coverage else None
    return _Planned(plan, optimum, cov)


# -- step 3: map back -------------------------------------------------------------------------
def _bearing(frame: _Frame, plan: Plan) -> float:
    """The transects' bearing, degrees clockwise from north (from the plan frame's y axis)."""
    u = np.array([math.cos(plan.angle), math.sin(plan.angle)])
    if frame.proj.planar:
        return math.degrees(math.atan2(u[0], u[1])) % 180.0
    main = plan.cells[_main_cell(plan)].polygon if frame.region is not None else frame.poly
    c = main.centre
    a, b = frame.proj.to_lonlat(np.stack([c - 5 * u, c + 5 * u]))
    azimuth, _, _ = frame.proj._geod.inv(a[0], a[1], b[0], b[1])
    return float(azimuth) % 180.0


def _map_back(
    frame: _Frame, planned: _Planned, *, altitude: float | None, turnaround: float
) -> Mission:
    """The :class:`Mission`: the plan's coordinates in the area's CRS and in lon/lat."""
    proj, plan, sensor = frame.proj, planned.plan, frame.sensor
    bearing = _bearing(frame, plan)
    if altitude is None:
        altitude = sensor.altitude
    else:
        value = as_number("altitude", altitude)
        if not (math.isfinite(value) and value >= 0):
            raise InvalidParameterError(
                f"altitude must be a finite number >= 0 (metres above take-off), got {altitude!r}"
            )
    home_plan = frame.start if frame.given_start else plan.waypoints[0]
    lonlat = None if proj.planar else proj.to_lonlat
    return Mission(
        name=frame.area.name,
        area=frame.area,
        projection=proj,
        plan=plan,
        optimum=planned.optimum,
        spacing=sensor.spacing,
        reach=sensor.reach,
        nadir_gap=sensor.nadir_gap,
        turnaround=float(turnaround),
        hull_depth=frame.depth / proj.scale_min,
        altitude=None if altitude is None else float(altitude),
        coverage=planned.coverage,
        sensor=sensor.text,
        waypoints=proj.to_source(plan.waypoints),
        transects=proj.to_source(plan.transects),
        waypoints_lonlat=None if lonlat is None else lonlat(plan.waypoints),
        transects_lonlat=None if lonlat is None else lonlat(plan.transects),
        area_lonlat=None if lonlat is None else lonlat(frame.ring),
        bearing=bearing,
        home=proj.to_source(home_plan),
        home_lonlat=None if lonlat is None else lonlat(home_plan),
        holes_lonlat=() if lonlat is None else tuple(lonlat(h) for h in frame.holes),
    )


def _main_cell(plan: Plan) -> int:
    return max(range(len(plan.cells)), key=lambda i: plan.cells[i].region.area)


def _region_optimum(plan: Plan, spacing: float) -> OptimizeResult:
    """One :class:`OptimizeResult` for a plan of cells: the largest cell's angle and offset,
    the area-weighted mean of the cells' fitness, the evaluations and time of all of them."""
    cells = plan.cells
    results = [c.optimum for c in cells if c.optimum is not None]
    areas = np.array([c.region.area for c in cells])
    values = np.array([c.fitness for c in cells])
    ok = np.isfinite(values)
    fitness = float(np.sum(values[ok] * areas[ok]) / np.sum(areas[ok])) if ok.any() else math.nan
    main = cells[_main_cell(plan)]
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
