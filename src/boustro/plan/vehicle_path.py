"""A plan driven by a vehicle model: turns of bounded curvature in the path
(:func:`drive_vehicle`).

A plan of one grid over a convex area (:func:`boustro.plan.build_plan`) gets its lanes in the
order that turns least (:func:`boustro.vehicle.lane_order`: boustrophedon, or every other lane
when ``2 * turn_radius > spacing`` makes that shorter) and a Dubins (forward only) or
Reeds-Shepp (with reverse) turn from every lane's exit pose to the next lane's entry pose. Any
other plan (concave areas, holes, headlands) keeps its order; every connecting move between two
passes becomes the vehicle's turn between their poses, unless the turn would enter a hole or
leave ``field`` (then the routed move is kept and a note says how many). The turns' waypoints
(kind ``turn``) are on the curve, densified so that no chord departs from it by more than
``tolerance``; the statistics count the exact length of the curves, and the length outside
(``outside_length``) is measured again on the driven path, curves included.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidParameterError
from ..geometry.region import Region
from ..vehicle import (
    Turn,
    Vehicle,
    dubins_paths,
    every_turn,
    lane_order,
    reeds_shepp_paths,
    turns_between,
)
from .outside import with_outside_length
from .types import Plan, PlanStats

__all__ = ["drive_vehicle", "order_lanes", "vehicle_stats"]

_EXITS = ("end", "run_out")
_ENTRIES = ("start", "run_in")


def drive_vehicle(
    plan: Plan,
    vehicle: Vehicle,
    *,
    tolerance: float = 0.05,
    field: Region | None = None,
) -> Plan:
    """``plan`` with its connecting moves driven as the vehicle's turns.

    Args:
        plan: a plan in the plan frame.
        vehicle: the vehicle, in ground units (metres); its radius is scaled by the plan's
            ``ground_scale``.
        tolerance: how far (ground units) a chord between two waypoints of a turn may depart
            from the curve.
        field: where the turns must stay (the field, plan frame: a turn that leaves it or
            enters one of its holes keeps the straight or routed move, with a note); ``None``:
            turns may reach beyond the area (as run-outs do) but never into one of the plan's
            holes.

    Example:
        >>> from boustro.plan import build_plan
        >>> plan = build_plan([(0, 0), (100, 0), (100, 100), (0, 100)], 10.0, 0.0)
        >>> turned = drive_vehicle(plan, Vehicle(turn_radius=6.0))
        >>> turned.stats.n_turns, round(turned.stats.turn_length, 2)  # every other lane
        (10, 270.36)
    """
    plan, v, tol = _prepare(plan, vehicle, tolerance)
    holes_only = field is None
    return _turn_moves(plan, v, vehicle, tol, plan.region if field is None else field, holes_only)


def vehicle_stats(
    plan: Plan, vehicle: Vehicle, *, tolerance: float = 0.05, field: Region | None = None
) -> PlanStats:
    """``drive_vehicle(plan, vehicle, tolerance=tolerance, field=field).stats`` without
    building its waypoints where no turn has to be tested against the field or holes (the
    turns' lengths from their words): what a search needs of each layout's plan. Without the
    waypoints the length outside is not measured again: ``outside_length`` is then the
    plan's own (:func:`drive_vehicle` and :func:`boustro.mission.plan_area` measure it on the
    driven path)."""
    region = plan.region if field is None else field
    allowed = None if region is None else _Allowed(region, field is None)
    if vehicle.turn_radius == 0 or (allowed is not None and allowed.tests):
        return drive_vehicle(plan, vehicle, tolerance=tolerance, field=field).stats
    plan, v, _ = _prepare(plan, vehicle, tolerance)
    w = plan.waypoints
    moves = _moves(plan)
    starts, goals = _poses(plan, moves)
    paths = reeds_shepp_paths if v.reverse else dubins_paths
    words = paths(starts, goals, v.turn_radius) if moves else []
    replaced = curves = 0.0
    for (i, j), word in zip(moves, words, strict=True):  # in the order drive_vehicle sums
        replaced += float(np.linalg.norm(np.diff(w[i : j + 1], axis=0), axis=1).sum())
        curves += word.length
    return _stats(plan, replaced, curves)


def _prepare(plan: Plan, vehicle: Vehicle, tolerance: float) -> tuple[Plan, Vehicle, float]:
    """The arguments checked; the plan reordered (a convex one), the vehicle and tolerance in
    the plan's units."""
    if not isinstance(vehicle, Vehicle):
        raise InvalidParameterError(f"vehicle must be a boustro.vehicle.Vehicle, got {vehicle!r}")
    if not (math.isfinite(tolerance) and tolerance > 0):
        raise InvalidParameterError(f"tolerance must be a finite number > 0, got {tolerance!r}")
    scale = plan.ground_scale
    v = dataclasses.replace(vehicle, turn_radius=vehicle.turn_radius * scale)
    if plan.region is None and plan.headland == 0:
        plan = _reorder(plan, v)
    return plan, v, tolerance * scale


