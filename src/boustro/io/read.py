"""Reading polygons and survey areas (ring + CRS) from GeoJSON, KML, GML and WKT files.

:func:`read_polygon` reads planar polygons, :func:`read_area` survey areas with their CRS.
"""

from __future__ import annotations

import json
import logging
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass
from importlib import resources
from typing import Any
from xml.etree import ElementTree

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidPolygonError, PolygonFileError
from ..geometry import Polygon

log = logging.getLogger(__name__)

__all__ = [
    "EMBEDDED_FIELD",
    "LONLAT",
    "PAPER_PARALLELOGRAM",
    "PAPER_SPACING",
    "Area",
    "area_from_json",
    "area_from_kml",
    "area_from_text",
    "area_from_wkt",
    "embedded_field",
    "polygon_from_json",
    "read_area",
    "read_polygon",
]

#: The parallelogram of the paper's Figure 1, in the authors' units.
PAPER_PARALLELOGRAM: tuple[tuple[float, float], ...] = ((8, 4), (8, 10), (4, 8), (4, 2))
#: The transect spacing the authors' scripts use with it (0.0559 of the normalised frame).
PAPER_SPACING = 0.5


def _ring(coords: Any, where: str) -> np.ndarray:
    if not isinstance(coords, Sequence) or isinstance(coords, str) or len(coords) == 0:
        raise PolygonFileError(f"{where}: expected a list of [x, y] positions, got {coords!r:.80}")
    rows = []
    for i, pos in enumerate(coords):
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
    holes = [_ring(h, f"{where}: hole {i}") for i, h in enumerate(coords[1:])]
    return _ring(coords[0], where), holes


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
                found[0][0],
            )
        i, feature = found[0]
        return feature["geometry"], f"{where}: feature {i}", feature
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
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise PolygonFileError(
            f"{name}: malformed JSON at line {exc.lineno} column {exc.colno}: {exc.msg}"
        ) from None
    return polygon_from_json(data, name)


# -- survey areas (ring + CRS) ----------------------------------------------------------------
#: WGS 84 longitude/latitude, the CRS of GeoJSON (RFC 7946), KML and GPX.
LONLAT = "EPSG:4326"

#: The embedded example field: a 3.6 ha parcel in the Netherlands from the Fields2Cover project
#: (BSD 3-Clause, Wageningen University; see ``data/LICENSE-Fields2Cover``).
EMBEDDED_FIELD = "fields2cover_test_field.json"


@dataclass(frozen=True)
class Area:
    """A survey area as read: its outer ring in the file's coordinates and their CRS.

    Attributes:
        ring: ``(N, 2)`` vertices ``(x, y)`` in file order (longitude, latitude for
            geographic CRSs), without a repeated closing vertex. Not yet validated as a
            polygon: :mod:`boustro.mission` projects it first.
        crs: the CRS, e.g. ``"EPSG:4326"``, or ``None`` for plain planar coordinates.
        name: a name for the area (placemark or feature name, else the file's stem).
        source: where it came from (a path, or ``"<embedded>"``).
        holes: the inner rings (obstacles), each ``(M, 2)`` like ``ring``; validated with the
            area (:class:`boustro.regions.Region`).
    """

    ring: NDArray[np.float64]
    crs: str | None
    name: str
    source: str
    holes: tuple[NDArray[np.float64], ...] = ()


def _close_open(ring: np.ndarray, where: str) -> np.ndarray:
    if len(ring) > 1 and np.array_equal(ring[0], ring[-1]):
        ring = ring[:-1]
    if len(ring) < 3:
        raise PolygonFileError(f"{where}: a polygon needs at least 3 vertices, got {len(ring)}")
    return ring


def _geojson_crs(data: Any) -> str | None:
    """The CRS named by an old-style (2008) GeoJSON ``crs`` member, if any."""
    crs = data.get("crs") if isinstance(data, dict) else None
    if not isinstance(crs, dict):
        return None
    name = (crs.get("properties") or {}).get("name")
    return _crs_name(name) if isinstance(name, str) else None


