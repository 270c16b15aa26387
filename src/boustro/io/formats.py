"""Mission files (GeoJSON, KML, GPX, CSV, QGroundControl ``.plan``, MAVLink ``QGC WPL 110``)."""

from __future__ import annotations

import csv
import io
import json
import os
import re
from collections.abc import Callable
from typing import TYPE_CHECKING, Any
from xml.sax.saxutils import escape, quoteattr

import numpy as np
from numpy.typing import NDArray

from .._files import atomic_write
from .._version import __version__
from ..errors import InvalidParameterError

if TYPE_CHECKING:
    from ..mission import Mission

__all__ = [
    "FORMATS",
    "MAV_CMD_DO_CHANGE_SPEED",
    "MAV_CMD_NAV_WAYPOINT",
    "MAV_FRAME_GLOBAL_RELATIVE_ALT",
    "atomic_write",
    "format_for",
    "render",
    "to_csv",
    "to_geojson",
    "to_gpx",
    "to_kml",
    "to_qgc_plan",
    "to_wpl",
    "write_mission",
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
#: QGroundControl's ``AltitudeModeRelative``.
_QGC_ALTITUDE_RELATIVE = 1


def _closed(ring: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.concatenate([ring, ring[:1]])


def _ccw(ring: NDArray[np.float64]) -> NDArray[np.float64]:
    """The ring counter-clockwise (RFC 7946's right-hand rule for exterior rings)."""
    x, y = ring[:, 0], ring[:, 1]
    signed = float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))
    return ring if signed > 0 else ring[::-1]


def _polygon_coordinates(
    ring: NDArray[np.float64], holes: tuple[NDArray[np.float64], ...] | list[NDArray[np.float64]]
) -> list[Any]:
    """GeoJSON Polygon coordinates: the exterior CCW, holes clockwise (RFC 7946)."""
    return [_closed(_ccw(ring)).tolist()] + [_closed(_ccw(h)[::-1]).tolist() for h in holes]


def _lonlat(
    mission: Mission, what: str
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """``(waypoints, transects, area, home)`` in WGS 84 longitude/latitude."""
    wp, tr = mission.waypoints_lonlat, mission.transects_lonlat
    area, home = mission.area_lonlat, mission.home_lonlat
    if wp is None or tr is None or area is None or home is None:
        raise InvalidParameterError(
            f"{what} needs longitude/latitude, but the area is in planar coordinates: give its "
            "CRS (e.g. --crs EPSG:28992), or write GeoJSON or CSV"
        )
    return wp, tr, area, home


def _need_altitude(mission: Mission, what: str) -> float:
    if mission.altitude is None:
        raise InvalidParameterError(
            f"{what} needs a mission altitude: give --altitude METRES above take-off (0 for a "
            "ground or surface vehicle), or a camera with --altitude or --gsd"
        )
    return float(mission.altitude)


#: Characters XML 1.0 does not allow anywhere (control characters other than tab, newline, CR).
_XML_INVALID = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ufffe\uffff]")


def _xml_text(text: str) -> str:
    """``text`` escaped for XML character data, characters XML 1.0 forbids replaced by ``?``."""
    return escape(_XML_INVALID.sub("?", text))


# -- GeoJSON --------------------------------------------------------------------------------
def _crs_member(crs: str | None) -> dict[str, Any] | None:
    if crs is None or crs.upper() in ("EPSG:4326", "OGC:CRS84"):
        return None
    name = crs
    if crs.upper().startswith("EPSG:"):
        name = f"urn:ogc:def:crs:EPSG::{crs.split(':', 1)[1]}"
    return {"type": "name", "properties": {"name": name}}


