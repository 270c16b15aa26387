"""Reading polygons from files (an edge of the system: the core never imports this module).

Supported inputs, taken as planar coordinates:

* a JSON list of ``[x, y]`` pairs (extra coordinates such as ``z`` are ignored);
* GeoJSON: a ``Polygon``, ``MultiPolygon`` (its first polygon), ``Feature``, or
  ``FeatureCollection`` (its first feature with a polygon geometry).
"""

from __future__ import annotations

import json
import os
from collections.abc import Sequence
from typing import Any

import numpy as np

from .errors import InvalidPolygonError, PolygonFileError
from .geometry import Polygon

__all__ = ["PAPER_PARALLELOGRAM", "PAPER_SPACING", "polygon_from_json", "read_polygon"]

#: The parallelogram of the paper's Figure 1, in the authors' units.
PAPER_PARALLELOGRAM: tuple[tuple[float, float], ...] = ((8, 4), (8, 10), (4, 8), (4, 2))
#: The transect spacing the authors' scripts use with it (0.0559 of the normalised frame).
PAPER_SPACING = 0.5


def _ring(coords: Any, where: str) -> np.ndarray:
    if not isinstance(coords, Sequence) or isinstance(coords, str) or len(coords) == 0:
        raise PolygonFileError(f"{where}: expected a list of [x, y] positions, got {coords!r:.80}")
    rows = []
    for i, pos in enumerate(coords):
        if (
            not isinstance(pos, Sequence)
            or isinstance(pos, str)
            or len(pos) < 2
            or not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in pos[:2])
        ):
            raise PolygonFileError(
                f"{where}: position {i} must be a list of at least two numbers, got {pos!r:.80}"
            )
        rows.append((float(pos[0]), float(pos[1])))
    return np.asarray(rows, dtype=np.float64)


def _from_geometry(geom: Any, where: str) -> Polygon:
    kind = geom.get("type")
    coords = geom.get("coordinates")
    if kind == "MultiPolygon":
        if not coords:
            raise PolygonFileError(f"{where}: empty MultiPolygon")
        coords, kind = coords[0], "Polygon"
    if kind != "Polygon":
        raise PolygonFileError(f"{where}: expected a Polygon geometry, got {kind!r}")
    if not isinstance(coords, list) or not coords:
        raise PolygonFileError(f"{where}: a Polygon needs at least one ring")
    if len(coords) > 1:
        raise PolygonFileError(
            f"{where}: the polygon has {len(coords) - 1} hole(s); holes are not supported yet"
        )
    try:
        return Polygon(_ring(coords[0], where))
    except InvalidPolygonError as exc:
        raise InvalidPolygonError(f"{where}: {exc}") from None


def polygon_from_json(data: Any, where: str = "input") -> Polygon:
    """A :class:`Polygon` from parsed JSON: a list of pairs or a GeoJSON object."""
    if isinstance(data, list):
        try:
            return Polygon(_ring(data, where))
        except InvalidPolygonError as exc:
            raise InvalidPolygonError(f"{where}: {exc}") from None
    if not isinstance(data, dict) or "type" not in data:
        raise PolygonFileError(
            f"{where}: expected a JSON list of [x, y] pairs or a GeoJSON object, "
            f"got {type(data).__name__}"
        )
    kind = data["type"]
    if kind == "FeatureCollection":
        for i, feature in enumerate(data.get("features") or []):
            geom = (feature or {}).get("geometry") or {}
            if geom.get("type") in ("Polygon", "MultiPolygon"):
                return _from_geometry(geom, f"{where}: feature {i}")
        raise PolygonFileError(f"{where}: the FeatureCollection holds no Polygon feature")
    if kind == "Feature":
        geom = data.get("geometry")
        if not isinstance(geom, dict):
            raise PolygonFileError(f"{where}: the Feature has no geometry")
        return _from_geometry(geom, where)
    return _from_geometry(data, where)


def read_polygon(path: str | os.PathLike[str]) -> Polygon:
    """Read a polygon from a JSON or GeoJSON file (see the module docstring).

    Raises:
        PolygonFileError: missing or unreadable file, malformed JSON, no polygon in it.
        InvalidPolygonError: the polygon itself is invalid (self-intersecting, zero area, ...).
    """
    name = os.fspath(path)
    try:
        with open(name, encoding="utf-8") as fh:
            text = fh.read()
    except FileNotFoundError:
        raise PolygonFileError(f"{name}: no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise PolygonFileError(f"{name}: cannot read: {exc}") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise PolygonFileError(
            f"{name}: malformed JSON at line {exc.lineno} column {exc.colno}: {exc.msg}"
        ) from None
    return polygon_from_json(data, name)
