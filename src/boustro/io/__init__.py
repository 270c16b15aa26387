"""The edges of boustro: reading areas, coordinate systems, writing mission files."""

from __future__ import annotations

from .._files import atomic_write
from .read import (
    EMBEDDED_FIELD,
    LONLAT,
    PAPER_PARALLELOGRAM,
    PAPER_SPACING,
    Area,
    area_from_json,
    area_from_kml,
    area_from_object,
    area_from_text,
    area_from_wkt,
    areas_from_object,
    areas_from_text,
    embedded_field,
    polygon_from_json,
    read_area,
    read_areas,
    read_polygon,
)

__all__ = [
    "EMBEDDED_FIELD",
    "LONLAT",
    "PAPER_PARALLELOGRAM",
    "PAPER_SPACING",
    "Area",
    "area_from_json",
    "area_from_kml",
    "area_from_object",
    "area_from_text",
    "area_from_wkt",
    "areas_from_object",
    "areas_from_text",
    "atomic_write",
    "embedded_field",
    "polygon_from_json",
    "read_area",
    "read_areas",
    "read_polygon",
]