def to_geojson(mission: Mission) -> str:
    """A GeoJSON FeatureCollection: the area, the path, each transect, each waypoint.

    Features carry a ``role`` property (``area`` (with its holes), ``path``, ``transect``,
    ``waypoint``, and ``cell`` for each cell of a decomposed plan);
    transects also ``pass`` (``lane``, or ``hole`` for an edge of a pass around a hole);
    waypoints also ``seq``, ``kind`` (:data:`boustro.plan.KINDS`) and ``transect``. The mission's
    summary is the foreign member ``boustro``.
    """
    plan = mission.plan
    lengths = np.linalg.norm(plan.transects[:, 1] - plan.transects[:, 0], axis=1)
    features: list[dict[str, Any]] = [
        {
            "type": "Feature",
            "properties": {"role": "area", "name": mission.name},
            "geometry": {
                "type": "Polygon",
                "coordinates": _polygon_coordinates(mission.area.ring, mission.area.holes),
            },
        },
        {
            "type": "Feature",
            "properties": {
                "role": "path",
                "name": mission.name,
                "length_m": mission.stats.path_length,
            },
            "geometry": {"type": "LineString", "coordinates": mission.waypoints.tolist()},
        },
    ]
    roles = plan.role()
    for i, seg in enumerate(mission.transects):
        features.append(
            {
                "type": "Feature",
                "properties": {
                    "role": "transect",
                    "transect": i,
                    "pass": roles[i],
                    "length_m": float(lengths[i] / plan.ground_scale),
                },
                "geometry": {"type": "LineString", "coordinates": seg.tolist()},
            }
        )
    if len(plan.cells) > 1:
        for i, (cell, rings) in enumerate(zip(plan.cells, mission.cell_rings(), strict=True)):
            features.append(
                {
                    "type": "Feature",
                    "properties": {
                        "role": "cell",
                        "cell": i,
                        "angle_deg": float(np.degrees(cell.angle)),
                        "n_transects": cell.n_transects,
                    },
                    "geometry": {
                        "type": "Polygon",
                        "coordinates": _polygon_coordinates(rings[0], rings[1:]),
                    },
                }
            )
    for i, (point, kind) in enumerate(zip(mission.waypoints, plan.kinds, strict=True)):
        features.append(
            {
                "type": "Feature",
                "properties": {
                    "role": "waypoint",
                    "seq": i,
                    "kind": kind,
                    "transect": int(plan.lane[i]),
                },
                "geometry": {"type": "Point", "coordinates": point.tolist()},
            }
        )
    doc: dict[str, Any] = {"type": "FeatureCollection", "name": mission.name or "boustro plan"}
    crs = _crs_member(mission.crs)
    if crs is not None:
        doc["crs"] = crs
    doc["boustro"] = mission.summary()
    doc["features"] = features
    return json.dumps(doc, allow_nan=False) + "\n"


# -- KML ------------------------------------------------------------------------------------
def _kml_coords(points: NDArray[np.float64], altitude: float | None = None) -> str:
    if altitude is None:
        return " ".join(f"{x:.10f},{y:.10f}" for x, y in points)
    return " ".join(f"{x:.10f},{y:.10f},{altitude:.3f}" for x, y in points)


def _describe(mission: Mission) -> str:
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


def to_kml(mission: Mission) -> str:
    """KML 2.2: a Document with the area (Polygon), the path and one LineString per transect."""
    waypoints, transects, area, _ = _lonlat(mission, "KML")
    alt = mission.altitude
    mode = "" if alt is None else "<altitudeMode>relativeToGround</altitudeMode>"
    name = _xml_text(mission.name or "boustro plan")
    out = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        '<kml xmlns="http://www.opengis.net/kml/2.2">',
        "<Document>",
        f"<name>{name}</name>",
        f"<description>{_xml_text(_describe(mission))}</description>",
        "<Placemark><name>Area</name><Polygon><outerBoundaryIs><LinearRing><coordinates>"
        + _kml_coords(_closed(_ccw(area)))
        + "</coordinates></LinearRing></outerBoundaryIs>"
        + "".join(
            "<innerBoundaryIs><LinearRing><coordinates>"
            + _kml_coords(_closed(_ccw(h)[::-1]))
            + "</coordinates></LinearRing></innerBoundaryIs>"
            for h in mission.holes_lonlat
        )
        + "</Polygon></Placemark>",
        "<Placemark><name>Path</name><LineString><tessellate>1</tessellate>"
        + mode
        + "<coordinates>"
        + _kml_coords(waypoints, alt)
        + "</coordinates></LineString></Placemark>",
        "<Folder><name>Transects</name>",
    ]
    counts = {"lane": 0, "hole": 0}
    for seg, role in zip(transects, mission.plan.role(), strict=True):
        counts[role] = counts.get(role, 0) + 1
        label = "Transect" if role == "lane" else "Hole pass"  # lanes and passes numbered apart
        out.append(
            f"<Placemark><name>{label} {counts[role]}</name><LineString><tessellate>1</tessellate>"
            + mode
            + f"<coordinates>{_kml_coords(seg, alt)}</coordinates></LineString></Placemark>"
        )
    out += ["</Folder>", "</Document>", "</kml>"]
    return "\n".join(out) + "\n"


