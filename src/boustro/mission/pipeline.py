"""Planning a survey area end to end: :func:`plan_area` (project, plan, map back)."""

from __future__ import annotations

import dataclasses
import math
import sys
from collections.abc import Callable, Sequence
from typing import Any

from numpy.typing import ArrayLike

from .._validate import as_number
from ..errors import InvalidParameterError
from ..geometry.region import Region
from ..io.read import Area
from ..objectives.smith import SmithFitness
from ..objectives.time import MissionTime
from ..optimize.cover import CoverCost
from ..optimize.cover.u_turns import UTurns
from ..optimize.methods import resolve_method
from ..plan import (
    Plan,
    add_headland,
    check_headland,
    coverage,
    drive_vehicle,
    inner_field,
    order_lanes,
    vehicle_stats,
)
from ..plan.lane_tour import refinement
from ..plan.outside import with_outside_length
from ..sensors import SensorSpacing
from ..vehicle import Vehicle
from .camera import camera_trigger, with_camera
from .cover import cover_cost, flown_cost, plan_cover
from .decomposed import MAX_CELLS, plan_decomposed
from .defaults import DEFAULT_HULL_TOLERANCE
from .estimate import SAY_SECONDS, WorkEstimate, check_work, frame_estimate
from .map_back import angle_for_bearing, map_back
from .options import check_turn_time
from .project import AUTO_CRS, MAX_SPACING, Frame, Sensor, as_area, project, sensor_spacing
from .steps import Planned, plan_concave, plan_convex
from .types import Mission

__all__ = ["MAX_SPACING", "estimate_work", "plan_area"]


