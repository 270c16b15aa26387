"""A lower bound on a routed tour's connecting moves that sees the tour's structure: the Held-Karp
1-tree bound with Lagrangian multipliers over the counted lanes' ends (docs/mission_time.md,
"The tour's 1-tree").

Per layout of the centre grid and line ``k`` (the area moves, not the grid) the band statistics
give ``count_k`` lanes every area ``S`` of the box has, each holding one inner piece, with the
ranges of their ends: the first lane starts in ``[a_k - t, a_k]`` and the last ends in ``[b_k,
b_k + t]`` (``a_k, b_k`` the first inner piece's start and the last one's end, exported by the
band kernel; collapsed, below; :mod:`~boustro.optimize.cover.extremes`); with
``count_k >= 2`` the first lane ends in ``[first_hi_k, P1_k + t]``, the last starts in ``[PL_k -
t, last_lo_k]``, and every lane between (inside the outer pieces from the second to the one
before the last, ``[P2_k, Q1_k]``) starts in ``[P2_k - t, min(last_lo_k, Q1_k)]`` and ends in
``[max(first_hi_k, P2_k), Q1_k + t]`` (``P1, P2, PL, Q1``: :attr:`BandStats.pieces`; ``t`` the
run-in). Two ends on lines ``j, k`` are at least ``sqrt(((j - k) s)^2 + g^2)`` apart, ``g`` the
gap between their ranges: a connecting move is never shorter.

**The collapsed outer ends.** Every inner piece (the inner projection minus the dilated holes'
chords) lies in a counted outer piece, so the plan's first counted lane on line ``k`` (the one
holding the first inner piece, ``[a_k, first_hi_k]``) starts in ``[A_k - t, a_k]`` (``A_k`` the
outer projection's extreme): its covered part starts at ``p <= a_k``, its run-in ``r <= t``
before. Its part ``[p, a_k)`` lies outside the inner pieces, so no other term of the bound counts
it (the lanes' length is the inner pieces', the run-ins ``t`` each or none, the extra lanes'
contraction their own flown length), and the point ``max(p - r, a_k - t)`` of ``[a_k - t,
a_k]`` is at most ``a_k - p`` from the real start: by the triangle inequality the path's one
move at that end, from the collapsed end, is at most the real move plus ``a_k - p``, which the
plan flies on top of what the bound counts. So the 1-tree over the collapsed ranges is at most
``moves + extra lanes + the lanes' length outside the inner pieces``, and the bound stays below
every plan. The same holds for the last lane's end (``[b_k, B_k + t]`` to ``[b_k, b_k + t]``),
for a one-lane line at both ends (its two parts outside the inner pieces are disjoint), with ``t
= 0``, and with split gaps (``pieces``: only the line's two outermost ends change, every other
end keeps its range). A box straddling an edge along the lines (random area 35: ``B_k - b_k`` =
105 m) no longer lets the line's lane end anywhere in between (docs/mission_time.md, "The tour's
1-tree"). Before the eleventh round ``a_k, b_k`` were the inner projection's extremes, which a
hole's chord can cut: a hole within the box's radius of the area's edge, the band reaching past
it (docs/mission_time.md, "The lines' extremes").

**The relaxation.** Contract every hole pass (a closed loop entered and left at one point ``x``:
``|e - x| + |x - f| >= |e - f|``) and every extra lane (a lane holding no inner piece, flown
from ``x`` to ``y``: ``|e - f| <= |e - x| + |x - y| + |y - f|``; its flown length is in the
plan's cost and in no other term of the bound). What remains is a path over the counted lanes
whose moves are at most ``moves + the extra lanes' flown length``. Close it with a dummy node
joined to every end at cost 0: a Hamiltonian cycle over the ends and the dummy that holds every
lane as an edge. Every such cycle is a 1-tree (a spanning tree of the ends holding every lane,
plus two edges of the dummy); with multipliers ``pi`` on the ends, ``L(pi) = min 1-tree under
costs c_ij + pi_i + pi_j - 2 sum(pi)`` is at most the cycle's cost for every ``pi`` (Held and
Karp 1970). The spanning tree that must hold the lanes is the lanes plus a minimum spanning tree
of the lanes contracted (Prim, the cost between two lanes the least over their four pairs of
ends). ``pi`` is improved by subgradient steps; the best ``L`` is kept. Where it stays a few
metres short of a target, :mod:`~.one_tree_branch` branches on the 1-tree (``branch``).
"""

