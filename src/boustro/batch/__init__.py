"""Thousands of fields: batch planning into a GeoPackage, locally or on a Dask cluster.

``boustro.batch(fields, out, spacing=10)`` plans every feature of a vector file (or a
GeoDataFrame) and writes the layers ``lanes``, ``paths`` and ``fields`` as the fields finish;
it resumes an interrupted output (see :mod:`boustro.batch.run`). The package is callable:
``boustro.batch(...)`` is :func:`boustro.batch.batch`. ``boustro.plan_area`` is the geo-stack
entry (:func:`boustro.batch.geo.plan_area`), and :func:`read_plans` reads an output back as
GeoDataFrames. Modules: ``options`` (per-field options), ``source`` (the input's features),
``gpkg`` (the GeoPackage written with sqlite3), ``worker`` (one field planned),
``executors`` (in-process, local processes, Dask), ``export`` (other formats), ``run``,
``frames`` (GeoPandas), ``geo``.
"""

from __future__ import annotations

import sys
import types
from typing import Any

from .frames import read_plans, source_from_frame
from .geo import GeoPlan, plan_area
from .options import COLUMN_OPTIONS, PlanOptions
from .run import BatchResult, batch
from .source import Feature, Source, read_source

__all__ = [
    "COLUMN_OPTIONS",
    "BatchResult",
    "Feature",
    "GeoPlan",
    "PlanOptions",
    "Source",
    "batch",
    "plan_area",
    "read_plans",
    "read_source",
    "source_from_frame",
]


class _CallableModule(types.ModuleType):
    """This package, callable as :func:`batch` (``boustro.batch(...)``)."""

    def __call__(self, *args: Any, **kwargs: Any) -> BatchResult:
        return batch(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
