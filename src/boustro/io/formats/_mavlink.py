"""The MAVLink mission items of a mission, shared by ``.plan`` and ``QGC WPL 110``.

In order: a ``MAV_CMD_DO_CHANGE_SPEED`` when the mission has a speed; one
``MAV_CMD_NAV_WAYPOINT`` per waypoint, at the mission's altitude above home
(``MAV_FRAME_GLOBAL_RELATIVE_ALT``) or, over terrain, at its altitude above mean sea level
(``MAV_FRAME_GLOBAL``); with a camera, ``MAV_CMD_DO_SET_CAM_TRIGG_DIST`` after each lane's
``start`` waypoint (params ``[distance, 0, 1, 0]``: trigger now and every ``distance`` metres)
and after its ``end`` (``[0, 0, 0, 0]``: stop), or only around the whole survey with
``images_in_turns``; a sortie of a split mission ends with ``MAV_CMD_NAV_RETURN_TO_LAUNCH``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

from ._common import (
    MAV_CMD_DO_CHANGE_SPEED,
    MAV_CMD_NAV_WAYPOINT,
    MAV_FRAME_GLOBAL,
    MAV_FRAME_GLOBAL_RELATIVE_ALT,
    MAV_FRAME_MISSION,
    lonlat,
    need_altitude,
)

if TYPE_CHECKING:
    from ...mission import Mission

__all__ = [
    "MAV_CMD_DO_SET_CAM_TRIGG_DIST",
    "MAV_CMD_NAV_RETURN_TO_LAUNCH",
    "MavItem",
    "home_altitude",
    "mission_items",
]

#: MAVLink ``MAV_CMD_NAV_RETURN_TO_LAUNCH``.
MAV_CMD_NAV_RETURN_TO_LAUNCH = 20
#: MAVLink ``MAV_CMD_DO_SET_CAM_TRIGG_DIST``.
MAV_CMD_DO_SET_CAM_TRIGG_DIST = 206


class MavItem(NamedTuple):
    """One mission item: command, frame, params 1-4, latitude, longitude, altitude.

    ``above_ground`` is a waypoint's height above the terrain when its altitude is AMSL from a
    DEM (QGroundControl shows it), else ``None``."""

    command: int
    frame: int
    params: tuple[float, float, float, float]  # ints where a file writes them so
    lat: float
    lon: float
    alt: float
    above_ground: float | None = None


def _command(command: int, *params: float) -> MavItem:
    p = (list(params) + [0] * 4)[:4]
    return MavItem(command, MAV_FRAME_MISSION, (p[0], p[1], p[2], p[3]), 0, 0, 0)


def home_altitude(mission: Mission) -> float:
    """The home position's altitude: 0 (relative), or the ground's AMSL over terrain."""
    return 0 if mission.terrain is None else float(mission.terrain.home_ground)


def _waypoints(mission: Mission, what: str) -> tuple[list[MavItem], tuple[str, ...]]:
    """The waypoint items and the kind of each."""
    if mission.terrain is not None:
        t = mission.terrain
        items = [
            MavItem(
                MAV_CMD_NAV_WAYPOINT,
                MAV_FRAME_GLOBAL,
                (0, 0, 0, 0),
                float(lat),
                float(lon),
                float(amsl),
                t.height,
            )
            for (lon, lat), amsl in zip(t.lonlat, t.amsl, strict=True)
        ]
        return items, t.kinds
    waypoints, _, _, _ = lonlat(mission, what)
    alt = need_altitude(mission, what)
    items = [
        MavItem(
            MAV_CMD_NAV_WAYPOINT,
            MAV_FRAME_GLOBAL_RELATIVE_ALT,
            (0, 0, 0, 0),
            float(lat),
            float(lon),
            alt,
        )
        for lon, lat in waypoints
    ]
    return items, mission.kinds


def mission_items(mission: Mission, what: str) -> list[MavItem]:
    """The items of ``mission`` in order (see the module docstring); ``what`` names the format
    in the errors (planar input, no altitude)."""
    items: list[MavItem] = []
    speed = mission.stats.speed
    if speed is not None:
        items.append(_command(MAV_CMD_DO_CHANGE_SPEED, 1, speed, -1, 0))
    waypoints, kinds = _waypoints(mission, what)
    camera = mission.camera
    on = [i for i, k in enumerate(kinds) if k == "start"]
    off = [i for i, k in enumerate(kinds) if k == "end"]
    if camera is not None and camera.images_in_turns and on and off:
        on, off = on[:1], off[-1:]
    on_set, off_set = set(on), set(off)
    for i, item in enumerate(waypoints):
        items.append(item)
        if camera is None:
            continue
        if i in on_set:
            items.append(_command(MAV_CMD_DO_SET_CAM_TRIGG_DIST, camera.distance, 0, 1, 0))
        elif i in off_set:
            items.append(_command(MAV_CMD_DO_SET_CAM_TRIGG_DIST, 0, 0, 0, 0))
    if mission.sortie is not None:
        items.append(_command(MAV_CMD_NAV_RETURN_TO_LAUNCH))
    return items
