"""The web API's work, without the web framework: a request's areas, their plans, the answer
(the object ``boustro plan --json`` prints, plus ``"geojson"``), exports and uploaded files.

Every step is the library's: areas are read by :mod:`boustro.io` (a GeoJSON object by
:func:`~boustro.io.areas_from_object`, an uploaded file by :func:`~boustro.io.read_areas`),
checked by :func:`~boustro.io.repair.check_area`, planned by
:func:`~boustro.mission.plan_area`, summarised by :meth:`~boustro.mission.Mission.summary` and
exported by :func:`~boustro.io.formats.render`. Errors are the library's hierarchy
(:class:`~boustro.errors.BoustroError`), one line each; the app maps them to HTTP 4xx.
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..errors import BoustroError, InvalidParameterError, PolygonFileError
from ..io import Area, areas_from_object, read_areas
from ..io.area import field_label
from ..io.crs import Projection
from ..io.formats import FORMATS, format_for, render
from ..io.formats._fields import render_fields, safe_name
from ..io.repair import check_area, detach_holes, repair_area
from ..mission import Mission, WorkEstimate, estimate_work, plan_area
from .limits import MAX_FIELDS, MAX_SECONDS, RequestTooLargeError, check_epsg, count_vertices
from .options import PlanOptions, parse_options
from .recent import RecentPlans

__all__ = [
    "MEDIA_TYPES",
    "estimate_request",
    "export_request",
    "plan_request",
    "plan_response",
    "read_upload",
    "request_areas",
]

#: The media type of each export format (anything else: ``application/octet-stream``).
MEDIA_TYPES = {
    "geojson": "application/geo+json",
    "kml": "application/vnd.google-earth.kml+xml",
    "gpx": "application/gpx+xml",
    "csv": "text/csv",
    "plan": "application/json",
    "wpl": "text/plain",
}


def _member_crs(obj: Any) -> str | None:
    """The CRS a GeoJSON object's 2008 ``crs`` member names, accepted only as an EPSG code
    (``EPSG:n`` or ``urn:ogc:def:crs:EPSG::n``); any other member is refused."""
    crs = obj.get("crs") if isinstance(obj, dict) else None
    if crs is None:
        return None
    name = crs.get("properties", {}).get("name") if isinstance(crs, dict) else None
    if isinstance(name, str) and name.lower().startswith("urn:ogc:def:crs:epsg:"):
        name = "EPSG:" + name.rsplit(":", 1)[-1]
    if isinstance(name, str) and name.upper() in ("OGC:CRS84", "URN:OGC:DEF:CRS:OGC:1.3:CRS84"):
        name = "EPSG:4326"
    return check_epsg(name, "the area's crs member")


def _pick(areas: list[Area], picked: str | None) -> list[Area]:
    """The field named (or numbered, from 1) ``picked``, else every field."""
    if picked is None:
        return areas
    named = [a for a in areas if a.name == picked]
    if named:
        return named[:1]
    if picked.isdigit() and 1 <= int(picked) <= len(areas):
        return [areas[int(picked) - 1]]
    names = ", ".join(repr(a.name) for a in areas)
    raise InvalidParameterError(f"options.field {picked!r}: no such field (fields: {names})")


def _checked(areas: list[Area]) -> list[Area]:
    if len(areas) > MAX_FIELDS:
        raise RequestTooLargeError(
            f"{len(areas)} fields in one request, over the limit of {MAX_FIELDS}"
        )
    count_vertices([r for a in areas for r in (a.ring, *a.holes)])
    return areas


def request_areas(area: Any, opts: PlanOptions) -> list[Area]:
    """The areas of a request's ``area`` (a GeoJSON geometry, Feature or FeatureCollection) in
    ``opts.crs``, else its ``crs`` member (which must be an EPSG code), else longitude/latitude;
    within the limits."""
    if not isinstance(area, dict) or "type" not in area:
        raise PolygonFileError(
            "area must be a GeoJSON object: a Polygon, MultiPolygon, Feature or FeatureCollection"
        )
    crs = opts.crs or _member_crs(area) or "EPSG:4326"
    areas = _checked(areas_from_object(area, crs=crs, where="area"))
    return _pick(areas, opts.field)


def _valid(area: Area, repair: bool) -> Area:
    """As ``boustro plan``: repaired or checked; a hole touching the shell cut back."""
    if repair:
        area = repair_area(area)[0]
    area = detach_holes(area)[0]
    if not repair:
        check_area(area)
    return area


def _estimate(area: Area, opts: PlanOptions) -> WorkEstimate:
    """The estimate before planning of ``area`` with the request's options."""
    kw = opts.kwargs
    names = (
        "hull_tolerance",
        "decompose",
        "method",
        "fitness",
        "speed",
        "turn_time",
        "keep_inside",
    )
    return estimate_work(area, opts.spacing, **{k: kw[k] for k in names})


