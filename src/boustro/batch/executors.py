"""Where the chunks of a batch run: in this process, on local worker processes, or on Dask.

Each runner takes an iterator of chunks (lists of features) and yields ``(chunk, results)`` as
chunks finish, in completion order, keeping a bounded number in flight (memory stays flat on a
million fields). A chunk that fails as a whole (a worker process killed, a Dask worker lost)
yields ``(chunk, exc)``; the caller turns it into error rows, so nothing is lost. The local pool
forks its processes from a fork server that imported :mod:`boustro.batch.worker` once (no
torch state of the caller is forked; ``spawn`` where there is no fork server). As with any
``multiprocessing`` code, a script that calls :func:`boustro.batch` with several workers needs
the ``if __name__ == "__main__":`` guard (its main module is imported in the workers).
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Any

from .._torch import threads
from ..errors import MissingDependencyError
from .source import Feature
from .worker import FieldResult, Job, plan_chunk, start_worker

__all__ = ["Outcome", "run_dask", "run_inline", "run_local"]

#: A finished chunk: its features and their results, or the exception that lost them all.
Outcome = tuple[list[Feature], "list[FieldResult] | BaseException"]


def run_inline(chunks: Iterable[list[Feature]], job: Job) -> Iterator[Outcome]:
    """Every chunk in this process, in order, on one torch thread as a worker process (small
    fields plan several times faster so on a loaded machine; restored afterwards)."""
    with threads(1):  # torch is imported by the plans that need it only
        for chunk in chunks:
            yield chunk, plan_chunk(chunk, job)


def _bounded(
    submit: Any, chunks: Iterable[list[Feature]], in_flight: int, done_of: Any
) -> Iterator[tuple[list[Feature], Any]]:
    """Submit chunks keeping ``in_flight`` running; yield each ``(chunk, future)`` when done."""
    pending: dict[Any, list[Feature]] = {}
    source = iter(chunks)
    for chunk in source:
        pending[submit(chunk)] = chunk
        if len(pending) >= in_flight:
            break
    while pending:
        for future in done_of(list(pending)):
            chunk = pending.pop(future)
            nxt = next(source, None)
            if nxt is not None:
                pending[submit(nxt)] = nxt
            yield chunk, future


def _first_done(futures: list[Future]) -> set[Future]:
    return wait(futures, return_when=FIRST_COMPLETED)[0]


def _context() -> Any:
    """Worker processes forked from a fork server that imported this module once (each worker
    starts in milliseconds, with nothing of this process's torch state), else spawned."""
    if "forkserver" not in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("spawn")
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload([__name__, "shapely", "pyproj"])  # imported on use else
    return context


def _pool(workers: int, context: Any) -> ProcessPoolExecutor:
    """A pool whose workers end when this process does, even killed outright."""
    return ProcessPoolExecutor(
        workers, mp_context=context, initializer=start_worker, initargs=(os.getpid(),)
    )


def run_local(
    chunks: Iterable[list[Feature]], job: Job, workers: int, rounds: int = 3
) -> Iterator[Outcome]:
    """The chunks on ``workers`` local processes. A chunk whose process died (killed, out of
    memory) is retried one field at a time on a new pool, the last of ``rounds`` one field at
    a time, so that only a field that kills its worker itself is lost: it is yielded with the
    exception."""
    context = _context()
    in_flight = 2 * workers if rounds > 1 else 1
    retry: list[list[Feature]] = []
    pools = [_pool(workers, context)]

    def submit(chunk: list[Feature]) -> Future:
        try:
            return pools[-1].submit(plan_chunk, chunk, job)
        except BrokenProcessPool:  # a worker died: a new pool for the chunks still to come
            pools[-1].shutdown(wait=False, cancel_futures=True)
            pools.append(_pool(workers, context))
            return pools[-1].submit(plan_chunk, chunk, job)

    try:
        for chunk, future in _bounded(submit, chunks, in_flight, _first_done):
            exc = future.exception()
            if exc is None:
                yield chunk, future.result()
            elif rounds > 1:
                retry += [[f] for f in chunk]
            else:
                yield chunk, exc
    finally:
        for pool in pools:
            pool.shutdown(wait=True, cancel_futures=True)
    if retry:
        yield from run_local(retry, job, workers, rounds - 1)


def run_dask(chunks: Iterable[list[Feature]], job: Job, client: Any) -> Iterator[Outcome]:
    """The chunks on a ``dask.distributed.Client`` (its workers import boustro once each)."""
    try:
        from distributed import as_completed
    except ImportError:
        raise MissingDependencyError(
            "a Dask cluster needs dask.distributed: pip install 'boustro[dask]'"
        ) from None
    threads = max(1, sum(client.nthreads().values()))

    def done_of(futures: list[Any]) -> list[Any]:
        return [next(as_completed(futures))]

    for chunk, future in _bounded(
        lambda c: client.submit(plan_chunk, c, job, pure=False),
        chunks,
        2 * threads,
        done_of,
    ):
        try:
            yield chunk, future.result()
        except Exception as exc:  # a lost worker (KilledWorker), a failed deserialisation
            yield chunk, exc
        future.release()
