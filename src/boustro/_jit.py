"""numba's compilation of a module's loops, one mechanism for every compiled kernel.

A kernel module keeps its loops as plain Python functions and, on first use, swaps the helpers
its kernels call by module-level name for their compiled versions (numba resolves those names
when it compiles a caller), then compiles the kernels. :func:`jit_globals` does the swap under
one process-wide lock and never compiles a compiled function again, so two threads that reach a
module's first use at once (a ``functools.cache`` lets both in) get the same kernels.
:func:`jit` uses numba's disk cache where a cache location is writable, and compiles in every
process otherwise. numba is imported by the calls, never by ``import boustro``. A kernel module's
cached ``_compiled()`` is :func:`compiled`: its kernels compiled, or its Python functions
where numba is not installed.

numba keys a cached function to its own source file only: a kernel whose helpers live in
another file would keep its old machine code after the helpers change (an upgrade, a checkout).
So each cache folder carries a stamp of the package's sources (:func:`fresh_cache`): a folder
whose stamp differs loses its cached kernels, once, and they are compiled again.
"""

from __future__ import annotations

import hashlib
import threading
from collections.abc import Callable, Iterable, MutableMapping
from functools import cache
from importlib.util import find_spec
from pathlib import Path
from typing import Any

__all__ = [
    "LOCK",
    "compiled",
    "fresh_cache",
    "jit",
    "jit_cached",
    "jit_globals",
    "sources_digest",
]

#: Held while helpers are swapped (re-entrant: a module's first use may reach another's).
LOCK = threading.RLock()
#: Cache folders checked by :func:`fresh_cache` in this process.
_CHECKED: set[Path] = set()


@cache
def sources_digest() -> str:
    """A digest of every Python source of the package (names and contents)."""
    root = Path(__file__).parent
    digest = hashlib.blake2b(digest_size=8)
    for path in sorted(root.rglob("*.py")):
        digest.update(path.relative_to(root).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def fresh_cache(folder: str | Path) -> None:
    """Make numba's cache ``folder`` hold only kernels compiled from the package's present
    sources: unless it carries this digest's stamp, its cached kernels (``*.nbi``, ``*.nbc``)
    and old stamps are removed and the stamp written. A missing folder is made and stamped
    (left unstamped but checked, as when the first-use check looked at it before numba made
    it, the next process would drop what this one compiles: a fresh installation compiled
    twice where Python writes no ``__pycache__``, e.g. under ``PYTHONDONTWRITEBYTECODE``).
    Once per folder and process; a folder that cannot be made or changed is left as it is."""
    folder = Path(folder)
    with LOCK:
        if folder in _CHECKED:
            return
        _CHECKED.add(folder)
        stamp = folder / f"boustro-sources-{sources_digest()}.stamp"
        if stamp.exists():
            return
        try:
            folder.mkdir(parents=True, exist_ok=True)
            for old in [*folder.glob("*.nb[ic]"), *folder.glob("boustro-sources-*.stamp")]:
                old.unlink(missing_ok=True)
            stamp.touch()
        except OSError:  # pragma: no cover - a folder numba writes but we may not change
            return


def jit_cached(function: Any, **options: Any) -> tuple[Any, bool]:
    """``(compiled, on_disk)``: ``function`` (or a compiled function's Python original)
    compiled by ``numba.njit(**options)``, with the disk cache unless no cache location is
    writable (``on_disk`` False: it compiles in every process)."""
    import numba

    function = getattr(function, "py_func", function)
    try:
        compiled = numba.njit(cache=True, **options)(function)
    except RuntimeError:  # no writable cache location
        return numba.njit(**options)(function), False
    cache = getattr(compiled, "_cache", None)  # None under NUMBA_DISABLE_JIT (a plain function)
    if cache is None:
        return compiled, False
    fresh_cache(cache.cache_path)  # before the first call loads from it
    return compiled, True


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


def compiled(
    namespace: MutableMapping[str, Any],
    kernels: str | tuple[str, ...],
    helpers: Iterable[str] = (),
    before: Iterable[Callable[[], Any]] = (),
) -> Any:
    """A kernel module's ``_compiled()`` (which caches it): its functions ``kernels`` (names in
    ``namespace``, the module's ``globals()``) compiled by :func:`jit`, after each of
    ``before`` is called (other modules' helpers swapped where these kernels look them up) and
    ``helpers`` are swapped (:func:`jit_globals`); the plain Python functions where numba is not
    installed. One function for one name, else a tuple in the order of ``kernels``."""
    names = (kernels,) if isinstance(kernels, str) else tuple(kernels)
    if find_spec("numba") is None:  # pragma: no cover - numba is a dependency
        out = tuple(namespace[name] for name in names)
    else:
        for step in before:
            step()
        jit_globals(namespace, helpers)
        out = tuple(jit(namespace[name]) for name in names)
    return out[0] if isinstance(kernels, str) else out