def _plan_one(area: Area, opts: PlanOptions) -> Mission:
    area = _valid(area, opts.repair)
    kw = opts.kwargs
    estimate = _estimate(area, opts)
    if estimate.seconds > MAX_SECONDS:
        raise RequestTooLargeError(
            f"{estimate.describe()}: over this server's limit of {MAX_SECONDS:g} s per plan; "
            "use a larger spacing, a simpler boundary, or boustro plan on the command line"
        )
    return plan_area(area, opts.spacing, progress=False, **kw)


def _checked_options(body: Any) -> PlanOptions:
    """The request's members checked (an object with an ``area``, nothing unknown) and its
    options parsed: what every request answers for, planned anew or not."""
    if not isinstance(body, dict):
        raise InvalidParameterError(
            'the request must be a JSON object {"area": ..., "options": ...}'
        )
    unknown = sorted(set(body) - {"area", "options", "format"})
    if unknown:
        raise InvalidParameterError(f"unknown member(s) {', '.join(map(repr, unknown))}")
    if "area" not in body:
        raise InvalidParameterError('the request has no "area" (a GeoJSON geometry or feature)')
    return parse_options(body.get("options"))


def plan_request(body: Any) -> list[Mission]:
    """Plan a request ``{"area": <GeoJSON>, "options": {...}}``: one mission per field.

    Example:
        >>> ring = [[5, 52], [5.003, 52], [5.003, 52.002], [5, 52.002], [5, 52]]
        >>> body = {"area": {"type": "Polygon", "coordinates": [ring]}, "options": {"spacing": 20}}
        >>> answer = plan_response(plan_request(body))
        >>> answer["n_transects"], answer["certified"], answer["geojson"]["type"]
        (12, True, 'FeatureCollection')
    """
    return _plan_checked(body, _checked_options(body))


def _plan_checked(body: dict[str, Any], opts: PlanOptions) -> list[Mission]:
    """:func:`plan_request` of a request whose members and options are checked."""
    areas = request_areas(body["area"], opts)
    missions, failed = [], []
    for i, area in enumerate(areas, start=1):
        try:
            missions.append(_plan_one(area, opts))
        except (InvalidParameterError, PolygonFileError, ValueError) as exc:
            label = field_label(area, i, len(areas))  # as boustro plan names it
            if len(areas) > 1:
                failed.append(f"{label}: {exc}")
            elif label and isinstance(exc, BoustroError):
                raise type(exc)(f"{label}: {exc}") from None
            else:
                raise
    if failed:
        raise InvalidParameterError("; ".join(failed))
    return missions


def _one_answer(mission: Mission) -> dict[str, Any]:
    out = mission.summary()
    out["written"] = []  # as `boustro plan --json`, which lists the files it wrote: none here
    out["geojson"] = json.loads(render(mission, "geojson"))
    return out


def plan_response(missions: Sequence[Mission]) -> Any:
    """The answer: for each mission the object ``boustro plan --json`` prints, plus
    ``"geojson"`` (the plan as a FeatureCollection, :mod:`boustro.io.formats.geojson`); the
    certificate is the summary's ``certified`` and ``gap``; one field: one object, several: a
    list, as on the command line."""
    answers = [_one_answer(m) for m in missions]
    return answers[0] if len(answers) == 1 else answers


