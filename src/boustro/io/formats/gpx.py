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
    transects as a track with one segment each. No ``ele``: GPX elevations are above sea level,
    mission altitudes are above take-off.

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


def gpx_route(mission: Mission) -> list[str]:
    """The mission's path as one GPX ``rte`` (lines), named after the mission."""
    waypoints, _, _, _ = lonlat(mission, "GPX")
    name = xml_text(mission.name or "boustro plan")
    out = [f"<rte><name>{name}</name>"]
    for i, ((lon, lat), kind) in enumerate(zip(waypoints, mission.kinds, strict=True)):
        out.append(
            f'<rtept lat="{lat:.10f}" lon="{lon:.10f}"><name>WP{i:04d}</name>'
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
                    f'<trkpt lat="{lat:.10f}" lon="{lon:.10f}"></trkpt>' for lon, lat in seg
                )
                out.append(f"<trkseg>{pts}</trkseg>")
        out.append("</trk>")
    return out
