"""Coordinate systems: from a survey area in real coordinates to a plan, and back (an edge).

Algorithms never see latitude and longitude. A survey area comes with the CRS of its coordinates
(:class:`boustro.io.Area`); :func:`plan_area` projects it into a metric *plan frame*, optimises
and plans there (:mod:`boustro.optimize`, :mod:`boustro.plan`) and returns the waypoints in the
area's own coordinates, plus WGS 84 longitude/latitude for the mission formats.

* Geographic input (longitude/latitude, e.g. GeoJSON, KML; any geographic CRS) is planned in the
  UTM zone of the area's centre (WGS 84 / UTM, ``EPSG:326zz`` north or ``EPSG:327zz`` south;
  Universal Polar Stereographic above 84 N or below 80 S). Latitudes outside [-90, 90],
  longitudes outside [-180, 180], an area that crosses the antimeridian or encloses a pole are
  refused with a message saying so.
* Projected input (``crs="EPSG:28992"`` etc.) is planned in that CRS directly.
* Planar input (``crs=None``) is planned as it is, in its own units.

Ground distances. A map projection scales distances by a factor ``k`` (plan units per metre on
the ground: 0.9996 on a UTM zone's central meridian, up to about 1.001 at its edges, other
values for a CRS in feet). :class:`Projection` measures ``k`` over the area (geodesic distances
on the WGS 84 ellipsoid) and the plan uses the smallest ``k`` for the spacing, so the spacing
measured on the ground never exceeds the one asked for (it is smaller by at most the variation of
``k`` over the area, about 1e-6 for a field), and reports statistics in metres.

pyproj is imported when a projection is built, shapely only for the coverage check.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .decompose import plan_region
from .errors import (
    BoustroError,
    InvalidParameterError,
    InvalidPolygonError,
    NonConvexPolygonError,
    ProblemTooLargeError,
    as_number,
)
from .fitness import SmithFitness
from .geometry import Polygon
from .io import LONLAT, Area
from .optimize import OptimizeResult, optimize
from .plan import Coverage, Plan, PlanStats, build_plan, coverage, nearly_convex
from .regions import Region
from .sensors import SensorSpacing

__all__ = [
    "DEFAULT_HULL_TOLERANCE",
    "DEFAULT_METHOD",
    "LONLAT",
    "METHOD_OPTIONS",
    "REGION_OPTIONS",
    "MissingDependencyError",
    "Mission",
    "Projection",
    "check_lonlat",
    "parse_crs",
    "plan_area",
    "projection_for",
    "utm_crs",
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
#: (:func:`boustro.decompose.optimize_region`; a cell or the whole area), overridden by
#: ``options``.
REGION_OPTIONS: dict[str, Any] = {"n_angles": 90, "n_offsets": 16}

_PLANAR_NAMES = ("planar", "local", "none")


class MissingDependencyError(BoustroError, ImportError):
    """An optional dependency that this operation needs is not installed."""


def _pyproj() -> Any:
    try:
        import pyproj
    except ImportError:  # pragma: no cover - pyproj is a dependency of the plan command
        raise MissingDependencyError(
            "geographic and projected coordinates need pyproj: pip install pyproj "
            "(or give planar coordinates with crs=None / --crs planar)"
        ) from None
    return pyproj


def parse_crs(crs: str | int | None) -> str | None:
    """A CRS name as boustro stores it: ``"EPSG:n"``, another pyproj name, or ``None`` (planar).

    Accepts ``None``, ``"planar"``/``"local"``/``"none"`` (planar coordinates), an EPSG code as
    an integer or ``"28992"``, or anything pyproj understands (``"EPSG:28992"``, a WKT or PROJ
    string). The CRS must be geographic (longitude/latitude) or projected.

    Raises:
        InvalidParameterError: unknown, or neither geographic nor projected.
    """
    if crs is None:
        return None
    text = str(crs).strip()
    if text.lower() in _PLANAR_NAMES:
        return None
    if text.isdigit():
        text = f"EPSG:{text}"
    pyproj = _pyproj()
    try:
        obj = pyproj.CRS.from_user_input(text)
    except pyproj.exceptions.CRSError as exc:
        raise InvalidParameterError(
            f"unknown coordinate reference system {crs!r} (expected e.g. EPSG:4326, "
            f"EPSG:28992, or 'planar'): {exc}"
        ) from None
    if not (obj.is_geographic or obj.is_projected):
        raise InvalidParameterError(
            f"the CRS {crs!r} ({obj.name}) is neither geographic (longitude/latitude) nor "
            "projected; give the area's coordinates in one that is"
        )
    return text


def _is_geographic(crs: str) -> bool:
    return bool(_pyproj().CRS.from_user_input(crs).is_geographic)


def utm_crs(lon: float, lat: float) -> str:
    """The WGS 84 UTM zone (or UPS) CRS for a point: ``"EPSG:326zz"``/``"EPSG:327zz"``.

    Standard 6-degree zones (the Norway and Svalbard exceptions are not applied; the scale
    factor is measured and corrected anyway); Universal Polar Stereographic North
    (``EPSG:32661``) above 84 N and South (``EPSG:32761``) below 80 S.
    """
    if lat > 84:
        return "EPSG:32661"
    if lat < -80:
        return "EPSG:32761"
    zone = min(60, max(1, math.floor((lon + 180) / 6) + 1))
    return f"EPSG:{(32600 if lat >= 0 else 32700) + zone}"


def check_lonlat(ring: ArrayLike, where: str = "area") -> NDArray[np.float64]:
    """Check a longitude/latitude ring and return it as an ``(N, 2)`` float array.

    Raises:
        InvalidPolygonError: non-finite values, latitude outside [-90, 90], longitude outside
            [-180, 180], a vertex on a pole, a ring around a pole, or an edge that crosses the
            antimeridian (a jump of more than 180 degrees of longitude).
    """
    pts = np.asarray(ring, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < 3:
        raise InvalidPolygonError(
            f"{where}: expected at least 3 (longitude, latitude) pairs, got shape {pts.shape}"
        )
    if not np.all(np.isfinite(pts)):
        raise InvalidPolygonError(f"{where}: coordinates must be finite numbers")
    lon, lat = pts[:, 0], pts[:, 1]
    bad = np.flatnonzero(np.abs(lat) > 90)
    if len(bad):
        i = int(bad[0])
        raise InvalidPolygonError(
            f"{where}: latitude {lat[i]:g} at vertex {i} is outside [-90, 90] (coordinates must "
            "be longitude, latitude in that order; for projected coordinates give --crs)"
        )
    bad = np.flatnonzero(np.abs(lon) > 180)
    if len(bad):
        i = int(bad[0])
        raise InvalidPolygonError(
            f"{where}: longitude {lon[i]:g} at vertex {i} is outside [-180, 180] (an area "
            "across the antimeridian must be split there; for projected coordinates give --crs)"
        )
    if np.any(np.abs(lat) == 90):
        raise InvalidPolygonError(f"{where}: a vertex lies on a pole; cannot plan across a pole")
    step = np.diff(np.append(lon, lon[0]))
    wrapped = (step + 180) % 360 - 180
    winding = float(np.sum(wrapped))
    if abs(winding) > 180:
        pole = "North" if np.mean(lat) > 0 else "South"
        raise InvalidPolygonError(
            f"{where}: the area encloses the {pole} Pole (its longitudes wind once around it); "
            "cannot plan across a pole: split the area, or give it in a polar projected CRS "
            "with --crs"
        )
    jumps = np.flatnonzero(np.abs(step) > 180)
    if len(jumps):
        i = int(jumps[0])
        raise InvalidPolygonError(
            f"{where}: the area crosses the antimeridian (180 degrees longitude) between vertex "
            f"{i} ({lon[i]:g}) and vertex {(i + 1) % len(lon)} ({lon[(i + 1) % len(lon)]:g}); "
            "split it there (RFC 7946, section 3.1.9) or give it in a projected CRS with --crs"
        )
    return pts


class Projection:
    """The map between an area's coordinates (source CRS) and its plan frame.

    Attributes:
        source_crs: CRS of the area's coordinates, ``None`` for planar.
        plan_crs: CRS of the plan frame (a UTM zone for geographic input, the source CRS for
            projected input), ``None`` for planar.
        scale: plan units per ground metre at the centre of the area (1 for planar).
        scale_min, scale_max: the smallest and largest of that factor over the area's bounding
            box, in every direction.
    """

    def __init__(self, source_crs: str | None, plan_crs: str | None) -> None:
        self.source_crs = source_crs
        self.plan_crs = plan_crs
        self.scale = self.scale_min = self.scale_max = 1.0
        self._fwd: Any = None
        self._inv: Any = None
        self._lonlat: Any = None
        self._geod: Any = None
        if source_crs is None:
            return
        pyproj = _pyproj()
        if plan_crs != source_crs:
            self._fwd = pyproj.Transformer.from_crs(source_crs, plan_crs, always_xy=True)
            self._inv = pyproj.Transformer.from_crs(plan_crs, source_crs, always_xy=True)
        self._lonlat = pyproj.Transformer.from_crs(plan_crs, LONLAT, always_xy=True)
        self._geod = pyproj.Geod(ellps="WGS84")

    def __repr__(self) -> str:
        return (
            f"Projection(source_crs={self.source_crs!r}, plan_crs={self.plan_crs!r}, "
            f"scale={self.scale:.9f})"
        )

    @property
    def planar(self) -> bool:
        """True for planar coordinates (no CRS)."""
        return self.source_crs is None

    @property
    def geographic(self) -> bool:
        """True when the source coordinates are longitude/latitude (planned in a UTM zone)."""
        return self.source_crs is not None and self.plan_crs != self.source_crs

    @staticmethod
    def _apply(transformer: Any, points: ArrayLike) -> NDArray[np.float64]:
        pts = np.asarray(points, dtype=np.float64)
        if transformer is None:
            return pts.copy()
        flat = pts.reshape(-1, 2)
        x, y = transformer.transform(flat[:, 0], flat[:, 1])
        return np.stack([np.asarray(x), np.asarray(y)], axis=-1).reshape(pts.shape)

    def to_plan(self, points: ArrayLike) -> NDArray[np.float64]:
        """Source coordinates ``(..., 2)`` to the plan frame."""
        return self._apply(self._fwd, points)

    def to_source(self, points: ArrayLike) -> NDArray[np.float64]:
        """Plan-frame points ``(..., 2)`` back to the source coordinates."""
        return self._apply(self._inv, points)

    def to_lonlat(self, points: ArrayLike) -> NDArray[np.float64]:
        """Plan-frame points ``(..., 2)`` to WGS 84 longitude, latitude.

        Raises:
            InvalidParameterError: planar coordinates have no longitude and latitude.
        """
        if self._lonlat is None:
            raise InvalidParameterError(
                "planar coordinates have no longitude and latitude: give the area's CRS "
                "(e.g. --crs EPSG:28992) to write geographic formats"
            )
        return self._apply(self._lonlat, points)

    def ground_distance(self, a: ArrayLike, b: ArrayLike) -> NDArray[np.float64]:
        """Distance on the ground (metres, geodesic on WGS 84) between plan-frame points."""
        if self.planar:
            return np.linalg.norm(np.asarray(b, float) - np.asarray(a, float), axis=-1)
        la, lb = self.to_lonlat(a).reshape(-1, 2), self.to_lonlat(b).reshape(-1, 2)
        _, _, dist = self._geod.inv(la[:, 0], la[:, 1], lb[:, 0], lb[:, 1])
        return np.asarray(dist).reshape(np.asarray(a).shape[:-1])

    def ground_area(self, ring_plan: ArrayLike) -> float:
        """Area on the ground (square metres, on WGS 84) of a plan-frame ring."""
        ring = np.asarray(ring_plan, dtype=np.float64)
        if self.planar:
            return Polygon(ring).area
        ll = self.to_lonlat(ring)
        area, _ = self._geod.polygon_area_perimeter(ll[:, 0], ll[:, 1])
        return abs(float(area))

    def measure_scale(self, ring_plan: ArrayLike) -> None:
        """Measure the scale factor over the ring's bounding box (5 x 5 grid and the vertices)."""
        if self.planar:
            return
        ring = np.asarray(ring_plan, dtype=np.float64)
        lo, hi = ring.min(axis=0), ring.max(axis=0)
        gx, gy = np.meshgrid(np.linspace(lo[0], hi[0], 5), np.linspace(lo[1], hi[1], 5))
        pts = np.concatenate([ring, np.stack([gx.ravel(), gy.ravel()], axis=1)])
        dirs = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, -1.0]]) / np.array(
            [[1.0], [1.0], [math.sqrt(2)], [math.sqrt(2)]]
        )
        step = 10.0
        a = pts[:, None, :] - step / 2 * dirs[None]
        b = pts[:, None, :] + step / 2 * dirs[None]
        k = step / self.ground_distance(a, b)
        centre = (lo + hi) / 2
        kc = step / self.ground_distance(centre - step / 2 * dirs, centre + step / 2 * dirs)
        self.scale = float(np.mean(kc))
        self.scale_min = float(k.min())
        self.scale_max = float(k.max())


