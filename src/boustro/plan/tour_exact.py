"""The exact order of a tour's few passes (Held-Karp over subsets of passes, the driving option
of each pass a node), compiled by numba on first use.

:func:`boustro.plan.tour._orders` orders passes greedily and improves the order by 2-opt; for
at most :data:`EXACT_TOUR_PASSES` passes it also solves the order exactly with this dynamic
programme (``2^n x options^2`` steps: about a millisecond for 8 passes) and puts it first where
it is cheaper, the shortest tour of its passes (on the moves flown,
:meth:`~boustro.plan.routing.Router.distances`); where the tour is then refined lane by lane,
both are refined and the shorter kept (:func:`boustro.plan.lane_tour.refine_best`), so a
plan's tour is never longer than the heuristic's. The same problem as
:func:`boustro.plan.cell_order.solve_order`'s ``"exact"``, as a compiled loop (the cover search
plans tens of layouts per area). numba is imported on use; without it the plain Python
function runs.
"""

from __future__ import annotations

import itertools
import math
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._jit import compiled
from ..errors import InvalidParameterError

__all__ = ["EXACT_TOUR_PASSES", "exact_nodes"]

#: Passes up to which the tour's order is also solved exactly.
EXACT_TOUR_PASSES = 10


def _held_karp(n, bit, first, move):
    """The sequence of nodes (one option of every pass) of least ``first[a0] + sum move[a, b]``;
    ``bit[a]`` the bit of node ``a``'s pass."""
    m = bit.shape[0]
    full = (1 << n) - 1
    dp = np.full((full + 1, m), np.inf)
    parent = np.full((full + 1, m), -1, dtype=np.int64)
    for a in range(m):
        if first[a] < dp[bit[a], a]:
            dp[bit[a], a] = first[a]
    for s in range(1, full + 1):
        for a in range(m):
            v = dp[s, a]
            if v == np.inf or (s & bit[a]) == 0:
                continue
            for b in range(m):
                if s & bit[b]:
                    continue
                w = v + move[a, b]
                t = s | bit[b]
                if w < dp[t, b]:
                    dp[t, b] = w
                    parent[t, b] = a
    last = 0
    for a in range(1, m):
        if dp[full, a] < dp[full, last]:
            last = a
    out = np.empty(n, dtype=np.int64)
    s, cur = full, last
    for i in range(n - 1, -1, -1):
        out[i] = cur
        prev = parent[s, cur]
        s ^= bit[cur]
        cur = prev
    return out


@cache
def _compiled() -> Any:
    """The loop compiled by numba (cached on disk), or the plain Python one without numba."""
    return compiled(globals(), "_held_karp")


def exact_nodes(
    pass_of: NDArray[np.int64], first: NDArray[np.float64], move: NDArray[np.float64]
) -> tuple[list[int], float]:
    """The least-cost sequence of nodes visiting every pass once and its cost: node ``a`` an
    option of pass ``pass_of[a]``, ``first[a]`` the cost of beginning with it, ``move[a, b]``
    of driving ``b`` after ``a``."""
    n = int(pass_of.max()) + 1
    if n > 20:  # 2^n states: the caller limits n to EXACT_TOUR_PASSES
        raise InvalidParameterError(f"the exact tour takes at most 20 passes, got {n}")
    bit = np.left_shift(1, pass_of.astype(np.int64))
    nodes = _compiled()(
        n, bit, np.ascontiguousarray(first, dtype=np.float64), np.ascontiguousarray(move)
    )
    out = [int(a) for a in nodes]
    cost = float(first[out[0]]) + sum(float(move[a, b]) for a, b in itertools.pairwise(out))
    return out, cost if math.isfinite(cost) else math.inf
