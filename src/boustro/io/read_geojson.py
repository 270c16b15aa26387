"""Polygons and survey areas from JSON: a list of ``[x, y]`` pairs or GeoJSON (RFC 7946)."""

from __future__ import annotations

import json
import logging
import os
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..errors import InvalidPolygonError, PolygonFileError
from ..geometry import Polygon
from .area import LONLAT, Area
from .area import close_ring as _close_open
from .file_crs import crs_from_file

__all__ = ["area_from_json", "parse_json", "polygon_from_json", "read_polygon"]

log = logging.getLogger("boustro.io.read")  # the name of the module these readers came from


def _ring(coords: Any, where: str) -> np.ndarray:
    if not isinstance(coords, Sequence) or isinstance(coords, str) or len(coords) == 0:
        raise PolygonFileError(f"{where}: expected a list of [x, y] positions, got {coords!r:.80}")
    rows = []
    for i, pos in enumerate(coords, start=1):
        if (
            not isinstance(pos, Sequence)
            or isinstance(pos, str)
            or len(pos) < 2
            or not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in pos[:2])
        ):
            raise PolygonFileError(
                f"{where}: position {i} must be a list of at least two numbers, got {pos!r:.80}"
            )
        try:
            rows.append((float(pos[0]), float(pos[1])))
        except OverflowError:
            raise PolygonFileError(
                f"{where}: position {i} has a number too large for float64: {pos!r:.80}"
            ) from None
    return np.asarray(rows, dtype=np.float64)


def _from_geometry(geom: Any, where: str) -> Polygon:
    ring = _geometry_ring(geom, where)
    try:
        return Polygon(ring)
    except InvalidPolygonError as exc:
        raise InvalidPolygonError(f"{where}: {exc}") from None


def _geometry_ring(geom: Any, where: str) -> np.ndarray:
    """The outer ring of a GeoJSON Polygon (or a MultiPolygon's first polygon), unvalidated;
    holes are refused (planar polygons for ``boustro score``)."""
    ring, holes = _geometry_rings(geom, where)
    if holes:
        raise PolygonFileError(
            f"{where}: the polygon has {len(holes)} hole(s); this command takes polygons "
            "without holes (boustro plan takes areas with holes)"
        )
    return ring


def _geometry_rings(geom: Any, where: str) -> tuple[np.ndarray, list[np.ndarray]]:
    """The outer ring and the holes of a GeoJSON Polygon (or a MultiPolygon's first polygon)."""
    if not isinstance(geom, dict):
        raise PolygonFileError(f"{where}: expected a GeoJSON geometry object, got {geom!r:.80}")
    kind = geom.get("type")
    coords = geom.get("coordinates")
    if kind == "MultiPolygon":
        if not isinstance(coords, list) or not coords:
            raise PolygonFileError(f"{where}: a MultiPolygon needs a non-empty list of polygons")
        if len(coords) > 1:
            log.warning(
                "%s: a MultiPolygon of %d parts: only the first part is used", where, len(coords)
            )
        coords, kind = coords[0], "Polygon"
    if kind != "Polygon":
        raise PolygonFileError(f"{where}: expected a Polygon geometry, got {kind!r}")
    if not isinstance(coords, list) or not coords:
        raise PolygonFileError(f"{where}: a Polygon needs at least one ring")
    holes = [
        _closed(_ring(h, f"{where}: hole {i}"), f"{where}: hole {i}")
        for i, h in enumerate(coords[1:], start=1)
    ]
    return _closed(_ring(coords[0], where), where), holes


def _closed(ring: np.ndarray, where: str) -> np.ndarray:
    """``ring``; a warning if it is open (RFC 7946 repeats the first position last): it is
    closed by a straight edge, which a wrong last position turns into a spike."""
    if len(ring) > 2 and not np.array_equal(ring[0], ring[-1]):
        log.warning(
            "%s: the ring is not closed: its last position %s differs from its first %s; "
            "closed by a straight edge between them",
            where,
            ring[-1].tolist(),
            ring[0].tolist(),
        )
    return ring


def _polygon_geometry(data: dict[str, Any], where: str) -> tuple[Any, str, Any]:
    """``(geometry, where, feature)`` of the polygon in a GeoJSON object: the object itself, a
    Feature's geometry, or a FeatureCollection's first Polygon or MultiPolygon feature (a warning
    names the ones left out)."""
    kind = data["type"]
    if kind == "FeatureCollection":
        features = data.get("features")
        if not isinstance(features, list):
            raise PolygonFileError(f"{where}: a FeatureCollection needs a list of features")
        found = [
            (i, f)
            for i, f in enumerate(features)
            if isinstance(f, dict)
            and isinstance(f.get("geometry"), dict)
            and f["geometry"].get("type") in ("Polygon", "MultiPolygon")
        ]
        if not found:
            raise PolygonFileError(f"{where}: the FeatureCollection holds no Polygon feature")
        if len(found) > 1:
            log.warning(
                "%s: %d polygon features; only the first (feature %d) is used",
                where,
                len(found),
                found[0][0] + 1,
            )
        i, feature = found[0]
        return feature["geometry"], f"{where}: feature {i + 1}", feature
    if kind == "Feature":
        geom = data.get("geometry")
        if not isinstance(geom, dict):
            raise PolygonFileError(f"{where}: the Feature has no geometry")
        return geom, where, data
    return data, where, None


