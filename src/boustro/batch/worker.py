"""Planning one field of a batch, where it runs (a worker process, a Dask worker, in-process).

:func:`plan_chunk` plans a list of features with :func:`boustro.mission.plan_area` (the one
implementation of planning, as ``boustro plan`` calls it: the area checked by GEOS first, or
repaired) and returns, per field, the rows of the three output layers ready to insert
(GeoPackage geometry blobs included, so that the writer only writes). Nothing escapes as an
exception: an empty, invalid or non-polygon geometry, a missing CRS, a bad per-field value or
any failure of planning becomes the field's ``error`` row with a one-line message. Warnings the
planner logs (e.g. the fallback to the hybrid optimiser) become the row's ``note``.

This module is imported once per worker process (its imports are the start-up cost).
"""

from __future__ import annotations

import functools
import logging
import math
import os
import threading
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._torch import set_threads
from ..errors import BoustroError, PolygonFileError
from ..io.area import Area, close_ring
from ..io.formats import FORMATS, render
from ..io.formats._fields import safe_name
from ..io.repair import check_area, detach_holes, repair_area
from ..mission import Mission, plan_area
from .gpkg import gpkg_geometry
from .options import PlanOptions
from .source import Feature

__all__ = ["FieldResult", "Job", "plan_chunk", "plan_feature", "start_worker"]

_captured = threading.local()


def _capture(record: logging.LogRecord) -> bool:
    """Logger filter: while a field is planned on this thread, its log lines become its note."""
    notes = getattr(_captured, "notes", None)
    if notes is None:
        return True
    notes.append(record.getMessage())
    return False


_LOG = logging.getLogger("boustro")
if _capture not in _LOG.filters:
    _LOG.addFilter(_capture)


@dataclass(frozen=True)
class Job:
    """What every field of a run shares: options, CRS, output SRS id, mission file format."""

    options: PlanOptions
    crs: str | None
    crs_missing: bool = False
    srs_id: int = -1
    mission_format: str | None = None


@dataclass
class FieldResult:
    """One field's outcome: ``rows`` per layer (``fields`` holds exactly one row) and the
    mission files to write (``(file name, data)``)."""

    field_id: int
    status: str
    rows: dict[str, list[tuple[Any, ...]]]
    files: list[tuple[str, str | bytes]] = field(default_factory=list)


def start_worker(parent: int | None = None) -> None:
    """Initialise a worker process: one torch thread (the processes are the parallelism),
    Ctrl-C left to the parent (which commits what is done and stops the pool), and, given the
    batch's process id ``parent``, an exit as soon as that process is gone (:func:`exit_with`)."""
    import signal

    set_threads(1)  # when torch is imported: a plan that needs it (most need none)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if parent is not None and os.name == "posix":  # os.kill(pid, 0) terminates on Windows
        threading.Thread(target=exit_with, args=(parent,), daemon=True).start()


def exit_with(parent: int, every: float = 1.0) -> None:
    """End this process when the process ``parent`` no longer exists (checked every ``every``
    seconds). A batch killed outright (SIGKILL, out of memory) cannot stop its pool, and the
    pool's workers would wait forever (each holds both ends of its task queue, so it never sees
    an end of file), holding their memory; the fork server waits for them."""
    while True:
        time.sleep(every)
        try:
            os.kill(parent, 0)
        except ProcessLookupError:
            os._exit(1)
        except PermissionError:  # alive, another user's: the id was reused, so ours is gone
            os._exit(1)


def plan_chunk(features: list[Feature], job: Job) -> list[FieldResult]:
    """:func:`plan_feature` of each feature, in order."""
    return [plan_feature(f, job) for f in features]


