"""Helpers shared by the mission formats: rings, lon/lat, altitude, XML text, MAVLink numbers."""

from __future__ import annotations

import re
from typing import TYPE_CHECKING, Any
from xml.sax.saxutils import escape

import numpy as np
from numpy.typing import NDArray

from ..._version import __version__
from ...errors import InvalidParameterError

if TYPE_CHECKING:
    from ...mission import Mission

__all__ = [
    "ALTITUDE_FORMATS",
    "MAV_CMD_DO_CHANGE_SPEED",
    "MAV_CMD_NAV_WAYPOINT",
    "MAV_FRAME_GLOBAL",
    "MAV_FRAME_GLOBAL_RELATIVE_ALT",
    "MAV_FRAME_MISSION",
    "check_altitude",
    "describe",
    "lonlat",
    "need_altitude",
    "polygon_coordinates",
    "ring_ccw",
    "ring_closed",
    "xml_text",
]

#: MAVLink ``MAV_CMD_NAV_WAYPOINT``.
MAV_CMD_NAV_WAYPOINT = 16
#: MAVLink ``MAV_CMD_DO_CHANGE_SPEED``.
MAV_CMD_DO_CHANGE_SPEED = 178
#: MAVLink ``MAV_FRAME_GLOBAL`` (absolute altitude; used for the home item of a WPL file).
MAV_FRAME_GLOBAL = 0
#: MAVLink ``MAV_FRAME_MISSION`` (for commands that are not positions).
MAV_FRAME_MISSION = 2
#: MAVLink ``MAV_FRAME_GLOBAL_RELATIVE_ALT``: altitude above the home position.
MAV_FRAME_GLOBAL_RELATIVE_ALT = 3


def ring_closed(ring: NDArray[np.float64]) -> NDArray[np.float64]:
    """``ring`` with its first vertex repeated at the end."""
    return np.concatenate([ring, ring[:1]])


def ring_ccw(ring: NDArray[np.float64]) -> NDArray[np.float64]:
    """The ring counter-clockwise (RFC 7946's right-hand rule for exterior rings).

    >>> ring_ccw(np.array([[0.0, 0.0], [0.0, 1.0], [1.0, 0.0]])).tolist()
    [[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]]
    """
    x, y = ring[:, 0], ring[:, 1]
    signed = float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))
    return ring if signed > 0 else ring[::-1]


def polygon_coordinates(
    ring: NDArray[np.float64], holes: tuple[NDArray[np.float64], ...] | list[NDArray[np.float64]]
) -> list[Any]:
    """GeoJSON Polygon coordinates: the exterior CCW, holes clockwise (RFC 7946)."""
    return [ring_closed(ring_ccw(ring)).tolist()] + [
        ring_closed(ring_ccw(h)[::-1]).tolist() for h in holes
    ]


def lonlat(
    mission: Mission, what: str
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """``(waypoints, transects, area, home)`` in WGS 84 longitude/latitude.

    Raises:
        InvalidParameterError: the mission is planar (no CRS); ``what`` names the format.
    """
    wp, tr = mission.waypoints_lonlat, mission.transects_lonlat
    area, home = mission.area_lonlat, mission.home_lonlat
    if wp is None or tr is None or area is None or home is None:
        raise InvalidParameterError(
            f"{what} needs longitude/latitude, but the area is in planar coordinates: give its "
            "CRS (e.g. --crs EPSG:28992), or write GeoJSON or CSV"
        )
    return wp, tr, area, home


#: The formats whose renderer calls :func:`need_altitude` (MAVLink missions, by
#: :mod:`._mavlink`): ``boustro plan`` refuses them without an altitude before any work.
ALTITUDE_FORMATS = {"plan": "a QGroundControl plan", "wpl": "a QGC WPL 110 waypoint file"}


def need_altitude(mission: Mission, what: str) -> float:
    """The mission's altitude; raises :class:`InvalidParameterError` naming ``what`` if unset."""
    check_altitude(mission.altitude, what)
    return float(mission.altitude)  # type: ignore[arg-type]


def check_altitude(altitude: float | None, what: str) -> None:
    """Raise :class:`InvalidParameterError` naming ``what`` if ``altitude`` is unset."""
    if altitude is None:
        raise InvalidParameterError(
            f"{what} needs a mission altitude: give --altitude METRES above take-off (0 for a "
            "ground or surface vehicle), or a camera with --altitude or --gsd"
        )


#: Characters XML 1.0 does not allow anywhere (control characters other than tab, newline, CR).
_XML_INVALID = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ufffe\uffff]")


def xml_text(text: str) -> str:
    """``text`` escaped for XML character data, characters XML 1.0 forbids replaced by ``?``.

    >>> xml_text("a < b\\x01")
    'a &lt; b?'
    """
    return escape(_XML_INVALID.sub("?", text))


def describe(mission: Mission) -> str:
    """One line summing the mission up (the description of a KML or GPX file)."""
    s = mission.stats
    parts = [
        f"{s.n_transects} transects at {mission.spacing:.4g} m spacing",
        f"bearing {mission.bearing:.2f} deg",
        f"transects {s.transect_length:.1f} m",
        f"path {s.path_length:.1f} m",
        f"area {s.area:.1f} m2",
    ]
    if mission.coverage is not None:
        parts.append(f"covered {100 * mission.coverage.covered_share:.4f}%")
    if s.duration is not None:
        parts.append(f"duration {s.duration:.0f} s")
    return "; ".join(parts) + f" (boustro {__version__})"
