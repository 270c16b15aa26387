"""Compatibility path: :mod:`boustro.io.crs` (coordinates) and :mod:`boustro.mission`."""

from __future__ import annotations

from .io.crs import (
    _PLANAR_NAMES,
    MissingDependencyError,
    Projection,
    _is_geographic,
    _pyproj,
    check_lonlat,
    parse_crs,
    projection_for,
    utm_crs,
)
from .io.read import LONLAT, Area
from .mission import (
    DEFAULT_HULL_TOLERANCE,
    DEFAULT_METHOD,
    FALLBACK_METHOD,
    METHOD_OPTIONS,
    REGION_OPTIONS,
    Mission,
    _main_cell,
    _region_optimum,
    _sensor_spacing,
    log,
    plan_area,
)

__all__ = [
    "DEFAULT_HULL_TOLERANCE",
    "DEFAULT_METHOD",
    "FALLBACK_METHOD",
    "LONLAT",
    "METHOD_OPTIONS",
    "REGION_OPTIONS",
    "_PLANAR_NAMES",
    "Area",
    "MissingDependencyError",
    "Mission",
    "Projection",
    "_is_geographic",
    "_main_cell",
    "_pyproj",
    "_region_optimum",
    "_sensor_spacing",
    "check_lonlat",
    "log",
    "parse_crs",
    "plan_area",
    "projection_for",
    "utm_crs",
]
