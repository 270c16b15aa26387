"""A constant height above ground over terrain: waypoint altitudes AMSL from a DEM.

The DEM is a GeoTIFF (any CRS) read with rasterio (``pip install 'boustro[terrain]'``),
imported when used; the ground is interpolated bilinearly between pixel centres. Along every
leg of the path the ground is sampled at half the DEM's pixel size, and points are added (kind
``"terrain"``) where the straight climb or descent between two waypoints would be more than
``tolerance`` metres off the constant height (a Douglas-Peucker simplification of the ground
profile: every sample within ``tolerance`` of the line between the points kept around it).
"""

from __future__ import annotations

import dataclasses
import math
import os
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._validate import as_number
from ..errors import InvalidParameterError
from .flight import TerrainRoute
from .types import Mission

__all__ = [
    "DEFAULT_TOLERANCE",
    "Dem",
    "check_height",
    "follow_terrain",
    "open_dem",
    "profile_points",
]

#: Largest vertical error between two waypoints, metres, by default.
DEFAULT_TOLERANCE = 1.0
#: At most this many ground samples over a whole mission (the step grows beyond).
MAX_SAMPLES = 2_000_000


@dataclasses.dataclass(frozen=True)
class Dem:
    """A DEM in memory: elevations, the affine transform, its CRS, its pixel size (metres)."""

    z: NDArray[np.float64]
    transform: Any
    crs: Any
    pixel_m: float
    name: str

    def sample(self, lonlat: NDArray[np.float64]) -> NDArray[np.float64]:
        """Bilinear elevations at ``(N, 2)`` longitude/latitude points.

        Raises:
            InvalidParameterError: a point outside the DEM or on a no-data pixel.
        """
        from pyproj import Transformer

        to_dem = Transformer.from_crs("EPSG:4326", self.crs, always_xy=True)
        x, y = to_dem.transform(lonlat[:, 0], lonlat[:, 1])
        inv = ~self.transform  # pixel (column, row) from the DEM's x, y
        x, y = np.asarray(x), np.asarray(y)
        c = inv.a * x + inv.b * y + inv.c - 0.5  # from pixel centres
        r = inv.d * x + inv.e * y + inv.f - 0.5
        h, w = self.z.shape
        outside = (r < -0.5) | (r > h - 0.5) | (c < -0.5) | (c > w - 0.5)
        if outside.any():
            lon, lat = lonlat[int(np.argmax(outside))]
            raise InvalidParameterError(
                f"--dem {self.name}: the point lon {lon:.6f}, lat {lat:.6f} is outside the DEM"
            )
        r0 = np.clip(np.floor(r), 0, max(h - 2, 0)).astype(np.int64)
        c0 = np.clip(np.floor(c), 0, max(w - 2, 0)).astype(np.int64)
        fr = np.clip(r - r0, 0.0, 1.0) if h > 1 else np.zeros_like(r)
        fc = np.clip(c - c0, 0.0, 1.0) if w > 1 else np.zeros_like(c)
        r1, c1 = np.minimum(r0 + 1, h - 1), np.minimum(c0 + 1, w - 1)
        z = self.z
        top = z[r0, c0] * (1 - fc) + z[r0, c1] * fc
        bottom = z[r1, c0] * (1 - fc) + z[r1, c1] * fc
        out = top * (1 - fr) + bottom * fr
        bad = ~np.isfinite(out)
        if bad.any():
            lon, lat = lonlat[int(np.argmax(bad))]
            raise InvalidParameterError(
                f"--dem {self.name}: no elevation (no-data) at lon {lon:.6f}, lat {lat:.6f}"
            )
        return np.asarray(out, dtype=np.float64)