def plan_area(
    area: Area | ArrayLike | Any,
    spacing: float | SensorSpacing | Any,
    *,
    crs: str | None = AUTO_CRS,
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
    angle: float | None = None,
    bearing: float | None = None,
    force: bool = False,
    keep_inside: bool = False,
    progress: bool | None = False,
    vehicle: Vehicle | None = None,
    headland: int = 0,
) -> Mission:
    """Plan a survey area end to end: project, optimise, build the path, map it back.

    Args:
        area: an :class:`~boustro.io.Area` (from :func:`boustro.io.read_area`), an ``(N, 2)``
            ring in ``crs``, or a geometry object: a shapely Polygon (or a MultiPolygon of one
            part), any object with ``__geo_interface__``, a GeoJSON geometry, Feature or
            FeatureCollection mapping (:mod:`boustro.io.read_objects`). Several polygons are
            several fields: refused, plan each of :func:`boustro.io.areas_from_object`.
        spacing: metres on the ground (planar units for planar input), or a sensor
            (:class:`~boustro.sensors.Camera`, :class:`~boustro.sensors.Swath`, or their
            :class:`~boustro.sensors.SensorSpacing`). An area narrower than the spacing in every
            direction (spacing >= its diameter) gets one lane along its diameter, planned by
            the region planner whatever ``method`` (its fitness is undefined: NaN).
        crs: CRS of a bare ring or a geometry object (ignored for an :class:`Area`, which
            carries its own); ``None`` for planar. The default ``"auto"``: WGS 84
            longitude/latitude for a bare ring, PLANAR for a geometry object (it carries no
            CRS; a GeoJSON mapping's ``crs`` member is used if it has one).
        method: optimiser (default :data:`DEFAULT_METHOD`), see :func:`boustro.optimize.optimize`;
            ``options`` override :data:`METHOD_OPTIONS`. Concave areas and areas with holes
            get, under Eq. 1 by default, the certified optimum over their segments
            (:func:`~boustro.optimize.smith_bb.region.smith_bb_region`, of the area and of
            each cell, :mod:`boustro.mission.region_certified`); ``method="grid"`` (or another
            objective) the grid search :func:`boustro.plan.optimize_region` (exact
            per-segment fitness, :data:`REGION_OPTIONS`, ``options`` override it).
        fitness: the objective (default Eq. 1, or mission time when ``speed`` is given):
            :class:`~boustro.objectives.MissionTime` (and fewest transects on a concave area or
            one with holes) is minimised over the flown plan by the certified search
            (:func:`boustro.optimize.cover.cover_optimum`, method ``certified-cover``).
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
            Given, it also turns off the convex-hull rule for nearly convex areas. With a
            plan-level objective and no candidate decomposition of at most 12 cells, ``True``
            plans the sweep decomposition's cells (each optimised for Eq. 1) with a note.
        sweep: sweep direction of the decomposition, degrees in the plan frame (default:
            chosen by :func:`boustro.plan.choose_sweep`).
        angle: a fixed transect angle, radians counter-clockwise from +x in the plan frame
            (taken modulo pi); only the offset is then optimised for ``fitness``
            (:func:`boustro.optimize.fixed_angle.optimize_offset`, its way in
            ``Mission.optimum.method``), and a concave area is planned as one grid (no
            decomposition). Not with ``method``, ``decompose=True`` or ``sweep``.
        bearing: a fixed transect direction as a bearing instead of ``angle``: degrees clockwise
            from true north (grid north, +y, for planar input), turned into the plan frame's
            angle at the area's centre (so ``Mission.bearing`` reports it back); as ``angle``
            otherwise.
        force: plan even when the estimate before planning (:func:`estimate_work`) is absurd:
            more than :data:`~boustro.mission.estimate.MAX_LANES` lanes, an area over
            :data:`~boustro.mission.estimate.MAX_AREA_KM2` km^2 or an estimated time over
            :data:`~boustro.mission.estimate.MAX_SECONDS` s (the hard limits, e.g.
            :data:`boustro.models.MAX_TRANSECTS`, still hold).
        keep_inside: no part of the path leaves the area or enters a hole: lanes end at the
            boundary, connecting moves follow the inside, and boundary passes (the contour half
            a spacing inside the edge, patches over corners and thin parts; transects of role
            ``"boundary"``, waypoints of kind ``"contour"``) cover what the lanes leave, so the
            coverage stays 100% (:mod:`boustro.plan.inside`). A nearly convex area is then
            planned on the area, not its hull. Run-ins and run-outs (``turnaround``) end at the
            boundary. Not with a nadir gap.
        progress: for a plan whose estimate is over
            :data:`~boustro.mission.estimate.SAY_SECONDS`: ``True`` says it on stderr
            ("boustro: planning ~N lanes over V vertices, estimated T s") and shows a bar over
            the stages of a concave plan, or the optimiser's bars for a convex one (the hybrid
            fallback, grid, gradient); ``None`` says it, and shows the bar if stderr is a
            terminal (what ``boustro plan`` does unless ``-q``); ``False`` (default): silent.
        vehicle: a :class:`~boustro.vehicle.Vehicle` (metres, m/s, s): the connecting moves
            become its Dubins turns (Reeds-Shepp with ``reverse``), with their waypoints along
            the curves, and a convex area's lanes are flown every other one where that turns
            less (:func:`boustro.plan.drive_vehicle`); its ``speed`` and ``turn_time`` are used
            where ``speed`` and ``turn_time`` are not given.
        headland: passes around the boundary and the holes (:mod:`boustro.plan.headland`): the
            lanes cover the field less a band of ``headland`` spacings, the passes the band,
            turns stay inside the field (a turn that would leave it keeps the straight move,
            with a note), coverage is measured on the whole field. Run-ins and run-outs
            (``turnaround``) end where they would leave the field. Not with a nadir gap.

    Raises:
        InvalidPolygonError, NonConvexPolygonError, InvalidParameterError, NoTransectError,
        TooMuchWorkError (the estimate, without ``force``).

    Example:
        >>> from boustro.io import embedded_field
        >>> mission = plan_area(embedded_field(), 10.0)
        >>> mission.plan.stats.n_transects, round(mission.bearing, 2)
        (19, 68.43)
    """
    if angle is not None and bearing is not None:
        raise InvalidParameterError("give a fixed angle or a bearing, not both")
    fixed = _check_fixed_angle(
        angle if bearing is None else bearing, method=method, decompose=decompose, sweep=sweep
    )
    passes = check_headland(headland)
    if vehicle is not None and not isinstance(vehicle, Vehicle):
        raise InvalidParameterError(f"vehicle must be a boustro.vehicle.Vehicle, got {vehicle!r}")
    if vehicle is not None:
        speed = vehicle.speed if speed is None else speed
        turn_time = vehicle.turn_time if turn_time == 0 else turn_time
    check_turn_time(speed, turn_time, lambda name: name)  # as plan, batch and the page's API
    area = as_area(area, crs, holes)
    sensor = Sensor(*sensor_spacing(spacing))
    if passes and sensor.nadir_gap > 0:
        raise InvalidParameterError(
            "headland (--headland) does not take a nadir gap: the headland passes would not "
            "cover their own blind strip, and the lanes' wider reach would leave the field"
        )
    frame = project(area, sensor, hull_tolerance, decompose, start)
    field = None
    whole = frame.region if frame.region is not None else Region(frame.surveyed)
    if passes:
        frame, field = _inner_frame(frame, passes)
    # where the vehicle's turns must stay: the field with headlands or keep_inside
    turns_in = field if field is not None or not keep_inside else whole
    angle = fixed if bearing is None or fixed is None else angle_for_bearing(frame, fixed)
    if _narrower_than_the_spacing(frame, sensor):
        # Nothing to optimise: the region planner lays one lane along the area's diameter.
        frame = frame._replace(region=Region(frame.surveyed), poly=frame.surveyed, depth=0.0)
        method = None
    if frame.region is None and method is not None:
        resolve_method(method)  # an unknown method: its error before the estimate
    if fitness is None and speed is not None:
        fitness = MissionTime()
    cost = cover_cost(fitness, frame, speed, turn_time, turnaround)
    estimate = check_work(
        frame, method, force=bool(force), cover=cost is not None, keep_inside=bool(keep_inside)
    )
    show = _say(estimate, progress)
    settings: dict[str, Any] = dict(
        method=method,
        fitness=fitness,
        options=options,
        layout=layout,
        turnaround=turnaround,
        speed=speed,
        turn_time=turn_time,
        check_coverage=check_coverage,
        angle=angle,
        progress=show,
        keep_inside=_check_flag("keep_inside", keep_inside),
    )
    # the tour refined lane by lane except where a turn radius's turns or the headland passes
    # are added to its order afterwards (plan.lane_tour.refinement)
    with refinement(not passes and (vehicle is None or vehicle.turn_radius <= 0)):
        planned = _plan_and_drive(
            frame, cost, settings, decompose, sweep, field, passes, vehicle, turns_in
        )
    # the length outside, measured once on the path flown (lanes, passes, moves, curves)
    # against the whole area (not its hull, nor the inner field of a headland)
    # (the file's holes where a touching one was cut back: io.repair.detach_holes)
    planned = planned._replace(plan=with_outside_length(planned.plan, _as_read(frame, whole)))
    if keep_inside:  # planned on the area, not its hull: nothing reaches beyond it
        frame = frame._replace(depth=0.0)
    mission = map_back(frame, planned, altitude=altitude, turnaround=turnaround)
    return with_camera(mission, camera_trigger(spacing))


