"""``boustro.batch``: plan every feature of a vector file and write the plans as they finish.

The output (:mod:`boustro.batch.gpkg`) is a GeoPackage with the layers ``lanes``, ``paths`` and
``fields``; finished fields are committed together, a few times a second, so a crash or Ctrl-C
loses at most the fields being planned, and running the same call again plans only the fields
that have no row yet (resume). Any other output format (by extension: ``.fgb``, ``.shp``,
``.geojson``, ...) is written from a hidden GeoPackage beside it (the resume state), as one file
per layer, ``STEM.lanes.EXT``, ``STEM.paths.EXT``, ``STEM.fields.EXT``, each written to a
temporary file and renamed when the run ends (or is interrupted).

"""

from __future__ import annotations

import contextlib
import os
import sys
import time
from collections.abc import Generator, Iterator
from dataclasses import dataclass
from typing import Any

from .._files import atomic_write_all
from ..errors import InvalidParameterError, MissingDependencyError
from ..io.formats import FORMATS
from .executors import Outcome, run_dask, run_inline, run_local
from .export import export_layers, layer_paths
from .frames import source_from_frame
from .gpkg import Store
from .options import PlanOptions
from .source import Feature, Source, read_source
from .worker import FieldResult, Job

__all__ = ["BatchResult", "batch", "store_path"]

#: Seconds between commits of finished fields.
COMMIT_SECONDS = 0.5


@dataclass(frozen=True)
class BatchResult:
    """What a run did. ``planned`` and ``failed`` count this run's fields, ``skipped`` those
    found done in the output (resume); ``fields_per_second`` is this run's rate.
    ``outputs`` are the files written (the GeoPackage, or one file per layer)."""

    out: str
    outputs: tuple[str, ...]
    total: int
    planned: int
    failed: int
    skipped: int
    seconds: float

    @property
    def fields_per_second(self) -> float:
        done = self.planned + self.failed
        return done / self.seconds if self.seconds > 0 else float("nan")


def store_path(out: str) -> str:
    """The GeoPackage a run appends to: ``out`` itself, or a hidden file beside it."""
    if out.lower().endswith(".gpkg"):
        return out
    folder, name = os.path.split(os.path.abspath(out))
    return os.path.join(folder, f".{name}.boustro.gpkg")


def _chunks(features: list[Feature], size: int) -> Iterator[list[Feature]]:
    for i in range(0, len(features), size):
        yield features[i : i + size]


def _lost(chunk: list[Feature], exc: BaseException, job: Job) -> list[FieldResult]:
    """Error rows for the fields of a chunk that its worker lost."""
    text = " ".join(f"{type(exc).__name__}: {exc}".split())
    empty: list[Any] = [None] * 19
    return [
        FieldResult(f.field_id, "error", {"fields": [(None, f.field_id, f.name, "error",
                    f"the worker planning it failed: {text}", *empty)]})
        for f in chunk
    ]  # fmt: skip


def _check_missions(missions: str | None, mission_format: str | None) -> str | None:
    if missions is None:
        if mission_format is not None:
            raise InvalidParameterError("--mission-format needs --missions FOLDER")
        return None
    fmt = mission_format or "geojson"
    if fmt not in FORMATS:
        raise InvalidParameterError(
            f"--mission-format {fmt!r}: expected one of {', '.join(FORMATS)}"
        )
    if os.path.exists(missions) and not os.path.isdir(missions):
        raise InvalidParameterError(f"--missions {missions}: a file, not a folder")
    try:  # a missing folder is made, its parents too
        os.makedirs(missions, exist_ok=True)
    except OSError as exc:
        raise InvalidParameterError(f"--missions {missions}: cannot make it: {exc}") from None
    return fmt


class _Writer:
    """Finished fields, committed to the store every :data:`COMMIT_SECONDS`."""

    def __init__(self, store: Store, missions: str | None, bar: Any) -> None:
        self.store, self.missions, self.bar = store, missions, bar
        self.pending: dict[str, list[tuple[Any, ...]]] = {}
        self.count = 0
        self.last = time.monotonic()
        self.planned = self.failed = 0

    def add(self, results: list[FieldResult]) -> None:
        for r in results:
            # a field's files (one per sortie), all or none, before the row that names them
            atomic_write_all((os.path.join(self.missions or ".", p), d) for p, d in r.files)
            for name, rows in r.rows.items():
                self.pending.setdefault(name, []).extend(rows)
            self.planned += r.status == "ok"
            self.failed += r.status != "ok"
        self.count += len(results)
        if time.monotonic() - self.last >= COMMIT_SECONDS:
            self.commit()

    def commit(self) -> None:
        if self.pending:
            self.store.append(self.pending)
            self.pending = {}
        self.bar.update(self.count)
        self.bar.set_postfix(errors=self.failed, refresh=False)
        self.count = 0
        self.last = time.monotonic()