def _crs_name(name: str) -> str:
    """``urn:ogc:def:crs:EPSG::28992``, ``EPSG:28992``, ``.../EPSG/0/28992`` -> ``EPSG:28992``."""
    text = name.strip()
    if text.upper() in ("URN:OGC:DEF:CRS:OGC:1.3:CRS84", "OGC:CRS84", "CRS84"):
        return LONLAT
    m = re.search(r"EPSG(?:::|:|/0/|/)(\d+)$", text, flags=re.IGNORECASE)
    return f"EPSG:{m.group(1)}" if m else text


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
    file_crs = _geojson_crs(data) if isinstance(data, dict) else None
    return Area(
        _close_open(ring, where),
        crs or file_crs or LONLAT,
        name,
        where,
        tuple(_close_open(h, f"{where}: hole {i}") for i, h in enumerate(holes)),
    )


def _feature_name(feature: Any) -> str:
    props = feature.get("properties") if isinstance(feature, dict) else None
    if isinstance(props, dict):
        for key in ("name", "Name", "NAME", "title"):
            if isinstance(props.get(key), str):
                return props[key]
    return ""


def _local(tag: str) -> str:
    return tag.rsplit("}", 1)[-1]


def _xml_coordinates(element: ElementTree.Element, where: str) -> np.ndarray:
    """Vertices of a KML/GML ``LinearRing`` (``coordinates`` or GML 3 ``posList``/``pos``)."""
    for child in element.iter():
        tag = _local(child.tag)
        if tag == "coordinates":
            rows = []
            for i, token in enumerate((child.text or "").split()):
                parts = token.split(",")
                try:
                    rows.append((float(parts[0]), float(parts[1])))
                except (ValueError, IndexError):
                    raise PolygonFileError(
                        f"{where}: coordinate tuple {i} must be 'x,y[,z]', got {token!r:.60}"
                    ) from None
            return np.asarray(rows, dtype=np.float64).reshape(-1, 2)
        if tag == "posList":
            dim = int(child.get("srsDimension") or child.get("dimension") or 2)
            try:
                values = [float(x) for x in (child.text or "").split()]
            except ValueError:
                raise PolygonFileError(f"{where}: non-numeric value in a GML posList") from None
            if dim < 2 or len(values) % dim:
                raise PolygonFileError(
                    f"{where}: a GML posList of {len(values)} numbers is not made of "
                    f"{dim}-dimensional positions"
                )
            return np.asarray(values, dtype=np.float64).reshape(-1, dim)[:, :2]
    positions = [c for c in element.iter() if _local(c.tag) == "pos"]
    if positions:
        try:
            pos_rows = [[float(x) for x in (p.text or "").split()[:2]] for p in positions]
            return np.asarray(pos_rows, dtype=np.float64).reshape(-1, 2)
        except ValueError:
            raise PolygonFileError(f"{where}: non-numeric value in a GML pos") from None
    raise PolygonFileError(f"{where}: the polygon's outer ring has no coordinates")


def area_from_kml(text: str, where: str = "input", crs: str | None = None) -> Area:
    """An :class:`Area` from KML (first ``Polygon``) or an XML document with a GML polygon.

    KML coordinates are WGS 84 longitude, latitude; a GML ``srsName`` names the CRS of a GML
    polygon. Its coordinates are taken as ``x, y`` (longitude first), except under a URN or URI
    ``srsName`` of a latitude-first CRS (``urn:ogc:def:crs:EPSG::4326``), whose axis order they
    follow.
    """
    try:
        root = ElementTree.fromstring(text)
    except ElementTree.ParseError as exc:
        raise PolygonFileError(f"{where}: malformed XML: {exc}") from None
    polygon = next((e for e in root.iter() if _local(e.tag) == "Polygon"), None)
    if polygon is None:
        raise PolygonFileError(
            f"{where}: no Polygon in the file (expected a KML Polygon placemark)"
        )
    outer = [e for e in polygon if _local(e.tag) in ("outerBoundaryIs", "exterior")]
    inner = [e for e in polygon if _local(e.tag) in ("innerBoundaryIs", "interior")]
    if not outer:
        raise PolygonFileError(f"{where}: the Polygon has no outer boundary")
    ring = _xml_coordinates(outer[0], where)
    holes: list[np.ndarray] = []
    for element in inner:
        # KML may hold several LinearRings in one innerBoundaryIs.
        rings = [e for e in element.iter() if _local(e.tag) == "LinearRing"] or [element]
        for r in rings:
            holes.append(_close_open(_xml_coordinates(r, where), f"{where}: hole {len(holes)}"))
    name = ""
    for placemark in (e for e in root.iter() if _local(e.tag) == "Placemark"):
        if any(e is polygon for e in placemark.iter()):
            found = next((c for c in placemark if _local(c.tag) == "name"), None)
            name = (found.text or "").strip() if found is not None else ""
            break
    srs = polygon.get("srsName")
    file_crs = _crs_name(srs) if srs else None
    if srs and _north_first(srs):  # a URN/URI srsName: the CRS's own axis order, lat first
        ring, holes = ring[:, ::-1], [h[:, ::-1] for h in holes]
    return Area(_close_open(ring, where), crs or file_crs or LONLAT, name, where, tuple(holes))


