"""The registry of mission formats: name -> (file extensions, renderer), and writing a mission."""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np

from ..._files import atomic_write
from ..._registry import Registry
from ...errors import InvalidParameterError

if TYPE_CHECKING:
    from ...mission import Mission

__all__ = [
    "FORMATS",
    "Renderer",
    "check_finite",
    "format_for",
    "register_format",
    "render",
    "write_mission",
]

#: A renderer: the text of a mission in one format, or its bytes for a binary format.
Renderer = Callable[["Mission"], "str | bytes"]
R = TypeVar("R", bound=Callable[..., "str | bytes"])

#: name -> (file extensions, renderer). Each module of :mod:`boustro.io.formats` registers its
#: format with :func:`register_format`; the package imports them all (:meth:`Registry.discover`).
FORMATS: Registry[tuple[tuple[str, ...], Renderer]] = Registry(
    "format", package="boustro.io.formats"
)


def register_format(name: str, extensions: tuple[str, ...] | list[str] = ()) -> Callable[[R], R]:
    """Decorator: register the renderer it wraps as format ``name`` for files ``extensions``.

    Extensions are lower case with their dot (``".kml"``); the first format registered for an
    extension is the one :func:`format_for` picks for it. The renderer is returned unchanged.

    >>> @register_format("names", extensions=(".names",))
    ... def to_names(mission):
    ...     return mission.name or ""
    >>> format_for("mission.NAMES"), FORMATS.pop("names")[0]
    ('names', ('.names',))
    """
    exts = tuple(str(e).lower() for e in extensions)
    bad = [e for e in exts if not e.startswith(".") or len(e) < 2]
    if bad:
        raise InvalidParameterError(f"format {name!r}: extensions start with a dot, got {bad}")

    def add(renderer: R) -> R:
        old = FORMATS.get(name)
        # The same function again (its module imported anew, e.g. reloaded) replaces itself.
        same = old is not None and _qualified(old[1]) == _qualified(renderer)
        FORMATS.register(name, (exts, renderer), replace=same)
        return renderer

    return add


def _qualified(fn: Callable[..., object]) -> tuple[str, str]:
    return getattr(fn, "__module__", ""), getattr(fn, "__qualname__", repr(fn))


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


def _first_non_finite(value: Any, path: str) -> str | None:
    """The path of the first number in ``value`` that is not finite (inf, nan), else None."""
    if isinstance(value, dict):
        items: Any = ((f"{path}.{k}", v) for k, v in value.items())
    elif isinstance(value, (list, tuple)):
        items = ((f"{path}[{i}]", v) for i, v in enumerate(value))
    elif isinstance(value, np.ndarray):
        bad: Any = np.argwhere(~np.isfinite(value)) if value.dtype.kind in "fc" else []
        return f"{path}[{', '.join(str(int(i)) for i in bad[0])}]" if len(bad) else None
    elif isinstance(value, (float, np.floating)):
        return None if math.isfinite(value) else path
    else:
        return None
    for where, item in items:
        found = _first_non_finite(item, where)
        if found is not None:
            return found
    return None


def check_finite(mission: Mission, fmt: str = "the mission") -> None:
    """Refuse a mission holding a number that is not finite, before anything is rendered.

    Checks the summary every format may carry and every coordinate array (area, holes, cells,
    transects, waypoints, home; source and longitude/latitude).

    Raises:
        InvalidParameterError: one line naming the first such number.
    """
    fields = (
        "waypoints transects waypoints_lonlat transects_lonlat area_lonlat home home_lonlat "
        "holes_lonlat"
    ).split()
    values: dict[str, Any] = {name: getattr(mission, name) for name in fields}
    values.update(
        ring=mission.area.ring,
        holes=mission.area.holes,
        plan_transects=mission.plan.transects,
        summary=mission.summary(),
    )
    if len(mission.plan.cells) > 1:
        values["cells"] = mission.cell_rings()
    found = _first_non_finite(values, "mission")
    if found is not None:
        raise InvalidParameterError(
            f"cannot write {fmt}: {found} is not a finite number (inf or nan); nothing written"
        )


def render(mission: Mission, fmt: str) -> str | bytes:
    """The text (or bytes) of ``mission`` in format ``fmt`` (a key of :data:`FORMATS`), after
    :func:`check_finite` (every number in every export is finite, or nothing is rendered).

    Example:
        >>> from boustro.io import embedded_field
        >>> from boustro.mission import plan_area
        >>> sorted(FORMATS)
        ['csv', 'geojson', 'gpx', 'kml', 'plan', 'wpl']
        >>> render(plan_area(embedded_field(), 10.0), "csv").splitlines()[0]
        'seq,kind,transect,lon,lat'
    """
    name = format_for("", fmt)
    check_finite(mission, name)
    return FORMATS[name][1](mission)


def write_mission(mission: Mission, path: str | os.PathLike[str], fmt: str | None = None) -> str:
    """Render ``mission`` (format from ``fmt`` or the extension) and write it atomically.

    Returns the format name. Nothing is written if rendering fails.
    """
    name = format_for(path, fmt)
    text = render(mission, name)
    atomic_write(path, text)
    return name
