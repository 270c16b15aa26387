"""Survey areas from a QGroundControl ``.plan`` file: its survey and geofence polygons.

A ``.plan`` is JSON (``"fileType": "Plan"``). Its fields: each survey of the mission
(``mission.items[*]`` with ``"complexItemType": "survey"``: its ``polygon``), named
``survey N`` (N: the item's position in the mission, from 1), then each inclusion geofence
(``geoFence.polygons[*]`` with ``"inclusion": true``, or the single ``geoFence.polygon`` of a
version 1 file), named ``geofence N``. Every vertex is ``[latitude, longitude]`` (latitude
FIRST, unlike GeoJSON), read as WGS 84 longitude/latitude; exclusion fences, circles and
corridor scans are not fields. An exclusion fence or circle is not an obstacle either, nor an
inclusion circle a boundary: each is named in a warning (the plan may cross the one and leave
the other; give an obstacle as a hole in GeoJSON, KML or WKT).
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np

from ..errors import PolygonFileError
from .area import LONLAT, Area
from .area import close_ring as _close_open
from .read_geojson import _ring

__all__ = ["is_qgc_plan", "qgc_fields"]

log = logging.getLogger("boustro.io.read")  # as the other readers


def is_qgc_plan(data: Any) -> bool:
    """Parsed JSON is a QGroundControl plan (``"fileType": "Plan"``)."""
    return isinstance(data, dict) and data.get("fileType") == "Plan"


def _lonlat(polygon: Any, where: str) -> np.ndarray:
    return _close_open(_ring(polygon, where)[:, ::-1], where)  # [lat, lon] -> (lon, lat)


def _survey_polygons(mission: Any, where: str) -> list[tuple[str, Any, str]]:
    items = mission.get("items", []) if isinstance(mission, dict) else []
    if not isinstance(items, list):
        raise PolygonFileError(f"{where}: mission.items must be a list")
    return [
        (f"survey {k}", item.get("polygon"), f"{where}: mission item {k}")
        for k, item in enumerate(items, start=1)
        if isinstance(item, dict) and str(item.get("complexItemType", "")).lower() == "survey"
    ]


def _fence_polygons(fence: Any, where: str) -> list[tuple[str, Any, str]]:
    if not isinstance(fence, dict):
        return []
    if "polygons" not in fence and fence.get("polygon"):  # version 1: one inclusion polygon
        return [("geofence 1", fence["polygon"], f"{where}: geoFence.polygon")]
    polygons = fence.get("polygons", [])
    if not isinstance(polygons, list):
        raise PolygonFileError(f"{where}: geoFence.polygons must be a list")
    circles = fence.get("circles", [])
    circles = circles if isinstance(circles, list) else []
    for k, p in enumerate(polygons):
        if isinstance(p, dict) and not _inclusion(p):
            _not_avoided(where, f"geoFence.polygons[{k}] (an exclusion fence)")
    for k, c in enumerate(circles):
        if isinstance(c, dict) and _inclusion(c):  # a boundary the plan may leave
            log.warning(
                "%s: geoFence.circles[%d] (an inclusion circle) is not a boundary for boustro: "
                "the plan may leave it (give the area as a polygon)",
                where,
                k,
            )
        else:
            _not_avoided(where, f"geoFence.circles[{k}] (an exclusion circle)")
    return [
        (f"geofence {k}", p.get("polygon"), f"{where}: geoFence.polygons[{k - 1}]")
        for k, p in enumerate(polygons, start=1)
        if isinstance(p, dict) and _inclusion(p)
    ]


def _inclusion(fence: dict[str, Any]) -> bool:
    """A geofence polygon or circle is an inclusion fence (QGC's ``inclusion``, true if absent)."""
    return fence.get("inclusion", True) is True


def _not_avoided(where: str, what: str) -> None:
    """Warn that the exclusion fence or circle ``what`` of the plan is no obstacle."""
    log.warning(
        "%s: %s is not an obstacle for boustro: the plan may cross it (give it as a hole "
        "of the area in GeoJSON, KML or WKT)",
        where,
        what,
    )


def qgc_fields(data: dict[str, Any], where: str, crs: str | None) -> list[tuple[str, Area]]:
    """Every survey and inclusion geofence polygon of a parsed ``.plan`` as ``(name, area)``.

    Raises:
        PolygonFileError: a polygon that is not a list of ``[lat, lon]`` pairs, or no survey
            nor inclusion geofence polygon in the plan.
    """
    found = _survey_polygons(data.get("mission"), where)
    found += _fence_polygons(data.get("geoFence"), where)
    if not found:
        raise PolygonFileError(
            f"{where}: the QGroundControl plan holds no survey polygon and no inclusion "
            "geofence (simple waypoint items are not an area)"
        )
    return [(name, Area(_lonlat(p, at), crs or LONLAT, name, at)) for name, p, at in found]
