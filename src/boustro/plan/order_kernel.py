"""The 2-opt improvement of a tour's order, compiled by numba on first use.

Each evaluated order is costed by the same dynamic programme as
:func:`boustro.plan.tour._orders` (the driving option of every pass chosen for the least total),
with the same floating-point operations in the same order, so the compiled loop returns the
order the Python loop would; it only removes the interpreter's overhead (a few microseconds
per pass per evaluated order, seconds for the :data:`~boustro.plan.tour.ORDER_BUDGET` orders of
a large field). numba is imported on use; without it the plain Python functions run.
"""

from __future__ import annotations

import math
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._jit import compiled

__all__ = ["OR_OPT_UNITS", "improve_lanes", "improve_order", "kick_lanes"]

#: The most consecutive units (lanes, hole and boundary passes) one or-opt move of
#: :func:`improve_lanes` takes elsewhere by default. It was 3 before the sixteenth round: the
#: refined tour, from the planner's chain by chain, was then often a local optimum whose
#: moves were tens of metres longer than those of tours found over the same lanes from random
#: starts; moving up to a chain's worth of lanes at once reaches some of those tours
#: (docs/mission_time.md). A sweep costs ``O(units n^2)`` evaluations.
OR_OPT_UNITS = 16


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
    return compiled(globals(), "_two_opt", ("_cost",))


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


# -- lanes as units: 2-opt and or-opt with directions, and the iterated local search's kicks
# (:mod:`boustro.plan.lane_tour`) ------------------------------------------------------------
def _en(seq, flip, k):
    """The point (index into the distances) where the unit at position ``k`` is entered; the
    start (0) before the first position, -1 (no move) past the last."""
    if k < 0:
        return 0
    if k >= seq.shape[0]:
        return -1
    return 1 + 2 * seq[k] + flip[k]


def _ex(seq, flip, k):
    """The point where the unit at position ``k`` is left (0: the start, before the first)."""
    if k < 0:
        return 0
    return 2 + 2 * seq[k] - flip[k]


def _d(dist, a, b):
    """The move from point ``a`` to ``b`` (none, 0, to the end of the tour: ``b`` = -1)."""
    if b < 0:
        return 0.0
    return dist[a, b]


def _reverse(seq, flip, i, j):
    """Positions ``i..j`` driven in reverse: their order and every unit's direction."""
    seq[i : j + 1] = seq[i : j + 1][::-1].copy()
    flip[i : j + 1] = 1 - flip[i : j + 1][::-1]


def _two_opt_lanes(seq, flip, fixed, dist, left):
    """One first-improvement 2-opt move (a segment reversed, a single unit turned round); the
    evaluations left after it (negative: none improved, ``-left - 1``)."""
    n = seq.shape[0]
    for i in range(fixed, n):
        a = _ex(seq, flip, i - 1)
        ei = _en(seq, flip, i)
        for j in range(i, n):
            b = _en(seq, flip, j + 1)
            before = _d(dist, a, ei) + _d(dist, _ex(seq, flip, j), b)
            after = _d(dist, a, _ex(seq, flip, j)) + _d(dist, ei, b)
            left -= 1
            if after < before - 1e-9:
                _reverse(seq, flip, i, j)
                return left
            if left <= 0:
                return -1
    return -left - 1


def _or_opt_lanes(seq, flip, fixed, dist, left, units):
    """One first-improvement or-opt move: 1 to ``units`` consecutive units (the fewest first)
    moved elsewhere, either way round; the evaluations left as :func:`_two_opt_lanes`."""
    n = seq.shape[0]
    for size in range(1, min(units, n - 1) + 1):
        for i in range(fixed, n - size + 1):
            j = i + size - 1
            p, q = _ex(seq, flip, i - 1), _en(seq, flip, j + 1)
            s_in, s_out = _en(seq, flip, i), _ex(seq, flip, j)
            gain = _d(dist, p, s_in) + _d(dist, s_out, q) - _d(dist, p, q)
            for k in range(fixed - 1, n):  # insert between positions k and k + 1
                if i - 1 <= k <= j:
                    continue
                x, y = _ex(seq, flip, k), _en(seq, flip, k + 1)
                base = _d(dist, x, y)
                fwd = _d(dist, x, s_in) + _d(dist, s_out, y) - base
                # reversed: entered where it was left, left where it was entered
                rev = _d(dist, x, s_out) + _d(dist, s_in, y) - base
                left -= 2
                if min(fwd, rev) < gain - 1e-9:
                    _move(seq, flip, i, j, k, rev < fwd)
                    return left
                if left <= 0:
                    return -1
    return -left - 1


def _move(seq, flip, i, j, k, reverse):
    """Positions ``i..j`` moved to after position ``k`` (reversed with ``reverse``)."""
    if reverse:
        _reverse(seq, flip, i, j)
    if k > j:  # rotate i..k left by the segment's size
        size = j - i + 1
        s, f = seq[i : j + 1].copy(), flip[i : j + 1].copy()
        seq[i : k - size + 1] = seq[j + 1 : k + 1].copy()
        flip[i : k - size + 1] = flip[j + 1 : k + 1].copy()
        seq[k - size + 1 : k + 1] = s
        flip[k - size + 1 : k + 1] = f
    else:  # k < i - 1: rotate k+1..j right
        size = j - i + 1
        s, f = seq[i : j + 1].copy(), flip[i : j + 1].copy()
        seq[k + 1 + size : j + 1] = seq[k + 1 : i].copy()
        flip[k + 1 + size : j + 1] = flip[k + 1 : i].copy()
        seq[k + 1 : k + 1 + size] = s
        flip[k + 1 : k + 1 + size] = f


