"""numba's compilation of a module's loops, one mechanism for every compiled kernel.

A kernel module keeps its loops as plain Python functions and, on first use, swaps the helpers
its kernels call by module-level name for their compiled versions (numba resolves those names
when it compiles a caller), then compiles the kernels. :func:`jit_globals` does the swap under
one process-wide lock and never compiles a compiled function again, so two threads that reach a
module's first use at once (a ``functools.cache`` lets both in) get the same kernels.
:func:`jit` uses numba's disk cache where a cache location is writable, and compiles in every
process otherwise. numba is imported by the calls, never by ``import boustro``.
"""

from __future__ import annotations

import threading
from collections.abc import Iterable, MutableMapping
from typing import Any

__all__ = ["LOCK", "jit", "jit_cached", "jit_globals"]

#: Held while helpers are swapped (re-entrant: a module's first use may reach another's).
LOCK = threading.RLock()


def jit_cached(function: Any, **options: Any) -> tuple[Any, bool]:
    """``(compiled, on_disk)``: ``function`` (or a compiled function's Python original)
    compiled by ``numba.njit(**options)``, with the disk cache unless no cache location is
    writable (``on_disk`` False: it compiles in every process)."""
    import numba

    function = getattr(function, "py_func", function)
    try:
        return numba.njit(cache=True, **options)(function), True
    except RuntimeError:  # no writable cache location
        return numba.njit(**options)(function), False


def jit(function: Any, **options: Any) -> Any:
    """``function`` compiled (:func:`jit_cached`), whether or not the disk cache holds it."""
    return jit_cached(function, **options)[0]


def jit_globals(namespace: MutableMapping[str, Any], names: Iterable[str], **options: Any) -> bool:
    """Swap the functions ``names`` of ``namespace`` (a module's ``globals()``) for their
    compiled versions, under :data:`LOCK`, skipping those already compiled. Returns whether
    the disk cache holds every one compiled here."""
    on_disk = True
    with LOCK:
        for name in names:
            if not hasattr(namespace[name], "py_func"):
                namespace[name], cached = jit_cached(namespace[name], **options)
                on_disk = on_disk and cached
    return on_disk
