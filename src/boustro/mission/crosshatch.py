"""Crosshatch: two passes over the area at 90 degrees to each other (3D mapping).

The angle is chosen for the pair: the objective of the first pass at angle ``a`` (its best
offset) plus that of the second at ``a + 90`` degrees, optimised over ``a`` in ``[0, 90)``
degrees (a scan of :data:`N_ANGLES` angles over ``[0, 180)``, each pair read off the same
scan, then a golden-section refinement around the best pair; for a convex area the certified
one-pass optimum is tried as either pass too). Each pass is then planned at its
angle (:func:`~boustro.mission.plan_area` with ``angle=``, coverage-guaranteed), the second
starting at its lane end nearest the first's last waypoint, and the mission flies both.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..errors import InvalidParameterError, ProblemTooLargeError
from ..geometry.region import Region
from ..objectives import SmithFitness, objective_sign
from ..optimize import optimize
from ..optimize.fixed_angle import optimize_offset
from ..plan import PlanStats
from ..plan.outside import outside_length
from .camera import with_camera
from .defaults import DEFAULT_HULL_TOLERANCE, DEFAULT_METHOD
from .map_back import angle_for_bearing
from .pipeline import plan_area
from .project import AUTO_CRS, Frame, Sensor, as_area, project, sensor_spacing
from .types import Mission

__all__ = ["N_ANGLES", "crosshatch_angle", "join_passes", "plan_crosshatch"]

#: Angles scanned over ``[0, 180)`` degrees (the pairs: ``N_ANGLES / 2`` of them).
N_ANGLES = 60


def crosshatch_angle(
    target: Any, spacing: float, fitness: Any = None, candidates: Sequence[float] = ()
) -> tuple[float, float]:
    """``(angle, value)``: the first pass's angle (radians, ``[0, pi/2)``) whose pair with
    ``angle + pi/2`` has the best summed objective (``fitness``, default Eq. 1, in its sense)
    over ``target`` (a convex polygon or a region, plan units), and that sum. ``candidates``:
    angles also tried as either pass's (e.g. the one-pass optimum, which often sits on a knife
    edge of Eq. 1 that a scan misses). Not certified: the best of the scan, its refinement
    and the candidates."""
    fitness = SmithFitness() if fitness is None else fitness
    sign = objective_sign(fitness)

    def value(a: float) -> float:
        return sum(
            optimize_offset(target, spacing, a + k * math.pi / 2, fitness=fitness).fitness
            for k in (0, 1)
        )

    angles = np.arange(N_ANGLES) * math.pi / N_ANGLES
    single = [optimize_offset(target, spacing, a, fitness=fitness).fitness for a in angles]
    half = N_ANGLES // 2
    pairs = [single[i] + single[i + half] for i in range(half)]
    best = max(range(half), key=lambda i: sign * pairs[i])
    lo, hi = angles[best] - math.pi / N_ANGLES, angles[best] + math.pi / N_ANGLES
    g = (math.sqrt(5) - 1) / 2
    a, b = hi - g * (hi - lo), lo + g * (hi - lo)
    fa, fb = value(a), value(b)
    for _ in range(14):  # the bracket shrinks to 0.6% of 6 degrees
        if sign * fa >= sign * fb:
            hi, b, fb = b, a, fa
            a = hi - g * (hi - lo)
            fa = value(a)
        else:
            lo, a, fa = a, b, fb
            b = lo + g * (hi - lo)
            fb = value(b)
    found = [(angles[best], pairs[best]), (a, fa), (b, fb)]
    found += [(c - k * math.pi / 2, value(c)) for c in candidates for k in (0, 1)]
    angle, val = max(found, key=lambda p: sign * p[1])
    return float(angle) % (math.pi / 2), float(val)


def _one_pass(frame: Frame, s_plan: float, fitness: Any) -> list[float]:
    """The certified one-pass optimum's angle of a convex area (none for a concave one, or
    where the certified optimiser would take too long)."""
    if frame.region is not None:
        return []
    try:
        return [optimize(frame.poly, s_plan, method=DEFAULT_METHOD, fitness=fitness).angle]
    except ProblemTooLargeError:
        return []


def join_passes(first: Mission, second: Mission) -> Mission:
    """One mission flying ``first`` then ``second`` (a straight move between them); its
    ``passes`` are the two, its coverage the first's (each pass's is in ``passes``)."""
    p1, p2 = first.plan, second.plan
    move = float(np.hypot(*(p2.waypoints[0] - p1.waypoints[-1]))) / p1.ground_scale
    s1, s2 = p1.stats, p2.stats
    path = s1.path_length + move + s2.path_length
    turns = s1.n_turns + s2.n_turns + 1
    stats = PlanStats(
        n_transects=s1.n_transects + s2.n_transects,
        n_turns=turns,
        transect_length=s1.transect_length + s2.transect_length,
        path_length=path,
        area=s1.area,
        speed=s1.speed,
        turn_time=s1.turn_time,
        duration=None if s1.speed is None else path / s1.speed + turns * s1.turn_time,
        n_cells=s1.n_cells + s2.n_cells,
        hole_pass_length=s1.hole_pass_length + s2.hole_pass_length,
        outside_length=_outside(first, p1.waypoints, p2.waypoints),
    )

    def both(a: Any, b: Any) -> Any:
        return None if a is None or b is None else np.concatenate([a, b])

    t1 = len(p1.transects)
    plan = dataclasses.replace(
        p1,
        positions=np.concatenate([p1.positions, p2.positions]),
        transects=np.concatenate([p1.transects, p2.transects]),
        waypoints=np.concatenate([p1.waypoints, p2.waypoints]),
        kinds=p1.kinds + p2.kinds,
        lane=np.concatenate([p1.lane, p2.lane + t1]),
        stats=stats,
        cells=p1.cells + p2.cells,
        transect_angles=np.concatenate([p1.transect_angle(), p2.transect_angle()]),
        roles=p1.role() + p2.role(),
        transect_cells=both(p1.transect_cells, p2.transect_cells),
        notes=p1.notes + p2.notes,
    )
    out = dataclasses.replace(
        first,
        plan=plan,
        waypoints=np.concatenate([first.waypoints, second.waypoints]),
        transects=np.concatenate([first.transects, second.transects]),
        waypoints_lonlat=both(first.waypoints_lonlat, second.waypoints_lonlat),
        transects_lonlat=both(first.transects_lonlat, second.transects_lonlat),
        passes=(first, second),
    )
    return with_camera(out, first.camera)


def _outside(first: Mission, w1: np.ndarray, w2: np.ndarray) -> float:
    """The length of both passes' path and the move between them outside the area or in a
    hole, measured once on the whole path (ground units)."""
    proj, area = first.projection, first.area
    region = Region(proj.to_plan(area.ring), [proj.to_plan(h) for h in area.holes])
    return outside_length(np.concatenate([w1, w2]), region) / first.plan.ground_scale


def plan_crosshatch(
    area: Any,
    spacing: Any,
    *,
    crs: str | None = AUTO_CRS,
    angle: float | None = None,
    bearing: float | None = None,
    fitness: Any = None,
    start: ArrayLike | None = None,
    **kwargs: Any,
) -> Mission:
    """Two passes at 90 degrees, the angle chosen for the pair (see the module docstring), as
    one :class:`Mission`; the arguments as :func:`~boustro.mission.plan_area`'s (``angle`` or
    ``bearing`` fix the first pass; ``method``, ``decompose`` and ``sweep`` are refused: each
    pass is one grid at its angle)."""
    for name in ("method", "decompose", "sweep"):
        if kwargs.get(name) is not None:
            raise InvalidParameterError(
                f"a crosshatch plans each pass as one grid at its angle: not with {name}"
            )
    kwargs = {k: v for k, v in kwargs.items() if k not in ("method", "decompose", "sweep")}
    if angle is not None and bearing is not None:
        raise InvalidParameterError("give a fixed angle or a bearing, not both")
    holes = kwargs.pop("holes", ())
    area = as_area(area, crs, holes)
    sensor = Sensor(*sensor_spacing(spacing))
    frame = project(area, sensor, kwargs.get("hull_tolerance", DEFAULT_HULL_TOLERANCE), None, start)
    if bearing is not None:
        angle = angle_for_bearing(frame, float(bearing))
    if angle is None:
        s_plan = sensor.spacing * frame.proj.scale_min
        target = frame.poly if frame.region is None else frame.region
        # a plan-level objective (mission time) scores flown plans, not lengths: the pair's
        # angle is then chosen by Eq. 1 and each pass's offset by the objective
        scan = None if getattr(fitness, "needs_plan", False) else fitness
        angle, _ = crosshatch_angle(target, s_plan, scan, _one_pass(frame, s_plan, scan))
    first = plan_area(area, spacing, angle=angle, fitness=fitness, start=start, **kwargs)
    second = plan_area(
        area,
        spacing,
        angle=float(angle) + math.pi / 2,
        fitness=fitness,
        start=first.waypoints[-1],
        **kwargs,
    )
    return join_passes(first, second)
