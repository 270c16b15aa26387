"""QGroundControl ``.plan`` files (JSON): MAVLink waypoint items at a relative altitude."""

from __future__ import annotations

import json
from typing import TYPE_CHECKING, Any

from ._common import (
    MAV_CMD_DO_CHANGE_SPEED,
    MAV_CMD_NAV_WAYPOINT,
    MAV_FRAME_GLOBAL_RELATIVE_ALT,
    MAV_FRAME_MISSION,
    lonlat,
    need_altitude,
)
from .registry import register_format

if TYPE_CHECKING:
    from ...mission import Mission

__all__ = ["to_qgc_plan"]

#: QGroundControl's ``AltitudeModeRelative``.
_QGC_ALTITUDE_RELATIVE = 1


def _qgc_item(seq: int, command: int, frame: int, params: list[Any], altitude: Any) -> dict:
    item: dict[str, Any] = {
        "autoContinue": True,
        "command": command,
        "doJumpId": seq,
        "frame": frame,
        "params": params,
        "type": "SimpleItem",
    }
    if command == MAV_CMD_NAV_WAYPOINT:
        item.update(
            {
                "AMSLAltAboveTerrain": None,
                "Altitude": altitude,
                "AltitudeMode": _QGC_ALTITUDE_RELATIVE,
            }
        )
    return item


def _mission_items(mission: Mission) -> list[dict[str, Any]]:
    """The speed item (if the mission has a speed), then one waypoint item per waypoint."""
    waypoints, _, _, _ = lonlat(mission, "a QGroundControl plan")
    alt = need_altitude(mission, "a QGroundControl plan")
    items = []
    speed = mission.stats.speed
    if speed is not None:
        items.append(
            _qgc_item(1, MAV_CMD_DO_CHANGE_SPEED, MAV_FRAME_MISSION, [1, speed, -1, 0, 0, 0, 0], 0)
        )
    for lon, lat in waypoints:
        params = [0, 0, 0, None, float(lat), float(lon), alt]
        items.append(
            _qgc_item(
                len(items) + 1, MAV_CMD_NAV_WAYPOINT, MAV_FRAME_GLOBAL_RELATIVE_ALT, params, alt
            )
        )
    return items


@register_format("plan", extensions=(".plan",))
def to_qgc_plan(mission: Mission, *, firmware_type: int = 0, vehicle_type: int = 0) -> str:
    """A QGroundControl Plan file (JSON, file version 1, mission version 2).

    One ``SimpleItem`` ``MAV_CMD_NAV_WAYPOINT`` per waypoint in ``MAV_FRAME_GLOBAL_RELATIVE_ALT``
    (params ``[hold 0, acceptance 0, pass-through 0, yaw null, lat, lon, altitude]``), preceded
    by a ``MAV_CMD_DO_CHANGE_SPEED`` (ground speed) when the mission has a speed. The planned
    home position is the mission's home at altitude 0. ``firmware_type`` and ``vehicle_type`` are
    MAVLink ``MAV_AUTOPILOT`` / ``MAV_TYPE`` values (0: generic).

    >>> from boustro.io import embedded_field
    >>> from boustro.mission import plan_area
    >>> doc = json.loads(to_qgc_plan(plan_area(embedded_field(), 10.0, altitude=30.0)))
    >>> doc["fileType"], doc["mission"]["items"][0]["command"]
    ('Plan', 16)
    """
    items = _mission_items(mission)
    _, _, _, home = lonlat(mission, "a QGroundControl plan")
    speed = mission.stats.speed
    home_lon, home_lat = (float(v) for v in home)
    doc = {
        "fileType": "Plan",
        "geoFence": {"circles": [], "polygons": [], "version": 2},
        "groundStation": "QGroundControl",
        "mission": {
            "cruiseSpeed": 15 if speed is None else speed,
            "firmwareType": int(firmware_type),
            "globalPlanAltitudeMode": _QGC_ALTITUDE_RELATIVE,
            "hoverSpeed": 5 if speed is None else speed,
            "items": items,
            "plannedHomePosition": [home_lat, home_lon, 0],
            "vehicleType": int(vehicle_type),
            "version": 2,
        },
        "rallyPoints": {"points": [], "version": 2},
        "version": 1,
    }
    return json.dumps(doc, indent=4, allow_nan=False) + "\n"
