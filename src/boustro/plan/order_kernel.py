"""The 2-opt improvement of a tour's order, compiled by numba on first use.

Each evaluated order is costed by the same dynamic programme as
:func:`boustro.plan.tour._order` (the driving option of every pass chosen for the least total),
with the same floating-point operations in the same order, so the compiled loop returns the
order the Python loop would; it only removes the interpreter's overhead (a few microseconds
per pass per evaluated order, seconds for the :data:`~boustro.plan.tour.ORDER_BUDGET` orders of
a large field). numba is imported on use; without it the plain Python functions run.
"""

from __future__ import annotations

import math
from functools import cache
from importlib.util import find_spec
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._jit import jit, jit_globals

__all__ = ["improve_order"]


def _cost(order, start, dist, entry, exit_, internal, n_opt):
    """The least cost of driving the passes in ``order`` (options free)."""
    first = order[0]
    width = entry.shape[1]
    acc = np.full(width, np.inf)
    for a in range(n_opt[first]):
        acc[a] = start[first, a]
    for s in range(1, order.shape[0]):
        prev, cur = order[s - 1], order[s]
        new = np.full(width, np.inf)
        for b in range(n_opt[cur]):
            low = np.inf
            for a in range(n_opt[prev]):
                v = dist[exit_[prev, a], entry[cur, b]] + acc[a]
                if v < low:
                    low = v
            new[b] = low + internal[cur, b]
        acc = new
    low = np.inf
    for a in range(n_opt[order[-1]]):
        if acc[a] < low:
            low = acc[a]
    return low


def _two_opt(order, best, budget, fixed, start, dist, entry, exit_, internal, n_opt):
    n = order.shape[0]
    left = budget
    improved = n > 2
    while improved and left > 0:
        improved = False
        for i in range(fixed, n - 1):
            for j in range(i + 1, n):
                cand = order.copy()
                cand[i : j + 1] = order[i : j + 1][::-1]
                c = _cost(cand, start, dist, entry, exit_, internal, n_opt)
                left -= 1
                if c < best - 1e-9:
                    order, best, improved = cand, c, True
                if left <= 0:
                    break
            if left <= 0:
                break
    return order


@cache
def _compiled() -> Any:
    if find_spec("numba") is None:  # pragma: no cover - numba is a dependency
        return _two_opt
    jit_globals(globals(), ("_cost",))
    return jit(_two_opt)


def improve_order(
    order: list[int],
    best: float,
    budget: int,
    fixed: int,
    start: list[NDArray[np.float64]],
    dist: NDArray[np.float64],
    entry: list[NDArray[np.int64]],
    exit_: list[NDArray[np.int64]],
    internal: list[NDArray[np.float64]],
) -> list[int]:
    """The order after 2-opt (at most ``budget`` orders evaluated; the first ``fixed`` passes
    stay), from ``order`` of cost ``best``. Per pass: ``start`` the cost of beginning with each
    option, ``entry``/``exit_`` indices into ``dist`` of each option's ends, ``internal``."""
    n = len(entry)
    width = max(len(e) for e in entry)
    n_opt = np.array([len(e) for e in entry], dtype=np.int64)

    def pad(rows: list[NDArray[Any]], fill: float, dtype: Any) -> NDArray[Any]:
        out = np.full((n, width), fill, dtype=dtype)
        for k, row in enumerate(rows):
            out[k, : len(row)] = row
        return out

    out = _compiled()(
        np.asarray(order, dtype=np.int64), float(best), int(budget), int(fixed),
        pad(start, math.inf, np.float64), np.ascontiguousarray(dist, dtype=np.float64),
        pad(entry, 0, np.int64), pad(exit_, 0, np.int64), pad(internal, math.inf, np.float64),
        n_opt,
    )  # fmt: skip
    return [int(k) for k in out]