def _polygons(feature: Feature) -> tuple[Any, list[Any]]:
    """The feature's shapely geometry and its polygons; a one-line error for anything else."""
    import shapely

    if feature.wkb is None:
        raise PolygonFileError("no geometry (null)")
    try:
        geom = shapely.from_wkb(feature.wkb)
    except shapely.errors.GEOSException as exc:
        raise PolygonFileError(f"unreadable geometry: {exc}") from None
    if geom.is_empty:
        raise PolygonFileError(f"empty geometry ({geom.geom_type})")
    if geom.geom_type == "Polygon":
        return geom, [geom]
    if geom.geom_type == "MultiPolygon":
        return geom, [g for g in geom.geoms if not g.is_empty]
    raise PolygonFileError(f"not a polygon: a {geom.geom_type}")


def _area(poly: Any, feature: Feature, crs: str | None, part: int, parts: int) -> Area:
    name = feature.name if parts == 1 else f"{feature.name} part {part}"
    where = f"field {feature.field_id} ({name})"
    ring = close_ring(np.asarray(poly.exterior.coords, dtype=np.float64)[:, :2], where)
    holes = tuple(
        close_ring(np.asarray(h.coords, dtype=np.float64)[:, :2], f"{where}: hole {j}")
        for j, h in enumerate(poly.interiors, start=1)
    )
    return Area(ring, crs, name, where, holes)


@functools.lru_cache(maxsize=16)
def _plans_in_place(crs: str | None) -> bool:
    """Whether an area in ``crs`` is planned in its own coordinates (planar, or a projected
    CRS; a geographic one is planned in a UTM zone)."""
    import pyproj

    return crs is None or not pyproj.CRS.from_user_input(crs).is_geographic


def _plan_part(area: Area, options: PlanOptions) -> tuple[Mission, list[str]]:
    """One polygon planned as ``boustro plan`` plans it: checked by :func:`check_area` (or
    repaired), then :func:`plan_area`. An area planned in its own coordinates is checked by
    ``plan_area`` with the same rules on the same numbers, so :func:`check_area` runs only if
    planning fails, for its message (GEOS's reason, the hint to ``--repair``), which is then
    the field's error as it would have been had it run first."""
    notes: list[str] = []
    deferred = False
    if options.repair:
        area, note = repair_area(area)
        if note is not None:
            notes.append(note)
    area, note = detach_holes(area)  # a hole touching the shell at a point, as plan does
    if note is not None:
        notes.append(note)
    if not options.repair:
        if _plans_in_place(area.crs):
            deferred = True
        else:
            check_area(area)
    _captured.notes = notes
    try:
        mission = plan_area(area, options.spacing_arg(), **options.plan_kwargs())
    except Exception:
        if deferred:
            check_area(area)  # its error first, as when it runs before planning
        raise
    finally:
        _captured.notes = None
    return mission, notes


def _line(points: np.ndarray, srs_id: int) -> bytes | None:
    import shapely

    line = shapely.LineString(points)
    return gpkg_geometry(shapely.to_wkb(line), line.bounds, srs_id)


def _lanes(mission: Mission, srs_id: int) -> list[tuple[bytes | None, float, str]]:
    """``(geometry blob, ground length, pass)`` of each transect ``(a, b)`` of ``mission``
    (a lane, or an edge of a pass around a hole, the boundary or a headland pass:
    ``Plan.role``), made in one call (as :func:`_line` makes each). The length is on the
    ground, as the GeoJSON export's (``Plan.transect_lengths``), not in the output CRS's units
    (degrees for lon/lat)."""
    import shapely

    t = np.asarray(mission.transects, dtype=np.float64).reshape(-1, 2, 2)
    blobs = shapely.to_wkb(shapely.linestrings(t))
    lo, hi = t.min(axis=1), t.max(axis=1)
    lengths = mission.plan.transect_lengths().tolist()
    return [
        (gpkg_geometry(blob, (x0, y0, x1, y1), srs_id), length, role)
        for blob, (x0, y0), (x1, y1), length, role in zip(
            blobs, lo.tolist(), hi.tolist(), lengths, mission.plan.role(), strict=True
        )
    ]


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return text if isinstance(exc, BoustroError) else f"{type(exc).__name__}: {text}"


