"""The fields of a batch: every feature of one layer of a vector file, read through pyogrio.

Unlike :func:`boustro.io.read_areas`, nothing is refused here as a whole for one bad feature:
each feature keeps its raw geometry (WKB) and is judged where it is planned, so that an empty,
invalid or non-polygon feature becomes an error row of the output, never a failed run. A layer
without a CRS is NOT taken as longitude/latitude: its features are reported (``no CRS``) unless
``crs`` says what the coordinates are (``"planar"`` for plain x/y). A CRS named in the file is
checked before GDAL opens it, as for ``boustro plan`` (:mod:`boustro.io.read_gdal`).
"""

from __future__ import annotations

import math
import os
import sqlite3
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..errors import InvalidParameterError, PolygonFileError
from ..io.crs import parse_crs
from ..io.file_crs import crs_from_file
from ..io.read_gdal import NAME_COLUMNS, _check_gpkg, _check_prj, _is_sqlite, _one_line, _pyogrio

__all__ = ["Feature", "Source", "read_source"]


@dataclass(frozen=True)
class Feature:
    """One input feature: its id (position in the layer, from 1), name, geometry as WKB
    (``None`` for a null geometry) and the values of the attribute columns asked for."""

    field_id: int
    name: str
    wkb: bytes | None
    values: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Source:
    """The features of one layer and the CRS of their coordinates.

    Attributes:
        crs: ``"EPSG:n"``, another CRS, or ``None`` for planar coordinates.
        crs_missing: the layer has no CRS and none was given: every feature is an error row.
    """

    where: str
    crs: str | None
    features: list[Feature]
    crs_missing: bool = False


def _plain(value: Any) -> Any:
    """A column's value as plain Python (``None`` for a null or NaN)."""
    if hasattr(value, "item"):
        value = value.item()
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return None
    return value


def _gdal_undefined(path: str) -> bool:
    """A GeoPackage whose geometry columns all use GDAL's "Undefined SRS" (what GDAL writes for
    a layer without a CRS): no CRS, so each field is reported, not the file refused."""
    try:
        db = sqlite3.connect(Path(path).resolve().as_uri() + "?mode=ro", uri=True)
        try:
            rows = db.execute(
                "SELECT definition FROM gpkg_spatial_ref_sys WHERE srs_id IN "
                "(SELECT srs_id FROM gpkg_geometry_columns)"
            ).fetchall()
        finally:
            db.close()
    except sqlite3.Error:
        return False  # the full check says what is wrong
    return bool(rows) and all(
        isinstance(d, str) and d.startswith('LOCAL_CS["Undefined SRS"') for (d,) in rows
    )


def _pick_layer(pyogrio: Any, path: str, layer: str | None, where: str) -> str:
    layers = [(str(n), k) for n, k in pyogrio.list_layers(path)]
    if layer is not None:
        if layer not in [n for n, _ in layers]:
            names = ", ".join(n for n, _ in layers)
            raise InvalidParameterError(f"{where}: no layer {layer!r}; its layers: {names}")
        return layer
    spatial = [n for n, kind in layers if kind is not None]
    if not spatial:
        raise PolygonFileError(f"{where}: no layer with geometries")
    if len(spatial) > 1:  # not the first silently: boustro plan reads every layer
        raise InvalidParameterError(
            f"{where}: {len(spatial)} layers with geometries ({', '.join(spatial)}): give one "
            "with --layer, or plan each in its own batch"
        )
    return spatial[0]


def read_source(
    path: str | os.PathLike[str],
    *,
    layer: str | None = None,
    crs: str | None = None,
    columns: Sequence[str] = (),
) -> Source:
    """The features of ``layer`` (default: the file's only layer with geometries) of a file GDAL
    reads.

    Args:
        crs: the CRS of the coordinates, overriding the file's (``"planar"`` for plain x/y).
        columns: attribute columns whose values each feature carries (per-field options).

    Raises:
        PolygonFileError: a missing or unreadable file, a refused CRS, no layer of geometries.
        InvalidParameterError: an unknown layer or column, an unknown ``crs``, no ``layer`` for
            a file of several layers with geometries.
        MissingDependencyError: pyogrio is not installed.
    """
    name = os.fspath(path)
    where = name
    if os.path.isdir(name):
        raise PolygonFileError(
            f"{where}: is a directory, not a vector file: give one file of fields (e.g. a "
            "GeoPackage; merge a folder of Shapefiles into one first)"
        )
    if not os.path.isfile(name):
        raise PolygonFileError(f"{where}: no such file")
    pyogrio = _pyogrio("a batch's fields")
    given = parse_crs(crs) if crs is not None else None
    if crs is None and name.lower().endswith(".shp"):
        _check_prj(name, where)
    if crs is None and (name.lower().endswith(".gpkg") or _is_sqlite(name)):
        if not _gdal_undefined(name):
            _check_gpkg(name, where)
    try:
        chosen = _pick_layer(pyogrio, name, layer, where)
        info = pyogrio.read_info(name, layer=chosen)
        fields = [str(f) for f in info["fields"]]
        missing = [c for c in columns if c not in fields]
        if missing:
            raise InvalidParameterError(
                f"{where}: no column {', '.join(map(repr, missing))} in layer {chosen!r}; its "
                f"columns: {', '.join(fields) or '(none)'}"
            )
        label = next((c for c in NAME_COLUMNS if c in fields), None)
        wanted = sorted(set(columns) | ({label} if label else set()))
        meta, fids, wkb, data = pyogrio.raw.read(
            name, layer=chosen, columns=wanted, return_fids=True
        )
    except pyogrio.errors.DataSourceError as exc:
        raise PolygonFileError(f"{where}: GDAL cannot read it: {_one_line(exc)}") from None
    except (pyogrio.errors.DataLayerError, pyogrio.errors.FieldError) as exc:
        raise PolygonFileError(f"{where}: GDAL cannot read a layer: {_one_line(exc)}") from None
    file_crs = crs_from_file(meta["crs"], where) if meta.get("crs") else None
    read = [str(f) for f in meta["fields"]]
    features = []
    for i in range(len(fids)):
        values = {c: _plain(data[read.index(c)][i]) for c in columns}
        title = _plain(data[read.index(label)][i]) if label else None
        text = str(title).strip() if title is not None else ""
        blob = wkb[i] if wkb is not None else None
        features.append(Feature(i + 1, text or f"feature {i + 1}", blob, values))
    where = where if layer is None else f"{where}: layer {chosen}"
    if crs is not None:
        return Source(where, given, features)
    return Source(where, file_crs, features, crs_missing=file_crs is None)