def _as_read(frame: Frame, whole: Region) -> Any:
    """The area the path's length outside is measured against: ``whole``, or, where
    :func:`~boustro.io.repair.detach_holes` cut a hole back from the shell, the plan frame's
    shell with the file's holes (a shapely Polygon: the Region refuses a touching hole)."""
    if not frame.area.cut_holes:
        return whole
    import shapely

    return shapely.Polygon(frame.ring, [frame.proj.to_plan(h) for h in frame.area.cut_holes])


def _plan_and_drive(
    frame: Frame,
    cost: CoverCost | None,
    settings: dict[str, Any],
    decompose: bool | None,
    sweep: float | None,
    field: Region | None,
    passes: int,
    vehicle: Vehicle | None,
    turns_in: Region | None,
) -> Planned:
    """The plan for the objective (a plan-level cost: :func:`_plan_for_cost`; else Eq. 1's
    convex or concave planner), then driven: headland passes around ``field`` and the
    vehicle's turns (:func:`_drive`)."""
    if cost is not None:
        finish = None
        if field is not None or vehicle is not None:  # the costs of what is flown

            def finish(plan: Plan) -> Plan:
                if field is None and vehicle is not None:  # its statistics, no waypoints
                    stats = vehicle_stats(plan, vehicle, field=turns_in)
                    return dataclasses.replace(plan, stats=stats)
                empty = Planned(plan, None, None)  # type: ignore[arg-type]
                return _drive(frame, empty, field, passes, vehicle, False, turns_in).plan

        cell_finish = None
        if vehicle is not None:  # a cell's own lanes with the vehicle's turns (no headland)

            def cell_finish(plan: Plan) -> Plan:
                return dataclasses.replace(plan, stats=vehicle_stats(plan, vehicle))

        skips = vehicle is not None and vehicle.turn_radius > 0  # every other lane possible
        u_turns = None  # every move a U-turn flown (no headland, no field to keep turns in)
        if vehicle is not None and skips and field is None and turns_in is None:
            u_turns = UTurns(vehicle.turn_radius, vehicle.reverse)
        planned = _plan_for_cost(
            frame, cost, decompose, sweep, settings, finish, skips, cell_finish, passes, u_turns
        )
    elif frame.region is None:
        planned = plan_convex(frame, **settings)
    else:
        planned = plan_concave(frame, decompose=decompose, sweep=sweep, **settings)
    return _drive(frame, planned, field, passes, vehicle, settings["check_coverage"], turns_in)