from __future__ import annotations

import math
from functools import cache
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..._jit import compiled
from . import one_tree_branch
from .bands import BandStats
from .cost import CoverCost
from .extremes import line_extremes
from .one_tree_branch import BRANCH_STEPS, _branch

__all__ = ["MAX_LANES", "ONE_TREE_STEPS", "POINT_TREE_STEPS", "Multipliers", "one_tree_bound"]

#: Layouts with more counted lanes than this are not bounded (``O(lanes^2)`` per step).
MAX_LANES = 160
#: Subgradient steps per layout.
ONE_TREE_STEPS = 40
#: Subgradient steps at a single layout (the search's point values, which set its lowest model
#: and so the certificate's settling floor): 40 steps fall 1-3 m of moves short of the
#: multipliers' limit there (docs/mission_time.md, "The 1-tree's steps at single layouts").
POINT_TREE_STEPS = 120
#: The walls lengthen the distances between ends on lines at most this many lines apart only:
#: the 1-tree's edges are short (on the random areas of ``benchmarks/tour_bound.py`` the
#: bounds with 1 and with every line are the same; the walls took 40% of its CPU).
WALL_LINES = 2


#: The room a proper crossing needs (:func:`_crosses`), relative to the segments' lengths: far
#: above the rounding of an orientation (1e-16), far below any real crossing.
CROSS_ROOM = 1e-9


def _lane_ends(count, ext, first_hi, last_lo, pieces, k0, s, t, lo, hi, v, lk, ls):
    """Fill the end ranges ``[lo, hi]`` (along the lines) and ``v`` (across) of every counted
    lane of one layout, ends ``2i`` (start) and ``2i + 1`` (end) of lane ``i``, and its line
    ``lk`` and slot ``ls`` (0 the first lane of its line, 2 the last, 1 one between); the
    lanes. ``ext (B, 4)``: the ranges of the line's first start and last end, run-ins
    included (:func:`line_extremes`)."""
    n = 0
    for k in range(count.shape[0]):
        c = count[k]
        if c < 1:
            continue
        for i in range(c):
            lk[n] = k
            ls[n] = 0 if i == 0 else (2 if i == c - 1 else 1)
            if i == 0:  # collapsed to the inner pieces' extreme (module docstring)
                lo[2 * n], hi[2 * n] = ext[k, 0], ext[k, 1]
            elif i == c - 1:
                lo[2 * n], hi[2 * n] = pieces[k, 2] - t, last_lo[k]
            else:
                lo[2 * n], hi[2 * n] = pieces[k, 1] - t, min(last_lo[k], pieces[k, 3])
            if i == c - 1:
                lo[2 * n + 1], hi[2 * n + 1] = ext[k, 2], ext[k, 3]
            elif i == 0:
                lo[2 * n + 1], hi[2 * n + 1] = first_hi[k], pieces[k, 0] + t
            else:
                lo[2 * n + 1], hi[2 * n + 1] = max(first_hi[k], pieces[k, 1]), pieces[k, 3] + t
            v[2 * n] = v[2 * n + 1] = (k0 + k) * s
            n += 1
    return n


def _orient(ax, ay, bx, by, cx, cy):
    """Twice the signed area of ``a, b, c``."""
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)


def _crosses(ax, ay, bx, by, cx, cy, dx, dy):
    """Whether the segments ``ab`` and ``cd`` cross properly (at one interior point of each),
    with room: every end at least ``CROSS_ROOM`` of the segments' lengths off the other's line.
    Segments along each other (a hull side along a wall, where lane ends lie on one hole edge and
    a move runs along it) are not crossing: their orientations are rounding, of either sign (a
    review: a 7.0 m move charged 23.0 m, a box bound 3.7 s above a plan in the box)."""
    o1 = _orient(ax, ay, bx, by, cx, cy)
    o2 = _orient(ax, ay, bx, by, dx, dy)
    o3 = _orient(cx, cy, dx, dy, ax, ay)
    o4 = _orient(cx, cy, dx, dy, bx, by)
    room = CROSS_ROOM * (abs(bx - ax) + abs(by - ay)) * (abs(dx - cx) + abs(dy - cy))
    return ((o1 > room and o2 < -room) or (o1 < -room and o2 > room)) and (
        (o3 > room and o4 < -room) or (o3 < -room and o4 > room)
    )