def _north_first(srs: str) -> bool:
    """True when a GML ``srsName`` in URN or URI form (``urn:ogc:def:crs:EPSG::4326``,
    ``http://www.opengis.net/def/crs/EPSG/0/4326``) names a CRS whose first axis points north
    (latitude first, as those forms require). The short form ``EPSG:4326`` keeps x, y
    (longitude first), the common GIS convention."""
    m = re.fullmatch(
        r"(?:urn:ogc:def:crs:EPSG:[^:]*:|https?://www\.opengis\.net/def/crs/EPSG/0/)(\d+)",
        srs.strip(),
        flags=re.IGNORECASE,
    )
    if m is None:
        return False
    import pyproj  # a dependency of boustro; imported here, only for such files

    try:
        axes = pyproj.CRS.from_epsg(int(m.group(1))).axis_info
    except pyproj.exceptions.CRSError:
        return False
    return bool(axes) and axes[0].direction.lower() in ("north", "south")


_WKT_TYPES = frozenset(
    "POINT LINESTRING POLYGON MULTIPOINT MULTILINESTRING MULTIPOLYGON GEOMETRYCOLLECTION "
    "CIRCULARSTRING COMPOUNDCURVE CURVEPOLYGON MULTICURVE MULTISURFACE TRIANGLE TIN "
    "POLYHEDRALSURFACE".split()
)

_WKT_HEAD = re.compile(
    r"^\s*(?:SRID\s*=\s*(\d+)\s*;)?\s*([A-Za-z]+)\s*(ZM|Z|M)?\s*", flags=re.IGNORECASE
)


def _wkt_nested(text: str, where: str) -> list[Any]:
    """Parse ``((x y, x y), (...))`` into nested lists whose leaves are coordinate strings."""
    pos = 0

    def parse() -> list[Any]:
        nonlocal pos
        pos += 1  # past the "(" that the caller saw
        items: list[Any] = []
        start = pos
        while pos < len(text):
            ch = text[pos]
            if ch == "(":
                items.append(parse())
                start = pos
            elif ch in ",)":
                chunk = text[start:pos].strip()
                if chunk:
                    items.append(chunk)
                pos += 1
                if ch == ")":
                    return items
                start = pos
            else:
                pos += 1
        raise PolygonFileError(f"{where}: unbalanced parentheses in WKT")

    text = text.strip()
    if not text.startswith("("):
        raise PolygonFileError(f"{where}: expected '(' after the WKT geometry type")
    out = parse()
    if text[pos:].strip():
        raise PolygonFileError(f"{where}: unexpected text after the WKT geometry")
    return out