def plan_feature(feature: Feature, job: Job) -> FieldResult:
    """Plan one feature (each polygon of a multi-part one); never raises for bad input."""
    import shapely

    t0, c0 = time.perf_counter(), time.thread_time()
    geometry = None
    try:
        geom, polygons = _polygons(feature)
        geometry = gpkg_geometry(shapely.to_wkb(geom), geom.bounds, job.srs_id)
        if job.crs_missing:
            raise PolygonFileError(
                "the layer has no CRS: give it with --crs (EPSG:4326 for longitude/latitude, "
                "'planar' for plain x/y)"
            )
        options = job.options.for_field(feature.values)
        planned = []
        for k, poly in enumerate(polygons, start=1):
            area = _area(poly, feature, job.crs, k, len(polygons))
            planned.append(_plan_part(area, options))
    except Exception as exc:  # every failure is the field's error row, never the run's
        empty: list[Any] = [None] * 19
        row = (geometry, feature.field_id, feature.name, "error", _one_line(exc), *empty)
        return FieldResult(feature.field_id, "error", {"fields": [row]})
    seconds = (time.perf_counter() - t0, time.thread_time() - c0)
    return _result(feature, job, geometry, planned, seconds)


def _share(missions: list[Mission], covered: list[float], area: float) -> float | None:
    """The covered share of all parts: one part's own (exactly), else weighted by area."""
    if len(covered) != len(missions) or area <= 0:
        return None
    if len(missions) == 1:
        return missions[0].coverage.covered_share  # type: ignore[union-attr]
    return sum(covered) / area


def _result(
    feature: Feature,
    job: Job,
    geometry: bytes | None,
    planned: list[tuple[Mission, list[str]]],
    seconds: tuple[float, float],
) -> FieldResult:
    lanes, paths, files = [], [], []
    missions = [m for m, _ in planned]
    for part, mission in enumerate(missions, start=1):
        for k, (blob, length, role) in enumerate(_lanes(mission, job.srs_id), start=1):
            lanes.append((blob, feature.field_id, feature.name, part, k, length, role))
        paths.append((_line(mission.waypoints, job.srs_id), feature.field_id, feature.name,
                      part, mission.stats.path_length))  # fmt: skip
        if job.mission_format is not None:
            ext = FORMATS[job.mission_format][0][0]
            suffix = "" if len(missions) == 1 else f"-part{part}"
            name = f"{feature.field_id}-{safe_name(feature.name)}{suffix}{ext}"
            files.append((name, render(mission, job.mission_format)))
    stats = [m.stats for m in missions]
    durations = [s.duration for s in stats]
    covered = [m.coverage.covered_share * m.stats.area for m in missions if m.coverage]
    gaps = [m.optimum.gap for m in missions]
    certified = all(
        m.optimum.upper_bound is not None and bool(m.optimum.info.get("converged", False))
        for m in missions
    )
    area = sum(s.area for s in stats)
    first = missions[0]
    notes = "; ".join(n for _, ns in planned for n in ns) or None
    row = (
        geometry, feature.field_id, feature.name, "ok", None, len(missions),
        sum(s.n_transects for s in stats), len(lanes), sum(s.n_turns for s in stats),
        sum(s.transect_length for s in stats), sum(s.path_length for s in stats),
        None if None in durations else sum(d for d in durations if d is not None),
        _share(missions, covered, area),
        certified, None if None in gaps else max(g for g in gaps if g is not None),
        first.optimum.method, math.degrees(first.plan.angle), first.bearing, first.spacing,
        area, *seconds, ",".join(n for n, _ in files) or None, notes,
    )  # fmt: skip
    rows: dict[str, list[tuple[Any, ...]]] = {"lanes": lanes, "paths": paths, "fields": [row]}
    return FieldResult(feature.field_id, "ok", rows, files)
