"""The limits of the web API: request size, vertices, fields, estimated work, and strict JSON.

A request is refused before any work when it is too large (:data:`MAX_BODY_BYTES`), holds too
many vertices or fields, or when the estimate before planning
(:func:`boustro.mission.estimate_work`) says it would take longer than :data:`MAX_SECONDS`.
JSON is parsed strictly: ``NaN`` and ``Infinity``, which Python's ``json`` accepts by default,
are refused.
"""

from __future__ import annotations

import json
import re
from typing import Any

from ..errors import InvalidParameterError

__all__ = [
    "EPSG",
    "MAX_BODY_BYTES",
    "MAX_FIELDS",
    "MAX_SECONDS",
    "MAX_VERTICES",
    "RequestTooLargeError",
    "check_epsg",
    "count_vertices",
    "parse_strict_json",
]

#: The largest request body, bytes (an uploaded area file or a JSON request).
MAX_BODY_BYTES = 5 * 1024 * 1024
#: The most vertices (rings and holes of every field) one request may hold.
MAX_VERTICES = 20_000
#: The most fields (polygons) one request may hold.
MAX_FIELDS = 20
#: The longest estimated planning time accepted for one request, seconds (the estimate before
#: planning, :mod:`boustro.mission.estimate`; the command line accepts up to 600 s).
MAX_SECONDS = 60.0
#: A CRS as the API accepts it: an EPSG code, ``EPSG:n`` (any letter case) or ``n``.
EPSG = re.compile(r"^(?:EPSG:)?([0-9]{1,6})$", re.IGNORECASE)


class RequestTooLargeError(InvalidParameterError):
    """A request over one of the limits of this module (HTTP 413)."""


def _no_constant(name: str) -> Any:
    raise InvalidParameterError(f"{name} is not a number JSON allows (non-finite value)")


def parse_strict_json(data: bytes | str, where: str = "request") -> Any:
    """``json.loads`` that refuses ``NaN`` and ``Infinity``; every error one line."""
    if len(data) > MAX_BODY_BYTES:
        raise RequestTooLargeError(
            f"{where}: {len(data)} bytes, over the limit of {MAX_BODY_BYTES} bytes"
        )
    try:
        text = data.decode("utf-8") if isinstance(data, bytes) else data
        return json.loads(text, parse_constant=_no_constant)
    except UnicodeDecodeError:
        raise InvalidParameterError(f"{where}: not UTF-8 text") from None
    except json.JSONDecodeError as exc:
        raise InvalidParameterError(
            f"{where}: malformed JSON at line {exc.lineno} column {exc.colno}: {exc.msg}"
        ) from None
    except RecursionError:
        raise InvalidParameterError(f"{where}: JSON nested too deeply to read") from None


def check_epsg(value: Any, what: str = "crs") -> str:
    """``"EPSG:n"`` from ``"EPSG:n"``, ``"n"`` or ``n``; anything else (a PROJ string, a WKT,
    a file name) is refused: the server accepts coordinate systems only as EPSG codes."""
    text = str(value).strip() if isinstance(value, (str, int)) else ""
    match = EPSG.match(text) if not isinstance(value, bool) else None
    if match is None:
        raise InvalidParameterError(
            f"{what} must be an EPSG code such as 'EPSG:4326' or 'EPSG:28992', got {value!r:.80}"
        )
    return f"EPSG:{int(match.group(1))}"


def count_vertices(rings: list[Any]) -> int:
    """The vertices of ``rings`` (arrays of points), checked against :data:`MAX_VERTICES`."""
    total = sum(len(r) for r in rings)
    if total > MAX_VERTICES:
        raise RequestTooLargeError(
            f"the area has {total} vertices, over the limit of {MAX_VERTICES} per request"
        )
    return total
