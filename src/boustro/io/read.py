"""Reading survey areas (ring + CRS) and polygons: the dispatcher over the per-format readers.

:func:`read_areas` reads every field of an area file, :func:`read_area` its first: GeoJSON, KML/GML
and WKT text (:mod:`boustro.io.read_geojson`, :mod:`boustro.io.read_kml`,
:mod:`boustro.io.read_wkt`), QGroundControl plans, KMZ and the formats GDAL reads (dispatched by
:mod:`boustro.io.read_file`); :func:`read_polygon` planar polygons.
"""

from __future__ import annotations

import os
from importlib import resources

from ..errors import PolygonFileError
from .area import LONLAT, Area
from .area import close_ring as _close_open
from .area import crs_name as _crs_name
from .read_fields import fields_from_text
from .read_file import load_file
from .read_geojson import (
    _feature_name,
    _from_geometry,
    _geojson_crs,
    _geometry_ring,
    _geometry_rings,
    _polygon_geometry,
    _ring,
    area_from_json,
    log,
    parse_json,
    polygon_from_json,
    read_polygon,
)
from .read_kml import _local, _north_first, _xml_coordinates, area_from_kml
from .read_objects import area_from_object, areas_from_object
from .read_wkt import _WKT_HEAD, _WKT_TYPES, _wkt_nested, area_from_wkt

__all__ = [
    "EMBEDDED_FIELD",
    "LONLAT",
    "PAPER_PARALLELOGRAM",
    "PAPER_SPACING",
    "Area",
    "area_from_json",
    "area_from_kml",
    "area_from_object",
    "area_from_text",
    "area_from_wkt",
    "areas_from_object",
    "areas_from_text",
    "embedded_field",
    "polygon_from_json",
    "read_area",
    "read_areas",
    "read_polygon",
]

#: The parallelogram of the paper's Figure 1, in the authors' units.
PAPER_PARALLELOGRAM: tuple[tuple[float, float], ...] = ((8, 4), (8, 10), (4, 8), (4, 2))
#: The transect spacing the authors' scripts use with it (0.0559 of the normalised frame).
PAPER_SPACING = 0.5

#: The embedded example field: a 3.6 ha parcel in the Netherlands from the Fields2Cover project
#: (BSD 3-Clause, Wageningen University; see ``data/LICENSE-Fields2Cover``).
EMBEDDED_FIELD = "fields2cover_test_field.json"


def _sniff(text: str) -> str:
    head = text.lstrip()[:1]
    return "kml" if head == "<" else "json" if head in ("{", "[") else "wkt"


def area_from_text(
    text: str, where: str = "input", crs: str | None = None, kind: str | None = None
) -> Area:
    """An :class:`Area` from file content; ``kind`` is ``json``, ``kml`` or ``wkt`` (sniffed
    from the first character when ``None``: ``<`` XML, ``{`` or ``[`` JSON, else WKT)."""
    if kind is None:
        kind = _sniff(text)
    if kind in ("json", "kml", "wkt") and not text.strip():
        raise PolygonFileError(f"{where}: the file is empty: no polygon in it")
    if kind == "json":
        return area_from_json(parse_json(text, where), where, crs)
    if kind == "kml":
        return area_from_kml(text, where, crs)
    if kind == "wkt":
        head = _WKT_HEAD.match(text)
        if head and (head.group(2) or "").upper() == "GEOMETRYCOLLECTION":
            # its polygons (other geometries left out), as read_areas reads them; the first
            fields = fields_from_text(text, where, crs, "wkt")
            if not fields:
                raise PolygonFileError(f"{where}: no polygon in the GEOMETRYCOLLECTION")
            return fields[0][1]
        return area_from_wkt(text, where, crs)
    raise PolygonFileError(f"{where}: unknown area format {kind!r}; expected json, kml or wkt")


