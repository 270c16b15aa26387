"""The compiled evaluation of angle intervals for the certified optimum of Eq. 1 (numba).

:func:`evaluate_smith_compiled` computes what :func:`.bounds._evaluate_smith` computes (the
exact best value and offset at every interval's centre, an upper bound over the interval, the
order of the bound) in one call into compiled code per branch-and-bound round: the per-angle
loops of :mod:`.kernel_pieces` and :mod:`.kernel_bounds`, no numpy temporaries. Why both stay:
the numpy code is the readable reference of the formulas and the path without numba
(``BOUSTRO_COMPILED=0``); tests/test_exact_kernel.py checks that they agree on seeded random
polygons. numba is imported on first use (``import boustro`` does not load it).
"""

from __future__ import annotations

import logging
import os
from functools import cache
from importlib.util import find_spec
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..._jit import LOCK, jit_cached, jit_globals
from ...models import MAX_CANDIDATES, grid_size
from . import (
    kernel_bounds,
    kernel_check,
    kernel_events,
    kernel_exact,
    kernel_pieces,
    kernel_search,
)
from .kernel_check import _finish
from .kernel_events import _event_terms
from .kernel_exact import _exact_grid
from .kernel_search import _pieces_at, _search
from .structure import Array

__all__ = [
    "Compiled",
    "compiled",
    "evaluate_smith_compiled",
    "exact_smith_compiled",
    "finish_smith_compiled",
    "first_compile",
    "pieces_compiled",
    "search_smith_compiled",
    "use_compiled",
]


_HELPERS = {
    kernel_pieces: (
        "_nmax _nmin _clip01 _sign _argmax _order_desc _argsort_into _weighted_row _angular_growth "
        "_chords_through_vertices _piece_max _structure_scratch"
    ),
    kernel_bounds: "_mu_ratio _parallel_edge _parallel_one _ends_one",
    kernel_exact: "_angle_setup _layout_value _halfplanes_into _top_pieces _check_into",
    kernel_check: "_chains_at _screen_angle _screened_check",
    kernel_events: "_event_merge",
    kernel_search: "_max_into _second_bound",
}
_STAGES = {
    kernel_pieces: "_structure_one _pieces_one _quick_one",
    kernel_bounds: "_chains_one _runs_piece _linearised_one _second_one _kink_one",
    kernel_search: "_evaluate",
}


class Compiled(NamedTuple):
    """The compiled kernels (numba dispatchers of the functions named)."""

    evaluate: Any  # .kernel_search._evaluate
    exact_grid: Any  # .kernel_exact._exact_grid
    search: Any  # .kernel_search._search
    pieces_at: Any  # .kernel_search._pieces_at
    finish: Any  # .kernel_check._finish
    event_terms: Any  # .kernel_events._event_terms
    cached: bool  # numba's on-disk cache holds them (else they compile in every process)


def _mode() -> str:
    """``BOUSTRO_COMPILED``: ``"off"`` (0, false, no, off), ``"on"`` (1, true, yes, on) or
    ``"auto"`` (unset or anything else)."""
    value = os.environ.get("BOUSTRO_COMPILED", "").strip().lower()
    if value in ("0", "false", "no", "off"):
        return "off"
    return "on" if value in ("1", "true", "yes", "on") else "auto"


def use_compiled() -> bool:
    """Whether the exact optimiser runs its compiled kernels: never with
    ``BOUSTRO_COMPILED=0`` or without numba; by default where numba's on-disk cache works (else
    every process would compile them again, 10-25 s); with ``BOUSTRO_COMPILED=1`` even there.

    The choice depends on the installation only, never on what the process did before: the two
    paths agree to rounding, not bit for bit, and a batch's outputs must not depend on which
    worker planned a field.
    """
    mode = _mode()
    if mode == "off":
        return False
    kernels = compiled()
    return kernels is not None and (kernels.cached or mode == "on")


log = logging.getLogger("boustro")


