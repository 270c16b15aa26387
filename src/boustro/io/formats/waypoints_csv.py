"""CSV: one row per waypoint, with its kind, transect, coordinates and altitude."""

from __future__ import annotations

import csv
import io
from typing import TYPE_CHECKING, Any

from .registry import register_format

if TYPE_CHECKING:
    from ...mission import Mission

__all__ = ["to_csv"]


@register_format("csv", extensions=(".csv",))
def to_csv(mission: Mission) -> str:
    """One row per waypoint: ``seq, kind, transect``, the coordinates, and the altitude if set.

    Geographic input: ``lon, lat`` (in the area's CRS); projected input: ``x, y`` (in its CRS)
    then WGS 84 ``lon, lat``; planar input: ``x, y``.

    >>> from boustro.io import embedded_field
    >>> from boustro.mission import plan_area
    >>> to_csv(plan_area(embedded_field(), 10.0, altitude=30.0)).splitlines()[0]
    'seq,kind,transect,lon,lat,altitude_m'
    """
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    geographic = mission.projection.geographic
    header = ["seq", "kind", "transect"]
    if geographic:
        header += ["lon", "lat"]
    else:
        header += ["x", "y"] + (["lon", "lat"] if mission.waypoints_lonlat is not None else [])
    if mission.altitude is not None:
        header.append("altitude_m")
    writer.writerow(header)
    for i, kind in enumerate(mission.kinds):
        row: list[Any] = [i, kind, int(mission.plan.lane[i])]
        row += [repr(float(v)) for v in mission.waypoints[i]]
        if not geographic and mission.waypoints_lonlat is not None:
            row += [repr(float(v)) for v in mission.waypoints_lonlat[i]]
        if mission.altitude is not None:
            row.append(repr(float(mission.altitude)))
        writer.writerow(row)
    return buf.getvalue()
