"""A survey area as read: its outer ring, holes and CRS; the spellings of a CRS name."""

from __future__ import annotations

import os
import re
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..errors import PolygonFileError

__all__ = ["LONLAT", "Area", "close_ring", "crs_name", "crs_text", "field_label"]

#: WGS 84 longitude/latitude, the CRS of GeoJSON (RFC 7946), KML and GPX.
LONLAT = "EPSG:4326"


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
        cut_holes: the holes as read where :func:`boustro.io.repair.detach_holes` cut one
            that touches the shell back from it (``holes`` is then what is planned); the
            path's length outside is measured against these. Empty otherwise.
    """

    ring: NDArray[np.float64]
    crs: str | None
    name: str
    source: str
    holes: tuple[NDArray[np.float64], ...] = ()
    cut_holes: tuple[NDArray[np.float64], ...] = ()


def field_label(area: Area, index: int, count: int) -> str:
    """How a message names field ``index`` (from 1, as ``--field``) of ``count``:
    ``field 'North' (2 of 3)``; one field: ``field 'North'``, or ``""`` without a name of its
    own (none, or the file's stem, which the message's location says already).

    Example:
        >>> a = Area(np.zeros((3, 2)), None, "North", "farm.kml: polygon 2")
        >>> field_label(a, 2, 3), field_label(a, 1, 1)
        ("field 'North' (2 of 3)", "field 'North'")
        >>> field_label(Area(np.zeros((3, 2)), None, "farm", "data/farm.kml"), 1, 1)
        ''
    """
    if count > 1:
        return f"field {area.name!r} ({index} of {count})"
    stem = os.path.splitext(os.path.basename(area.source.split(": ", 1)[0]))[0]
    return f"field {area.name!r}" if area.name and area.name != stem else ""


def close_ring(ring: np.ndarray, where: str) -> np.ndarray:
    if len(ring) > 1 and np.array_equal(ring[0], ring[-1]):
        ring = ring[:-1]
    if len(ring) < 3:
        raise PolygonFileError(f"{where}: a polygon needs at least 3 vertices, got {len(ring)}")
    return ring


def crs_name(name: str) -> str:
    """``urn:ogc:def:crs:EPSG::28992``, ``EPSG:28992``, ``.../EPSG/0/28992`` -> ``EPSG:28992``."""
    text = name.strip()
    if text.upper() in ("URN:OGC:DEF:CRS:OGC:1.3:CRS84", "OGC:CRS84", "CRS84"):
        return LONLAT
    m = re.search(r"EPSG(?:::|:|/0/|/)(\d+)$", text, flags=re.IGNORECASE)
    return f"EPSG:{m.group(1)}" if m else text


def crs_text(crs: object) -> str:
    """A CRS given as an object as its name: a ``pyproj.CRS`` (a GeoDataFrame's ``.crs``) as
    ``"AUTHORITY:code"`` when it has one, else its WKT; a string (or an EPSG integer) as text."""
    to_authority = getattr(crs, "to_authority", None)
    if callable(to_authority):
        authority = to_authority()
        return f"{authority[0]}:{authority[1]}" if authority else str(crs.to_wkt())  # type: ignore[attr-defined]
    return str(crs)
