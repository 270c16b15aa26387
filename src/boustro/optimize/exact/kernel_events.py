"""The event angles of the certified Eq. 1 optimum with compiled loops (numba), bit for bit.

:func:`.structure.event_angles` is a dozen numpy calls on small arrays: 30-190 us a polygon
of the paper's (a tenth of the compiled optimum), most of it per-call overhead. Here the
loops are compiled and numpy keeps only the two functions whose numbers numba's would not
reproduce (numpy's vectorised ``arctan2`` and ``arccos`` differ from the C library's in the
last place, and an event moved by one unit in the last place can move a knife-edge optimum):
:func:`_event_terms` gives the pairs' differences, distances and the ratios ``m s / dist``
with ``|m s / dist| <= 1`` (the same float test), numpy takes the arc tangents and arc
cosines, :func:`_event_merge` forms ``alpha +- acos`` modulo pi, sorts and merges them as
``event_angles`` does. tests/test_exact_check.py checks that the angles are equal, bit for
bit. Plain Python until :func:`.kernel.compiled` compiles them.
"""

from __future__ import annotations

import math

import numpy as np

from .structure import EVENT_MERGE

__all__: list[str] = []


def _event_terms(v: np.ndarray, s: float) -> tuple:
    """``(dx, dy, pair, ratio)``: every pair ``i < j`` (numpy's ``triu_indices`` order)'s
    ``v_i - v_j``, and for each multiple ``m`` of the spacing with ``|m s / dist| <= 1`` its
    pair and ratio ``m s / dist`` (``dist`` the pair's ``hypot``)."""
    n = v.shape[0]
    pairs = n * (n - 1) // 2
    dx, dy, dist = np.empty(pairs), np.empty(pairs), np.empty(pairs)
    top = np.empty(pairs, dtype=np.int64)
    k = 0
    total = 0
    for i in range(n):
        for j in range(i + 1, n):
            dx[k], dy[k] = v[i, 0] - v[j, 0], v[i, 1] - v[j, 1]
            dist[k] = np.hypot(dx[k], dy[k])
            reach = np.floor(dist[k] / s) + 1.0
            top[k] = int(reach) if math.isfinite(reach) else 0
            total += 2 * top[k] + 1
            k += 1
    pair, ratio = np.empty(total, dtype=np.int64), np.empty(total)
    c = 0
    for k in range(pairs):
        for mi in range(-top[k], top[k] + 1):
            r = float(mi) * s / dist[k]
            if abs(r) <= 1.0:
                pair[c], ratio[c] = k, r
                c += 1
    return dx, dy, pair[:c], ratio[:c]


def _event_merge(alpha: np.ndarray, pair: np.ndarray, acos: np.ndarray) -> np.ndarray:
    """The sorted, merged event angles from the pairs' ``alpha`` and the multiples' arc
    cosines (as the end of :func:`.structure.event_angles`)."""
    m = len(acos)
    cand = np.empty(2 * m + 1)
    for c in range(m):
        base = alpha[pair[c]]
        cand[c] = np.mod(base + acos[c], math.pi)
        cand[m + c] = np.mod(base - acos[c], math.pi)
    cand[2 * m] = 0.0
    cand.sort()
    out = np.empty(len(cand) + 1)
    count = 1
    out[0] = cand[0]
    for i in range(1, len(cand)):
        if cand[i] - cand[i - 1] > EVENT_MERGE:
            out[count] = cand[i]
            count += 1
    if out[count - 1] > math.pi - EVENT_MERGE:  # equal to 0 modulo pi
        count -= 1
    out[count] = math.pi
    return out[: count + 1]