def area_from_wkt(text: str, where: str = "input", crs: str | None = None) -> Area:
    """An :class:`Area` from WKT or EWKT: ``POLYGON``, ``POLYGON Z``, ``MULTIPOLYGON`` (first);
    rings after the first are holes."""
    m = _WKT_HEAD.match(text)
    if not m or not m.group(2):
        raise PolygonFileError(f"{where}: not WKT (expected e.g. 'POLYGON ((x y, ...))')")
    srid, kind = m.group(1), m.group(2).upper()
    rest = text[m.end() :].strip()
    if rest.upper() == "EMPTY":
        raise PolygonFileError(f"{where}: the {kind} is EMPTY: no polygon in the file")
    if kind not in _WKT_TYPES:
        raise PolygonFileError(
            f"{where}: not a polygon file: expected GeoJSON, a JSON list of [x, y] pairs, KML "
            f"or WKT, got text starting {text.strip()[:40]!r}"
        )
    if kind not in ("POLYGON", "MULTIPOLYGON"):
        raise PolygonFileError(f"{where}: expected a WKT POLYGON or MULTIPOLYGON, got {kind}")
    text = rest.strip()
    nested = _wkt_nested(text, where)
    if kind == "MULTIPOLYGON":
        if not nested or not isinstance(nested[0], list):
            raise PolygonFileError(f"{where}: empty MULTIPOLYGON")
        nested = nested[0]
    rings = [r for r in nested if isinstance(r, list)]
    if not rings or len(rings) != len(nested):
        raise PolygonFileError(f"{where}: a WKT POLYGON needs rings in parentheses")
    parsed = []
    for r_index, ring_items in enumerate(rings):
        what = where if r_index == 0 else f"{where}: hole {r_index - 1}"
        rows = []
        for i, pos in enumerate(ring_items):
            if not isinstance(pos, str):
                raise PolygonFileError(f"{what}: position {i} of the ring is nested, not 'x y'")
            parts = pos.split()
            try:
                rows.append((float(parts[0]), float(parts[1])))
            except (ValueError, IndexError):
                raise PolygonFileError(
                    f"{what}: position {i} must be two numbers 'x y', got {pos!r:.60}"
                ) from None
        parsed.append(_close_open(np.asarray(rows, dtype=np.float64).reshape(-1, 2), what))
    file_crs = f"EPSG:{srid}" if srid else None
    return Area(parsed[0], crs or file_crs or LONLAT, "", where, tuple(parsed[1:]))


def area_from_text(
    text: str, where: str = "input", crs: str | None = None, kind: str | None = None
) -> Area:
    """An :class:`Area` from file content; ``kind`` is ``json``, ``kml`` or ``wkt`` (sniffed
    from the first character when ``None``: ``<`` XML, ``{`` or ``[`` JSON, else WKT)."""
    if kind is None:
        head = text.lstrip()[:1]
        kind = "kml" if head == "<" else "json" if head in ("{", "[") else "wkt"
    if kind == "json":
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise PolygonFileError(
                f"{where}: malformed JSON at line {exc.lineno} column {exc.colno}: {exc.msg}"
            ) from None
        return area_from_json(data, where, crs)
    if kind == "kml":
        return area_from_kml(text, where, crs)
    if kind == "wkt":
        if not text.strip():
            raise PolygonFileError(f"{where}: the file is empty: no polygon in it")
        return area_from_wkt(text, where, crs)
    raise PolygonFileError(f"{where}: unknown area format {kind!r}; expected json, kml or wkt")


_AREA_KINDS = {
    ".json": "json",
    ".geojson": "json",
    ".kml": "kml",
    ".xml": "kml",
    ".gml": "kml",
    ".wkt": "wkt",
}


def read_area(path: str | os.PathLike[str], crs: str | None = None) -> Area:
    """Read a survey area: GeoJSON, a JSON list of pairs, KML, or WKT (by extension, else sniffed).

    Args:
        path: the file.
        crs: the CRS of its coordinates, overriding what the file says (default: the file's
            CRS, else WGS 84 longitude/latitude ``"EPSG:4326"``).

    Raises:
        PolygonFileError: missing or unreadable file, malformed content, no polygon.

    Example:
        >>> from importlib import resources
        >>> area = read_area(resources.files("boustro") / "data" / EMBEDDED_FIELD)
        >>> area.name, area.crs, len(area.ring)
        ('test parcel', 'EPSG:4326', 19)
    """
    name = os.fspath(path)
    try:
        with open(name, encoding="utf-8-sig") as fh:
            text = fh.read()
    except FileNotFoundError:
        raise PolygonFileError(f"{name}: no such file") from None
    except IsADirectoryError:
        raise PolygonFileError(f"{name}: is a directory, not a polygon file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise PolygonFileError(f"{name}: cannot read: {exc}") from None
    kind = _AREA_KINDS.get(os.path.splitext(name)[1].lower())
    area = area_from_text(text, name, crs, kind)
    if not area.name:
        stem = os.path.splitext(os.path.basename(name))[0]
        area = Area(area.ring, area.crs, stem, area.source, area.holes)
    return area


def embedded_field() -> Area:
    """The embedded example field (3.6 ha, the Netherlands, WGS 84), see :data:`EMBEDDED_FIELD`."""
    text = (resources.files("boustro") / "data" / EMBEDDED_FIELD).read_text("utf-8")
    area = area_from_text(text, "<embedded field>", None, "json")
    return Area(area.ring, area.crs, area.name or "test parcel", "<embedded>")