def _plan_for_cost(
    frame: Frame,
    cost: CoverCost,
    decompose: bool | None,
    sweep: float | None,
    settings: dict[str, Any],
    finish: Callable[[Plan], Plan] | None = None,
    skips: bool = False,
    cell_finish: Callable[[Plan], Plan] | None = None,
    headland: int = 0,
    u_turns: UTurns | None = None,
) -> Planned:
    """A plan-level objective: the certified one-grid plan (:func:`plan_cover`); for a concave
    area or one with holes also the decomposed plan (:func:`plan_decomposed`: every cell
    certified for the same cost, the order of the passes solved), kept only if it costs less
    (always with ``decompose=True``, never with ``False``). Costs are of ``finish(plan)``
    (headland passes and the vehicle's turns added) where given (``u_turns``: the one grid's
    bound charges the vehicle's U-turns, :func:`plan_cover`); both costs are in the kept
    plan's ``optimum.info`` (``one_grid``, ``decomposed``). A cell's search costs its own plan
    with the vehicle's turns (``cell_finish``), never the headland passes (they go around the
    whole field: a note says so). With ``decompose=True`` and no candidate decomposition (more
    than :data:`~boustro.mission.decomposed.MAX_CELLS` cells) the cells of
    :func:`plan_concave` (each optimised for Eq. 1), with a note; never one grid."""
    if settings["method"] not in (None, "certified-cover"):
        raise InvalidParameterError(
            f"the {cost.name} objective is optimised by the certified search over the flown "
            f"plan (method 'certified-cover'), not by {settings['method']!r}: leave --method out"
        )
    keys = ("layout", "turnaround", "speed", "turn_time", "check_coverage", "angle", "keep_inside")
    extra: dict[str, Any] = {
        "finish": finish,
        "boustrophedon": False if skips else None,
        "u_turns": u_turns,
    }
    if frame.region is None or decompose is False or settings["angle"] is not None:
        return plan_cover(frame, cost, **extra, **{k: settings[k] for k in keys})
    given = {k: settings[k] for k in keys}
    both = dict(sweep=sweep, finish=finish, cell_finish=cell_finish, **given)
    if decompose:
        cells = plan_decomposed(frame, cost, **both)
        if cells is None:
            return _fallback(frame, cost, sweep, settings, finish)
        return _noted(_headland_note(cells, headland), decomposed=cells.optimum.fitness)
    one = plan_cover(frame, cost, **extra, **given)
    cells = plan_decomposed(frame, cost, beat=one.optimum.fitness, **both)
    if cells is not None:
        cells = _headland_note(cells, headland)
    if cells is None:
        return _noted(one, one_grid=one.optimum.fitness, decomposed=None)
    value = cells.optimum.fitness
    if value < one.optimum.fitness:
        return _noted(cells, one_grid=one.optimum.fitness, decomposed=value)
    return _noted(one, one_grid=one.optimum.fitness, decomposed=value)


def _fallback(
    frame: Frame,
    cost: CoverCost,
    sweep: float | None,
    settings: dict[str, Any],
    finish: Callable[[Plan], Plan] | None,
) -> Planned:
    """``decompose=True`` without a candidate: :func:`plan_concave`'s cells (Eq. 1), noted."""
    planned = plan_concave(
        frame, decompose=True, sweep=sweep, **{**settings, "fitness": None, "method": None}
    )
    note = (
        f"no decomposition of at most {MAX_CELLS} cells to search for the {cost.name} "
        "objective: the cells of the sweep decomposition, each optimised for Eq. 1 (not "
        "certified)"
    )
    plan = dataclasses.replace(planned.plan, notes=(*planned.plan.notes, note))
    value = flown_cost(cost, plan, frame, finish)
    return _noted(planned._replace(plan=plan), objective=cost.name, decomposed=value)


def _headland_note(planned: Planned, headland: int) -> Planned:
    """With headland passes, the note that each cell's certificate is of its own plan."""
    if not headland:
        return planned
    note = (
        "each cell's certificate is of its own plan, without the headland passes around the "
        "field (the plan's cost includes them)"
    )
    plan = dataclasses.replace(planned.plan, notes=(*planned.plan.notes, note))
    return planned._replace(plan=plan)


def _noted(planned: Planned, **info: Any) -> Planned:
    """The plan with ``info`` added to its optimum's."""
    optimum = dataclasses.replace(planned.optimum, info={**planned.optimum.info, **info})
    return planned._replace(optimum=optimum)