def first_compile() -> bool:
    """Whether the search kernel is missing from numba's on-disk cache (the folder numba
    itself would use: the package's ``__pycache__``, or under ``NUMBA_CACHE_DIR``): this
    installation's first use, which compiles the kernels (once, up to about a minute of CPU).
    ``False`` where no cache location is writable (then every process compiles). Makes a
    dispatcher of the kernel (imports numba), compiles nothing."""
    dispatcher, on_disk = jit_cached(kernel_search._search)  # also drops stale kernels first
    if not on_disk:
        return False
    folder = Path(dispatcher._cache.cache_path)
    return not any(folder.glob("kernel_search._search-*.nbi"))


@cache
def compiled() -> Compiled | None:
    """The compiled kernels, or ``None`` where numba is missing or ``BOUSTRO_COMPILED=0``.
    The first call of each in a process loads it from numba's on-disk cache (or compiles it,
    some seconds, once per machine where the cache is writable)."""
    if _mode() == "off":
        return None
    if find_spec("numba") is None:  # pragma: no cover - numba is a dependency
        return None
    if first_compile():
        log.info("compiling the certified optimiser for this installation (once, up to a minute)")
    options: dict[str, Any] = {"nogil": True, "error_model": "numpy"}
    # Helpers first: the functions call them by their module-level names, which from here on
    # are compiled functions (numba resolves those names when it compiles a caller); a helper
    # imported by name into another kernel module is swapped there too.
    homes = (kernel_pieces, kernel_bounds, kernel_check, kernel_events, kernel_exact, kernel_search)
    with LOCK:
        for table in (_HELPERS, _STAGES):
            for module, names in table.items():
                for name in names.split():
                    jit_globals(vars(module), (name,), **options)
                    fn = getattr(module, name)
                    for other in homes:
                        if name in vars(other):
                            setattr(other, name, fn)
                    if name in globals():
                        globals()[name] = fn
    (grid, c1), (search, c2), (pieces, c3), (finish, c4), (terms, c5) = (
        jit_cached(f, **options) for f in (_exact_grid, _search, _pieces_at, _finish, _event_terms)
    )
    on_disk = c1 and c2 and c3 and c4 and c5  # the same folder as the helpers
    return Compiled(kernel_search._evaluate, grid, search, pieces, finish, terms, on_disk)


def evaluate_smith_compiled(
    v: Array, s: float, lo: Array, hi: Array, a: float, b: float, threshold: float, batch: int
) -> tuple[Array, Array, Array, Array] | None:
    """``(value, offset, upper_bound, order)`` of every interval, as
    :func:`.bounds._evaluate_smith`; ``None`` without the compiled kernel."""
    kernels = compiled()
    if kernels is None:
        return None
    m = len(lo)
    g, d, ub, order = np.empty(m), np.empty(m), np.empty(m), np.empty(m)
    kernels.evaluate(
        np.ascontiguousarray(v, dtype=np.float64),
        float(s),
        np.ascontiguousarray(lo, dtype=np.float64),
        np.ascontiguousarray(hi, dtype=np.float64),
        float(a),
        float(b),
        float(threshold),
        int(batch),
        g,
        d,
        ub,
        order,
    )
    return g, d, ub, order


def exact_smith_compiled(
    v: Array,
    halfplanes: tuple[Array, Array, float],
    s: float,
    thetas: Array,
    offsets: Array,
    a: float,
    b: float,
    pairs: bool = True,
) -> Array | None:
    """Eq. 1 by the exact model (``-inf`` where no transect counts), as
    :func:`boustro.optimize.evaluate_grid` scores it, of every pair ``(thetas[i], offsets[i])``
    (``pairs``) or of the grid ``thetas x offsets`` ``(A, O)``, for the convex polygon of
    vertices ``v`` whose half-planes are ``(normals, offsets, radius)``, all in the frame of
    ``s``. ``None`` without the compiled kernel.
    """
    kernels = compiled()
    if kernels is None:
        return None
    normals, boffs, radius = halfplanes
    k_count, m = grid_size(s, radius)
    thetas = np.ascontiguousarray(thetas, dtype=np.float64)
    offsets = np.ascontiguousarray(offsets, dtype=np.float64)
    out = np.empty(len(thetas) if pairs else (len(thetas), len(offsets)))
    kernels.exact_grid(
        np.ascontiguousarray(normals, dtype=np.float64),
        np.ascontiguousarray(boffs, dtype=np.float64),
        np.ascontiguousarray(v, dtype=np.float64),
        float(radius),
        float(s),
        k_count,
        m,
        thetas,
        offsets,
        bool(pairs),
        float(a),
        float(b),
        out.reshape(-1),
    )
    return out