def _poses(plan: Plan, moves: list[tuple[int, int]]) -> tuple[list[tuple], list[tuple]]:
    """The exit and entry poses ``(x, y, heading)`` of the moves."""
    w = plan.waypoints
    angles = plan.transect_angle()
    starts = [(*w[i], _heading(w, i, -1, float(angles[plan.lane[i]]))) for i, _ in moves]
    goals = [(*w[j], _heading(w, j, +1, float(angles[plan.lane[j]]))) for _, j in moves]
    return starts, goals


class _Allowed:
    """Where turns may go: the closed field, or (``holes_only``) anywhere but inside a hole;
    tested on the turn's polyline with shapely (prepared geometries, imported here)."""

    def __init__(self, region: Region, holes_only: bool) -> None:
        import shapely

        tol = 1e-9 * region.diameter
        self.shapely = shapely
        if holes_only:
            holes = [shapely.Polygon(h.vertices).buffer(-tol) for h in region.holes]
            self.forbidden = shapely.union_all([h for h in holes if not h.is_empty])
            if self.forbidden.is_empty:  # no hole: nothing to test
                self.forbidden = None
            self.field = None
        else:
            rings = [h.vertices for h in region.holes]
            self.field = shapely.Polygon(region.shell.vertices, rings).buffer(tol)
            self.forbidden = None
        for geom in (self.forbidden, self.field):
            if geom is not None:
                shapely.prepare(geom)

    @property
    def tests(self) -> bool:
        """Whether a turn can be refused at all (there is a field, or a hole)."""
        return self.field is not None or self.forbidden is not None

    def leaves(self, points: NDArray[np.float64]) -> bool:
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        if len(pts) < 2:  # a turn of length 0 (the next pass starts where this one ends)
            line = self.shapely.Point(pts[0]) if len(pts) else self.shapely.Point()
        else:
            line = self.shapely.LineString(pts)
        if self.field is not None:
            return not bool(self.field.covers(line))
        return self.forbidden is not None and bool(self.forbidden.intersects(line))


def order_lanes(plan: Plan, vehicle: Vehicle) -> Plan:
    """A plan of one grid over a convex area with its lanes in the order that turns least
    (:func:`boustro.vehicle.lane_order`), its connecting moves still straight; other plans as
    they are. ``vehicle`` in ground units."""
    if plan.region is not None or plan.headland:
        return plan
    v = dataclasses.replace(vehicle, turn_radius=vehicle.turn_radius * plan.ground_scale)
    return _reorder(plan, v)


def _reorder(plan: Plan, v: Vehicle) -> Plan:
    """A convex plan's lanes in :func:`lane_order` (boustrophedon or every other lane)."""
    t = plan.turnaround
    lanes = plan.transects
    if len(lanes) < 3 or v.turn_radius == 0:
        return plan
    order, driven, _ = lane_order(v, _extended(lanes, t))
    if order == list(range(len(lanes))):
        return plan
    transects = _extended(driven, -t)
    points, kinds, lane = [], [], []
    for i, (ext, seg) in enumerate(zip(driven, transects, strict=True)):
        if t > 0:
            points += [ext[0], seg[0], seg[1], ext[1]]
            kinds += ["run_in", "start", "end", "run_out"]
        else:
            points += [seg[0], seg[1]]
            kinds += ["start", "end"]
        lane += [i] * (4 if t > 0 else 2)
    return dataclasses.replace(
        plan,
        transects=transects,
        positions=plan.positions[order],
        waypoints=np.asarray(points),
        kinds=tuple(kinds),
        lane=np.asarray(lane, dtype=np.int64),
    )


def _extended(lanes: NDArray[np.float64], by: float) -> NDArray[np.float64]:
    """Lanes lengthened by ``by`` at both ends (along their direction; shortened if < 0)."""
    d = lanes[:, 1] - lanes[:, 0]
    norm = np.linalg.norm(d, axis=1, keepdims=True)
    u = d / np.where(norm > 0, norm, 1.0)
    return np.stack([lanes[:, 0] - by * u, lanes[:, 1] + by * u], axis=1)