def _to_range(px, py, lo, hi, v):
    """Distance from ``(px, py)`` to the segment ``[lo, hi] x {v}``."""
    g = max(max(lo - px, px - hi), 0.0)
    dv = py - v
    return math.sqrt(g * g + dv * dv)


def _detour(la, ha, va, lb, hb, vb, walls, w):
    """A lower bound on a path from range ``a`` to range ``b`` that crosses no wall: where
    wall ``w`` crosses both sides ``(la, va)-(lb, vb)`` and ``(ha, va)-(hb, vb)`` of the hull of
    the two ranges, every segment between them crosses it, and the path passes one of its ends
    (the shortest path past a segment); 0 otherwise."""
    x1, y1, x2, y2 = walls[w, 0], walls[w, 1], walls[w, 2], walls[w, 3]
    if max(y1, y2) <= min(va, vb) or min(y1, y2) >= max(va, vb):
        return 0.0
    if not _crosses(la, va, lb, vb, x1, y1, x2, y2):
        return 0.0
    if not _crosses(ha, va, hb, vb, x1, y1, x2, y2):
        return 0.0
    d1 = _to_range(x1, y1, la, ha, va) + _to_range(x1, y1, lb, hb, vb)
    d2 = _to_range(x2, y2, la, ha, va) + _to_range(x2, y2, lb, hb, vb)
    return min(d1, d2)


def _distances(lo, hi, v, n_ends, walls, reach, dist):
    """Least distance between every two ends' ranges (``dist``, ``n_ends`` square), past the
    walls (the largest detour of one wall) for ends at most ``reach`` apart across the lines
    (farther ends: the straight distance, also a lower bound)."""
    for a in range(n_ends):
        dist[a, a] = 0.0
        for b in range(a + 1, n_ends):
            g = max(max(lo[a], lo[b]) - min(hi[a], hi[b]), 0.0)
            dv = v[a] - v[b]
            best = math.sqrt(dv * dv + g * g)
            if abs(dv) > reach:
                dist[a, b] = dist[b, a] = best
                continue
            for w in range(walls.shape[0]):
                best = max(best, _detour(lo[a], hi[a], v[a], lo[b], hi[b], v[b], walls, w))
            dist[a, b] = dist[b, a] = best


