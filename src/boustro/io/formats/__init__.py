"""Mission files (GeoJSON, KML, GPX, CSV, QGroundControl ``.plan``, MAVLink ``QGC WPL 110``).

One module per format registers its renderer with :func:`register_format`; :data:`FORMATS` maps
each name to ``(extensions, renderer)``. Every module of this package is imported at the end of
this file (:meth:`~boustro._registry.Registry.discover`), so a new format is one new file.

>>> list(FORMATS)
['geojson', 'kml', 'gpx', 'csv', 'plan', 'wpl']
>>> format_for("survey.waypoints")
'wpl'
"""

from __future__ import annotations

from ..._files import atomic_write
from ._common import (
    _XML_INVALID,
    MAV_CMD_DO_CHANGE_SPEED,
    MAV_CMD_NAV_WAYPOINT,
    MAV_FRAME_GLOBAL,
    MAV_FRAME_GLOBAL_RELATIVE_ALT,
    MAV_FRAME_MISSION,
)
from ._common import describe as _describe
from ._common import lonlat as _lonlat
from ._common import need_altitude as _need_altitude
from ._common import polygon_coordinates as _polygon_coordinates
from ._common import ring_ccw as _ccw
from ._common import ring_closed as _closed
from ._common import xml_text as _xml_text
from .registry import FORMATS, Renderer, format_for, register_format, render, write_mission

# The built-in formats, imported in this order so that FORMATS (and --format's choices) keep it.
# isort: off
from .geojson import _crs_member, to_geojson
from .kml import _kml_coords, to_kml
from .gpx import to_gpx
from .waypoints_csv import to_csv
from .qgc_plan import _QGC_ALTITUDE_RELATIVE, _qgc_item, to_qgc_plan
from .wpl import to_wpl
# isort: on

__all__ = [
    "FORMATS",
    "MAV_CMD_DO_CHANGE_SPEED",
    "MAV_CMD_NAV_WAYPOINT",
    "MAV_FRAME_GLOBAL",
    "MAV_FRAME_GLOBAL_RELATIVE_ALT",
    "MAV_FRAME_MISSION",
    "Renderer",
    "atomic_write",
    "format_for",
    "register_format",
    "render",
    "to_csv",
    "to_geojson",
    "to_gpx",
    "to_kml",
    "to_qgc_plan",
    "to_wpl",
    "write_mission",
]

# Kept importable from the old module path (tests and callers use some of them).
_COMPAT = (
    _XML_INVALID,
    _ccw,
    _closed,
    _crs_member,
    _describe,
    _kml_coords,
    _lonlat,
    _need_altitude,
    _polygon_coordinates,
    _qgc_item,
    _QGC_ALTITUDE_RELATIVE,
    _xml_text,
)

FORMATS.discover()  # every other module of this package: a new format registers itself
