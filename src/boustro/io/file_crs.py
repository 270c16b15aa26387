"""A CRS named inside an input file, checked before PROJ sees it.

A file comes from anywhere, and PROJ opens the files a CRS definition names (grids with
``+nadgrids``/``+geoidgrids``, init files with ``+init=``, ``PARAMETERFILE`` in WKT). So a CRS
taken from a file (GeoJSON ``crs`` member, GML ``srsName``) is accepted only as

- an authority code: ``EPSG:n``, ``OGC:CRS84``/``CRS84`` and their URN and URL spellings
  (``urn:ogc:def:crs:EPSG::n``, ``http://www.opengis.net/def/crs/EPSG/0/n``,
  ``http://www.opengis.net/gml/srs/epsg.xml#n``), returned as ``"EPSG:n"``; or
- a WKT CRS (WKT1 or WKT2) that names no file or grid: no ``PARAMETERFILE``, no ``EXTENSION``
  (WKT1's embedded PROJ string), no ESRI ``GEOGTRAN``/``Dataset_`` grid, no PROJ parameter,
  no ``@`` grid list, no ``file:`` or backslash path.

Anything else (a PROJ string, PROJJSON, a name PROJ would look up) is refused with
:class:`~boustro.errors.PolygonFileError`, with no call to pyproj. A CRS the user gives on the
command line (``--crs``) is not checked here: it may be any pyproj input.
"""

from __future__ import annotations

import re

from ..errors import PolygonFileError
from .area import LONLAT

__all__ = ["MAX_WKT_CHARS", "crs_from_file"]

#: The longest WKT accepted from a file (a real CRS definition is a few thousand characters).
MAX_WKT_CHARS = 20_000

_CRS84 = re.compile(
    r"(?:OGC:CRS84|CRS84|urn:ogc:def:crs:OGC:(?:1\.3|2)?:CRS84"
    r"|https?://www\.opengis\.net/def/crs/OGC/(?:1\.3|0)/CRS84)",
    flags=re.IGNORECASE,
)
_EPSG = re.compile(
    r"(?:EPSG:|urn:(?:x-)?ogc:def:crs:EPSG:(?:[0-9.]*:)?|https?://www\.opengis\.net/def/crs/EPSG/0/"
    r"|https?://www\.opengis\.net/gml/srs/epsg\.xml#)(\d{1,9})",
    flags=re.IGNORECASE,
)
_WKT_ROOTS = (
    "GEOGCS PROJCS COMPD_CS GEOGCRS GEODCRS GEOGRAPHICCRS GEODETICCRS PROJCRS PROJECTEDCRS "
    "COMPOUNDCRS BOUNDCRS".split()
)
_WKT_HEAD = re.compile(r"\s*([A-Za-z_]+)\s*[\[(]")
#: Markers of a file or grid reference in a WKT (matched case-insensitively).
_WKT_FORBIDDEN = re.compile(
    r"PARAMETERFILE|EXTENSION\s*[\[(]|GEOGTRAN|DATASET_|nadgrids|geoidgrids|init\s*=|"
    r"\+\s*[a-z_]+\s*=|\bproj\s*=|@|file:|\\",
    flags=re.IGNORECASE,
)


def _refuse(text: str, where: str, why: str) -> PolygonFileError:
    shown = " ".join(text.split())
    shown = shown if len(shown) <= 60 else shown[:57] + "..."
    return PolygonFileError(
        f"{where}: the file's CRS {shown!r} is refused ({why}): a CRS read from a file must be "
        "an authority code (EPSG:n, OGC:CRS84) or a WKT that names no file or grid; if this "
        "CRS is intended, give it on the command line with --crs"
    )


def crs_from_file(text: str, where: str = "input") -> str:
    """The CRS named by a file, as boustro stores it, or :class:`PolygonFileError`.

    >>> crs_from_file("urn:ogc:def:crs:EPSG::28992")
    'EPSG:28992'
    >>> crs_from_file("urn:ogc:def:crs:OGC:1.3:CRS84")
    'EPSG:4326'
    >>> crs_from_file("+proj=longlat +nadgrids=/etc/passwd", "f.geojson")
    Traceback (most recent call last):
    ...
    boustro.errors.PolygonFileError: f.geojson: the file's CRS '+proj=longlat +nadgrids=/etc/passwd' is refused (a PROJ string): a CRS read from a file must be an authority code (EPSG:n, OGC:CRS84) or a WKT that names no file or grid; if this CRS is intended, give it on the command line with --crs
    """  # noqa: E501
    if not isinstance(text, str):
        raise PolygonFileError(f"{where}: the file's CRS must be a string, got {text!r:.60}")
    name = text.strip()
    if _CRS84.fullmatch(name):
        return LONLAT
    m = _EPSG.fullmatch(name)
    if m:
        return f"EPSG:{int(m.group(1))}"
    head = _WKT_HEAD.match(name)
    if head is None or head.group(1).upper() not in _WKT_ROOTS:
        if name.startswith("+") or "proj=" in name.lower():
            raise _refuse(name, where, "a PROJ string")
        raise _refuse(name, where, "neither an authority code nor a WKT CRS")
    if len(name) > MAX_WKT_CHARS:
        raise _refuse(name, where, f"a WKT of {len(name)} characters, over {MAX_WKT_CHARS}")
    bad = _WKT_FORBIDDEN.search(name)
    if bad:
        raise _refuse(name, where, f"the WKT names a file or grid: {bad.group(0)!r}")
    return name
