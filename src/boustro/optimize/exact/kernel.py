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

import os
from functools import cache
from typing import Any, NamedTuple

import numpy as np

from ...models import grid_size
from . import kernel_bounds, kernel_exact, kernel_pieces
from .kernel_bounds import _kink_one, _runs_one, _second_one
from .kernel_exact import _exact_pairs
from .kernel_pieces import (
    _LAM,
    _NMO,
    _TOTAL,
    _VALUE,
    _argmax,
    _nmax,
    _nmin,
    _pieces_one,
    _quick_one,
    _structure_one,
    _weighted_row,
)
from .structure import BOUND_SLACK, Array

__all__ = ["Compiled", "compiled", "evaluate_smith_compiled", "exact_smith_compiled"]


def _evaluate(
    v: np.ndarray,
    s: float,
    lo: np.ndarray,
    hi: np.ndarray,
    a: float,
    b: float,
    threshold: float,
    batch: int,
    g: np.ndarray,
    d: np.ndarray,
    ub: np.ndarray,
    order: np.ndarray,
) -> None:
    """:func:`.bounds._evaluate_smith` as loops; writes ``g, d, ub, order``."""
    n = v.shape[0]
    n_j = n - 1
    h, t, x, tu, td = np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    pc = np.empty((n, 5))
    fam = np.empty((n, 2), dtype=np.int64)
    rn = np.empty((n, n_j, 8))
    mo = np.empty((n, _NMO))
    cc = np.empty((n, n_j, 4))
    drift, curv = np.empty((n, n_j)), np.empty((n, n_j))
    d0, d1 = np.empty((2, n, n_j)), np.empty(n_j)
    pb, f1s, f2s = np.empty(n), np.empty(n), np.empty(n)
    bound = np.empty(len(lo))
    for start in range(0, len(lo), batch):
        stop = min(start + batch, len(lo))
        gmax = -np.inf
        for m in range(start, stop):
            mid = 0.5 * (lo[m] + hi[m])
            half = 0.5 * (hi[m] - lo[m])
            _structure_one(v, s, mid, h, t, x, tu, td, pc, fam, rn)
            _pieces_one(rn, a, b, mo, cc)
            ip = _argmax(mo[:, _VALUE])
            g[m] = mo[ip, _VALUE]
            d[m] = pc[ip, 0] + mo[ip, _LAM] * pc[ip, 1]
            gmax = g[m] if m == start else _nmax(gmax, g[m])
            bound[m] = _quick_one(x, tu, td, rn, mo, half, a, b)
            order[m] = 1.0
        thr = gmax if gmax > threshold else threshold  # Python's max(threshold, gmax)
        for m in range(start, stop):
            if bound[m] + BOUND_SLACK > thr:
                mid = 0.5 * (lo[m] + hi[m])
                half = 0.5 * (hi[m] - lo[m])
                _structure_one(v, s, mid, h, t, x, tu, td, pc, fam, rn)
                _pieces_one(rn, a, b, mo, cc)
                _runs_one(v, s, mid, half, h, x, tu, td, pc, fam, rn, drift, curv, d0, d1)
                for p in range(n):
                    total = mo[p, _TOTAL]
                    f1 = _weighted_row(rn[p, :, 0], drift[p], total, a, b)
                    second = _second_one(p, rn, mo, cc, curv, d0, d1, half, a, b)
                    kink = _kink_one(p, rn, mo, cc, curv, d0, d1, half, a, b)
                    f2 = _nmin(second, kink)
                    excess = _nmax(_nmin(f1, f2), 0.0)
                    pb[p] = mo[p, _VALUE] + excess if total > 0 else -np.inf
                    f1s[p], f2s[p] = f1, f2
                top = _argmax(pb)
                bound[m] = pb[top]
                order[m] = 2.0 if f2s[top] < f1s[top] else 1.0
            ub[m] = bound[m] + BOUND_SLACK


_HELPERS = {
    kernel_pieces: "_nmax _nmin _clip01 _sign _argmax _sum_sq_row _weighted_row _angular_growth",
    kernel_bounds: "_mu_ratio _parallel_one",
    kernel_exact: "_pair_value",
}
_STAGES = {
    kernel_pieces: "_structure_one _pieces_one _quick_one",
    kernel_bounds: "_runs_one _linearised_one _second_one _kink_one",
}


class Compiled(NamedTuple):
    """The compiled kernels (numba dispatchers of the functions named)."""

    evaluate: Any  # _evaluate
    exact_pairs: Any  # .kernel_exact._exact_pairs


@cache
def compiled() -> Compiled | None:
    """The compiled kernels, or ``None`` where numba is missing or ``BOUSTRO_COMPILED=0``.
    The first call of each in a process loads it from numba's on-disk cache (or compiles it,
    some seconds, once per machine where the cache is writable)."""
    if os.environ.get("BOUSTRO_COMPILED", "1").strip() in ("0", "false", "no", "off"):
        return None
    try:
        import numba
    except ImportError:  # pragma: no cover - numba is a dependency
        return None

    def jit(function: Any) -> Any:
        function = getattr(function, "py_func", function)  # idempotent
        options: dict[str, Any] = {"nogil": True, "error_model": "numpy"}
        try:
            return numba.njit(cache=True, **options)(function)
        except RuntimeError:  # no writable cache location: compile per process
            return numba.njit(**options)(function)

    # Helpers first: the functions call them by their module-level names, which from here on
    # are compiled functions (numba resolves those names when it compiles a caller).
    here = globals()
    for table in (_HELPERS, _STAGES):
        for module, names in table.items():
            for name in names.split():
                fn = jit(getattr(module, name))
                setattr(module, name, fn)
                for other in (kernel_pieces, kernel_bounds, kernel_exact):
                    if name in vars(other):
                        setattr(other, name, fn)
                if name in here:
                    here[name] = fn
    return Compiled(jit(_evaluate), jit(_exact_pairs))


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
    halfplanes: tuple[Array, Array, float],
    s: float,
    thetas: Array,
    offsets: Array,
    a: float,
    b: float,
) -> Array | None:
    """Eq. 1 by the exact model of every pair ``(thetas[i], offsets[i])`` (``-inf`` where no
    transect counts), as :func:`boustro.optimize.evaluate_grid` scores it; ``halfplanes`` is
    ``(normals, offsets, radius)`` in the frame of ``s``. ``None`` without the compiled kernel.
    """
    kernels = compiled()
    if kernels is None:
        return None
    normals, boffs, radius = halfplanes
    k_count, m = grid_size(s, radius)
    thetas = np.ascontiguousarray(thetas, dtype=np.float64)
    out = np.empty(len(thetas))
    kernels.exact_pairs(
        np.ascontiguousarray(normals, dtype=np.float64),
        np.ascontiguousarray(boffs, dtype=np.float64),
        float(radius),
        float(s),
        k_count,
        m,
        thetas,
        np.ascontiguousarray(offsets, dtype=np.float64),
        float(a),
        float(b),
        out,
    )
    return out