# -- GPX ------------------------------------------------------------------------------------
def to_gpx(mission: Mission) -> str:
    """GPX 1.1: the path as a route (``rtept`` per waypoint, named and typed by kind) and the
    transects as a track with one segment each. No ``ele``: GPX elevations are above sea level,
    mission altitudes are above take-off."""
    waypoints, transects, _, _ = _lonlat(mission, "GPX")
    name = _xml_text(mission.name or "boustro plan")
    out = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<gpx version="1.1" creator={quoteattr(f"boustro {__version__}")} '
        'xmlns="http://www.topografix.com/GPX/1/1">',
        f"<metadata><name>{name}</name><desc>{_xml_text(_describe(mission))}</desc></metadata>",
        f"<rte><name>{name}</name>",
    ]
    for i, ((lon, lat), kind) in enumerate(zip(waypoints, mission.kinds, strict=True)):
        out.append(
            f'<rtept lat="{lat:.10f}" lon="{lon:.10f}"><name>WP{i:04d}</name>'
            f"<type>{kind}</type></rtept>"
        )
    out += ["</rte>", f"<trk><name>{name} transects</name>"]
    for seg in transects:
        pts = "".join(f'<trkpt lat="{lat:.10f}" lon="{lon:.10f}"></trkpt>' for lon, lat in seg)
        out.append(f"<trkseg>{pts}</trkseg>")
    out += ["</trk>", "</gpx>"]
    return "\n".join(out) + "\n"


