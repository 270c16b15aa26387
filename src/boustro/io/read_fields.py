"""Every field in a file: each polygon of a file as a named area (:func:`boustro.io.read_areas`).

A GeoJSON FeatureCollection (each Polygon or MultiPolygon feature), a MultiPolygon or
GeometryCollection, KML (each Polygon, in or out of a placemark), GML (each parcel's polygon)
and WKT ``MULTIPOLYGON`` / ``GEOMETRYCOLLECTION`` hold several fields; the parts of a multi-part
geometry are separate fields. Names: the feature's ``name`` (or ``Name``, ``NAME``, ``title``)
property, else its ``id``; the placemark's ``<name>``, a GML feature's ``name`` or ``gml:id``;
a part of a multi-part feature adds `` part K``; an unnamed field is ``field N`` (N from 1, in
file order). A file with one field reads exactly as :func:`boustro.io.read_area` reads it.

"""

from __future__ import annotations

import json
import re
from typing import Any
from xml.etree import ElementTree

import numpy as np

from ..errors import PolygonFileError
from .area import LONLAT, Area
from .area import close_ring as _close_open
from .read_geojson import _feature_name, _geojson_crs, _geometry_rings
from .read_kml import _local, xml_polygon_area
from .read_wkt import _WKT_HEAD, _wkt_nested, wkt_rings

__all__ = ["fields_from_text"]

_MULTI = re.compile(r"\s*(SRID\s*=\s*\d+\s*;)?\s*(MULTIPOLYGON|GEOMETRYCOLLECTION)", re.I)

#: One field before its name is settled: ``(name or "", area)``.
_Named = tuple[str, Area]


def _part_names(name: str, count: int) -> list[str]:
    if count == 1 or not name:
        return [name] * count
    return [f"{name} part {k + 1}" for k in range(count)]


# -- GeoJSON -----------------------------------------------------------------------------------
def _geometry_polygons(geom: Any, where: str) -> list[Any]:
    """The polygon coordinate lists of a Polygon, MultiPolygon or GeometryCollection."""
    if not isinstance(geom, dict):
        return []
    kind, coords = geom.get("type"), geom.get("coordinates")
    if kind == "Polygon":
        return [coords]
    if kind == "MultiPolygon":
        if not isinstance(coords, list) or not coords:
            raise PolygonFileError(f"{where}: a MultiPolygon needs a non-empty list of polygons")
        return list(coords)
    if kind == "GeometryCollection" and isinstance(geom.get("geometries"), list):
        return [p for g in geom["geometries"] for p in _geometry_polygons(g, where)]
    return []


def _json_fields(data: Any, where: str, crs: str | None) -> list[_Named]:
    if not isinstance(data, dict) or "type" not in data:
        return []  # a list of pairs, or an error: read_area's reading
    area_crs = crs or _geojson_crs(data, where) or LONLAT
    if data["type"] == "FeatureCollection":
        features = data.get("features")
        if not isinstance(features, list):
            raise PolygonFileError(f"{where}: a FeatureCollection needs a list of features")
        items = [(f, f"{where}: feature {i}") for i, f in enumerate(features, start=1)]
    elif data["type"] == "Feature":
        items = [(data, where)]
    else:
        items = [({"geometry": data}, where)]
    out: list[_Named] = []
    for feature, at in items:
        if not isinstance(feature, dict):
            continue
        polygons = _geometry_polygons(feature.get("geometry"), at)
        name = _feature_name(feature)
        if not name and isinstance(feature.get("id"), (str, int)) and feature.get("id") != "":
            name = str(feature["id"])
        names = _part_names(name, len(polygons))
        for k, (coords, part) in enumerate(zip(polygons, names, strict=True)):
            here = at if len(polygons) == 1 else f"{at}: part {k + 1}"
            ring, holes = _geometry_rings({"type": "Polygon", "coordinates": coords}, here)
            holes_t = tuple(
                _close_open(h, f"{here}: hole {i}") for i, h in enumerate(holes, start=1)
            )
            out.append((part, Area(_close_open(ring, here), area_crs, part, here, holes_t)))
    return out


# -- KML and GML -------------------------------------------------------------------------------
def _xml_name(chain: list[ElementTree.Element]) -> tuple[str, ElementTree.Element | None]:
    """The name of the innermost placemark or GML feature around a polygon (``chain``: its
    ancestors, innermost first): a ``name`` child, else a feature member's ``id``; and the
    element named (its polygons are the parts of one field)."""
    for element in chain:
        found = next((c for c in element if _local(c.tag) in ("name", "Name", "NAME")), None)
        if found is not None and (found.text or "").strip():
            return (found.text or "").strip(), element
        if _local(element.tag) == "Placemark":
            return "", element
    for parent, element in zip(chain[1:], chain, strict=False):
        if _local(parent.tag) in ("featureMember", "member", "featureMembers"):
            ids = [v for k, v in element.attrib.items() if _local(k) in ("id", "fid")]
            return (ids[0] if ids else ""), element
    return "", None


