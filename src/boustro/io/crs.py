"""Coordinate reference systems: parsing, UTM zones, :class:`Projection` to/from the plan frame."""

from __future__ import annotations

import functools
import logging
import math
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import (
    InvalidParameterError,
    InvalidPolygonError,
    MissingDependencyError,
)
from ..geometry import Polygon
from .read import LONLAT

__all__ = [
    "MissingDependencyError",
    "Projection",
    "check_lonlat",
    "parse_crs",
    "plan_frame",
    "proj_errors",
    "projection_for",
    "utm_crs",
]


log = logging.getLogger("boustro")


@functools.lru_cache(maxsize=64)
def _transformer(source: str | None, target: str | None, thread: int) -> Any:
    """``pyproj.Transformer.from_crs(source, target)``, made once per thread (making one takes
    ~15 ms, more than planning a small field: a batch plans thousands in the same CRSs)."""
    return _pyproj().Transformer.from_crs(source, target, always_xy=True)


_PLANAR_NAMES = ("planar", "local", "none")


def _pyproj() -> Any:
    try:
        import pyproj
    except ImportError:  # pragma: no cover - pyproj is a dependency of the plan command
        raise MissingDependencyError(
            "geographic and projected coordinates need pyproj: pip install pyproj "
            "(or give planar coordinates with crs=None / --crs planar)"
        ) from None
    return pyproj


@contextmanager
def proj_errors(crs: object) -> Iterator[None]:
    """Turn any pyproj error raised inside into one line of :class:`InvalidParameterError`
    naming ``crs`` (a CRS, or a transformation).

    >>> with proj_errors("+proj=nonsense"):
    ...     raise _pyproj().exceptions.ProjError("bad step\\nsecond line")
    Traceback (most recent call last):
    ...
    boustro.errors.InvalidParameterError: coordinate reference system '+proj=nonsense': PROJ failed: bad step second line
    """  # noqa: E501
    pyproj = _pyproj()
    errors = (
        pyproj.exceptions.ProjError,  # CRSError derives from it
        pyproj.exceptions.GeodError,
        pyproj.exceptions.DataDirError,
    )
    try:
        yield
    except errors as exc:
        shown = " ".join(str(crs).split())
        shown = shown if len(shown) <= 80 else shown[:77] + "..."
        raise InvalidParameterError(
            f"coordinate reference system {shown!r}: PROJ failed: {' '.join(str(exc).split())}"
        ) from None


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
    except pyproj.exceptions.ProjError as exc:
        raise InvalidParameterError(
            f"unknown coordinate reference system {crs!r} (expected e.g. EPSG:4326, "
            f"EPSG:28992, or 'planar'): {' '.join(str(exc).split())}"
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
            f"{where}: latitude {lat[i]:g} at vertex {i + 1} is outside [-90, 90] (coordinates "
            "must be longitude, latitude in that order; for projected coordinates give --crs)"
        )
    bad = np.flatnonzero(np.abs(lon) > 180)
    if len(bad):
        i = int(bad[0])
        raise InvalidPolygonError(
            f"{where}: longitude {lon[i]:g} at vertex {i + 1} is outside [-180, 180] (an area "
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
            f"{i + 1} ({lon[i]:g}) and vertex {(i + 1) % len(lon) + 1} "
            f"({lon[(i + 1) % len(lon)]:g}); "
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
        with proj_errors(source_crs):
            self._transformers(plan_crs, source_crs)

    def _transformers(self, plan_crs: str | None, source_crs: str) -> None:
        if plan_crs != source_crs:
            self._fwd = _transformer(source_crs, plan_crs, threading.get_ident())
            self._inv = _transformer(plan_crs, source_crs, threading.get_ident())
        self._lonlat = _transformer(plan_crs, LONLAT, threading.get_ident())
        self._geod = _pyproj().Geod(ellps="WGS84")

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
        with proj_errors(getattr(transformer, "source_crs", transformer)):
            x, y = transformer.transform(flat[:, 0], flat[:, 1])
        return np.stack([np.asarray(x), np.asarray(y)], axis=-1).reshape(pts.shape)

    def to_plan(self, points: ArrayLike) -> NDArray[np.float64]:
        """Source coordinates ``(..., 2)`` to the plan frame."""
        return self._apply(self._fwd, points)

    def point_to_plan(self, point: ArrayLike, what: str) -> NDArray[np.float64]:
        """One point ``(x, y)`` of the source coordinates (a start, a home) in the plan frame.

        Raises:
            InvalidParameterError: not a finite pair, or a point the projection cannot map
                (e.g. a latitude outside [-90, 90]), named by ``what`` with its coordinates.
        """
        try:
            p = np.asarray(point, dtype=np.float64).reshape(-1)
        except (TypeError, ValueError):  # not numbers, or a ragged list
            p = np.full(0, np.nan)
        if p.shape != (2,) or not np.all(np.isfinite(p)):
            raise InvalidParameterError(f"{what} must be a finite (x, y) pair, got {point!r}")
        out = self.to_plan(p)
        if not np.all(np.isfinite(out)):
            hint = (
                ": longitude, latitude expected, in that order, latitude within [-90, 90]"
                if self.geographic
                else " (outside the CRS's area of use?)"
            )
            raise InvalidParameterError(
                f"{what} ({p[0]:g}, {p[1]:g}) cannot be projected from {self.source_crs} to "
                f"{self.plan_crs}{hint}"
            )
        return out

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
        with proj_errors(self.plan_crs):
            _, _, dist = self._geod.inv(la[:, 0], la[:, 1], lb[:, 0], lb[:, 1])
        return np.asarray(dist).reshape(np.asarray(a).shape[:-1])

    def ground_area(self, ring_plan: ArrayLike) -> float:
        """Area on the ground (square metres, on WGS 84) of a plan-frame ring."""
        ring = np.asarray(ring_plan, dtype=np.float64)
        if self.planar:
            return Polygon(ring).area
        ll = self.to_lonlat(ring)
        with proj_errors(self.plan_crs):
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
    """The projection to plan an area given by ``ring`` in ``crs`` (see the module docstring).

    Raises:
        InvalidParameterError: an unknown CRS, or any error of PROJ (one line).
        InvalidPolygonError: coordinates outside the CRS's range or area of use.
    """
    proj, ring_plan = plan_frame(ring, crs, where)
    if proj.planar:
        return proj
    with proj_errors(proj.source_crs):
        proj.measure_scale(ring_plan)
    if proj.scale_max / proj.scale_min - 1 > 1e-3:
        log.warning(
            "the map scale varies by %.2g%% over the area (%s): the ground spacing will be up "
            "to that much smaller than asked",
            100 * (proj.scale_max / proj.scale_min - 1),
            proj.plan_crs,
        )
    return proj


def plan_frame(
    ring: ArrayLike, crs: str | None, where: str = "area"
) -> tuple[Projection, NDArray[np.float64]]:
    """The projection of :func:`projection_for` before its scale is measured (nothing logged),
    and ``ring`` in its plan frame.

    Raises:
        as :func:`projection_for`.
    """
    crs = parse_crs(crs)
    with proj_errors(crs):
        return _plan_frame(ring, crs, where)


def _plan_frame(
    ring: ArrayLike, crs: str | None, where: str
) -> tuple[Projection, NDArray[np.float64]]:
    pts = np.asarray(ring, dtype=np.float64)
    if crs is None:
        return Projection(None, None), pts.copy()
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
    return proj, ring_plan
