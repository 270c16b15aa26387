"""GeoJSON (RFC 7946): the area, the path, each transect, each waypoint as features."""

from __future__ import annotations

import json
from typing import TYPE_CHECKING, Any

import numpy as np

from ._common import polygon_coordinates
from .registry import register_format

if TYPE_CHECKING:
    from ...mission import Mission

__all__ = ["to_geojson"]


def _crs_member(crs: str | None) -> dict[str, Any] | None:
    """The (pre-RFC 7946) ``crs`` member naming a CRS other than WGS 84, else None."""
    if crs is None or crs.upper() in ("EPSG:4326", "OGC:CRS84"):
        return None
    name = crs
    if crs.upper().startswith("EPSG:"):
        name = f"urn:ogc:def:crs:EPSG::{crs.split(':', 1)[1]}"
    return {"type": "name", "properties": {"name": name}}


def _feature(properties: dict[str, Any], kind: str, coordinates: Any) -> dict[str, Any]:
    return {
        "type": "Feature",
        "properties": properties,
        "geometry": {"type": kind, "coordinates": coordinates},
    }


def _transect_features(mission: Mission) -> list[dict[str, Any]]:
    plan = mission.plan
    lengths = plan.transect_lengths()
    roles = plan.role()
    return [
        _feature(
            {
                "role": "transect",
                "transect": i,
                "pass": roles[i],
                "length_m": float(lengths[i]),
            },
            "LineString",
            seg.tolist(),
        )
        for i, seg in enumerate(mission.transects)
    ]


def _cell_features(mission: Mission) -> list[dict[str, Any]]:
    plan = mission.plan
    if len(plan.cells) <= 1:
        return []
    return [
        _feature(
            {
                "role": "cell",
                "cell": i,
                "angle_deg": float(np.degrees(cell.angle)),
                "n_transects": cell.n_transects,
            },
            "Polygon",
            polygon_coordinates(rings[0], rings[1:]),
        )
        for i, (cell, rings) in enumerate(zip(plan.cells, mission.cell_rings(), strict=True))
    ]


def _waypoint_features(mission: Mission) -> list[dict[str, Any]]:
    plan = mission.plan
    return [
        _feature(
            {"role": "waypoint", "seq": i, "kind": kind, "transect": int(plan.lane[i])},
            "Point",
            point.tolist(),
        )
        for i, (point, kind) in enumerate(zip(mission.waypoints, plan.kinds, strict=True))
    ]


@register_format("geojson", extensions=(".geojson", ".json"))
def to_geojson(mission: Mission) -> str:
    """A GeoJSON FeatureCollection: the area, the path, each transect, each waypoint.

    Features carry a ``role`` property (``area`` (with its holes), ``path``, ``transect``,
    ``waypoint``, and ``cell`` for each cell of a decomposed plan);
    transects also ``pass`` (``lane``, ``hole`` for an edge of a pass around a hole, or
    ``boundary`` for an edge of a boundary pass of a ``keep_inside`` plan);
    waypoints also ``seq``, ``kind`` (:data:`boustro.plan.KINDS`) and ``transect``. The mission's
    summary is the foreign member ``boustro``.

    >>> from boustro.io import embedded_field
    >>> from boustro.mission import plan_area
    >>> doc = json.loads(to_geojson(plan_area(embedded_field(), 10.0)))
    >>> doc["type"], doc["features"][1]["properties"]["role"]
    ('FeatureCollection', 'path')
    """
    features = [
        _feature(
            {"role": "area", "name": mission.name},
            "Polygon",
            polygon_coordinates(mission.area.ring, mission.area.holes),
        ),
        _feature(
            {"role": "path", "name": mission.name, "length_m": mission.stats.path_length},
            "LineString",
            mission.waypoints.tolist(),
        ),
    ]
    features += _transect_features(mission) + _cell_features(mission)
    features += _waypoint_features(mission)
    doc: dict[str, Any] = {"type": "FeatureCollection", "name": mission.name or "boustro plan"}
    crs = _crs_member(mission.crs)
    if crs is not None:
        doc["crs"] = crs
    doc["boustro"] = mission.summary()
    doc["features"] = features
    return json.dumps(doc, allow_nan=False) + "\n"