# -- CSV ------------------------------------------------------------------------------------
def to_csv(mission: Mission) -> str:
    """One row per waypoint: ``seq, kind, transect``, the coordinates, and the altitude if set.

    Geographic input: ``lon, lat`` (in the area's CRS); projected input: ``x, y`` (in its CRS)
    then WGS 84 ``lon, lat``; planar input: ``x, y``.
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


# -- QGroundControl .plan -------------------------------------------------------------------
def _qgc_item(seq: int, command: int, frame: int, params: list[Any], altitude: Any) -> dict:
    item: dict[str, Any] = {
        "autoContinue": True,
        "command": command,
        "doJumpId": seq,
        "frame": frame,
        "params": params,
        "type": "SimpleItem",
    }
    if command == MAV_CMD_NAV_WAYPOINT:
        item.update(
            {
                "AMSLAltAboveTerrain": None,
                "Altitude": altitude,
                "AltitudeMode": _QGC_ALTITUDE_RELATIVE,
            }
        )
    return item


def to_qgc_plan(mission: Mission, *, firmware_type: int = 0, vehicle_type: int = 0) -> str:
    """A QGroundControl Plan file (JSON, file version 1, mission version 2).

    One ``SimpleItem`` ``MAV_CMD_NAV_WAYPOINT`` per waypoint in ``MAV_FRAME_GLOBAL_RELATIVE_ALT``
    (params ``[hold 0, acceptance 0, pass-through 0, yaw null, lat, lon, altitude]``), preceded
    by a ``MAV_CMD_DO_CHANGE_SPEED`` (ground speed) when the mission has a speed. The planned
    home position is the mission's home at altitude 0. ``firmware_type`` and ``vehicle_type`` are
    MAVLink ``MAV_AUTOPILOT`` / ``MAV_TYPE`` values (0: generic).
    """
    waypoints, _, _, home = _lonlat(mission, "a QGroundControl plan")
    alt = _need_altitude(mission, "a QGroundControl plan")
    items = []
    speed = mission.stats.speed
    if speed is not None:
        items.append(
            _qgc_item(1, MAV_CMD_DO_CHANGE_SPEED, MAV_FRAME_MISSION, [1, speed, -1, 0, 0, 0, 0], 0)
        )
    for lon, lat in waypoints:
        params = [0, 0, 0, None, float(lat), float(lon), alt]
        items.append(
            _qgc_item(
                len(items) + 1, MAV_CMD_NAV_WAYPOINT, MAV_FRAME_GLOBAL_RELATIVE_ALT, params, alt
            )
        )
    home_lon, home_lat = (float(v) for v in home)
    doc = {
        "fileType": "Plan",
        "geoFence": {"circles": [], "polygons": [], "version": 2},
        "groundStation": "QGroundControl",
        "mission": {
            "cruiseSpeed": 15 if speed is None else speed,
            "firmwareType": int(firmware_type),
            "globalPlanAltitudeMode": _QGC_ALTITUDE_RELATIVE,
            "hoverSpeed": 5 if speed is None else speed,
            "items": items,
            "plannedHomePosition": [home_lat, home_lon, 0],
            "vehicleType": int(vehicle_type),
            "version": 2,
        },
        "rallyPoints": {"points": [], "version": 2},
        "version": 1,
    }
    return json.dumps(doc, indent=4, allow_nan=False) + "\n"


# -- MAVLink waypoint text ------------------------------------------------------------------
def to_wpl(mission: Mission) -> str:
    """The MAVLink plain-text mission format ``QGC WPL 110`` (tab-separated).

    Line 0 is the home position (``MAV_FRAME_GLOBAL``, altitude 0, current = 1), as ArduPilot
    and QGroundControl write it; then one ``MAV_CMD_NAV_WAYPOINT`` per waypoint in
    ``MAV_FRAME_GLOBAL_RELATIVE_ALT`` (a ``MAV_CMD_DO_CHANGE_SPEED`` first when there is a
    speed). Columns: index, current, frame, command, param1-4, latitude, longitude, altitude,
    autocontinue.
    """
    waypoints, _, _, home = _lonlat(mission, "a QGC WPL 110 waypoint file")
    alt = _need_altitude(mission, "a QGC WPL 110 waypoint file")

    def line(seq: int, current: int, frame: int, cmd: int, p: list[float], x, y, z) -> str:
        fields = [str(seq), str(current), str(frame), str(cmd)]
        fields += [f"{v:.8f}" for v in p] + [f"{x:.10f}", f"{y:.10f}", f"{z:.6f}", "1"]
        return "\t".join(fields)

    home_lon, home_lat = (float(v) for v in home)
    rows = [
        "QGC WPL 110",
        line(0, 1, MAV_FRAME_GLOBAL, MAV_CMD_NAV_WAYPOINT, [0] * 4, home_lat, home_lon, 0.0),
    ]
    speed = mission.stats.speed
    if speed is not None:
        rows.append(
            line(1, 0, MAV_FRAME_MISSION, MAV_CMD_DO_CHANGE_SPEED, [1, speed, -1, 0], 0.0, 0.0, 0.0)
        )
    for lon, lat in waypoints:
        rows.append(
            line(
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


# -- registry and atomic writing ------------------------------------------------------------
#: name -> (file extensions, renderer); a renderer returns text, or bytes for a binary format.
FORMATS: dict[str, tuple[tuple[str, ...], Callable[[Mission], str | bytes]]] = {
    "geojson": ((".geojson", ".json"), to_geojson),
    "kml": ((".kml",), to_kml),
    "gpx": ((".gpx",), to_gpx),
    "csv": ((".csv",), to_csv),
    "plan": ((".plan",), to_qgc_plan),
    "wpl": ((".waypoints", ".txt", ".mission"), to_wpl),
}


def format_for(path: str | os.PathLike[str], fmt: str | None = None) -> str:
    """The format name for ``path``: ``fmt`` if given, else from the file's extension."""
    if fmt is not None:
        if fmt not in FORMATS:
            raise InvalidParameterError(
                f"unknown format {fmt!r}; expected one of {', '.join(FORMATS)}"
            )
        return fmt
    ext = os.path.splitext(os.fspath(path))[1].lower()
    for name, (exts, _) in FORMATS.items():
        if ext in exts:
            return name
    known = ", ".join(e for exts, _ in FORMATS.values() for e in exts)
    raise InvalidParameterError(
        f"cannot tell the format of {os.fspath(path)!r} from its extension {ext or '(none)'!r}; "
        f"use one of {known}, or give --format"
    )


def render(mission: Mission, fmt: str) -> str | bytes:
    """The text (or bytes) of ``mission`` in format ``fmt`` (a key of :data:`FORMATS`).

    Example:
        >>> from boustro.io import embedded_field
        >>> from boustro.mission import plan_area
        >>> sorted(FORMATS)
        ['csv', 'geojson', 'gpx', 'kml', 'plan', 'wpl']
        >>> render(plan_area(embedded_field(), 10.0), "csv").splitlines()[0]
        'seq,kind,transect,lon,lat'
    """
    return FORMATS[format_for("", fmt)][1](mission)


def write_mission(mission: Mission, path: str | os.PathLike[str], fmt: str | None = None) -> str:
    """Render ``mission`` (format from ``fmt`` or the extension) and write it atomically.

    Returns the format name. Nothing is written if rendering fails.
    """
    name = format_for(path, fmt)
    text = render(mission, name)
    atomic_write(path, text)
    return name
