"""MAVLink plain-text missions ``QGC WPL 110`` (ArduPilot, QGroundControl, Mission Planner)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from ._common import ALTITUDE_FORMATS, MAV_CMD_NAV_WAYPOINT, MAV_FRAME_GLOBAL, lonlat
from ._mavlink import home_altitude, mission_items
from .registry import register_format

if TYPE_CHECKING:
    from ...mission import Mission

__all__ = ["to_wpl"]

_WHAT = ALTITUDE_FORMATS["wpl"]


def _line(
    seq: int, current: int, frame: int, cmd: int, p: Sequence[float], x: float, y: float, z: float
) -> str:
    """One tab-separated item: index, current, frame, command, params 1-4, x, y, z, continue."""
    fields = [str(seq), str(current), str(frame), str(cmd)]
    fields += [f"{v:.8f}" for v in p] + [f"{x:.10f}", f"{y:.10f}", f"{z:.6f}", "1"]
    return "\t".join(fields)


@register_format("wpl", extensions=(".waypoints", ".txt", ".mission"))
def to_wpl(mission: Mission) -> str:
    """The MAVLink plain-text mission format ``QGC WPL 110`` (tab-separated).

    Line 0 is the home position (``MAV_FRAME_GLOBAL``, altitude 0, current = 1), as ArduPilot
    and QGroundControl write it; then one ``MAV_CMD_NAV_WAYPOINT`` per waypoint in
    ``MAV_FRAME_GLOBAL_RELATIVE_ALT`` (a ``MAV_CMD_DO_CHANGE_SPEED`` first when there is a
    speed). Columns: index, current, frame, command, param1-4, latitude, longitude, altitude,
    autocontinue. Camera triggers, terrain altitudes (``MAV_FRAME_GLOBAL``, home at the
    ground's AMSL altitude) and a sortie's return to launch as in
    :mod:`boustro.io.formats._mavlink`.

    >>> from boustro.io import embedded_field
    >>> from boustro.mission import plan_area
    >>> to_wpl(plan_area(embedded_field(), 10.0, altitude=30.0)).splitlines()[0]
    'QGC WPL 110'
    """
    _, _, _, home = lonlat(mission, _WHAT)
    items = mission_items(mission, _WHAT)
    home_lon, home_lat = (float(v) for v in home)
    home_alt = float(home_altitude(mission))
    rows = [
        "QGC WPL 110",
        _line(0, 1, MAV_FRAME_GLOBAL, MAV_CMD_NAV_WAYPOINT, [0] * 4, home_lat, home_lon, home_alt),
    ]
    for item in items:
        rows.append(
            _line(
                len(rows) - 1,
                0,
                item.frame,
                item.command,
                item.params,
                item.lat,
                item.lon,
                item.alt,
            )
        )
    return "\n".join(rows) + "\n"
