"""``boustro plan`` over every field of a file: picking fields, planning each, naming outputs.

Every field is planned before anything is written. A field that fails does not stop the others
from being planned, but the run then writes nothing and exits with status 2, with one line naming
each failed field and its error (``--field`` plans the others one by one).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import TypeVar

from ..errors import BoustroError, InvalidParameterError
from ..io import Area
from ..io.area import field_label
from ..io.formats import render
from ..io.formats._fields import field_path, render_fields
from ..mission import Mission

__all__ = [
    "FieldsError",
    "mission_files",
    "output_files",
    "pick_fields",
    "plan_fields",
    "read_picked",
]

T = TypeVar("T")


class FieldsError(BoustroError, ValueError):
    """One or more fields of a file failed to plan (the message names each)."""


def pick_fields(areas: list[Area], field: str | None) -> list[Area]:
    """All ``areas``, or the one ``--field`` names: its name, else its index (from 1)."""
    if field is None:
        return areas
    named = [a for a in areas if a.name == field]
    if len(named) == 1:
        return named
    names = ", ".join(f"{i} {a.name!r}" for i, a in enumerate(areas, start=1))
    if len(named) > 1:
        raise InvalidParameterError(
            f"--field {field!r}: {len(named)} fields have that name; give its index ({names})"
        )
    try:
        index = int(field)
    except ValueError:
        index = 0
    if not 1 <= index <= len(areas):
        raise InvalidParameterError(
            f"--field {field!r}: no field of that name or index; the file's fields: {names}"
        )
    return [areas[index - 1]]


def read_picked(read: Callable[[], list[Area]], field: str | None) -> list[Area]:
    """``pick_fields(read(), field)``; with ``--field``, the warnings of reading the other
    fields (an open ring, a part left out: each names its field's place in the file, its
    ``source``) are not shown, only the picked field's and the file's own; a ``--field`` that
    names no field shows none of the fields' warnings before its error."""
    if field is None:
        return pick_fields(read(), field)
    with _held_log() as held:
        areas = read()
        picked: list[Area] = []
        try:
            picked = pick_fields(areas, field)
        finally:
            others = [a.source + ":" for a in areas if a.source and not any(a is p for p in picked)]
            held[:] = [r for r in held if not r.getMessage().startswith(tuple(others))]
    return picked


class _Hold(logging.Handler):
    """A handler that keeps its records."""

    def __init__(self) -> None:
        super().__init__()
        self.records: list[logging.LogRecord] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.records.append(record)


@contextmanager
def _held_log() -> Iterator[list[logging.LogRecord]]:
    """Hold the records of the ``boustro`` loggers (the caller may drop some from the list),
    and log the rest at the end, in order (all of them if the block raised)."""
    handler = _Hold()
    records = handler.records
    logger = logging.getLogger("boustro")
    propagate, logger.propagate = logger.propagate, False
    logger.addHandler(handler)
    try:
        yield records
    finally:
        logger.removeHandler(handler)
        logger.propagate = propagate
        for record in records:
            logging.getLogger(record.name).handle(record)


def plan_fields(areas: Sequence[Area], plan_one: Callable[[Area], T]) -> list[T]:
    """``plan_one`` of every area. A single area's error names the field if it has a name
    (``field 'North': farm.kml: polygon 2: ...``); with several, every area is tried and the
    failures become one :class:`FieldsError` naming each."""
    if len(areas) == 1:
        try:
            return [plan_one(areas[0])]
        except BoustroError as exc:
            label = field_label(areas[0], 1, 1)
            if not label:
                raise
            raise type(exc)(f"{label}: {exc}") from None
    done: list[T] = []
    failed: list[str] = []
    for i, area in enumerate(areas, start=1):
        try:
            done.append(plan_one(area))
        except BoustroError as exc:
            failed.append(f"{field_label(area, i, len(areas))}: {exc}")
    if failed:
        raise FieldsError(
            f"{len(failed)} of {len(areas)} fields failed, nothing written (--field NAME plans "
            "one): " + "; ".join(failed)
        )
    return done


def output_files(
    missions: Sequence[T],
    names: Sequence[str],
    path: str,
    one_file: Callable[[Sequence[T]], bytes | str | None],
    render_one: Callable[[T], bytes | str],
) -> list[tuple[str, bytes | str, int | None]]:
    """``(path, data, field index or None)`` of each file to write: one file for one field or
    where ``one_file`` holds them all (not None), else ``path-<name>.ext`` per field."""
    if len(missions) == 1:
        return [(path, render_one(missions[0]), None)]
    data = one_file(missions)
    if data is not None:
        return [(path, data, None)]
    taken: set[str] = set()
    return [
        (field_path(path, name, taken), render_one(m), i)
        for i, (m, name) in enumerate(zip(missions, names, strict=True))
    ]


def mission_files(
    missions: Sequence[Mission], path: str, fmt: str
) -> list[tuple[str, bytes | str, int | None]]:
    """The mission file(s) of ``missions`` in format ``fmt`` (see :func:`output_files`)."""
    return output_files(
        missions,
        [m.name for m in missions],
        path,
        lambda ms: render_fields(ms, fmt),
        lambda m: render(m, fmt),
    )
