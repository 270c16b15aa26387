"""boustro._jit: one thread-safe, idempotent compilation of a module's helpers for every kernel."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

from boustro._jit import jit, jit_globals


def _twice(x: float) -> float:
    return 2.0 * x


def test_helpers_are_swapped_once_and_kernels_compile_against_them():
    ns = {"_twice": _twice}
    assert jit_globals(ns, ("_twice",)) in (True, False)
    first = ns["_twice"]
    assert first.py_func is _twice and first(3.0) == 6.0
    jit_globals(ns, ("_twice",))
    assert ns["_twice"] is first  # not compiled again over the compiled one
    again = jit(first)  # a compiled function is compiled from its Python original
    assert again.py_func is _twice and again(1.5) == 3.0


def test_first_use_from_several_threads_at_once():
    ns = {"_twice": _twice}
    with ThreadPoolExecutor(4) as pool:
        list(pool.map(lambda _: jit_globals(ns, ("_twice",)), range(8)))
    assert ns["_twice"].py_func is _twice and ns["_twice"](2.0) == 4.0
