"""Survey areas from the files GDAL reads, through pyogrio (the optional ``boustro[geo]`` extra).

Shapefile (plain or zipped), GeoPackage, FlatGeobuf, GeoParquet (when the local GDAL has the
driver) and, as a fallback for a binary file of another type, any vector format GDAL reads.
Every polygon feature of every layer is a field (each part of a multi-part feature too, as
``NAME part K``), named by its ``name``/``Name``/``NAME``/``id``/``ID`` column when there is one.
A layer's CRS is taken only through :func:`boustro.io.file_crs.crs_from_file` (an authority
code, or a WKT that names no file or grid), and the CRS text of a Shapefile (its ``.prj``) or a
GeoPackage (its ``gpkg_spatial_ref_sys`` definitions, read with ``sqlite3``) is checked the same
way BEFORE GDAL opens the file, so that GDAL's PROJ never sees a refused definition. A layer
without a CRS is WGS 84 longitude/latitude, as for the other readers, unless ``crs`` is given.
pyogrio and shapely are imported on use. GDAL's warnings are recorded by
:func:`recorded_warnings`, one block at a time in the process: ``warnings.catch_warnings``
swaps the process's filters and printer (not thread-safe before Python 3.14), so two at once on
two threads (the web server reading two files at once) left a finished block's printer in place
and every later warning of the process went into its list. A warning raised on another thread
during a block is still recorded by it (as with ``catch_warnings``).
"""

from __future__ import annotations

import logging
import os
import sqlite3
import tempfile
import threading
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import MissingDependencyError, PolygonFileError
from .area import LONLAT, Area
from .area import close_ring as _close_open
from .file_crs import MAX_WKT_CHARS, crs_from_file
from .read_zip import shapefile_members

__all__ = ["NAME_COLUMNS", "gdal_fields", "recorded_warnings", "zipped_shapefile_fields"]

log = logging.getLogger("boustro")

#: The columns that name a feature, first found first.
NAME_COLUMNS = ("name", "Name", "NAME", "id", "ID", "Id")

#: Held by :func:`recorded_warnings` (re-entrant: a block inside a block on one thread).
_WARNINGS_LOCK = threading.RLock()


@contextmanager
def recorded_warnings() -> Iterator[list[warnings.WarningMessage]]:
    """Every warning raised inside, recorded (``catch_warnings(record=True)``, each one
    shown), one such block at a time in the process (see the module)."""
    with _WARNINGS_LOCK, warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        yield caught


def _pyogrio(what: str) -> Any:
    try:
        import pyogrio
        import pyogrio.raw
    except ImportError:
        raise MissingDependencyError(
            f"reading {what} needs pyogrio: pip install 'boustro[geo]'"
        ) from None
    return pyogrio


def _check_prj(shp: str, where: str) -> None:
    """Every ``.prj`` beside the Shapefile, in any letter case (GDAL opens ``.PRJ`` too)."""
    stem = os.path.splitext(shp)[0]
    folder = os.path.dirname(stem) or "."
    base = os.path.basename(stem)
    for entry in sorted(os.listdir(folder)):
        if entry.lower() == base.lower() + ".prj":
            with open(os.path.join(folder, entry), "rb") as fh:
                raw = fh.read(MAX_WKT_CHARS + 1)
            crs_from_file(raw.decode("utf-8", "replace"), f"{where}: {entry[len(base) :]}")


def _check_gpkg(path: str, where: str) -> None:
    """Every CRS definition a GeoPackage's geometry columns use, checked before GDAL."""
    try:
        db = sqlite3.connect(Path(path).resolve().as_uri() + "?mode=ro", uri=True)
    except sqlite3.Error as exc:
        raise PolygonFileError(f"{where}: not a readable GeoPackage: {exc}") from None
    try:
        rows = db.execute(
            "SELECT * FROM gpkg_spatial_ref_sys WHERE srs_id IN "
            "(SELECT srs_id FROM gpkg_geometry_columns)"
        )
        names = [d[0].lower() for d in rows.description]
        found = [dict(zip(names, row, strict=True)) for row in rows.fetchall()]
    except sqlite3.OperationalError as exc:
        if "no such table" not in str(exc):
            raise PolygonFileError(f"{where}: not a readable GeoPackage: {exc}") from None
        raise PolygonFileError(
            f"{where}: an SQLite database but not a GeoPackage ({exc}); boustro reads "
            "GeoPackages among SQLite files"
        ) from None
    except sqlite3.Error as exc:
        raise PolygonFileError(f"{where}: not a readable GeoPackage: {exc}") from None
    finally:
        db.close()
    for row in found:
        for key in ("definition", "definition_12_063"):
            text = row.get(key)
            if isinstance(text, str) and text.strip().lower() not in ("", "undefined"):
                crs_from_file(text, f"{where}: CRS {row.get('srs_id')}")


def _parts(geom: Any) -> list[Any]:
    """The polygons of a shapely geometry (none for points and lines)."""
    kind = geom.geom_type if geom is not None else ""
    if kind == "Polygon":
        return [] if geom.is_empty else [geom]
    if kind in ("MultiPolygon", "GeometryCollection"):
        return [p for g in geom.geoms for p in _parts(g)]
    return []


