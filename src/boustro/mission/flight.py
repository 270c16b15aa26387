"""What a flying mission adds to a plan: altitudes over terrain, and its place among sorties.

These are data only; :mod:`boustro.mission.terrain` and :mod:`boustro.mission.sorties` build
them, :class:`~boustro.mission.Mission` carries them, and the MAVLink formats read them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["Sortie", "TerrainRoute"]


@dataclass(frozen=True)
class TerrainRoute:
    """The waypoints at a constant height above ground, altitudes above mean sea level.

    Attributes:
        points: ``(N, 2)`` in the area's coordinates: the mission's waypoints with points added
            along lanes and moves where the terrain bends more than ``tolerance``.
        lonlat: ``(N, 2)`` the same in WGS 84 longitude/latitude.
        kinds: ``(N,)`` each point's kind: the waypoint's, or ``"terrain"`` for an added one.
        ground: ``(N,)`` the ground's elevation under each point (the DEM's, metres AMSL).
        height: the height above ground flown, metres.
        tolerance: the largest vertical error allowed between points, metres.
        home_ground: the ground's elevation at the home position, metres AMSL.
        dem: the DEM's file name.
    """

    points: NDArray[np.float64]
    lonlat: NDArray[np.float64]
    kinds: tuple[str, ...]
    ground: NDArray[np.float64]
    height: float
    tolerance: float
    home_ground: float
    dem: str

    @property
    def amsl(self) -> NDArray[np.float64]:
        """``(N,)`` each point's altitude above mean sea level: ground + height."""
        return self.ground + self.height

    def summary(self) -> dict[str, Any]:
        return {
            "dem": self.dem,
            "height_above_ground_m": self.height,
            "tolerance_m": self.tolerance,
            "points": len(self.points),
            "added_points": int(sum(k == "terrain" for k in self.kinds)),
            "amsl_min_m": float(self.amsl.min()),
            "amsl_max_m": float(self.amsl.max()),
            "home_ground_m": self.home_ground,
        }


@dataclass(frozen=True)
class Sortie:
    """One flight of a mission split by a flight-time or distance limit.

    Attributes:
        index, count: this sortie (from 1) and how many there are.
        lanes: ``(first, last)`` of the whole mission's lanes flown (from 0, inclusive).
        length: metres from home, over the lanes, back to home.
        duration: seconds (``length / speed`` plus the turns), or ``None`` without a speed.
        limit: the limit, as given (e.g. ``"max flight time 900 s"``).
    """

    index: int
    count: int
    lanes: tuple[int, int]
    length: float
    duration: float | None
    limit: str

    def summary(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "index": self.index,
            "count": self.count,
            "lanes": [self.lanes[0] + 1, self.lanes[1] + 1],
            "length_m": self.length,
            "limit": self.limit,
        }
        if self.duration is not None:
            out["duration_s"] = self.duration
        return out
