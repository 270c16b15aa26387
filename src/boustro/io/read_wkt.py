"""Survey areas from WKT and EWKT: ``POLYGON`` (``Z``/``M``), ``MULTIPOLYGON`` (first part)."""

from __future__ import annotations

import re
from typing import Any

import numpy as np

from ..errors import PolygonFileError
from .area import LONLAT, Area
from .area import close_ring as _close_open

__all__ = ["area_from_wkt", "wkt_rings"]


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


def wkt_rings(nested: list[Any], where: str) -> list[np.ndarray]:
    """The rings of one parsed WKT polygon (``[[x y, ...], ...]``), closed rings opened; the
    first is the shell, the others holes."""
    rings = [r for r in nested if isinstance(r, list)]
    if not rings or len(rings) != len(nested):
        raise PolygonFileError(f"{where}: a WKT POLYGON needs rings in parentheses")
    parsed = []
    for r_index, ring_items in enumerate(rings):
        what = where if r_index == 0 else f"{where}: hole {r_index}"
        rows = []
        for i, pos in enumerate(ring_items, start=1):
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
    return parsed


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
    parsed = wkt_rings(nested, where)
    file_crs = f"EPSG:{srid}" if srid else None
    return Area(parsed[0], crs or file_crs or LONLAT, "", where, tuple(parsed[1:]))