def _one_tree(dist, pi, n, deg, key, near, done):
    """The 1-tree's cost under ``pi`` minus ``2 sum(pi)``; its ends' degrees in ``deg``."""
    m = 2 * n
    for e in range(m):
        deg[e] = 1  # the lane
    total = 0.0
    for a in range(n):
        key[a] = math.inf
        done[a] = False
    key[0] = 0.0
    near[0] = -1
    a, best = 0, 0.0
    for _ in range(n):  # Prim: the next lane is chosen while the keys are updated
        done[a] = True
        if near[a] >= 0:
            total += best
            deg[near[a] // 4] += 1  # the tree end (packed: tree end * 4 + pair)
            deg[2 * a + near[a] % 2] += 1
        r0, r1 = 2 * a, 2 * a + 1
        p0, p1 = pi[r0], pi[r1]
        nxt, low = -1, math.inf
        for b in range(n):
            if done[b]:
                continue
            q0, q1 = pi[2 * b], pi[2 * b + 1]
            kb, nb = key[b], near[b]
            c = dist[r0, 2 * b] + p0 + q0
            if c < kb:
                kb, nb = c, r0 * 4
            c = dist[r0, 2 * b + 1] + p0 + q1
            if c < kb:
                kb, nb = c, r0 * 4 + 1
            c = dist[r1, 2 * b] + p1 + q0
            if c < kb:
                kb, nb = c, r1 * 4
            c = dist[r1, 2 * b + 1] + p1 + q1
            if c < kb:
                kb, nb = c, r1 * 4 + 1
            key[b], near[b] = kb, nb
            if kb < low:
                nxt, low = b, kb
        a, best = nxt, low
    # the dummy: its two cheapest edges (cost pi of the end)
    i1, i2 = -1, -1
    for e in range(m):
        if i1 < 0 or pi[e] < pi[i1]:
            i1, i2 = e, i1
        elif i2 < 0 or pi[e] < pi[i2]:
            i2 = e
    total += pi[i1] + (pi[i2] if i2 >= 0 else 0.0)
    deg[i1] += 1
    if i2 >= 0:
        deg[i2] += 1
    for e in range(m):
        total -= pi[e]  # forced lanes add sum(pi); minus 2 sum(pi)
    return total


def _load(pi0, warm, n, lk, ls, kofs, pi, best_pi):
    """Start ``pi`` (and ``best_pi``) from one layout's kept multipliers ``pi0`` ``(W, 3, 2)``
    where ``warm`` (lanes on lines it does not hold: 0), else at 0."""
    for i in range(n):
        col = lk[i] + kofs
        inside = warm and 0 <= col < pi0.shape[0]
        for side in range(2):
            pi[2 * i + side] = pi0[col, ls[i], side] if inside else 0.0
            best_pi[2 * i + side] = pi[2 * i + side]


def _store(pi0, n, lk, ls, kofs, best_pi):
    """Keep ``best_pi`` in one layout's ``pi0`` ``(W, 3, 2)`` (0 where no lane)."""
    pi0[:] = 0.0
    for i in range(n):
        col = lk[i] + kofs
        if 0 <= col < pi0.shape[0]:
            for side in range(2):
                pi0[col, ls[i], side] = best_pi[2 * i + side]


def _bounds(
    count,
    ext,
    first_hi,
    last_lo,
    pieces,
    todo,
    enough,
    walls,
    k0,
    s,
    t,
    steps,
    pi0,
    warm,
    kofs,
    nodes,
    window,
):
    """Per layout (where ``todo``): the best 1-tree bound on the moves, in plan units (the
    steps stop once it reaches ``enough``); where it stays below ``enough`` by at most
    ``window``, branched (:mod:`~.one_tree_branch`, at most ``nodes`` children)."""
    n_layouts = count.shape[0]
    big = 0
    for la in range(n_layouts):
        big = max(big, int(count[la].sum()))
    m = 2 * big
    lo, hi, v = np.empty(m), np.empty(m), np.empty(m)
    dist = np.empty((m, m))
    pi, deg = np.empty(m), np.empty(m, dtype=np.int64)
    key, near = np.empty(big), np.empty(big, dtype=np.int64)
    done = np.empty(big, dtype=np.bool_)
    lk, ls = np.empty(big, dtype=np.int64), np.empty(big, dtype=np.int64)
    best_pi = np.empty(m)
    out = np.zeros(n_layouts)
    for la in range(n_layouts):
        if not todo[la]:
            continue
        n = _lane_ends(count[la], ext[la], first_hi[la], last_lo[la], pieces[la], k0, s, t,
                       lo, hi, v, lk, ls)  # fmt: skip
        if n < 2:
            continue
        _distances(lo, hi, v, 2 * n, walls[la], (WALL_LINES + 0.5) * s, dist)
        _load(pi0[la], warm[la], n, lk, ls, kofs, pi, best_pi)
        best = 0.0  # the moves are never negative
        lam, stall = 1.0, 0
        for _ in range(steps):
            val = _one_tree(dist, pi, n, deg, key, near, done)
            if val > best * (1.0 + 1e-9):
                best, stall = val, 0
                for e in range(2 * n):
                    best_pi[e] = pi[e]
                if best >= enough[la]:
                    break
            else:
                stall += 1
                if stall >= 3:
                    lam *= 0.5
                    stall = 0
            norm = 0.0
            for e in range(2 * n):
                norm += (deg[e] - 2) * (deg[e] - 2)
            if norm == 0.0:
                break  # the 1-tree is a tour: the bound is its cost
            step = lam * 0.2 * max(best, s) / norm
            for e in range(2 * n):
                pi[e] += step * (deg[e] - 2)
        if nodes > 0 and best < enough[la] <= best + window:
            best = _branch(dist, n, best_pi, best, enough[la], s, nodes, BRANCH_STEPS)
        out[la] = max(best, 0.0)
        _store(pi0[la], n, lk, ls, kofs, best_pi)  # the best 1-tree's, for the next boxes
    return out


class Multipliers(NamedTuple):
    """Held-Karp multipliers kept between the 1-trees of boxes (a box's halves start from
    its own): ``values`` ``(L, W, 3, 2)`` per layout, line (absolute index ``k0 + column``), slot
    (the first lane of the line, one between, the last) and side (start, end); ``warm`` ``(L,)``
    where they hold a 1-tree's. :func:`one_tree_bound` starts from them where ``warm`` and
    writes its best 1-tree's multipliers back (any start gives a valid bound)."""

    values: NDArray[np.float64]
    warm: NDArray[np.bool_]
    k0: int


@cache
def _compiled() -> Any:
    """The loop compiled by numba (cached on disk), or the plain Python one without numba."""
    helpers = ("_orient", "_crosses", "_to_range", "_detour", "_lane_ends", "_distances",
               "_one_tree", "_load", "_store", "_branch")  # fmt: skip
    return compiled(globals(), "_bounds", helpers, before=(one_tree_branch.swap,))


def one_tree_bound(
    st: BandStats,
    spacing: float,
    cost: CoverCost,
    todo: NDArray[np.bool_] | None = None,
    steps: int | None = None,
    walls: NDArray[np.float64] | None = None,
    enough: NDArray[np.float64] | None = None,
    multipliers: Multipliers | None = None,
    branch: tuple[int, float] | None = None,
) -> NDArray[np.float64]:
    """``(L,)`` a lower bound, in cost units, on ``per_length`` times the connecting moves plus
    the extra lanes' flown length of every plan of each layout's sandwich (module docstring);
    0 where not ``todo`` or with more than :data:`MAX_LANES` counted lanes. ``walls`` ``(L, W,
    4)``: segments no move crosses, in each layout's frame (:func:`~.walls.walls_in_frames`);
    ``enough`` ``(L,)`` (cost units): a layout's steps stop once its bound reaches it;
    ``multipliers``: where to start the steps and where to keep their best (read, written);
    ``branch`` ``(nodes, window)``: where a layout's 1-tree stays below ``enough`` by at most
    ``window`` (cost units), branch on it with at most ``nodes`` children
    (:mod:`~.one_tree_branch`; the multipliers kept are the root's)."""
    n_layouts = st.count.shape[0]
    lanes = st.count.sum(axis=1)
    ok = lanes <= MAX_LANES if todo is None else todo & (lanes <= MAX_LANES)
    if cost.per_length <= 0 or not (ok & (lanes >= 1)).any():
        return np.zeros(n_layouts)
    if walls is None:
        walls = np.zeros((n_layouts, 0, 4))
    stop = np.full(n_layouts, np.inf) if enough is None else enough / cost.per_length
    cols = np.nonzero((st.count >= 1).any(axis=0))[0]
    c0, c1 = int(cols[0]), int(cols[-1]) + 1

    def crop(a: NDArray[Any]) -> NDArray[Any]:
        return np.ascontiguousarray(a[:, c0:c1])

    if multipliers is None:
        pi0, warm, kofs = np.zeros((n_layouts, 1, 3, 2)), np.zeros(n_layouts, bool), -(2**40)
    else:
        pi0, warm = multipliers.values, multipliers.warm
        kofs = int(st.k0 + c0) - multipliers.k0
    moves = _compiled()(
        crop(st.count), crop(line_extremes(st, cost.turnaround)),
        crop(st.first_hi), crop(st.last_lo),
        crop(st.pieces), np.ascontiguousarray(ok),
        np.ascontiguousarray(stop, dtype=np.float64), np.ascontiguousarray(walls, dtype=np.float64),
        int(st.k0 + c0), float(spacing), float(cost.turnaround),
        int(ONE_TREE_STEPS if steps is None else steps), pi0,
        np.ascontiguousarray(warm), kofs,
        0 if branch is None else int(branch[0]),
        0.0 if branch is None else float(branch[1]) / cost.per_length,
    )  # fmt: skip
    if multipliers is not None:
        multipliers.warm[ok] = True
    return cost.per_length * moves
