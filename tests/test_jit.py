"""boustro._jit: one thread-safe, idempotent compilation of a module's helpers for every kernel."""

from __future__ import annotations

import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from boustro import _jit
from boustro._jit import (
    _CHECKED,
    compiled,
    fresh_cache,
    jit,
    jit_cached,
    jit_globals,
    sources_digest,
)


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


def _kernel_module() -> dict:
    """The globals of a small kernel module: ``add_twice`` calls the helper ``twice`` by name."""
    ns: dict = {}
    exec("def twice(x):\n    return 2.0 * x\ndef add_twice(x):\n    return x + twice(x)\n", ns)
    return ns


def test_compiled_swaps_helpers_after_the_steps_before_and_compiles_the_kernels(monkeypatch):
    """A kernel module's ``_compiled()``: ``before`` called in order, then the helpers swapped,
    then the kernels compiled (one function for one name, a tuple for several); without numba
    the Python functions, nothing called or swapped."""
    calls: list[str] = []
    ns = _kernel_module()
    twice, add_twice = ns["twice"], ns["add_twice"]
    one = compiled(ns, "twice", (), [lambda: calls.append("a"), lambda: calls.append("b")])
    assert calls == ["a", "b"] and one.py_func is twice and one(2.0) == 4.0
    assert ns["twice"] is twice  # not a helper here: left as it is
    swapped = [lambda: calls.append(f"swapped {hasattr(ns['twice'], 'py_func')}")]
    both = compiled(ns, ("add_twice", "twice"), ("twice",), swapped)
    assert calls[-1] == "swapped False"  # the steps before come before the helpers' swap
    assert isinstance(both, tuple) and [f.py_func for f in both] == [add_twice, twice]
    assert ns["twice"].py_func is twice and both[0](1.0) == 3.0
    monkeypatch.setattr(_jit, "find_spec", lambda name: None)
    plain = _kernel_module()
    got = compiled(plain, ("add_twice",), ("twice",), [lambda: calls.append("c")])
    assert got == (plain["add_twice"],) and compiled(plain, "twice") is plain["twice"]
    assert not hasattr(plain["twice"], "py_func") and calls == ["a", "b", "swapped False"]


def test_every_kernel_module_compiles_through_the_one_helper():
    """The kernel modules' ``_compiled()`` (and order_kernel's ``_compiled_lanes``) return what
    ``compiled`` gives: numba functions of their Python kernels."""
    from boustro.optimize.cover import bands, ends, one_tree, piece_ends
    from boustro.optimize.smith_bb import kernel, region_kernel
    from boustro.plan import edge_grid, order_kernel, straight_moves, tour_exact, visibility_kernel

    table = {
        bands._compiled: ("_all",),
        ends._compiled: ("_ends",),
        one_tree._compiled: ("_bounds",),
        piece_ends._compiled: ("_charges",),
        kernel._compiled: ("_bounds", "_values"),
        region_kernel._compiled: ("_bounds", "_values"),
        edge_grid._compiled: ("_grid_crossings", "_grid_near"),
        order_kernel._compiled: ("_two_opt",),
        order_kernel._compiled_lanes: ("_lane_search", "_kick"),
        straight_moves._compiled: ("_edge_tests",),
        tour_exact._compiled: ("_held_karp",),
        visibility_kernel._compiled: ("_crossings", "_near"),
    }
    for get, names in table.items():
        got = get()
        got = got if isinstance(got, tuple) else (got,)
        home = sys.modules[get.__module__]
        assert [f.py_func for f in got] == [getattr(home, n) for n in names], get.__module__


def test_first_use_from_several_threads_at_once():
    ns = {"_twice": _twice}
    with ThreadPoolExecutor(4) as pool:
        list(pool.map(lambda _: jit_globals(ns, ("_twice",)), range(8)))
    assert ns["_twice"].py_func is _twice and ns["_twice"](2.0) == 4.0


def test_a_cache_folder_of_other_sources_loses_its_kernels_once(tmp_path):
    stale = tmp_path / "stale"
    stale.mkdir()
    for name in ("kernel._search-40.py311.nbi", "kernel._search-40.py311.1.nbc", "x.pyc"):
        (stale / name).write_bytes(b"old")
    (stale / "boustro-sources-0123456789abcdef.stamp").touch()
    fresh_cache(stale)
    stamp = f"boustro-sources-{sources_digest()}.stamp"
    assert sorted(p.name for p in stale.iterdir()) == sorted([stamp, "x.pyc"])
    # a folder already stamped with these sources keeps what numba wrote there
    (stale / "kernel._search-40.py311.nbi").write_bytes(b"new")
    _CHECKED.discard(stale)
    fresh_cache(stale)
    assert (stale / "kernel._search-40.py311.nbi").read_bytes() == b"new"


def test_a_missing_cache_folder_is_made_and_stamped_so_the_next_process_keeps_it(tmp_path):
    """Where Python writes no ``__pycache__`` (``PYTHONDONTWRITEBYTECODE``) the folder is
    missing at first use: unstamped, the next process dropped every kernel compiled there."""
    folder = tmp_path / "pkg" / "__pycache__"
    fresh_cache(folder)
    stamp = f"boustro-sources-{sources_digest()}.stamp"
    assert [p.name for p in folder.iterdir()] == [stamp]
    (folder / "kernel._search-40.py311.nbi").write_bytes(b"compiled")  # numba saves
    _CHECKED.discard(folder)  # the next process
    fresh_cache(folder)
    assert (folder / "kernel._search-40.py311.nbi").read_bytes() == b"compiled"


def test_compiling_with_the_disk_cache_checks_its_folder():
    compiled, on_disk = jit_cached(_twice)
    if on_disk:  # the tests' folder is writable here; elsewhere numba compiles in memory
        assert Path(compiled._cache.cache_path) in _CHECKED
        assert any(Path(compiled._cache.cache_path).glob("boustro-sources-*.stamp"))
    assert compiled(2.5) == 5.0


def test_numba_disabled_runs_the_python_functions():
    code = (
        "from boustro._jit import jit_cached\n"
        "def twice(x):\n    return 2.0 * x\n"
        "f, on_disk = jit_cached(twice)\n"
        "print(f is twice, on_disk, f(2.0))\n"
    )
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1"}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["True", "False", "4.0"]