def batch(
    fields: str | os.PathLike[str] | Source | Any,
    out: str | os.PathLike[str],
    options: PlanOptions | None = None,
    *,
    layer: str | None = None,
    crs: str | None = None,
    workers: int | None = None,
    client: Any = None,
    scheduler: str | None = None,
    missions: str | os.PathLike[str] | None = None,
    mission_format: str | None = None,
    chunk_size: int = 8,
    progress: bool | None = False,
    **plan_options: Any,
) -> BatchResult:
    """Plan every feature of ``fields`` and write the plans to ``out``; see the module.

    Args:
        fields: a vector file GDAL reads (every feature of ``layer``, needed when the file
            has several layers with geometries, is a field), a GeoDataFrame, or a :class:`Source`.
        out: the output: a ``.gpkg`` (layers ``lanes``, ``paths``, ``fields``), or a file name
            in another vector format (one file per layer). An existing output is resumed: its
            fields are skipped; one made with other options is refused.
        options: the options of every field (:class:`PlanOptions`); or give them as keywords
            (``spacing=10``, ``objective="fewest-transects"``, ``columns={"spacing": "sp"}``).
        crs: the CRS of the input's coordinates, overriding the file's (``"planar"``).
        workers: local processes (default: the CPU count; 1 plans in this process).
        client: a ``dask.distributed.Client`` to run on instead; ``scheduler``: its address.
        missions: a folder for one mission file per field, in ``mission_format`` (default
            ``geojson``; any ``boustro plan --format``), named ``ID-NAME.EXT``; made (its
            parents too) if missing, refused if it is a file.
        chunk_size: fields sent to a worker at a time.
        progress: a progress bar on stderr with fields/s (``None``: if stderr is a terminal).

    Returns:
        a :class:`BatchResult`. A field that fails is an ``error`` row, never an exception.

    Raises:
        BoustroError: the input cannot be read, bad options, an output of other options.
    """
    if options is None:
        options = PlanOptions(**plan_options)
    elif plan_options:
        raise InvalidParameterError("give options= or option keywords, not both")
    options.check()  # e.g. no spacing at all: one error, not one per field
    fmt = _check_missions(None if missions is None else os.fspath(missions), mission_format)
    out = os.fspath(out)
    source = _source(fields, layer, crs, options)
    settings = {"options": options.settings(), "crs": source.crs, "missions": fmt}
    targets = layer_paths(out)  # an unknown format: refused before any work
    _check_counts(workers, chunk_size)  # and these, and the scheduler, before the output is made
    with contextlib.ExitStack() as stack:
        if client is None and scheduler is not None:
            client = stack.enter_context(_connect(scheduler))
        return _run(source, out, targets, settings, options, fmt, missions, workers, client,
                    chunk_size, progress)  # fmt: skip


def _run(
    source: Source, out: str, targets: dict[str, str], settings: dict[str, Any],
    options: PlanOptions, fmt: str | None, missions: str | os.PathLike[str] | None,
    workers: int | None, client: Any, chunk_size: int, progress: bool | None,
) -> BatchResult:  # fmt: skip
    """:func:`batch` once its inputs are checked (and a scheduler connected)."""
    t0 = time.perf_counter()
    label = out if not targets else f"{out} (its state {store_path(out)})"
    store = Store(store_path(out), source.crs, settings, label)
    try:
        done = store.done()
        todo = [f for f in source.features if f.field_id not in done]
        job = Job(options, source.crs, source.crs_missing, store.srs_id, fmt)
        writer = _Writer(store, None if missions is None else os.fspath(missions),
                         _bar(len(todo), progress))  # fmt: skip
        outcomes = _outcomes(todo, job, workers, client, chunk_size)
        try:
            for chunk, outcome in outcomes:
                writer.add(_lost(chunk, outcome, job) if isinstance(outcome, BaseException)
                           else outcome)  # fmt: skip
        finally:
            outcomes.close()  # the pool stopped now (Ctrl-C: the running chunks end first)
            writer.commit()
            writer.bar.close()
    finally:
        store.close()
        if targets:
            export_layers(store.path, targets)
    return BatchResult(
        out, tuple(targets.values()) if targets else (out,), len(source.features),
        writer.planned, writer.failed, len(source.features) - len(todo),
        time.perf_counter() - t0,
    )  # fmt: skip


def _source(fields: Any, layer: str | None, crs: str | None, options: PlanOptions) -> Source:
    if isinstance(fields, Source):
        return fields
    if isinstance(fields, (str, os.PathLike)):
        return read_source(fields, layer=layer, crs=crs, columns=list(options.columns.values()))
    return source_from_frame(fields, crs=crs, columns=list(options.columns.values()))


def _check_counts(workers: int | None, chunk_size: int) -> None:
    if chunk_size < 1:
        raise InvalidParameterError(f"chunk_size must be >= 1, got {chunk_size!r}")
    if workers is not None and workers < 1:
        raise InvalidParameterError(f"workers must be >= 1, got {workers!r}")


def _outcomes(
    todo: list[Feature], job: Job, workers: int | None, client: Any, chunk_size: int
) -> Generator[Outcome, None, None]:
    if client is not None:
        yield from run_dask(_chunks(todo, chunk_size), job, client)
        return
    count = (os.cpu_count() or 1) if workers is None else workers
    if count == 1 or len(todo) <= 1:
        yield from run_inline(_chunks(todo, chunk_size), job)
    else:  # chunks small enough that every worker gets several (few fields: no idle worker)
        size = max(1, min(chunk_size, len(todo) // (4 * count)))
        yield from run_local(_chunks(todo, size), job, count)


def _connect(scheduler: str) -> Any:
    """A ``dask.distributed.Client`` of ``scheduler`` (a context manager that closes it)."""
    try:
        from distributed import Client
    except ImportError:
        raise MissingDependencyError(
            "--scheduler needs dask.distributed: pip install 'boustro[dask]'"
        ) from None
    try:
        return Client(scheduler, timeout=30)
    except OSError as exc:
        raise InvalidParameterError(f"--scheduler {scheduler}: cannot connect: {exc}") from None


def _bar(total: int, progress: bool | None) -> Any:
    from tqdm.auto import tqdm

    show = sys.stderr.isatty() if progress is None else bool(progress)
    return tqdm(total=total, unit="field", disable=not show, file=sys.stderr, smoothing=0.1)