def _inner_frame(frame: Frame, passes: int) -> tuple[Frame, Region]:
    """The frame of the inner field that the lanes cover, and the whole field (plan frame)."""
    field = frame.region if frame.region is not None else Region(frame.surveyed)
    inner = inner_field(field, frame.sensor.spacing * frame.proj.scale_min, passes)
    convex = inner.is_convex
    return (
        frame._replace(
            poly=inner.shell, surveyed=inner.shell, region=None if convex else inner, depth=0.0
        ),
        field,
    )


def _drive(
    frame: Frame,
    planned: Planned,
    field: Region | None,
    passes: int,
    vehicle: Vehicle | None,
    check_coverage: bool,
    turns_in: Region | None = None,
) -> Planned:
    """The headland passes added around the planned inner field, then the vehicle's turns
    (kept inside ``turns_in`` where given: a turn that would leave it keeps the routed move)."""
    plan, cov = planned.plan, planned.coverage
    if field is not None:
        scale = frame.proj.scale_min
        if vehicle is not None:  # a convex inner field: every other lane where that turns less
            plan = order_lanes(plan, vehicle)
        plan = add_headland(
            plan,
            field,
            passes,
            spacing=frame.sensor.spacing * scale,
            reach=frame.sensor.reach * scale,
        )
        cov = coverage(plan, field) if check_coverage else None
    if vehicle is not None:
        plan = drive_vehicle(plan, vehicle, field=turns_in)
    return Planned(plan, planned.optimum, cov)


def _check_flag(name: str, value: Any) -> bool:
    if value not in (True, False):
        raise InvalidParameterError(f"{name} must be True or False, got {value!r}")
    return bool(value)


def _narrower_than_the_spacing(frame: Frame, sensor: Sensor) -> bool:
    """A convex (or hull-planned) area whose diameter is at most the spacing on the ground: a
    lake under a wide swath. Planned over the area itself, not its hull."""
    return frame.region is None and sensor.spacing * frame.proj.scale_min >= frame.poly.diameter


def _say(estimate: WorkEstimate, progress: bool | None) -> bool:
    """Say a long estimate on stderr (unless ``progress`` is False); whether to show progress
    bars (a long plan, and ``progress``, or ``None`` and stderr is a terminal)."""
    if estimate.seconds <= SAY_SECONDS or progress is False:
        return False
    print(f"boustro: {estimate.describe()}", file=sys.stderr, flush=True)
    return sys.stderr.isatty() if progress is None else True


def estimate_work(
    area: Area | ArrayLike,
    spacing: float | SensorSpacing | Any,
    *,
    crs: str | None = AUTO_CRS,
    holes: Sequence[ArrayLike] = (),
    hull_tolerance: float = DEFAULT_HULL_TOLERANCE,
    decompose: bool | None = None,
    method: str | None = None,
    fitness: Any | None = None,
    speed: float | None = None,
    turn_time: float = 0.0,
    keep_inside: bool = False,
) -> WorkEstimate:
    """What :func:`plan_area` would take for this area: lanes, vertices, holes, area and the
    estimated time (the arguments as :func:`plan_area`'s: ``fitness``, ``speed`` and
    ``keep_inside`` choose the row of a plan-level objective). Never refuses (see ``force``).

    Example:
        >>> from boustro.io import embedded_field
        >>> est = estimate_work(embedded_field(), 10.0)
        >>> round(est.lanes), est.vertices, est.kind, est.seconds < 3
        (29, 19, 'certified', True)
    """
    area = as_area(area, crs, holes)
    sensor = Sensor(*sensor_spacing(spacing))
    frame = project(area, sensor, hull_tolerance, decompose, None)
    if fitness is None and speed is not None:
        fitness = MissionTime()
    cover = cover_cost(fitness, frame, speed, turn_time, 0.0) is not None
    return frame_estimate(frame, method, cover=cover, keep_inside=keep_inside)


def _check_fixed_angle(
    angle: Any, *, method: str | None, decompose: bool | None, sweep: float | None
) -> float | None:
    """A fixed angle checked (finite, radians) against the options it excludes."""
    if angle is None:
        return None
    value = as_number("angle", angle)
    if not math.isfinite(value):
        raise InvalidParameterError(f"angle must be a finite number, got {angle!r}")
    for given, what in (
        (
            method is not None,
            "a method (the offset at a fixed angle is found exactly or by a dense offset scan)",
        ),
        (decompose is True, "decompose=True (a fixed angle plans one grid over the whole area)"),
        (sweep is not None, "a sweep (a fixed angle plans one grid over the whole area)"),
    ):
        if given:
            raise InvalidParameterError(f"a fixed angle does not take {what}")
    return value
