"""A batch's layers in another vector format than GeoPackage: one file per layer.

The run appends to its GeoPackage (:func:`boustro.batch.run.store_path`); for an output named
``plans.fgb`` (or ``.shp``, ``.geojson``, any format GDAL writes and pyogrio recognises by its
extension) each layer is then written as ``plans.lanes.fgb``, ``plans.paths.fgb``,
``plans.fields.fgb``: all into one temporary folder beside them, then renamed into place once
every layer is written: each file is the previous complete one or the new one, and a layer
that fails leaves every file as it was. pyogrio is imported on use.
A format that renames columns (a Shapefile cuts them to 10 characters: ``transect_length_m`` is
``transect_l``) says so in one warning per file, instead of GDAL's ten Python warnings.
"""

from __future__ import annotations

import logging
import os
import tempfile
import warnings
from typing import Any

from ..errors import InvalidParameterError
from ..io.read_gdal import _one_line, _pyogrio, recorded_warnings
from .gpkg import LAYERS

__all__ = ["export_layers", "layer_paths"]

log = logging.getLogger("boustro")

#: How GDAL (through pyogrio) says that it renamed a column for the format.
_RENAMED = "Normalized/laundered field name: "


def layer_paths(out: str) -> dict[str, str]:
    """``{layer: file}`` for an output that is not a GeoPackage (``{}`` for one).

    Raises:
        InvalidParameterError: GDAL writes no format of that extension (or several).
    """
    if out.lower().endswith(".gpkg"):
        return {}
    pyogrio = _pyogrio("a batch's output in another format than GeoPackage")
    try:
        pyogrio.raw.detect_write_driver(out)
    except ValueError as exc:
        raise InvalidParameterError(
            f"--out {out}: {' '.join(str(exc).split())} (a .gpkg holds every layer in one file)"
        ) from None
    stem, ext = os.path.splitext(out)
    return {layer.name: f"{stem}.{layer.name}{ext}" for layer in LAYERS}


def export_layers(store: str, targets: dict[str, str]) -> None:
    """Write each layer of the GeoPackage ``store`` to its file in ``targets``: all into one
    temporary folder beside them, then renamed into place once every layer is written (a
    layer that fails leaves every target as it was)."""
    pyogrio = _pyogrio("a batch's output in another format than GeoPackage")
    folder = os.path.dirname(os.path.abspath(next(iter(targets.values()))))
    with tempfile.TemporaryDirectory(prefix=".boustro-", dir=folder) as tmp:
        for layer, target in targets.items():
            _write_layer(pyogrio, store, layer, target, os.path.join(tmp, os.path.basename(target)))
        for name in sorted(os.listdir(tmp)):  # a Shapefile is several files
            os.replace(os.path.join(tmp, name), os.path.join(folder, name))


def _write_layer(pyogrio: Any, store: str, layer: str, target: str, path: str) -> None:
    """Layer ``layer`` of ``store`` written to ``path`` in the format of ``target``."""
    driver = pyogrio.raw.detect_write_driver(target)
    meta, _, geometry, data = pyogrio.raw.read(store, layer=layer)
    kind = "Unknown" if layer == "fields" else "LineString"
    if driver == "ESRI Shapefile" and layer == "fields":
        kind = "Polygon"  # a Shapefile needs one type; it holds multipolygons in it
    # FlatGeobuf's spatial index takes no null geometry (a field reported without one)
    extra = {"SPATIAL_INDEX": "NO"} if driver == "FlatGeobuf" else {}
    quiet = logging.getLogger("pyogrio")
    level = quiet.level
    quiet.setLevel(logging.WARNING)  # not "Created N records" on the command line
    try:
        with recorded_warnings() as caught:
            pyogrio.raw.write(
                path, geometry, data, meta["fields"], crs=meta["crs"], driver=driver,
                geometry_type=kind, **extra,
            )  # fmt: skip
        _say_renamed(target, caught)
    except pyogrio.errors.DataSourceError as exc:
        raise InvalidParameterError(
            f"--out {target}: GDAL cannot write it: {_one_line(exc)}"
        ) from None
    except (pyogrio.errors.DataLayerError, pyogrio.errors.FeatureError) as exc:
        raise InvalidParameterError(
            f"--out {target}: GDAL cannot write layer {layer}: {_one_line(exc)}"
        ) from None
    finally:
        quiet.setLevel(level)


def _say_renamed(target: str, caught: list[warnings.WarningMessage]) -> None:
    """The columns the format renamed, in one warning; other warnings passed on."""
    renamed = []
    for w in caught:
        text = str(w.message)
        if text.startswith(_RENAMED):
            renamed.append(text[len(_RENAMED) :])
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    if renamed:
        log.warning("%s: the format renamed columns: %s", target, ", ".join(renamed))
