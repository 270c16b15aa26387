"""Step 1 of a mission: the area and the sensor, projected into the metric plan frame."""

from __future__ import annotations

import contextvars
import dataclasses
import math
from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError, InvalidPolygonError, NonConvexPolygonError
from ..geometry import Polygon
from ..geometry.region import Region
from ..io.crs import Projection, check_lonlat, parse_crs, projection_for
from ..io.read import LONLAT, Area
from ..io.read_objects import area_from_object, is_geo_object
from ..plan import nearly_convex
from ..sensors import SensorSpacing
from .defaults import log

__all__ = [
    "AUTO_CRS",
    "MAX_SPACING",
    "START_NAME",
    "Frame",
    "Sensor",
    "as_area",
    "project",
    "sensor_spacing",
]

#: What the far-start warning calls the start: ``boustro plan --home`` sets "home" while it
#: plans from the home (the start is the home there, and the user gave no start).
START_NAME: contextvars.ContextVar[str] = contextvars.ContextVar("start_name", default="the start")


#: The widest spacing (and sensor footprint) planned, metres or planar units: far beyond any
#: survey (an area narrower than the spacing gets one lane whatever the spacing), and far below
#: where the geometry overflows float64 (a buffer of the reach squares it: from ~1.3e154 on,
#: shapely warned of overflows and invalid values while planning 1e300).
MAX_SPACING = 1e100


def sensor_spacing(spacing: Any) -> tuple[float, float, float, float | None, str | None]:
    """(spacing, reach, nadir gap, altitude, description) from a number or a sensor; a spacing
    or footprint wider than :data:`MAX_SPACING` is refused (``boustro plan``, ``batch`` and the
    page's API all plan through :func:`~boustro.mission.plan_area`: one rule)."""
    out = _sensor_spacing(spacing)
    if not max(out[0], 2 * out[1]) <= MAX_SPACING:
        raise InvalidParameterError(
            f"spacing {max(out[0], 2 * out[1]):g} is too wide: at most "
            f"{MAX_SPACING:g} (an area narrower than the spacing gets one lane anyway)"
        )
    return out


def _sensor_spacing(spacing: Any) -> tuple[float, float, float, float | None, str | None]:
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


class Sensor(NamedTuple):
    """The spacing and footprint asked for, on the ground (metres, or planar units)."""

    spacing: float
    reach: float
    nadir_gap: float
    altitude: float | None
    text: str | None


class Frame(NamedTuple):
    """Step 1: the area projected into the plan frame, with what the plan needs."""

    area: Area
    sensor: Sensor
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


#: The default ``crs`` of :func:`boustro.mission.plan_area`: WGS 84 longitude/latitude for bare
#: vertices, planar for a geometry object (which carries no CRS).
AUTO_CRS = "auto"


def as_area(area: Area | ArrayLike | Any, crs: str | None, holes: Sequence[ArrayLike]) -> Area:
    """An :class:`Area` with one spelling of its CRS ("EPSG:n", or None for planar), from an
    Area, vertices (``crs`` ``"auto"``: lon/lat) or a geometry object (``"auto"``: planar, see
    :mod:`boustro.io.read_objects`)."""
    if isinstance(area, Area):
        return dataclasses.replace(area, crs=parse_crs(area.crs))
    if is_geo_object(area):
        if len(holes):
            raise InvalidParameterError(
                "holes= goes with bare vertices; a geometry object carries its own holes"
            )
        got = area_from_object(area, None if crs == AUTO_CRS else crs)
        return dataclasses.replace(got, crs=parse_crs(got.crs))
    crs = LONLAT if crs == AUTO_CRS else crs
    try:
        ring = np.asarray(area, dtype=np.float64)
        hole_rings = tuple(np.asarray(h, dtype=np.float64) for h in holes)
    except (TypeError, ValueError):
        raise InvalidParameterError(
            "area must be an Area, (N, 2) vertices, a shapely geometry, an object with "
            f"__geo_interface__ or a GeoJSON mapping, got {type(area).__name__}"
        ) from None
    return Area(ring, parse_crs(crs), "", "<array>", hole_rings)


# -- step 1: project --------------------------------------------------------------------------
def _project_holes(area: Area, proj: Projection) -> list[NDArray[np.float64]]:
    """The holes in the plan frame, checked."""
    where = area.source
    holes_plan = []
    for i, hole in enumerate(area.holes, start=1):
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


def project(
    area: Area,
    sensor: Sensor,
    hull_tolerance: float,
    decompose: bool | None,
    start: ArrayLike | None,
) -> Frame:
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
    start_plan = (
        ring_plan[0]
        if start is None
        else proj.point_to_plan(start, "the start point (also the mission's home)")
    )
    if start is not None:
        _warn_far_start(ring_plan, start_plan, k_lo, proj.geographic)
    ground_area = proj.ground_area(ring_plan) - sum(proj.ground_area(h) for h in holes_plan)
    return Frame(
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


def _warn_far_start(
    ring: NDArray[np.float64], start: NDArray[np.float64], k_lo: float, geographic: bool
) -> None:
    """Warn of a start more than 10 times the area's size away from it, with the likely cause:
    longitude and latitude swapped (lon/lat input), else a point in other coordinates than
    the area's (projected or planar input, where there is no longitude to swap)."""
    far = float(np.min(np.hypot(*(ring - start).T))) / k_lo
    size = float(np.max(np.hypot(*(ring - ring.mean(axis=0)).T))) * 2 / k_lo
    if far > 10 * size:
        cause = (
            "swapped longitude and latitude?"
            if geographic
            else f"a point in other coordinates than the area's ({START_NAME.get()} is in the "
            "area's CRS)?"
        )
        log.warning(
            "%s is %.3g m from the area, %.0f times its size: %s",
            START_NAME.get(), far, far / size, cause,
        )  # fmt: skip