def search_smith_compiled(
    v: Array,
    s: float,
    a: float,
    b: float,
    tol: float,
    max_evaluations: int,
    batch: int,
    min_width: float,
    max_children: int,
) -> Array | None:
    """The whole branch and bound (:func:`.search._branch_and_bound` of
    :func:`.bounds._evaluate_smith` over :func:`.structure.event_angles`) in one compiled
    call, the event angles' loops compiled (:mod:`.kernel_events`: the same angles, bit for
    bit): ``(theta, lo, hi, offset, value, upper_bound, evaluations, rounds, converged,
    intervals between events)``; ``None`` without the compiled kernel."""
    kernels = compiled()
    if kernels is None:
        return None
    v = np.ascontiguousarray(v, dtype=np.float64)
    dx, dy, pair, ratio = kernels.event_terms(v, float(s))
    # numpy's own arc tangents and arc cosines: the numbers of structure.event_angles
    alpha, acos = np.arctan2(-dx, dy), np.arccos(ratio)
    out = np.empty(10)
    kernels.search(
        v,
        float(s),
        alpha,
        pair,
        acos,
        float(a),
        float(b),
        float(tol),
        int(max_evaluations),
        int(batch),
        float(min_width),
        int(max_children),
        out,
    )
    return out


def pieces_compiled(v: Array, s: float, thetas: Array, a: float, b: float) -> Array | None:
    """Every piece's ``(beta, width, value, lam)`` at each angle ``(M, P, 4)``, as
    ``_structure`` and ``_smith_pieces`` give them; ``None`` without the compiled kernel."""
    kernels = compiled()
    if kernels is None:
        return None
    thetas = np.ascontiguousarray(thetas, dtype=np.float64)
    out = np.empty((len(thetas), len(v), 4))
    kernels.pieces_at(np.ascontiguousarray(v, dtype=np.float64), float(s), thetas, a, b, out)
    return out


def finish_smith_compiled(
    v: Array,
    s: float,
    thetas: Array,
    a: float,
    b: float,
    check_angles: Array,
    check_offsets: Array,
    tops: NDArray[np.int64] | None = None,
    check: bool = True,
) -> Array | None:
    """The certified optimiser's work after its search in one compiled call
    (:func:`.kernel_check._finish`): ``(fitness, angle, offset, check angle, check offset,
    check fitness)`` of the best layout near the closed-form optimum at ``thetas`` and of the
    spot check, normalised frame, as :func:`.smith._attained` and :func:`.smith._spot_check`
    give them, then a flag: 0 done, 1 the caller must compute them (too many lines for the
    exact model), 2 it must give the candidate pieces ``tops (3, 4)`` (count and pieces at
    each angle, in numpy's order): without them the kernel finds them, unless two pieces'
    values tie; ``check=False``: without the spot check (``out[3:6]`` undefined). ``None``
    without the compiled kernel."""
    kernels = compiled()
    if kernels is None:
        return None
    if tops is None:
        tops = np.full((len(thetas), 4), -1, dtype=np.int64)
    out = np.empty(7)
    kernels.finish(
        np.ascontiguousarray(v, dtype=np.float64),
        float(s),
        np.ascontiguousarray(thetas, dtype=np.float64),
        float(a),
        float(b),
        float(MAX_CANDIDATES),
        np.ascontiguousarray(check_angles, dtype=np.float64),
        np.ascontiguousarray(check_offsets, dtype=np.float64),
        np.ascontiguousarray(tops, dtype=np.int64),
        bool(check),
        out,
    )
    return out
