"""QGroundControl ``.plan`` files (JSON): MAVLink waypoint items at a relative altitude."""

from __future__ import annotations

import json
from typing import TYPE_CHECKING, Any

from ._common import ALTITUDE_FORMATS, MAV_CMD_NAV_WAYPOINT, lonlat
from ._mavlink import home_altitude, mission_items
from .registry import register_format

if TYPE_CHECKING:
    from ...mission import Mission

__all__ = ["to_qgc_plan"]

_WHAT = ALTITUDE_FORMATS["plan"]

#: QGroundControl's ``AltitudeModeRelative``.
_QGC_ALTITUDE_RELATIVE = 1
#: QGroundControl's ``AltitudeModeCalcAboveTerrain``: an AMSL altitude (``MAV_FRAME_GLOBAL``)
#: computed from terrain data for a height above ground (the item's ``Altitude``).
_QGC_ALTITUDE_ABOVE_TERRAIN = 3


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
    """The mission's items (:func:`~boustro.io.formats._mavlink.mission_items`) as QGC
    ``SimpleItem`` objects: waypoints at a relative altitude, or over terrain at their AMSL
    altitude in ``MAV_FRAME_GLOBAL`` with QGC's "calculated above terrain" mode."""
    items: list[dict[str, Any]] = []
    for item in mission_items(mission, _WHAT):
        seq = len(items) + 1
        if item.command != MAV_CMD_NAV_WAYPOINT:
            items.append(_qgc_item(seq, item.command, item.frame, [*item.params, 0, 0, 0], 0))
            continue
        params: list[Any] = [0, 0, 0, None, item.lat, item.lon, item.alt]
        if item.above_ground is None:
            items.append(_qgc_item(seq, item.command, item.frame, params, item.alt))
        else:
            qgc = _qgc_item(seq, item.command, item.frame, params, item.above_ground)
            qgc.update(AMSLAltAboveTerrain=item.alt, AltitudeMode=_QGC_ALTITUDE_ABOVE_TERRAIN)
            items.append(qgc)
    return items


@register_format("plan", extensions=(".plan",))
def to_qgc_plan(mission: Mission, *, firmware_type: int = 0, vehicle_type: int = 0) -> str:
    """A QGroundControl Plan file (JSON, file version 1, mission version 2).

    One ``SimpleItem`` ``MAV_CMD_NAV_WAYPOINT`` per waypoint in ``MAV_FRAME_GLOBAL_RELATIVE_ALT``
    (params ``[hold 0, acceptance 0, pass-through 0, yaw null, lat, lon, altitude]``), preceded
    by a ``MAV_CMD_DO_CHANGE_SPEED`` (ground speed) when the mission has a speed. The planned
    home position is the mission's home at altitude 0. A camera adds
    ``MAV_CMD_DO_SET_CAM_TRIGG_DIST`` items (params ``[distance, 0, 1, 0, 0, 0, 0]`` after a
    lane's start, ``[0, 0, 0, 0, 0, 0, 0]`` after its end); over terrain the waypoints are in
    ``MAV_FRAME_GLOBAL`` at their AMSL altitude (``AltitudeMode`` 3, QGC's "calculated above
    terrain", ``Altitude`` the height above ground) and home at the ground's altitude; a
    sortie ends with ``MAV_CMD_NAV_RETURN_TO_LAUNCH`` (:mod:`boustro.io.formats._mavlink`).
    ``firmware_type`` and ``vehicle_type`` are MAVLink ``MAV_AUTOPILOT`` / ``MAV_TYPE``
    values (0: generic).

    >>> from boustro.io import embedded_field
    >>> from boustro.mission import plan_area
    >>> doc = json.loads(to_qgc_plan(plan_area(embedded_field(), 10.0, altitude=30.0)))
    >>> doc["fileType"], doc["mission"]["items"][0]["command"]
    ('Plan', 16)
    """
    items = _mission_items(mission)
    _, _, _, home = lonlat(mission, _WHAT)
    speed = mission.stats.speed
    home_lon, home_lat = (float(v) for v in home)
    doc = {
        "fileType": "Plan",
        "geoFence": {"circles": [], "polygons": [], "version": 2},
        "groundStation": "QGroundControl",
        "mission": {
            "cruiseSpeed": 15 if speed is None else speed,
            "firmwareType": int(firmware_type),
            "globalPlanAltitudeMode": _QGC_ALTITUDE_RELATIVE
            if mission.terrain is None
            else _QGC_ALTITUDE_ABOVE_TERRAIN,
            "hoverSpeed": 5 if speed is None else speed,
            "items": items,
            "plannedHomePosition": [home_lat, home_lon, home_altitude(mission)],
            "vehicleType": int(vehicle_type),
            "version": 2,
        },
        "rallyPoints": {"points": [], "version": 2},
        "version": 1,
    }
    return json.dumps(doc, indent=4, allow_nan=False) + "\n"
