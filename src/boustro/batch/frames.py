"""GeoPandas in and out of a batch (the optional ``boustro[geopandas]`` extra, imported on use).

:func:`source_from_frame` turns a GeoDataFrame into a batch's fields (what
:func:`boustro.batch` does when given one): every row a field, its CRS the frame's (a frame
without one is reported per row unless ``crs`` is given), names from a ``name``/``id`` column.
:func:`read_plans` reads a batch's output back as GeoDataFrames, one per layer.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any

from ..errors import InvalidParameterError, MissingDependencyError
from ..io.crs import parse_crs
from ..io.file_crs import crs_from_file
from ..io.read_gdal import NAME_COLUMNS
from .export import layer_paths
from .gpkg import LAYERS
from .source import Feature, Source, _plain

__all__ = ["read_plans", "source_from_frame"]


def _geopandas() -> Any:
    try:
        import geopandas
    except ImportError:
        raise MissingDependencyError(
            "GeoDataFrames need geopandas: pip install 'boustro[geopandas]'"
        ) from None
    return geopandas


def _frame_crs(frame: Any) -> str | None:
    found = getattr(frame, "crs", None)
    if found is None:
        return None
    authority = found.to_authority()
    if authority is not None:
        return f"{authority[0]}:{authority[1]}"
    return crs_from_file(found.to_wkt(), "the GeoDataFrame's CRS")


def source_from_frame(frame: Any, *, crs: str | None = None, columns: Sequence[str] = ()) -> Source:
    """The rows of a GeoDataFrame (or GeoSeries) as a batch's fields, in order (ids from 1).

    Raises:
        InvalidParameterError: not a GeoDataFrame, or a column asked for is missing.
    """
    import shapely

    geometry = getattr(frame, "geometry", None)
    if geometry is None:
        raise InvalidParameterError(
            f"expected a vector file or a GeoDataFrame, got {type(frame).__name__}"
        )
    names = list(getattr(frame, "columns", []))
    missing = [c for c in columns if c not in names]
    if missing:
        raise InvalidParameterError(
            f"no column {', '.join(map(repr, missing))} in the GeoDataFrame; its columns: "
            f"{', '.join(map(str, names))}"
        )
    label = next((c for c in NAME_COLUMNS if c in names), None)
    blobs = shapely.to_wkb(geometry.values)
    features = []
    for i, blob in enumerate(blobs):
        row = frame.iloc[i]
        title = _plain(row[label]) if label else None
        values = {c: _plain(row[c]) for c in columns}
        text = str(title).strip() if title is not None else ""
        features.append(Feature(i + 1, text or f"row {frame.index[i]}", blob, values))
    if crs is not None:
        return Source("<GeoDataFrame>", parse_crs(crs), features)
    found = _frame_crs(frame)
    return Source("<GeoDataFrame>", found, features, crs_missing=found is None)


def read_plans(out: str | os.PathLike[str]) -> dict[str, Any]:
    """``{"lanes": ..., "paths": ..., "fields": ...}``: a batch's output as GeoDataFrames."""
    geopandas = _geopandas()
    name = os.fspath(out)
    targets = layer_paths(name)
    if not targets:
        return {ly.name: geopandas.read_file(name, layer=ly.name) for ly in LAYERS}
    return {layer: geopandas.read_file(path) for layer, path in targets.items()}
