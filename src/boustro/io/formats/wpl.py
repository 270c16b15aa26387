"""MAVLink plain-text missions ``QGC WPL 110`` (ArduPilot, QGroundControl, Mission Planner)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from ._common import (
    MAV_CMD_DO_CHANGE_SPEED,
    MAV_CMD_NAV_WAYPOINT,
    MAV_FRAME_GLOBAL,
    MAV_FRAME_GLOBAL_RELATIVE_ALT,
    MAV_FRAME_MISSION,
    lonlat,
    need_altitude,
)
from .registry import register_format

if TYPE_CHECKING:
    from ...mission import Mission

__all__ = ["to_wpl"]

_WHAT = "a QGC WPL 110 waypoint file"


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
    autocontinue.

    >>> from boustro.io import embedded_field
    >>> from boustro.mission import plan_area
    >>> to_wpl(plan_area(embedded_field(), 10.0, altitude=30.0)).splitlines()[0]
    'QGC WPL 110'
    """
    waypoints, _, _, home = lonlat(mission, _WHAT)
    alt = need_altitude(mission, _WHAT)
    home_lon, home_lat = (float(v) for v in home)
    rows = [
        "QGC WPL 110",
        _line(0, 1, MAV_FRAME_GLOBAL, MAV_CMD_NAV_WAYPOINT, [0] * 4, home_lat, home_lon, 0.0),
    ]
    speed = mission.stats.speed
    if speed is not None:
        rows.append(
            _line(1, 0, MAV_FRAME_MISSION, MAV_CMD_DO_CHANGE_SPEED, [1, speed, -1, 0], 0, 0, 0)
        )
    for lon, lat in waypoints:
        rows.append(
            _line(
                len(rows) - 1,
                0,
                MAV_FRAME_GLOBAL_RELATIVE_ALT,
                MAV_CMD_NAV_WAYPOINT,
                [0] * 4,
                float(lat),
                float(lon),
                alt,
            )
        )
    return "\n".join(rows) + "\n"
