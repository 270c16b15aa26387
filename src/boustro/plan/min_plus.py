"""The min-plus product of a router's length rows, compiled by numba on first use.

A :class:`~boustro.plan.routing.Router` on a visibility graph measures a point's shortest
lengths through its visible nodes (``w = v (min,+) D``: ``v`` the point's lengths to the nodes,
``inf`` where hidden, ``D`` the graph's all-pairs lengths), and a pair of points through the
graph (``min_n w[i, n] + v[j, n]``). numpy formed every sum of the ``(P, N, N)`` (or
``(U, U, N)``) block, in blocks of 64 rows; most of them add ``inf`` (a point sees a few of
the nodes). :func:`min_plus` skips the row entries that are ``inf`` (each of their sums is
``inf``, never below a finite one, and the minimum of an empty set is ``inf`` too) and adds
the others in a compiled loop: the minimum of the same finite sums, each the same
floating-point addition (addition is commutative in IEEE arithmetic, so ``a + b`` and
``b + a`` are the same number), so the answers equal numpy's bit for bit. The lengths are never
NaN (sums and minima of non-negative lengths and ``inf``), where numpy's minimum would differ.
numba is imported on use; without it the plain Python loop runs.
"""

from __future__ import annotations

import math
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._jit import compiled

__all__ = ["min_plus"]


def _min_plus(a, b, out):
    for i in range(a.shape[0]):
        for k in range(a.shape[1]):
            x = a[i, k]
            if x == math.inf:  # every sum is inf: never below out's entries (inf or less)
                continue
            for j in range(b.shape[1]):
                y = x + b[k, j]
                if y < out[i, j]:
                    out[i, j] = y


@cache
def _compiled() -> Any:
    return compiled(globals(), "_min_plus")


def min_plus(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(P, M)``: ``min_k a[i, k] + b[k, j]`` for ``a (P, K)``, ``b (K, M)`` of non-negative
    lengths or ``inf`` (``inf`` where ``K == 0``); numpy's ``np.min(a[:, :, None] + b,
    axis=1)`` bit for bit (module docstring)."""
    a = np.ascontiguousarray(a, dtype=np.float64)
    b = np.ascontiguousarray(b, dtype=np.float64)
    out = np.full((a.shape[0], b.shape[1]), math.inf)
    if a.size and b.size:
        _compiled()(a, b, out)
    return out
