"""An area file's bytes dispatched to its reader, by extension and by content.

Text formats (GeoJSON, JSON pairs, KML, GML, WKT, QGroundControl ``.plan``) go to the text
readers; binary ones never do: a zip (``PK``) is a KMZ when it holds a ``.kml``, a zipped
Shapefile when it holds a ``.shp`` (:mod:`boustro.io.read_zip`); a Shapefile, GeoPackage
(``SQLite format 3``), FlatGeobuf (``fgb``) or GeoParquet (``PAR1``), by extension or by
signature, goes to GDAL (:mod:`boustro.io.read_gdal`), and a file named as one of them without
its signature is refused (GDAL would open a text file, e.g. a VRT naming other files, whatever
its name); any other binary file goes to GDAL as a fallback, else one line says its type is
unknown.
"""

from __future__ import annotations

import json
import os
from typing import NamedTuple, NoReturn

from ..errors import PolygonFileError
from .area import Area
from .read_gdal import gdal_fields, zipped_shapefile_fields
from .read_qgc import is_qgc_plan, qgc_fields
from .read_zip import kml_from_kmz

__all__ = ["GDAL_EXTENSIONS", "Loaded", "load_file"]

#: Extensions read by GDAL (through pyogrio).
GDAL_EXTENSIONS = (".shp", ".gpkg", ".fgb", ".parquet", ".geoparquet")

_SIGNATURES = (
    (b"PK\x03\x04", "zip"),
    (b"PK\x05\x06", "zip"),
    (b"SQLite format 3\x00", ".gpkg"),
    (b"fgb\x03", ".fgb"),  # FlatGeobuf, major version 3
    (b"PAR1", ".parquet"),
    (b"\x00\x00\x27\x0a", ".shp"),
)
_EXPECTED = {
    ".shp": ("Shapefile", b"\x00\x00\x27\x0a"),
    ".gpkg": ("GeoPackage", b"SQLite format 3\x00"),
    ".fgb": ("FlatGeobuf file", b"fgb"),
    ".parquet": ("GeoParquet file", b"PAR1"),
    ".geoparquet": ("GeoParquet file", b"PAR1"),
}
_TEXT_KINDS = {
    ".json": "json",
    ".geojson": "json",
    ".plan": "json",
    ".kml": "kml",
    ".xml": "kml",
    ".gml": "kml",
    ".wkt": "wkt",
}


class Loaded(NamedTuple):
    """A file as loaded: its text and kind (``json``, ``kml``, ``wkt``, or ``None``: sniff
    it), or its fields as read by a field-list reader (GDAL, ``.plan``)."""

    text: str | None
    kind: str | None
    fields: list[tuple[str, Area]] | None


def _kind(name: str, head: bytes) -> str | None:
    lower = name.lower()
    if lower.endswith((".kmz", ".zip")):
        return "zip"
    ext = os.path.splitext(lower)[1]
    if ext in GDAL_EXTENSIONS:
        # A GDAL format by its name must be one by its content: GDAL would open a text file
        # (a VRT naming other files, a GeoJSON) whatever it is called.
        if not head.startswith(_EXPECTED[ext][1]):
            raise PolygonFileError(
                f"{name}: not a {_EXPECTED[ext][0]}: its first bytes are not the format's signature"
            )
        return ext
    for signature, kind in _SIGNATURES:
        if head.startswith(signature):
            return kind
    return None


def _from_zip(data: bytes, name: str, crs: str | None) -> Loaded:
    kml = kml_from_kmz(data, name)
    if kml is not None:
        return Loaded(kml, "kml", None)
    fields = zipped_shapefile_fields(data, name, crs)
    if fields is None:
        raise PolygonFileError(
            f"{name}: the zip holds no .kml (a KMZ) and no .shp (a zipped Shapefile)"
        )
    return Loaded(None, None, fields)


def _unknown_binary(name: str) -> NoReturn:
    """Refuse a file that is neither UTF-8 text nor a binary format recognised by its signature.

    GDAL is never asked to guess: given any other file it would pick a driver by content, and a
    VRT or similar text naming other files would make it open them."""
    raise PolygonFileError(
        f"{name}: neither UTF-8 text nor a binary area format boustro reads (KMZ, zipped "
        "Shapefile, Shapefile, GeoPackage, FlatGeobuf, GeoParquet, recognised by their "
        "signature); save text formats as UTF-8"
    )


def _plan(text: str, name: str, crs: str | None) -> Loaded | None:
    """The fields of a QGroundControl plan, ``None`` for other JSON."""
    try:
        data = json.loads(text)
    except json.JSONDecodeError:
        return None  # the JSON reader's own message
    if is_qgc_plan(data):
        return Loaded(None, None, qgc_fields(data, name, crs))
    if name.lower().endswith(".plan"):
        raise PolygonFileError(
            f'{name}: not a QGroundControl plan (no "fileType": "Plan"); boustro reads the '
            "survey and geofence polygons of a .plan"
        )
    return None


def load_file(name: str, crs: str | None) -> Loaded:
    """Read ``name`` and dispatch it (see the module docstring).

    Raises:
        PolygonFileError: missing or unreadable file, a binary file of unknown type, and
            every error of the binary readers.
        MissingDependencyError: a GDAL format without pyogrio installed.
    """
    try:
        with open(name, "rb") as fh:
            data = fh.read()
    except FileNotFoundError:
        raise PolygonFileError(f"{name}: no such file") from None
    except IsADirectoryError:
        raise PolygonFileError(f"{name}: is a directory, not a polygon file") from None
    except OSError as exc:
        raise PolygonFileError(f"{name}: cannot read: {exc.strerror or exc}") from None
    kind = _kind(name, data[:16])
    if kind == "zip":
        return _from_zip(data, name, crs)
    if kind is not None:
        return Loaded(None, None, gdal_fields(name, name, crs, kind))
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError:
        _unknown_binary(name)
    if "\x00" in text[:4096]:
        _unknown_binary(name)
    kind = _TEXT_KINDS.get(os.path.splitext(name)[1].lower())
    if name.lower().endswith(".plan") or (text.lstrip()[:1] == "{" and '"Plan"' in text):
        plan = _plan(text, name, crs)
        if plan is not None:
            return plan
    return Loaded(text, kind, None)