def polygon_from_json(data: Any, where: str = "input") -> Polygon:
    """A :class:`Polygon` from parsed JSON: a list of pairs or a GeoJSON object."""
    if isinstance(data, list):
        try:
            return Polygon(_ring(data, where))
        except InvalidPolygonError as exc:
            raise InvalidPolygonError(f"{where}: {exc}") from None
    if not isinstance(data, dict) or "type" not in data:
        raise PolygonFileError(
            f"{where}: expected a JSON list of [x, y] pairs or a GeoJSON object, "
            f"got {type(data).__name__}"
        )
    geom, where, _ = _polygon_geometry(data, where)
    return _from_geometry(geom, where)


def read_polygon(path: str | os.PathLike[str]) -> Polygon:
    """Read a polygon from a JSON or GeoJSON file (see the module docstring).

    Raises:
        PolygonFileError: missing or unreadable file, malformed JSON, no polygon in it.
        InvalidPolygonError: the polygon itself is invalid (self-intersecting, zero area, ...).
    """
    name = os.fspath(path)
    try:
        with open(name, encoding="utf-8-sig") as fh:  # a byte-order mark is not an error
            text = fh.read()
    except FileNotFoundError:
        raise PolygonFileError(f"{name}: no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise PolygonFileError(f"{name}: cannot read: {exc}") from None
    if not text.strip():
        raise PolygonFileError(f"{name}: the file is empty: no polygon in it")
    if text.strip()[:1] not in ("{", "["):  # KML, WKT, ...: say what is read here
        raise PolygonFileError(
            f"{name}: not JSON: a planar polygon is read from a JSON list of [x, y] pairs or "
            "GeoJSON (the other area formats, KML, WKT, GML, ..., through boustro plan)"
        )
    return polygon_from_json(parse_json(text, name), name)


def parse_json(text: str, where: str) -> Any:
    """``json.loads(text)``, its errors as one :class:`PolygonFileError` line naming ``where``."""
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise PolygonFileError(
            f"{where}: malformed JSON at line {exc.lineno} column {exc.colno}: {exc.msg}"
        ) from None
    except RecursionError:
        raise PolygonFileError(f"{where}: JSON nested too deeply to read") from None


def _geojson_crs(data: Any, where: str = "input") -> str | None:
    """The CRS named by an old-style (2008) GeoJSON ``crs`` member, if any, checked by
    :func:`boustro.io.file_crs.crs_from_file` (a linked CRS is refused, never followed)."""
    crs = data.get("crs") if isinstance(data, dict) else None
    if crs is None:
        return None
    kind = crs.get("type") if isinstance(crs, dict) else None
    props = crs.get("properties") if isinstance(crs, dict) else None
    if kind == "link":
        raise PolygonFileError(
            f"{where}: the crs member links to a CRS definition elsewhere; boustro does not "
            "follow links: give the CRS on the command line with --crs"
        )
    if kind != "name" or not isinstance(props, dict) or "name" not in props:
        raise PolygonFileError(
            f'{where}: the crs member must be {{"type": "name", "properties": '
            f'{{"name": ...}}}}, got {crs!r:.80}'
        )
    return crs_from_file(props["name"], where)


def area_from_json(data: Any, where: str = "input", crs: str | None = None) -> Area:
    """An :class:`Area` from parsed JSON: a list of ``[x, y]`` pairs or a GeoJSON object."""
    name = ""
    holes: list[np.ndarray] = []
    if isinstance(data, list):
        ring = _ring(data, where)
    elif not isinstance(data, dict) or "type" not in data:
        raise PolygonFileError(
            f"{where}: expected a JSON list of [x, y] pairs or a GeoJSON object, "
            f"got {type(data).__name__}"
        )
    else:
        geom, where_geom, feature = _polygon_geometry(data, where)
        ring, holes = _geometry_rings(geom, where_geom)
        name = _feature_name(feature)
    if crs is None and isinstance(data, dict):
        crs = _geojson_crs(data, where)  # a CRS given by the caller overrides the file's
    return Area(
        _close_open(ring, where),
        crs or LONLAT,
        name,
        where,
        tuple(_close_open(h, f"{where}: hole {i}") for i, h in enumerate(holes, start=1)),
    )


def _feature_name(feature: Any) -> str:
    props = feature.get("properties") if isinstance(feature, dict) else None
    if isinstance(props, dict):
        for key in ("name", "Name", "NAME", "title"):
            if isinstance(props.get(key), str):
                return props[key]
    return ""
