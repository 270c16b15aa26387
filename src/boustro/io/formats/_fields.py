"""Several fields in one mission file, where the format can hold them.

:data:`FIELD_FORMATS` maps a format to the renderer of a list of missions (one per field):
GeoJSON (every feature with a ``field`` property, the summaries as a list), KML (a ``Folder``
per field), GPX (a route and a track per field) and CSV (a leading ``field`` column). A format
not in it (QGroundControl ``.plan``, ``QGC WPL 110``, any format registered later) holds one
mission: :func:`field_path` names one file per field.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import os
import re
import unicodedata
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any
from xml.sax.saxutils import quoteattr

from ..._version import __version__
from ...errors import InvalidParameterError
from ._common import describe, xml_text
from .geojson import to_geojson
from .gpx import gpx_route, gpx_track
from .kml import kml_body
from .waypoints_csv import to_csv

if TYPE_CHECKING:
    from ...mission import Mission

__all__ = ["FIELD_FORMATS", "field_path", "render_fields", "safe_name"]


def _title(missions: Sequence[Mission]) -> str:
    return f"boustro plan: {len(missions)} fields"


def fields_geojson(missions: Sequence[Mission]) -> str:
    """One FeatureCollection: each field's features, each with a ``field`` property (the
    field's name); the foreign member ``boustro`` is the list of the fields' summaries."""
    docs = [json.loads(to_geojson(m)) for m in missions]
    features = []
    for mission, doc in zip(missions, docs, strict=True):
        for feature in doc["features"]:
            feature["properties"] = {"field": mission.name, **feature["properties"]}
            features.append(feature)
    out: dict[str, Any] = {"type": "FeatureCollection", "name": _title(missions)}
    if "crs" in docs[0]:
        out["crs"] = docs[0]["crs"]  # one file: one CRS for all its fields
    out["boustro"] = [doc["boustro"] for doc in docs]
    out["features"] = features
    return json.dumps(out, allow_nan=False) + "\n"


def fields_kml(missions: Sequence[Mission]) -> str:
    """One KML Document with a Folder per field (named after it): its area, path, transects."""
    out = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        '<kml xmlns="http://www.opengis.net/kml/2.2">',
        "<Document>",
        f"<name>{xml_text(_title(missions))}</name>",
    ]
    for m in missions:
        out.append(f"<Folder><name>{xml_text(m.name or 'field')}</name>")
        out.append(f"<description>{xml_text(describe(m))}</description>")
        out += kml_body(m)
        out.append("</Folder>")
    out += ["</Document>", "</kml>"]
    return "\n".join(out) + "\n"


def fields_gpx(missions: Sequence[Mission]) -> str:
    """One GPX 1.1 file: a route per field (named after it), then a track per field."""
    out = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<gpx version="1.1" creator={quoteattr(f"boustro {__version__}")} '
        'xmlns="http://www.topografix.com/GPX/1/1">',
        f"<metadata><name>{xml_text(_title(missions))}</name></metadata>",
    ]
    for m in missions:
        out += gpx_route(m)
    for m in missions:
        out += gpx_track(m)
    out.append("</gpx>")
    return "\n".join(out) + "\n"


def fields_csv(missions: Sequence[Mission]) -> str:
    """One CSV: the columns of :func:`~boustro.io.formats.to_csv` after a ``field`` column."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    header: list[str] | None = None
    for m in missions:
        rows = list(csv.reader(io.StringIO(to_csv(m))))
        if header is None:
            header = rows[0]
            writer.writerow(["field", *header])
        elif rows[0] != header:
            raise InvalidParameterError(
                f"field {m.name!r}: its CSV columns {rows[0]} differ from the first field's"
            )
        writer.writerows([m.name, *row] for row in rows[1:])
    return buf.getvalue()


#: format name -> renderer of several missions (one per field) into one file.
FIELD_FORMATS: dict[str, Callable[[Sequence[Mission]], str]] = {
    "geojson": fields_geojson,
    "kml": fields_kml,
    "gpx": fields_gpx,
    "csv": fields_csv,
}


def render_fields(missions: Sequence[Mission], fmt: str) -> str | None:
    """The text of all ``missions`` in one file of format ``fmt``, or None if it holds one."""
    combine = FIELD_FORMATS.get(fmt)
    return None if combine is None else combine(missions)


#: Longest safe name, UTF-8 bytes, before its digest: file systems take 255 bytes a name, and
#: the output's own name, ``-2``, the extension and the temporary file's prefix come around it.
SAFE_NAME_BYTES = 100


def safe_name(name: str) -> str:
    """``name`` for a file name: runs of anything but letters, digits (of any script, NFC),
    ``.``, ``_``, ``-`` become ``_`` (no path separators, no leading dot); empty gives ``field``.
    A name longer than :data:`SAFE_NAME_BYTES` is cut there and ends with ``-`` and 8 hex
    digits of its SHA-1, so that two long names stay two files.

    >>> safe_name("Field 3/North: wheat")
    'Field_3_North_wheat'
    >>> safe_name("Feld Lärche ü")
    'Feld_Lärche_ü'
    >>> len(safe_name("N" * 300))
    109
    """
    text = re.sub(r"[^\w.-]+", "_", unicodedata.normalize("NFC", name)).strip("._")
    raw = text.encode("utf-8")
    if len(raw) > SAFE_NAME_BYTES:
        digest = hashlib.sha1(raw).hexdigest()[:8]
        text = raw[:SAFE_NAME_BYTES].decode("utf-8", errors="ignore").rstrip("._")
        text = f"{text}-{digest}"
    return text or "field"


def field_path(path: str, name: str, taken: set[str] | None = None) -> str:
    """``dir/mission.plan`` -> ``dir/mission-<safe name>.plan``; a path already in ``taken``
    gets ``-2``, ``-3``... appended to the name (and the result is added to ``taken``)."""
    root, ext = os.path.splitext(path)
    base = f"{root}-{safe_name(name)}"
    out, k = f"{base}{ext}", 1
    while taken is not None and out in taken:
        k += 1
        out = f"{base}-{k}{ext}"
    if taken is not None:
        taken.add(out)
    return out