def read_area(path: str | os.PathLike[str], crs: str | None = None) -> Area:
    """Read a survey area: the first field of any area file :func:`read_areas` reads.

    Args:
        path: the file.
        crs: the CRS of its coordinates, overriding what the file says (default: the file's
            CRS, else WGS 84 longitude/latitude ``"EPSG:4326"``).

    Raises:
        PolygonFileError: missing or unreadable file, malformed content, no polygon.
        MissingDependencyError: a format read through GDAL without pyogrio installed.

    Example:
        >>> from importlib import resources
        >>> area = read_area(resources.files("boustro") / "data" / EMBEDDED_FIELD)
        >>> area.name, area.crs, len(area.ring)
        ('test parcel', 'EPSG:4326', 19)
    """
    name = os.fspath(path)
    loaded = load_file(name, crs)
    if loaded.fields is not None:
        if len(loaded.fields) > 1:
            log.warning("%s: %d fields; only the first is used", name, len(loaded.fields))
        area = loaded.fields[0][1]
    else:
        area = area_from_text(loaded.text or "", name, crs, loaded.kind)
    return _named(area, name)


def _named(area: Area, path: str) -> Area:
    """``area``, named after the file's stem if it has no name."""
    if area.name:
        return area
    stem = os.path.splitext(os.path.basename(path))[0]
    return Area(area.ring, area.crs, stem, area.source, area.holes)


def areas_from_text(
    text: str, where: str = "input", crs: str | None = None, kind: str | None = None
) -> list[Area]:
    """Every field of a file's content (:mod:`boustro.io.read_fields`), in file order; ``kind``
    as in :func:`area_from_text`. Several fields: unnamed ones are ``field N`` (N from 1); one
    field: ``[area_from_text(...)]``.

    Raises:
        PolygonFileError: malformed content, or no polygon in it.
    """
    kind = _sniff(text) if kind is None else kind
    fields = fields_from_text(text, where, crs, kind)
    if len(fields) <= 1:  # one field (or an error): read as one area
        return [area_from_text(text, where, crs, kind)]
    return [
        Area(a.ring, a.crs, name or f"field {i}", a.source, a.holes)
        for i, (name, a) in enumerate(fields, start=1)
    ]


def read_areas(path: str | os.PathLike[str], crs: str | None = None) -> list[Area]:
    """Read every field of an area file, each an :class:`Area` with its name, in file order.

    Text: GeoJSON (each polygon of a FeatureCollection, MultiPolygon), KML, GML, WKT
    MULTIPOLYGON/GEOMETRYCOLLECTION (see :mod:`boustro.io.read_fields`), QGroundControl
    ``.plan`` (:mod:`boustro.io.read_qgc`); binary: KMZ, and through GDAL (the ``boustro[geo]``
    extra) Shapefile (plain or zipped), GeoPackage, FlatGeobuf, GeoParquet
    (:mod:`boustro.io.read_gdal`); dispatched by :mod:`boustro.io.read_file`. A file with one
    field gives ``[read_area(path, crs)]``.

    Raises:
        PolygonFileError: missing or unreadable file, malformed content, no polygon.
        MissingDependencyError: a format read through GDAL without pyogrio installed.

    Example:
        >>> from importlib import resources
        >>> [a.name for a in read_areas(resources.files("boustro") / "data" / EMBEDDED_FIELD)]
        ['test parcel']
    """
    name = os.fspath(path)
    loaded = load_file(name, crs)
    if loaded.fields is None:
        text = loaded.text or ""
        areas = areas_from_text(text, name, crs, loaded.kind or _sniff(text))
    elif len(loaded.fields) == 1:
        areas = [loaded.fields[0][1]]
    else:  # several fields: the unnamed ones are "field N"
        areas = [
            Area(a.ring, a.crs, n or f"field {i}", a.source, a.holes)
            for i, (n, a) in enumerate(loaded.fields, start=1)
        ]
    return [_named(areas[0], name)] if len(areas) == 1 else areas


def embedded_field() -> Area:
    """The embedded example field (3.6 ha, the Netherlands, WGS 84), see :data:`EMBEDDED_FIELD`."""
    text = (resources.files("boustro") / "data" / EMBEDDED_FIELD).read_text("utf-8")
    area = area_from_text(text, "<embedded field>", None, "json")
    return Area(area.ring, area.crs, area.name or "test parcel", "<embedded>")


# Helpers of the former single module, importable from it still.
_HELPERS = (
    _close_open,
    _crs_name,
    _feature_name,
    _from_geometry,
    _geojson_crs,
    _geometry_ring,
    _geometry_rings,
    _local,
    _north_first,
    _polygon_geometry,
    _ring,
    _wkt_nested,
    _xml_coordinates,
    _WKT_HEAD,
    _WKT_TYPES,
    log,
)
