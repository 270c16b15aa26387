"""Survey areas from XML: the first KML ``Polygon``, or a GML polygon (with its ``srsName``)."""

from __future__ import annotations

import re
from xml.etree import ElementTree

import numpy as np

from ..errors import PolygonFileError
from .area import LONLAT, Area
from .area import close_ring as _close_open
from .file_crs import crs_from_file

__all__ = ["area_from_kml", "xml_polygon_area"]


def _local(tag: str) -> str:
    return tag.rsplit("}", 1)[-1]


def _xml_coordinates(element: ElementTree.Element, where: str) -> np.ndarray:
    """Vertices of a KML/GML ``LinearRing`` (``coordinates`` or GML 3 ``posList``/``pos``)."""
    for child in element.iter():
        tag = _local(child.tag)
        if tag == "coordinates":
            rows = []
            for i, token in enumerate((child.text or "").split(), start=1):
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
        if _local(root.tag) == "gpx":  # a mission boustro wrote, or a walked boundary's track
            raise PolygonFileError(
                f"{where}: a GPX file holds routes and tracks, not an area (boustro writes GPX "
                "but reads areas as polygons: GeoJSON, KML, GML, WKT, ...; a boundary track "
                "must be made a polygon first)"
            )
        raise PolygonFileError(
            f"{where}: no Polygon in the file (expected a KML Polygon placemark)"
        )
    name = ""
    for placemark in (e for e in root.iter() if _local(e.tag) == "Placemark"):
        if any(e is polygon for e in placemark.iter()):
            found = next((c for c in placemark if _local(c.tag) == "name"), None)
            name = (found.text or "").strip() if found is not None else ""
            break
    return xml_polygon_area(polygon, where, crs, name, polygon.get("srsName"))


def xml_polygon_area(
    polygon: ElementTree.Element, where: str, crs: str | None, name: str, srs: str | None
) -> Area:
    """The :class:`Area` of one KML/GML ``Polygon`` element; ``srs``: the GML ``srsName`` that
    applies to it (its own or an enclosing geometry's), if any."""
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
            holes.append(_close_open(_xml_coordinates(r, where), f"{where}: hole {len(holes) + 1}"))
    if crs is None and srs:  # a CRS given by the caller overrides the file's
        crs = crs_from_file(srs, where)
    if srs and _north_first(srs):  # a URN/URI srsName: the CRS's own axis order, lat first
        ring, holes = ring[:, ::-1], [h[:, ::-1] for h in holes]
    return Area(_close_open(ring, where), crs or LONLAT, name, where, tuple(holes))


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
    except pyproj.exceptions.ProjError:  # CRSError and every other PROJ error
        return False
    return bool(axes) and axes[0].direction.lower() in ("north", "south")
