"""KML 2.2 (Google Earth): the area, the path and each transect, in WGS 84.

The area's placemark is named after the field (``Area`` when it has no name), so that a KML
boustro wrote reads back (:func:`boustro.io.read_areas`) with its fields' names, which
``--field NAME`` picks.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ._common import describe, lonlat, ring_ccw, ring_closed, xml_text
from .registry import register_format

if TYPE_CHECKING:
    from ...mission import Mission

__all__ = ["kml_body", "to_kml"]


def _kml_coords(points: NDArray[np.float64], altitude: float | None = None) -> str:
    if altitude is None:
        return " ".join(f"{x:.10f},{y:.10f}" for x, y in points)
    return " ".join(f"{x:.10f},{y:.10f},{altitude:.3f}" for x, y in points)


def _area_placemark(
    name: str, area: NDArray[np.float64], holes: Sequence[NDArray[np.float64]]
) -> str:
    return (
        f"<Placemark><name>{xml_text(name or 'Area')}</name>"
        "<Polygon><outerBoundaryIs><LinearRing><coordinates>"
        + _kml_coords(ring_closed(ring_ccw(area)))
        + "</coordinates></LinearRing></outerBoundaryIs>"
        + "".join(
            "<innerBoundaryIs><LinearRing><coordinates>"
            + _kml_coords(ring_closed(ring_ccw(h)[::-1]))
            + "</coordinates></LinearRing></innerBoundaryIs>"
            for h in holes
        )
        + "</Polygon></Placemark>"
    )


#: The name of each transect's placemark by its role (``Plan.role()``), then its number.
_LABELS = {"lane": "Transect", "hole": "Hole pass", "boundary": "Boundary pass"}


def _transect_placemarks(mission: Mission, transects: NDArray[np.float64], mode: str) -> list[str]:
    alt = mission.altitude
    out = []
    counts = {"lane": 0, "hole": 0, "boundary": 0}
    for seg, role in zip(transects, mission.plan.role(), strict=True):
        counts[role] = counts.get(role, 0) + 1
        label = _LABELS.get(role, role)  # lanes and each kind of pass numbered apart
        out.append(
            f"<Placemark><name>{label} {counts[role]}</name><LineString><tessellate>1</tessellate>"
            + mode
            + f"<coordinates>{_kml_coords(seg, alt)}</coordinates></LineString></Placemark>"
        )
    return out


@register_format("kml", extensions=(".kml",))
def to_kml(mission: Mission) -> str:
    """KML 2.2: a Document with the area (a Polygon named after the field), the path and one
    LineString per transect.

    >>> from boustro.io import embedded_field
    >>> from boustro.mission import plan_area
    >>> to_kml(plan_area(embedded_field(), 10.0)).splitlines()[1]
    '<kml xmlns="http://www.opengis.net/kml/2.2">'
    """
    name = xml_text(mission.name or "boustro plan")
    out = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        '<kml xmlns="http://www.opengis.net/kml/2.2">',
        "<Document>",
        f"<name>{name}</name>",
        f"<description>{xml_text(describe(mission))}</description>",
    ]
    out += kml_body(mission)
    out += ["</Document>", "</kml>"]
    return "\n".join(out) + "\n"


def kml_body(mission: Mission) -> list[str]:
    """The area, the path and the Transects folder of one mission (KML elements, one a line)."""
    waypoints, transects, area, _ = lonlat(mission, "KML")
    alt = mission.altitude
    mode = "" if alt is None else "<altitudeMode>relativeToGround</altitudeMode>"
    out = [
        _area_placemark(mission.name, area, mission.holes_lonlat),
        "<Placemark><name>Path</name><LineString><tessellate>1</tessellate>"
        + mode
        + "<coordinates>"
        + _kml_coords(waypoints, alt)
        + "</coordinates></LineString></Placemark>",
        "<Folder><name>Transects</name>",
    ]
    out += _transect_placemarks(mission, transects, mode)
    out.append("</Folder>")
    return out
