"""Survey areas from in-memory geometries: shapely, ``__geo_interface__``, GeoJSON mappings.

The API (:func:`boustro.mission.plan_area`, :func:`areas_from_object`) takes, besides an
:class:`~boustro.io.Area` or vertices, a shapely Polygon/MultiPolygon, any object with a
``__geo_interface__`` (shapely, geopandas, fiona, ...), or a GeoJSON mapping (a geometry, a
Feature or a FeatureCollection). Such an object carries no CRS, so its coordinates are PLANAR
unless ``crs`` says otherwise, or the mapping has a (2008) GeoJSON ``crs`` member (checked like
a file's, :func:`boustro.io.file_crs.crs_from_file`); an object and its ``__geo_interface__``
mapping give the same area. Several polygons (a MultiPolygon of several parts, a collection of
several polygon features) are several fields: :func:`area_from_object` refuses them, pointing to
:func:`areas_from_object`, which gives each as an :class:`Area` (named as
:func:`boustro.io.read_areas` names a file's fields). No shapely import: the geometry is read
through its ``__geo_interface__``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ..errors import PolygonFileError
from .area import Area, crs_text
from .read_fields import _json_fields
from .read_geojson import _geojson_crs

__all__ = ["area_from_object", "areas_from_object", "is_geo_object"]

#: How deep coordinate lists may nest (a GeometryCollection of MultiPolygons is 5).
_MAX_DEPTH = 32


def is_geo_object(obj: Any) -> bool:
    """``obj`` is a geometry object this module reads (a mapping or a ``__geo_interface__``)."""
    return isinstance(obj, Mapping) or hasattr(obj, "__geo_interface__")


def _plain(value: Any, depth: int = 0) -> Any:
    """Tuples, arrays and mappings as JSON-like lists and dicts (shapely gives tuples)."""
    if depth > _MAX_DEPTH:
        raise PolygonFileError(f"the geometry nests deeper than {_MAX_DEPTH} levels")
    if isinstance(value, Mapping):
        return {k: _plain(v, depth + 1) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (list, tuple)):
        return [_plain(v, depth + 1) for v in value]
    return value


def _mapping(obj: Any, where: str) -> dict[str, Any]:
    geo = getattr(obj, "__geo_interface__", obj)
    if callable(geo):
        geo = geo()
    if not isinstance(geo, Mapping) or "type" not in geo:
        raise PolygonFileError(
            f"{where}: expected a GeoJSON geometry, Feature or FeatureCollection mapping, or an "
            f"object with __geo_interface__, got {type(obj).__name__}"
            + (
                " (for an (N, 2) ring of coordinates use boustro.mission.plan_area, or "
                "shapely.Polygon(ring))"
                if isinstance(obj, (list, tuple, np.ndarray))
                else ""
            )
        )
    return _plain(geo)


def areas_from_object(obj: Any, crs: Any = None, where: str = "<geometry>") -> list[Area]:
    """Every polygon of a geometry object as an :class:`Area`, in order (see the module).

    Args:
        obj: a shapely geometry, an object with ``__geo_interface__``, or a GeoJSON mapping.
        crs: the CRS of its coordinates (default: the mapping's ``crs`` member, else planar): a
            name, an EPSG integer or a ``pyproj.CRS`` (a GeoDataFrame's ``.crs``).

    Raises:
        PolygonFileError: not a geometry object, or no polygon in it.
    """
    data = _mapping(obj, where)
    area_crs = crs_text(crs) if crs is not None else _geojson_crs(data, where)
    fields = _json_fields(data, where, area_crs or "planar")
    if not fields:
        raise PolygonFileError(f"{where}: no Polygon in the {data['type']} given")
    several = len(fields) > 1
    return [
        Area(a.ring, area_crs, n or (f"field {i}" if several else ""), a.source, a.holes)
        for i, (n, a) in enumerate(fields, start=1)
    ]


def area_from_object(obj: Any, crs: str | None = None, where: str = "<geometry>") -> Area:
    """The one polygon of a geometry object as an :class:`Area` (see the module).

    Raises:
        PolygonFileError: not a geometry object, no polygon, or several polygons (several
            fields: plan each area of :func:`areas_from_object`).
    """
    areas = areas_from_object(obj, crs, where)
    if len(areas) > 1:
        raise PolygonFileError(
            f"{where}: {len(areas)} polygons given (several fields); plan one area at a time: "
            "boustro.io.areas_from_object(geometry) gives each as an Area"
        )
    return areas[0]