def open_dem(path: str | os.PathLike[str]) -> Dem:
    """The first band of a GeoTIFF DEM (no-data as NaN).

    Raises:
        InvalidParameterError: rasterio missing, the file unreadable or without a CRS.
    """
    name = os.fspath(path)
    try:
        import rasterio
    except ImportError:
        raise InvalidParameterError(
            "--dem needs rasterio: pip install 'boustro[terrain]'"
        ) from None
    try:
        with rasterio.open(name) as src:
            z = src.read(1, masked=True).astype(np.float64).filled(np.nan)
            transform, crs, res = src.transform, src.crs, src.res
    except rasterio.errors.RasterioError as exc:
        raise InvalidParameterError(f"--dem {name}: {exc}") from None
    if crs is None:
        raise InvalidParameterError(f"--dem {name}: the DEM has no coordinate reference system")
    unit = 111_320.0 if crs.is_geographic else 1.0  # metres per degree, roughly (step only)
    return Dem(z, transform, crs.to_wkt(), min(abs(res[0]), abs(res[1])) * unit, name)


def profile_points(
    along: NDArray[np.float64], ground: NDArray[np.float64], tolerance: float
) -> list[int]:
    """Indices of the samples to keep, ends included, so that the line between consecutive
    kept samples is within ``tolerance`` of every sample between them (Douglas-Peucker).

    >>> profile_points(np.arange(5.0), np.array([0, 0, 3, 0, 0.0]), 1.0)
    [0, 1, 2, 3, 4]
    """
    keep = {0, len(along) - 1}
    stack = [(0, len(along) - 1)]
    while stack:
        i, j = stack.pop()
        if j - i < 2:
            continue
        t = (along[i + 1 : j] - along[i]) / (along[j] - along[i])
        line = ground[i] + t * (ground[j] - ground[i])
        error = np.abs(ground[i + 1 : j] - line)
        k = int(np.argmax(error))
        if error[k] > tolerance:
            keep.add(i + 1 + k)
            stack += [(i, i + 1 + k), (i + 1 + k, j)]
    return sorted(keep)


def check_height(altitude: float | None) -> float:
    """The height above ground; :class:`InvalidParameterError` when there is none."""
    if altitude is None:
        raise InvalidParameterError(
            "--dem needs the height above ground: --altitude METRES, or a camera's"
        )
    return float(altitude)


def follow_terrain(
    mission: Mission, dem: str | os.PathLike[str] | Dem, *, tolerance: float = DEFAULT_TOLERANCE
) -> Mission:
    """``mission`` at its altitude above ground over ``dem``: its :class:`TerrainRoute`."""
    tol = as_number("terrain tolerance", tolerance)
    if not (math.isfinite(tol) and tol > 0):
        raise InvalidParameterError(f"terrain tolerance must be > 0 metres, got {tolerance!r}")
    height = check_height(mission.altitude)
    proj = mission.projection
    if proj.planar:
        raise InvalidParameterError(
            "--dem needs longitude/latitude, but the area is in planar coordinates: give its CRS"
        )
    grid = dem if isinstance(dem, Dem) else open_dem(dem)
    plan = mission.plan
    path = plan.waypoints
    legs = np.hypot(*np.diff(path, axis=0).T) / plan.ground_scale
    step = max(grid.pixel_m / 2, float(legs.sum()) / MAX_SAMPLES, 1e-3)
    points, kinds, ground = [path[:1]], [plan.kinds[0]], [grid.sample(proj.to_lonlat(path[:1]))]
    for k, length in enumerate(legs):
        n = max(2, math.ceil(length / step) + 1)
        t = np.linspace(0.0, 1.0, n)
        samples = path[k] + t[:, None] * (path[k + 1] - path[k])
        z = grid.sample(proj.to_lonlat(samples))
        keep = profile_points(t * length, z, tol)[1:]
        points.append(samples[keep])
        ground.append(z[keep])
        kinds += ["terrain"] * (len(keep) - 1) + [plan.kinds[k + 1]]
    plan_points = np.concatenate(points)
    home = proj.to_lonlat(proj.to_plan(mission.home).reshape(1, 2))
    route = TerrainRoute(
        points=proj.to_source(plan_points),
        lonlat=proj.to_lonlat(plan_points),
        kinds=tuple(kinds),
        ground=np.concatenate(ground),
        height=height,
        tolerance=tol,
        home_ground=float(grid.sample(home)[0]),
        dem=os.path.basename(grid.name),
    )
    return dataclasses.replace(mission, terrain=route)
