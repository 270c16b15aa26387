"""Step 3 of a mission: the plan mapped back to the area's coordinates and longitude/latitude."""

from __future__ import annotations

import math

import numpy as np

from .._validate import as_number
from ..errors import InvalidParameterError
from ..plan import Plan
from .project import Frame
from .steps import Planned, main_cell
from .types import Mission

__all__ = ["angle_for_bearing", "map_back"]


def _bearing(frame: Frame, plan: Plan) -> float:
    """The transects' bearing, degrees clockwise from north (from the plan frame's y axis)."""
    if frame.proj.planar:
        return _azimuth(frame, np.zeros(2), plan.angle)
    main = plan.cells[main_cell(plan)].polygon if frame.region is not None else frame.poly
    return _azimuth(frame, main.centre, plan.angle)


def _azimuth(frame: Frame, c: np.ndarray, angle: float) -> float:
    """The bearing of direction ``angle`` (plan frame) at ``c``, degrees in ``[0, 180)``."""
    u = np.array([math.cos(angle), math.sin(angle)])
    if frame.proj.planar:
        return math.degrees(math.atan2(u[0], u[1])) % 180.0
    a, b = frame.proj.to_lonlat(np.stack([c - 5 * u, c + 5 * u]))
    azimuth, _, _ = frame.proj._geod.inv(a[0], a[1], b[0], b[1])
    return float(azimuth) % 180.0


def angle_for_bearing(frame: Frame, bearing: float) -> float:
    """The plan-frame angle (radians) of transects at ``bearing`` (degrees clockwise from true
    north; from grid north +y for planar input): the inverse of the bearing a mission reports,
    at the same point (the area's centre; true north turns across a projected area), found by
    three corrections of the angle by the bearing's error (the map is a rotation up to the
    projection's small distortion)."""
    c = (frame.poly if frame.region is None else frame.region.shell).centre
    angle = math.radians(90.0 - float(bearing)) % math.pi
    for _ in range(3):  # at the angle in [0, pi) that the plan will have (the azimuth's sense)
        error = (_azimuth(frame, c, angle) - float(bearing) + 90.0) % 180.0 - 90.0
        angle = (angle + math.radians(error)) % math.pi
    return angle


def _check_mapped(frame: Frame, plan: Plan, mapped: np.ndarray) -> None:
    """Refuse a path that the projection cannot map back (its points ``inf``/``nan``): a turn
    radius or turnaround so large that the path runs far beyond the area, where the plan's CRS
    is not defined; nothing else would say so before an export refuses the numbers."""
    if np.isfinite(mapped).all():
        return
    lo, hi = frame.ring.min(axis=0), frame.ring.max(axis=0)
    beyond = np.maximum(np.maximum(lo - plan.waypoints, plan.waypoints - hi), 0.0)
    far = float(np.linalg.norm(beyond, axis=1).max())
    raise InvalidParameterError(
        f"the path reaches {far / frame.proj.scale_min / 1000:.0f} km from the area, where its "
        "coordinates cannot be mapped back to the area's CRS; is the turn radius or the "
        "turnaround far larger than the area?"
    )


def map_back(
    frame: Frame, planned: Planned, *, altitude: float | None, turnaround: float
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
    waypoints = proj.to_source(plan.waypoints)
    waypoints_lonlat = None if lonlat is None else lonlat(plan.waypoints)
    _check_mapped(frame, plan, waypoints if waypoints_lonlat is None else waypoints_lonlat)
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
        waypoints=waypoints,
        transects=proj.to_source(plan.transects),
        waypoints_lonlat=waypoints_lonlat,
        transects_lonlat=None if lonlat is None else lonlat(plan.transects),
        area_lonlat=None if lonlat is None else lonlat(frame.ring),
        bearing=bearing,
        home=proj.to_source(home_plan),
        home_lonlat=None if lonlat is None else lonlat(home_plan),
        holes_lonlat=() if lonlat is None else tuple(lonlat(h) for h in frame.holes),
    )