def _xml_fields(text: str, where: str, crs: str | None) -> list[_Named]:
    try:
        root = ElementTree.fromstring(text)
    except ElementTree.ParseError as exc:
        raise PolygonFileError(f"{where}: malformed XML: {exc}") from None
    parent = {child: element for element in root.iter() for child in element}
    polygons = [e for e in root.iter() if _local(e.tag) == "Polygon"]
    found = []
    for polygon in polygons:
        chain, e = [], polygon
        while e in parent:
            e = parent[e]
            chain.append(e)
        srs = next((x.get("srsName") for x in [polygon, *chain] if x.get("srsName")), None)
        found.append((polygon, srs, *_xml_name(chain)))
    owners = [id(owner) for *_, owner in found if owner is not None]
    out: list[_Named] = []
    part: dict[int, int] = {}
    for i, (polygon, srs, name, owner) in enumerate(found):
        if owner is not None and name and owners.count(id(owner)) > 1:
            part[id(owner)] = part.get(id(owner), 0) + 1
            name = f"{name} part {part[id(owner)]}"
        at = f"{where}: polygon {i + 1}" if len(polygons) > 1 else where
        out.append((name, xml_polygon_area(polygon, at, crs, name, srs)))
    return out


# -- WKT ---------------------------------------------------------------------------------------
def _split_top(body: str, where: str) -> list[str]:
    """``(A (..), B (..))`` -> ``["A (..)", "B (..)"]``: split at the top level's commas."""
    body = body.strip()
    if not (body.startswith("(") and body.endswith(")")):
        raise PolygonFileError(f"{where}: expected '(' after GEOMETRYCOLLECTION")
    parts, depth, start = [], 0, 1
    for pos, ch in enumerate(body[1:-1], start=1):
        depth += (ch == "(") - (ch == ")")
        if ch == "," and depth == 0:
            parts.append(body[start:pos])
            start = pos + 1
    parts.append(body[start:-1])
    return [p.strip() for p in parts if p.strip()]


def _wkt_polygons(text: str, where: str) -> tuple[list[list[np.ndarray]], str | None]:
    """The rings of every polygon of a WKT text, and its SRID."""
    m = _WKT_HEAD.match(text)
    if not m or not m.group(2):
        raise PolygonFileError(f"{where}: not WKT (expected e.g. 'POLYGON ((x y, ...))')")
    srid, kind, rest = m.group(1), m.group(2).upper(), text[m.end() :].strip()
    if rest.upper() == "EMPTY":
        return [], srid
    if kind == "POLYGON":
        return [wkt_rings(_wkt_nested(rest, where), where)], srid
    if kind == "MULTIPOLYGON":
        parts = _wkt_nested(rest, where)
        if not all(isinstance(p, list) for p in parts):
            raise PolygonFileError(f"{where}: a MULTIPOLYGON holds polygons in parentheses")
        return [wkt_rings(p, f"{where}: polygon {k}") for k, p in enumerate(parts, start=1)], srid
    if kind == "GEOMETRYCOLLECTION":
        found = []
        for k, piece in enumerate(_split_top(rest, where), start=1):
            found += _wkt_polygons(piece, f"{where}: geometry {k}")[0]
        return found, srid
    return [], srid


def _wkt_fields(text: str, where: str, crs: str | None) -> list[_Named]:
    polygons, srid = _wkt_polygons(text, where)
    area_crs = crs or (f"EPSG:{srid}" if srid else None) or LONLAT
    return [("", Area(r[0], area_crs, "", where, tuple(r[1:]))) for r in polygons]


# -- the reader --------------------------------------------------------------------------------
def fields_from_text(text: str, where: str, crs: str | None, kind: str) -> list[tuple[str, Area]]:
    """Every polygon of a file's content as ``(name or "", area)``, in file order; ``kind`` is
    ``json``, ``kml`` or ``wkt``. An empty list or a single field: the caller reads the file
    as one area (:func:`boustro.io.read.area_from_text`, its errors and its naming)."""
    if not text.strip():  # an empty file: area_from_text says so
        return []
    if kind == "json":
        try:
            data = json.loads(text)
        except (json.JSONDecodeError, RecursionError):
            return []
        return _json_fields(data, where, crs)
    if kind == "kml":
        return _xml_fields(text, where, crs)
    if kind == "wkt" and _MULTI.match(text):
        return _wkt_fields(text, where, crs)
    return []
