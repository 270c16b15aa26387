"""GPX 1.1: the path as a route of waypoints, the transects as a track, in WGS 84."""

from __future__ import annotations

from typing import TYPE_CHECKING
from xml.sax.saxutils import quoteattr

from ..._version import __version__
from ._common import describe, lonlat, xml_text
from .registry import register_format

if TYPE_CHECKING:
    from ...mission import Mission

__all__ = ["gpx_route", "gpx_track", "to_gpx"]


@register_format("gpx", extensions=(".gpx",))
def to_gpx(mission: Mission) -> str:
    """GPX 1.1: the path as a route (``rtept`` per waypoint, named and typed by kind) and the
    transects as a track with one segment each.

    Altitudes (``ele``, metres), as the MAVLink files fly them: over a DEM
    (:func:`~boustro.mission.terrain.follow_terrain`) the route is the terrain route, its points
    added where the ground bends included, each at its altitude above mean sea level (GPX's own
    reference), and the track's points have none (the ground under a lane's end is not kept);
    without a DEM every point is at the mission altitude, which is above take-off (not sea
    level), as the route's description says. Without an altitude: no ``ele``.

    >>> from boustro.io import embedded_field
    >>> from boustro.mission import plan_area
    >>> to_gpx(plan_area(embedded_field(), 10.0)).count("<trkseg>")
    19
    """
    name = xml_text(mission.name or "boustro plan")
    route, track = gpx_route(mission), gpx_track(mission)
    out = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<gpx version="1.1" creator={quoteattr(f"boustro {__version__}")} '
        'xmlns="http://www.topografix.com/GPX/1/1">',
        f"<metadata><name>{name}</name><desc>{xml_text(describe(mission))}</desc></metadata>",
        *route,
        *track,
        "</gpx>",
    ]
    return "\n".join(out) + "\n"


def _ele_note(mission: Mission) -> str:
    """The route's ``desc`` element saying what its ``ele`` values are ("" without any)."""
    if mission.terrain is not None:
        t = mission.terrain
        note = f"ele: metres above mean sea level, {t.height:g} m above the ground of {t.dem}"
    elif mission.altitude is not None:
        note = f"ele: {mission.altitude:g} m above take-off, not above sea level"
    else:
        return ""
    return f"<desc>{xml_text(note)}</desc>"


def _ele(value: float | None) -> str:
    return "" if value is None else f"<ele>{value:.3f}</ele>"


def gpx_route(mission: Mission) -> list[str]:
    """The mission's path as one GPX ``rte`` (lines), named after the mission; over a DEM its
    terrain route (see :func:`to_gpx`)."""
    waypoints, _, _, _ = lonlat(mission, "GPX")
    kinds: tuple[str, ...] = mission.kinds
    ele: list[float | None] = [mission.altitude] * len(waypoints)
    if mission.terrain is not None:
        waypoints, kinds = mission.terrain.lonlat, mission.terrain.kinds
        ele = [float(z) for z in mission.terrain.amsl]
    name = xml_text(mission.name or "boustro plan")
    out = [f"<rte><name>{name}</name>{_ele_note(mission)}"]
    for i, ((lon, lat), kind, z) in enumerate(zip(waypoints, kinds, ele, strict=True)):
        out.append(
            f'<rtept lat="{lat:.10f}" lon="{lon:.10f}">{_ele(z)}<name>WP{i:04d}</name>'
            f"<type>{kind}</type></rtept>"
        )
    out.append("</rte>")
    return out


def gpx_track(mission: Mission) -> list[str]:
    """The mission's transects as a GPX ``trk`` with a segment each (lines); the edges of the
    boundary passes of a ``keep_inside`` plan as a second ``trk`` of ``<type>boundary</type>``."""
    _, transects, _, _ = lonlat(mission, "GPX")
    name = xml_text(mission.name or "boustro plan")
    boundary = [role == "boundary" for role in mission.plan.role()]
    ele = _ele(mission.altitude if mission.terrain is None else None)
    out = []
    for title, kind, pick in (
        ("transects", "", [not b for b in boundary]),
        ("boundary passes", "<type>boundary</type>", boundary),
    ):
        if title != "transects" and not any(pick):
            continue
        out.append(f"<trk><name>{name} {title}</name>{kind}")
        for seg, keep in zip(transects, pick, strict=True):
            if keep:
                pts = "".join(
                    f'<trkpt lat="{lat:.10f}" lon="{lon:.10f}">{ele}</trkpt>' for lon, lat in seg
                )
                out.append(f"<trkseg>{pts}</trkseg>")
        out.append("</trk>")
    return out