def _feature_name(fields: list[str], data: list[Any], i: int) -> str:
    for column in NAME_COLUMNS:
        if column in fields:
            value = data[fields.index(column)][i]
            if value is not None and str(value).strip() and str(value) != "nan":
                return str(value).strip()
    return ""


def _layer_fields(pyogrio: Any, path: str, layer: str, where: str, crs: str | None) -> list:
    import shapely

    meta, _, wkb, data = pyogrio.raw.read(path, layer=layer)
    if wkb is None:  # a table without geometry
        return []
    layer_crs = crs or (crs_from_file(meta["crs"], where) if meta.get("crs") else LONLAT)
    fields = [str(f) for f in meta["fields"]]
    out = []
    for i, blob in enumerate(wkb):  # feature N: the N-th of the layer, from 1 (not GDAL's FID)
        try:
            polygons = _parts(shapely.from_wkb(blob) if blob is not None else None)
        except shapely.errors.GEOSException as exc:
            raise PolygonFileError(
                f"{where}: feature {i + 1}: unreadable geometry: {exc}"
            ) from None
        name = _feature_name(fields, data, i)
        for k, poly in enumerate(polygons):
            part = f"{name} part {k + 1}" if name and len(polygons) > 1 else name
            at = f"{where}: feature {i + 1}" + (f": part {k + 1}" if len(polygons) > 1 else "")
            ring = _close_open(np.asarray(poly.exterior.coords, dtype=np.float64)[:, :2], at)
            holes = tuple(
                _close_open(np.asarray(h.coords, dtype=np.float64)[:, :2], f"{at}: hole {j}")
                for j, h in enumerate(poly.interiors, start=1)
            )
            out.append((part, Area(ring, layer_crs, part, at, holes)))
    return out


def gdal_fields(path: str, where: str, crs: str | None, what: str) -> list[tuple[str, Area]]:
    """Every polygon of every layer of a file GDAL reads, as ``(name or "", area)``.

    ``what`` names the format in the message when pyogrio is missing (e.g. ``".gpkg"``).

    Raises:
        MissingDependencyError: pyogrio is not installed.
        PolygonFileError: GDAL cannot read the file, a refused CRS, or no polygon in it.
    """
    pyogrio = _pyogrio(what)
    if what in (".parquet", ".geoparquet") and "Parquet" not in pyogrio.list_drivers():
        raise PolygonFileError(
            f"{where}: reading GeoParquet needs GDAL's Parquet driver, which the GDAL of this "
            f"pyogrio ({pyogrio.__gdal_version_string__}) lacks"
        )
    if path.lower().endswith(".shp") and crs is None:
        _check_prj(path, where)
    if path.lower().endswith(".gpkg") or _is_sqlite(path):
        if crs is None:
            _check_gpkg(path, where)
    try:
        with recorded_warnings() as caught:
            layers = pyogrio.list_layers(path)
            out = []
            for name, _kind in layers:
                here = where if len(layers) == 1 else f"{where}: layer {name}"
                out += _layer_fields(pyogrio, path, str(name), here, crs)
        _log_gdal_warnings(caught, where)
    except pyogrio.errors.DataSourceError as exc:
        raise PolygonFileError(f"{where}: GDAL cannot read it: {_one_line(exc)}") from None
    except (pyogrio.errors.DataLayerError, pyogrio.errors.FieldError) as exc:
        raise PolygonFileError(f"{where}: GDAL cannot read a layer: {_one_line(exc)}") from None
    except pyogrio.errors.GeometryError as exc:
        raise PolygonFileError(f"{where}: unreadable geometry: {_one_line(exc)}") from None
    if not out:
        raise PolygonFileError(f"{where}: no polygon in the file ({len(layers)} layer(s) read)")
    return out


def zipped_shapefile_fields(
    data: bytes, where: str, crs: str | None
) -> list[tuple[str, Area]] | None:
    """The fields of the first Shapefile in a zip (unpacked, within the limits of
    :mod:`boustro.io.read_zip`, into a temporary directory); ``None`` if it holds none."""
    members = shapefile_members(data, where)
    if members is None:
        return None
    with tempfile.TemporaryDirectory(prefix="boustro-") as tmp:
        for ext, blob in members.items():
            Path(tmp, "area" + ext).write_bytes(blob)
        return gdal_fields(os.path.join(tmp, "area.shp"), where, crs, "a zipped Shapefile")


def _log_gdal_warnings(caught: list[warnings.WarningMessage], where: str) -> None:
    """GDAL's warnings (pyogrio's RuntimeWarnings) as one line each on the log, once each;
    the one about a file whose extension does not match its format is left out: boustro
    recognises a file by its signature, whatever its name."""
    seen = set()
    for w in caught:
        text = _one_line(w.message) if isinstance(w.message, Warning) else str(w.message)
        if "non conformant file extension" in text or text in seen:
            continue
        seen.add(text)
        log.warning("%s: GDAL: %s", where, text)


def _is_sqlite(path: str) -> bool:
    with open(path, "rb") as fh:
        return fh.read(16) == b"SQLite format 3\x00"


def _one_line(exc: BaseException) -> str:
    text = str(exc).split("; It might help", 1)[0]  # GDAL's hint about driver prefixes
    return " ".join(text.split())[:300]