def export_request(body: Any, recent: RecentPlans | None = None) -> tuple[bytes, str, str]:
    """Plan a request and render it in ``body["format"]``: ``(bytes, file name, media type)``.
    Several fields go into one file where the format holds them, else are refused. A request
    whose area and options ``recent`` holds (the plan the page shows) is not planned again."""
    fmt = body.get("format") if isinstance(body, dict) else None
    if not isinstance(fmt, str) or fmt not in FORMATS:
        raise InvalidParameterError(f"format must be one of {', '.join(FORMATS)}, got {fmt!r:.40}")
    fmt = format_for("", fmt)
    opts = _checked_options(body)  # the same answer to a bad request, planned before or not
    missions = None if recent is None else recent.get(body)
    if missions is None:
        missions = _plan_checked(body, opts)
    if len(missions) == 1:
        data = render(missions[0], fmt)
        name = missions[0].name or "mission"
    else:
        combined = render_fields(missions, fmt)
        if combined is None:
            raise InvalidParameterError(
                f"a {fmt} file holds one field: pick one with options.field"
            )
        data, name = combined, "missions"
    payload = data.encode("utf-8") if isinstance(data, str) else data
    ext = FORMATS[fmt][0][0] if FORMATS[fmt][0] else f".{fmt}"
    return payload, f"{safe_name(name)}{ext}", MEDIA_TYPES.get(fmt, "application/octet-stream")


def estimate_request(body: Any) -> dict[str, Any]:
    """The estimate before planning of each field of a request (no planning)."""
    if not isinstance(body, dict):
        raise InvalidParameterError("the request must be a JSON object")
    opts = parse_options(body.get("options"))
    out = []
    for area in request_areas(body.get("area"), opts):
        est = _estimate(area, opts)
        out.append({"name": area.name, "seconds": est.seconds, "text": est.describe()})
    return {"fields": out, "limit_seconds": MAX_SECONDS}


def _ring_lonlat(proj: Projection | None, ring: np.ndarray) -> list[list[float]]:
    pts = ring if proj is None else proj.to_lonlat(ring)
    closed = np.vstack([pts, pts[:1]])
    return [[float(x), float(y)] for x, y in closed]


def _feature(area: Area) -> dict[str, Any]:
    if area.crs is None:
        raise PolygonFileError(
            f"{area.source}: planar coordinates (no CRS) cannot be shown on a map; "
            "give the file's CRS as an EPSG code"
        )
    proj = None if area.crs == "EPSG:4326" else Projection(area.crs, area.crs)
    rings = [_ring_lonlat(proj, area.ring)] + [_ring_lonlat(proj, h) for h in area.holes]
    return {
        "type": "Feature",
        "properties": {"name": area.name, "crs": area.crs},
        "geometry": {"type": "Polygon", "coordinates": rings},
    }


def read_upload(name: str, data: bytes, crs: str | None = None) -> dict[str, Any]:
    """The fields of an uploaded area file as a GeoJSON FeatureCollection in longitude/latitude.

    The file is read by :func:`boustro.io.read_areas` (format from the extension, else the
    content) from a private temporary directory that is removed afterwards: the server writes
    nowhere else. ``name`` only gives the extension; ``crs`` (an EPSG code) overrides the file's.
    """
    ext = os.path.splitext(os.path.basename(name or ""))[1].lower()
    if not ext[1:].replace(".", "").isalnum() or len(ext) > 12:
        ext = ""
    if name.lower().endswith(".shp.zip"):
        ext = ".shp.zip"
    crs = None if crs is None else check_epsg(crs)
    with tempfile.TemporaryDirectory(prefix="boustro-web-") as folder:
        path = os.path.join(folder, f"upload{ext}")
        with open(path, "wb") as fh:
            fh.write(data)
        shown = os.path.basename(name or "upload")
        try:
            areas = _checked(read_areas(path, crs=crs))
        except BoustroError as exc:  # name the upload, not the temporary file
            raise type(exc)(str(exc).replace(path, shown)) from None
    for i, area in enumerate(areas):
        if area.name == "upload":  # named after the temporary file: use the upload's name
            areas[i] = Area(area.ring, area.crs, os.path.splitext(shown)[0], shown, area.holes)
    return {"type": "FeatureCollection", "features": [_feature(a) for a in areas]}