def _search(seq, flip, fixed, dist, budget, units):
    """2-opt and or-opt moves until neither improves or ``budget`` evaluations are spent; the
    evaluations left (``seq``, ``flip`` changed in place)."""
    left = budget
    while left > 0:
        left = _two_opt_lanes(seq, flip, fixed, dist, left)
        if left >= 0:
            continue
        left = -left - 1
        if left <= 0:
            break
        left = _or_opt_lanes(seq, flip, fixed, dist, left, units)
        if left < 0:
            return -left - 1  # a local optimum (0: the budget spent)
    return max(left, 0)


def _lane_search(seq, flip, fixed, dist, budget, units):
    """2-opt and or-opt moves until neither improves or ``budget`` evaluations are spent."""
    _search(seq, flip, fixed, dist, budget, units)
    return seq, flip


def _tour_moves(seq, flip, dist):
    """The tour's moves by ``dist`` (the approach from the start ``dist[0]`` counted)."""
    total = dist[0, 1 + 2 * seq[0] + flip[0]]
    for k in range(1, seq.shape[0]):
        total += dist[2 + 2 * seq[k - 1] - flip[k - 1], 1 + 2 * seq[k] + flip[k]]
    return total


def _draw(state, low, high):
    """A deterministic draw in ``[low, high)`` and the generator's next state (a linear
    congruential generator: the same numbers compiled and in plain Python)."""
    state = (state * 1103515245 + 12345) % 2147483648
    return low + (state >> 8) % (high - low), state


def _kick(seq, flip, fixed, dist, budget, units, state):
    """One kick of the iterated local search: a double bridge of the positions from
    ``fixed`` (the tour ``A B C D`` driven ``A C B D``, three cuts drawn from ``state``), then
    :func:`_search`. ``(seq, flip, its moves by dist, evaluations left, next state)``; the
    given arrays are not changed."""
    n = seq.shape[0]
    s, f = seq.copy(), flip.copy()
    a, state = _draw(state, fixed + 1, n - 1)
    b, state = _draw(state, fixed + 1, n - 1)
    c, state = _draw(state, fixed + 1, n - 1)
    lo, mid, hi = min(a, b, c), a + b + c - min(a, b, c) - max(a, b, c), max(a, b, c)
    if lo < mid < hi:
        m = hi - mid  # C = mid..hi-1 first, then B = lo..mid-1
        s[lo : lo + m] = seq[mid:hi]
        f[lo : lo + m] = flip[mid:hi]
        s[lo + m : hi] = seq[lo:mid]
        f[lo + m : hi] = flip[lo:mid]
    left = _search(s, f, fixed, dist, budget, units)
    return s, f, _tour_moves(s, f, dist), left, state


@cache
def _compiled_lanes() -> Any:
    helpers = (
        "_en",
        "_ex",
        "_d",
        "_reverse",
        "_two_opt_lanes",
        "_or_opt_lanes",
        "_move",
        "_search",
    )
    return compiled(globals(), ("_lane_search", "_kick"), (*helpers, "_tour_moves", "_draw"))


def improve_lanes(
    seq: NDArray[np.int64],
    flip: NDArray[np.int64],
    fixed: int,
    dist: NDArray[np.float64],
    budget: int,
    units: int = OR_OPT_UNITS,
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Units (lanes, hole and boundary passes) in the order ``seq``, each driven forwards
    (``flip`` 0: entered at point ``1 + 2 u``, left at ``2 + 2 u`` of ``dist``) or backwards,
    improved by 2-opt (segments reversed, units turned round) and or-opt (1 to
    ``units`` consecutive units moved, either way round) until neither improves or
    ``budget`` moves were evaluated; the first ``fixed`` positions stay. ``dist[0]``: the moves
    from the start (zeros: a free start). The deltas assume symmetric moves
    (:meth:`~boustro.plan.routing.Router.distances`)."""
    seq, flip = _compiled_lanes()[0](
        np.array(seq, dtype=np.int64), np.array(flip, dtype=np.int64), int(fixed),
        np.ascontiguousarray(dist, dtype=np.float64), int(budget), int(units),
    )  # fmt: skip
    return seq, flip


def kick_lanes(
    seq: NDArray[np.int64],
    flip: NDArray[np.int64],
    fixed: int,
    dist: NDArray[np.float64],
    budget: int,
    state: int,
    units: int = OR_OPT_UNITS,
) -> tuple[NDArray[np.int64], NDArray[np.int64], float, int, int]:
    """One kick of an iterated local search from the tour ``seq``/``flip`` (as
    :func:`improve_lanes`'s): a double bridge on the units from position ``fixed + 1`` (three
    cut points drawn from the generator's ``state``: the same state, the same kick), then 2-opt
    and or-opt within ``budget`` evaluations. ``(seq, flip, moves, budget left, next state)``,
    ``moves`` by ``dist`` with ``dist[0]`` counted; at least 4 units after ``fixed``."""
    if seq.shape[0] - fixed < 4:
        raise ValueError("a double bridge needs 4 units after the fixed ones")
    s, f, moves, left, state = _compiled_lanes()[1](
        np.array(seq, dtype=np.int64), np.array(flip, dtype=np.int64), int(fixed),
        np.ascontiguousarray(dist, dtype=np.float64), int(budget), int(units), int(state),
    )  # fmt: skip
    return s, f, float(moves), int(left), int(state)