def _heading(w: NDArray[np.float64], i: int, step: int, fallback: float) -> float:
    """Heading at waypoint ``i``: along the path into it (``step = -1``) or out of it (+1)."""
    j = i + step
    while 0 <= j < len(w):
        d = (w[i] - w[j]) if step < 0 else (w[j] - w[i])
        if np.linalg.norm(d) > 1e-12:
            return math.atan2(d[1], d[0])
        j += step
    return fallback


def _moves(plan: Plan) -> list[tuple[int, int]]:
    """``(exit, entry)`` waypoint indices of every connecting move (only ``via`` between)."""
    k = plan.kinds
    out = []
    for i in range(len(k) - 1):
        if k[i] not in _EXITS or (k[i] == "end" and k[i + 1] == "run_out"):
            continue
        j = i + 1
        while j < len(k) and k[j] == "via":
            j += 1
        if j < len(k) and k[j] in _ENTRIES:
            out.append((i, j))
    return out


def _turn_moves(
    plan: Plan, v: Vehicle, ground: Vehicle, tol: float, field: Region | None, holes_only: bool
) -> Plan:
    """Every connecting move replaced by the vehicle's turn (where it is allowed)."""
    w = plan.waypoints
    moves = _moves(plan)
    turns: dict[int, tuple[int, Turn]] = {}
    kept = 0
    allowed = None if field is None else _Allowed(field, holes_only)
    starts, goals = _poses(plan, moves)
    longer = 0
    for k, ((i, j), turn) in enumerate(
        zip(moves, turns_between(v, starts, goals, tol), strict=True)
    ):
        if allowed is not None and allowed.leaves(turn.points):
            inside = _turn_inside(v, starts[k], goals[k], tol, allowed)
            if inside is None:
                kept += 1
                continue
            turn, longer = inside, longer + 1
        turns[i] = (j, turn)
    points, kinds, lane = [], [], []
    replaced = 0.0
    curves = 0.0
    i = 0
    while i < len(w):
        points.append(w[i])
        kinds.append(plan.kinds[i])
        lane.append(int(plan.lane[i]))
        if i in turns:
            j, turn = turns[i]
            replaced += float(np.linalg.norm(np.diff(w[i : j + 1], axis=0), axis=1).sum())
            curves += turn.length
            points += list(turn.points[1:-1])
            kinds += ["turn"] * (len(turn.points) - 2)
            lane += [int(plan.lane[j])] * (len(turn.points) - 2)
            i = j
            continue
        i += 1
    notes = list(plan.notes)
    if longer:
        notes.append(
            f"{longer} of {len(moves)} turns take a longer path of radius "
            f"{ground.turn_radius:g} m than the shortest, which would leave the field or enter "
            "a hole"
        )
    if kept:
        what = "enter a hole" if holes_only else "leave the field or enter a hole"
        notes.append(
            f"{kept} of {len(moves)} moves between passes are straight or routed: the turn of "
            f"radius {ground.turn_radius:g} m would {what}"
        )
    driven = dataclasses.replace(
        plan,
        waypoints=np.asarray(points),
        kinds=tuple(kinds),
        lane=np.asarray(lane, dtype=np.int64),
        stats=_stats(plan, replaced, curves),
        notes=tuple(notes),
        vehicle=ground,
        routed_moves=kept,
    )
    area = field if field is not None else plan.polygon  # the curves included
    return with_outside_length(driven, area)


def _turn_inside(
    v: Vehicle, start: tuple, goal: tuple, tol: float, allowed: _Allowed
) -> Turn | None:
    """The shortest of the vehicle's other turns between the poses (:func:`every_turn`: the
    loop the other way, a bulb, with ``reverse`` a manoeuvre with reversing) that stays where
    ``allowed``; ``None`` if none does."""
    for turn in every_turn(v, start, goal, tol)[1:]:
        if not allowed.leaves(turn.points):
            return turn
    return None


def _stats(plan: Plan, replaced: float, curves: float) -> PlanStats:
    """The plan's statistics with the moves of length ``replaced`` driven as turns of length
    ``curves`` (plan units)."""
    s = plan.stats
    scale = plan.ground_scale
    polyline = float(np.linalg.norm(np.diff(plan.waypoints, axis=0), axis=1).sum())
    path_length = (polyline - replaced + curves) / scale
    duration = None
    if s.speed is not None:
        duration = path_length / s.speed + s.n_turns * s.turn_time
    return dataclasses.replace(
        s, path_length=path_length, duration=duration, turn_length=curves / scale
    )
