"""The ``options`` of a web request, checked and turned into :func:`boustro.mission.plan_area`'s
arguments: the same choices as ``boustro plan``'s options, under the same names (snake case).

Every value is checked here, once: unknown keys, wrong types and out-of-range numbers are one
:class:`~boustro.errors.InvalidParameterError` line naming the option. A number must be a JSON
number: a numeric string (``"spacing": "10"``) is refused, as ``boustro plan`` refuses a
non-number, so a client's mistake is never planned on a guess.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from .. import objectives
from ..errors import InvalidParameterError, as_number
from ..mission import DEFAULT_HULL_TOLERANCE
from ..mission.options import check_turn_time
from ..plan import check_headland
from ..sensors import Camera, Swath
from ..vehicle import Vehicle
from .limits import check_epsg

__all__ = ["OPTIONS", "PlanOptions", "parse_options", "web_objectives"]

#: Every option the API takes, with what it is (the page's form and the README list the same).
OPTIONS: dict[str, str] = {
    "spacing": "transect spacing, metres (or a camera, or a swath)",
    "camera": "[sensor width mm, focal length mm, image width px], with altitude or gsd",
    "gsd": "camera ground sample distance, cm/px",
    "swath": "swath sensor width, metres",
    "overlap": "side overlap, percent (camera default 70, swath 0)",
    "nadir_gap": "swath sensor's blind strip under the vehicle, metres",
    "objective": "time (the default with a speed), smith (the default without), or "
    "fewest-transects",
    "method": "optimiser (default: global)",
    "angle": "fixed transect angle, degrees counter-clockwise from east in the plan frame",
    "bearing": "fixed transect direction, degrees clockwise from north",
    "start": "[x, y] start point in the area's coordinates (lon, lat)",
    "turnaround": "run-in / run-out beyond each transect end, metres",
    "speed": "ground speed, m/s",
    "turn_time": "seconds per turn",
    "keep_inside": "true: no part of the path leaves the area or enters a hole (boundary passes)",
    "turn_radius": "the vehicle's turn radius, metres (its turns driven as Dubins paths)",
    "reverse": "with turn_radius: the vehicle may reverse (Reeds-Shepp turns)",
    "headland": "headland passes around the boundary and every hole (a whole number, default 0)",
    "altitude": "mission altitude above take-off, metres (needed by .plan and .waypoints)",
    "layout": "guaranteed (default) or chords",
    "hull_tolerance": "plan a nearly convex area on its hull within this many metres",
    "decompose": "true, false or null (default: when it saves turns)",
    "sweep": "sweep direction of the decomposition, degrees",
    "crs": "the area's CRS as an EPSG code (default EPSG:4326, longitude/latitude)",
    "field": "plan only this field: its name, or its index from 1",
    "repair": "make an invalid area valid (shapely.make_valid) instead of refusing it",
}


def web_objectives() -> dict[str, Any]:
    """The objectives offered, by kebab-case name: the registry's, as ``boustro plan`` offers
    them (objectives scored on the chords' ends, ``needs_chords``, are not)."""
    return {
        name.replace("_", "-"): factory
        for name, factory in objectives.OBJECTIVES.items()
        if not getattr(factory, "needs_chords", False)
    }


@dataclass
class PlanOptions:
    """Checked options: the spacing (a number or a sensor), ``plan_area``'s keyword arguments,
    the area's CRS (``None``: the area's ``crs`` member, else WGS 84 longitude/latitude), the
    field asked for and whether to repair."""

    spacing: Any
    kwargs: dict[str, Any] = field(default_factory=dict)
    crs: str | None = None
    field: str | None = None
    repair: bool = False


def _json_number(key: str, value: Any) -> float:
    """``value`` as a float if it is a JSON number; a string (``"10"``), a flag or anything else
    is refused, as the command line refuses a non-number."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InvalidParameterError(f"options.{key} must be a number, got {value!r:.40}")
    return as_number(f"options.{key}", value)


def _number(options: dict[str, Any], key: str, low: float | None = None, strict: bool = False):
    value = options.get(key)
    if value is None:
        return None
    x = _json_number(key, value)
    if not math.isfinite(x):
        raise InvalidParameterError(f"options.{key} must be finite, got {value!r}")
    if low is not None and (x < low or (strict and x == low)):
        sign = ">" if strict else ">="
        raise InvalidParameterError(f"options.{key} must be {sign} {low:g}, got {value!r}")
    return x


def _numbers(options: dict[str, Any], key: str, count: int) -> list[float] | None:
    value = options.get(key)
    if value is None:
        return None
    if not isinstance(value, (list, tuple)) or len(value) != count:
        raise InvalidParameterError(f"options.{key} must be a list of {count} numbers")
    out = [_json_number(key, v) for v in value]
    if not all(math.isfinite(v) for v in out):
        raise InvalidParameterError(f"options.{key} must be finite numbers, got {value!r}")
    return out


def _choice(options: dict[str, Any], key: str, choices: tuple[str, ...], default: str) -> str:
    value = options.get(key)
    if value is None:
        return default
    if value not in choices:
        raise InvalidParameterError(
            f"options.{key} must be one of {', '.join(choices)}, got {value!r:.40}"
        )
    return str(value)


def _spacing(options: dict[str, Any]) -> Any:
    """A number, a :class:`Camera` or a :class:`Swath`, as ``boustro plan`` builds them."""
    given = [k for k in ("spacing", "camera", "swath") if options.get(k) is not None]
    if len(given) != 1:
        raise InvalidParameterError(
            "give exactly one of options.spacing (metres), options.camera or options.swath"
            + (f", got {', '.join(given)}" if given else "")
        )
    overlap = _number(options, "overlap", 0.0)
    if overlap is not None and overlap >= 100:
        raise InvalidParameterError(f"options.overlap must be below 100 (percent), got {overlap}")
    if given[0] == "camera":
        sw, f, px = _numbers(options, "camera", 3) or (0.0, 0.0, 0.0)
        pixels: Any = px  # checked by Camera.spacing (> 0), as the command line passes it
        gsd = _number(options, "gsd", 0.0, strict=True)
        altitude = _number(options, "altitude")
        if gsd is not None and altitude is not None:
            raise InvalidParameterError("give the camera's altitude or its gsd, not both")
        side = (70.0 if overlap is None else overlap) / 100
        return Camera(sw, f, pixels, altitude=altitude, gsd=gsd, side_overlap=side)
    if options.get("gsd") is not None:
        raise InvalidParameterError("options.gsd needs options.camera")
    gap = _number(options, "nadir_gap", 0.0) or 0.0
    if given[0] == "swath":
        width = _number(options, "swath", 0.0, strict=True)
        return Swath(float(width or 0.0), (overlap or 0.0) / 100, gap)
    if gap or overlap is not None:
        raise InvalidParameterError("options.overlap and options.nadir_gap need a camera or swath")
    return _number(options, "spacing", 0.0, strict=True)


def _flag(options: dict[str, Any], key: str) -> bool | None:
    value = options.get(key)
    if value is not None and not isinstance(value, bool):
        raise InvalidParameterError(f"options.{key} must be true, false or null, got {value!r}")
    return value


def _headland(options: dict[str, Any]) -> int:
    value = options.get("headland")
    if value is not None:
        _json_number("headland", value)  # a JSON number; check_headland wants a whole one
    try:
        return check_headland(0 if value is None else value)
    except InvalidParameterError as exc:
        raise InvalidParameterError(f"options.{exc}") from None


def _vehicle(options: dict[str, Any]) -> Vehicle | None:
    """The vehicle of ``turn_radius`` and ``reverse`` (``None`` without a radius)."""
    radius = _number(options, "turn_radius", 0.0, strict=True)
    reverse = bool(_flag(options, "reverse"))
    if radius is None:
        if reverse:
            raise InvalidParameterError("options.reverse needs options.turn_radius")
        return None
    return Vehicle(turn_radius=radius, reverse=reverse)


def parse_options(options: Any) -> PlanOptions:
    """Check ``options`` (a JSON object) and build :class:`PlanOptions`."""
    if options is None:
        options = {}
    if not isinstance(options, dict):
        raise InvalidParameterError("options must be a JSON object")
    unknown = sorted(set(options) - set(OPTIONS))
    if unknown:
        raise InvalidParameterError(
            f"unknown option(s) {', '.join(map(repr, unknown))}; expected {', '.join(OPTIONS)}"
        )
    if isinstance(options.get("objective"), str):  # the snake spelling too (fewest_transects)
        options = {**options, "objective": options["objective"].replace("_", "-")}
    objective = _choice(options, "objective", tuple(sorted(web_objectives())), "")
    method = options.get("method")
    if method is not None and not isinstance(method, str):
        raise InvalidParameterError(f"options.method must be a name, got {method!r}")
    angle = _number(options, "angle")
    start = _numbers(options, "start", 2)
    decompose = _flag(options, "decompose")
    hull = _number(options, "hull_tolerance", 0.0)
    kwargs: dict[str, Any] = dict(
        method=method or None,
        fitness=web_objectives()[objective]() if objective else None,  # plan_area's default
        start=None if start is None else tuple(start),
        turnaround=_number(options, "turnaround", 0.0) or 0.0,
        speed=_number(options, "speed", 0.0, strict=True),
        turn_time=_number(options, "turn_time", 0.0) or 0.0,
        altitude=_number(options, "altitude"),
        hull_tolerance=DEFAULT_HULL_TOLERANCE if hull is None else hull,
        layout=_choice(options, "layout", ("guaranteed", "chords"), "guaranteed"),
        decompose=decompose,
        sweep=_number(options, "sweep"),
        angle=None if angle is None else math.radians(angle),
        bearing=_number(options, "bearing"),
        keep_inside=bool(_flag(options, "keep_inside")),
        vehicle=_vehicle(options),
        headland=_headland(options),
    )
    check_turn_time(kwargs["speed"], kwargs["turn_time"], lambda name: f"options.{name}")
    crs = check_epsg(options["crs"], "options.crs") if options.get("crs") is not None else None
    picked = options.get("field")
    if picked is not None and (isinstance(picked, bool) or not isinstance(picked, (str, int))):
        raise InvalidParameterError(f"options.field must be a name or an index, got {picked!r}")
    return PlanOptions(
        spacing=_spacing(options),
        kwargs=kwargs,
        crs=crs,
        field=None if picked is None else str(picked),
        repair=bool(_flag(options, "repair")),
    )