def projection_for(ring: ArrayLike, crs: str | None, where: str = "area") -> Projection:
    """The projection to plan an area given by ``ring`` in ``crs`` (see the module docstring)."""
    crs = parse_crs(crs)
    pts = np.asarray(ring, dtype=np.float64)
    if crs is None:
        return Projection(None, None)
    if _is_geographic(crs):
        lonlat = pts
        if crs != LONLAT:
            lonlat = Projection._apply(
                _pyproj().Transformer.from_crs(crs, LONLAT, always_xy=True), pts
            )
        lonlat = check_lonlat(lonlat, where)
        lon_c = float((lonlat[:, 0].min() + lonlat[:, 0].max()) / 2)
        lat_c = float((lonlat[:, 1].min() + lonlat[:, 1].max()) / 2)
        proj = Projection(crs, utm_crs(lon_c, lat_c))
    else:
        proj = Projection(crs, crs)
    ring_plan = proj.to_plan(pts)
    if not np.all(np.isfinite(ring_plan)):
        raise InvalidPolygonError(
            f"{where}: the coordinates cannot be projected from {crs} (outside its area of use?)"
        )
    proj.measure_scale(ring_plan)
    if proj.scale_max / proj.scale_min - 1 > 1e-3:
        log.warning(
            "the map scale varies by %.2g%% over the area (%s): the ground spacing will be up "
            "to that much smaller than asked",
            100 * (proj.scale_max / proj.scale_min - 1),
            proj.plan_crs,
        )
    return proj


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
            are optimised by :func:`boustro.decompose.optimize_region` (a grid search with the
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
            with lines cut at the boundary and the holes (:func:`boustro.decompose.plan_region`).
            Given, it also turns off the convex-hull rule for nearly convex areas.
        sweep: sweep direction of the decomposition, degrees in the plan frame (default:
            chosen by :func:`boustro.decompose.choose_sweep`).

    Raises:
        InvalidPolygonError, NonConvexPolygonError, InvalidParameterError, NoTransectError.
    """
    if not isinstance(area, Area):
        hole_rings = tuple(np.asarray(h, dtype=np.float64) for h in holes)
        area = Area(np.asarray(area, dtype=np.float64), parse_crs(crs), "", "<array>", hole_rings)
    else:  # one spelling of the CRS from here on ("EPSG:n", or None for planar)
        area = dataclasses.replace(area, crs=parse_crs(area.crs))
    where = area.source
    s_m, reach_m, gap_m, sensor_altitude, sensor_text = _sensor_spacing(spacing)
    proj = projection_for(area.ring, area.crs, where)
    ring_plan = proj.to_plan(area.ring)
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
    try:
        surveyed = Polygon(ring_plan)
        region = Region(surveyed, holes_plan) if holes_plan else None
    except InvalidPolygonError as exc:
        raise InvalidPolygonError(f"{where}: {exc}") from None
    k_lo, k_hi = proj.scale_min, proj.scale_max
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
    s_plan = s_m * k_lo
    start_plan = ring_plan[0] if start is None else proj.to_plan(np.asarray(start, float))
    if start is not None:
        far = float(np.min(np.hypot(*(ring_plan - start_plan).T))) / k_lo
        size = float(np.max(np.hypot(*(ring_plan - ring_plan.mean(axis=0)).T))) * 2 / k_lo
        if far > 10 * size:
            log.warning(
                "the start is %.3g m from the area, %.0f times its size: swapped longitude and "
                "latitude?",
                far,
                far / size,
            )
    ground_area = proj.ground_area(ring_plan) - sum(proj.ground_area(h) for h in holes_plan)
    if region is None:
        chosen = method or DEFAULT_METHOD
        opts = dict(METHOD_OPTIONS.get(chosen, {}))
        opts.update(options or {})
        try:
            optimum = optimize(poly, s_plan, method=chosen, fitness=fitness, **opts)
        except ProblemTooLargeError as exc:
            if method is not None:
                raise
            log.warning("%s; planning with the hybrid optimiser instead", exc)
            optimum = optimize(poly, s_plan, method=FALLBACK_METHOD, fitness=fitness)
        plan = build_plan(
            poly,
            s_plan,
            optimum.angle,
            optimum.offset,
            layout=layout,  # type: ignore[arg-type]
            start=start_plan,
            turnaround=float(turnaround) * k_hi,
            reach=reach_m * k_lo,
            nadir_gap=gap_m * k_hi,
            ground_scale=proj.scale,
            speed=speed,
            turn_time=turn_time,
            area=ground_area,
        )
        cov = coverage(plan, surveyed) if check_coverage else None
    else:
        if method not in (None, DEFAULT_METHOD, "grid", "region-grid"):
            raise InvalidParameterError(
                f"method {method!r} optimises convex areas only; a concave area or one with "
                "holes is optimised by grid search over its segments (leave --method out)"
            )
        opts = dict(REGION_OPTIONS)
        opts.update({k: v for k, v in (options or {}).items() if k in ("n_angles", "n_offsets")})
        plan = plan_region(
            region,
            s_plan,
            decompose_area="auto" if decompose is None else bool(decompose),
            sweep=None if sweep is None else math.radians(float(sweep)),
            fitness=fitness,
            layout=layout,  # type: ignore[arg-type]
            start=None if start is None else start_plan,  # None: the shortest tour
            turnaround=float(turnaround) * k_hi,
            reach=reach_m * k_lo,
            nadir_gap=gap_m * k_hi,
            ground_scale=proj.scale,
            speed=speed,
            turn_time=turn_time,
            area=ground_area,
            **opts,
        )
        optimum = _region_optimum(plan, s_plan)
        cov = coverage(plan, region) if check_coverage else None
    if proj.planar:
        wp_ll = tr_ll = area_ll = None
        holes_ll: tuple[NDArray[np.float64], ...] = ()
        u = np.array([math.cos(plan.angle), math.sin(plan.angle)])
        bearing = math.degrees(math.atan2(u[0], u[1])) % 180.0
    else:
        wp_ll = proj.to_lonlat(plan.waypoints)
        tr_ll = proj.to_lonlat(plan.transects)
        area_ll = proj.to_lonlat(ring_plan)
        holes_ll = tuple(proj.to_lonlat(h) for h in holes_plan)
        c = poly.centre if region is None else plan.cells[_main_cell(plan)].polygon.centre
        u = np.array([math.cos(plan.angle), math.sin(plan.angle)])
        a, b = proj.to_lonlat(np.stack([c - 5 * u, c + 5 * u]))
        azimuth, _, _ = proj._geod.inv(a[0], a[1], b[0], b[1])
        bearing = float(azimuth) % 180.0
    if altitude is None:
        altitude = sensor_altitude
    else:
        value = as_number("altitude", altitude)
        if not (math.isfinite(value) and value >= 0):
            raise InvalidParameterError(
                f"altitude must be a finite number >= 0 (metres above take-off), got {altitude!r}"
            )
    home_plan = plan.waypoints[0] if start is None else start_plan
    return Mission(
        name=area.name,
        area=area,
        projection=proj,
        plan=plan,
        optimum=optimum,
        spacing=s_m,
        reach=reach_m,
        nadir_gap=gap_m,
        turnaround=float(turnaround),
        hull_depth=depth / k_lo,
        altitude=None if altitude is None else float(altitude),
        coverage=cov,
        sensor=sensor_text,
        waypoints=proj.to_source(plan.waypoints),
        transects=proj.to_source(plan.transects),
        waypoints_lonlat=wp_ll,
        transects_lonlat=tr_ll,
        area_lonlat=area_ll,
        bearing=bearing,
        home=proj.to_source(home_plan),
        home_lonlat=None if proj.planar else proj.to_lonlat(home_plan),
        holes_lonlat=holes_ll,
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
