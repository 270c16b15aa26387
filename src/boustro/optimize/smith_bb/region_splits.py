"""The split choices of a region's box, pooled and branched (numba).

Where the uncertain lines of a box have more gaps between inner pieces than
:data:`.region_kernel.MAX_CHOICES` lets it enumerate (a noisy traced field with holes: 4-18),
the choices are *pooled*: one segment per O-component of each uncertain line (between its
shortest piece and the component), up to ``sum(min(extra, gaps))`` more split segments, each
between the shortest piece and the longest group of a split component (:func:`_extent`: a
group of a split component leaves out its first or its last piece), and up to ``sum(extra)``
free ones in ``[0, G]``; Eq. 1 is convex in the two shares, so only their four extreme counts
are tried. That keeps a component whole AND adds its split groups: on issue 21's traced field
(2000 vertices, 10 holes, 10 m) it was 0.003-0.024 (median 0.014) above the exact maximum over
every choice of splits in the boxes open at the work budget (docs/global_optimum.md, section
10, "Branched split choices").

:func:`split_bound` is a branch and bound over those choices, line by line (a line's choice:
the gaps between its pieces at which its segments split, at most its ``extra``): a node fixes
the choices of its first lines exactly (:func:`_line_segments`) and pools the others, so its value
bounds every choice below it (the root: the pooled bound); nodes at most the best complete
choice or the caller's ``cut`` are not branched. The lines with the longest possible split
groups are branched first (they make the pooled bound loose). Free segments (holding no
piece) are counted as in the pooled bound. Lines with more than :data:`MAX_GAPS` gaps stay
pooled. After :data:`NODES` nodes the bound is the largest of the best complete choice, the
nodes cut, and the nodes left; boxes of more than :data:`NODE_LINES` lines keep the pooled
bound (no node; any number of nodes gives a bound, fewer a looser one).
"""

from __future__ import annotations

import numpy as np

from ..._jit import jit_globals
from . import kernel
from .kernel import _sup_w

__all__ = ["MAX_GAPS", "NODES", "NODE_LINES", "prepare", "split_bound", "split_nodes"]

#: Nodes of the branch and bound per box (each: four exact maxima of Eq. 1). Measured on issue
#: 21's field: 8 gives the gaps of 24 at two thirds of its CPU (4: wider gaps, 64: more CPU).
NODES = 8
#: Boxes of more lines than this (``lines_range`` of the region: about its circumscribed
#: diameter over the spacing) are not branched (:func:`split_nodes`; their bound is the pooled
#: one, the root): a node is four exact maxima over every segment of the box, so its cost grows
#: with the lines while what it recovers does not. Measured on issue 21's field (2026-11-28,
#: docs/global_optimum.md, section 10, "Finer spacing"): at 10, 7 and 5 m (94, 130, 180 lines)
#: the branching certifies or halves the gap at the default budget (without it: 0.008, 0.016,
#: 0.017); at 3 m (296) it took 60% of the CPU for 0.0016 of bound a box: 0.019 in 20 s with
#: it, 0.0205 in 8.2 s without at the same budget (0.018 in 12.8 s with
#: :data:`~boustro.optimize.smith_bb.region.REGION_EXTEND_POOLED`).
NODE_LINES = 200
#: Lines with more gaps than this (``2^gaps`` choices) are never branched, only pooled.
MAX_GAPS = 3


def split_nodes(lines: int) -> int:
    """The nodes of :func:`split_bound` for a box of ``lines`` lines: :data:`NODES` up to
    :data:`NODE_LINES` lines, none beyond (the pooled bound)."""
    return NODES if lines <= NODE_LINES else 0


def _extent(oa, ob, o0, o1, p0, p1, pa, pb, owner):
    """The longest group of a split component of one line (as
    :func:`.region_kernel._proper_extent`)."""
    out = 0.0
    for o in range(o0, o1):
        first, last = -1, -1
        for p in range(p0, p1):
            if owner[p] == o:
                if first < 0:
                    first = p
                last = p
        if last > first >= 0:
            out = max(out, pa[last] - oa[o], ob[o] - pb[first])
    return out


def _line_segments(oa, ob, o0, o1, pa, pb, p0, p1, owner, mask, g, lo, hi, n):
    """Append the segments of one line to ``lo, hi`` from ``n``: per O-component, its pieces
    grouped at the split points whose bit of ``mask`` (from bit ``g``) is set. Returns
    ``(n, g, splits)``."""
    splits = 0
    p = p0
    while p < p1:
        if owner[p] < 0:
            p += 1
            continue
        o = owner[p]
        left = oa[o]  # the group lies right of this
        first = p
        last = p
        q = p + 1
        while q < p1 and (owner[q] < 0 or owner[q] == o):
            if owner[q] < 0:
                q += 1
                continue
            if (mask >> g) & 1:  # a split between last and q
                lo[n] = pb[last] - pa[first]
                hi[n] = pa[q] - left
                n += 1
                splits += 1
                left = pb[last]
                first = q
            g += 1
            last = q
            q += 1
        lo[n] = pb[last] - pa[first]
        hi[n] = ob[o] - left
        n += 1
        p = q
    return n, g, splits


def _node(oa, ob, ost, pa, pb, ist, owner, extra, gaps, order, nl, depth, chosen, lo, hi, w,
          n_fixed, free, gfree, a, b, pos):  # fmt: skip
    """The bound of a node: lines ``order[:depth]`` with the choices ``chosen``, the other
    uncertain lines pooled; ``-inf`` if a choice splits a line more than its ``extra``."""
    n = n_fixed
    for i in range(depth):
        q = order[i]
        n, _, splits = _line_segments(oa, ob, ost[q], ost[q + 1], pa, pb, ist[q], ist[q + 1], owner,
                              chosen[i], 0, lo, hi, n)  # fmt: skip
        if splits > extra[q]:
            return -np.inf
    pooled, smin, smax = 0, np.inf, 0.0
    for i in range(depth, nl):
        q = order[i]
        pooled += min(extra[q], gaps[q])
        prev_o = -1
        for p in range(ist[q], ist[q + 1]):
            o = owner[p]
            if o < 0:
                continue
            if o != prev_o:
                lo[n] = pb[p] - pa[p]
                hi[n] = ob[o] - oa[o]
                n += 1
                prev_o = o
            else:
                lo[n - 1] = min(lo[n - 1], pb[p] - pa[p])
            if gaps[q] > 0:
                smin = min(smin, pb[p] - pa[p])
        if gaps[q] > 0:
            smax = max(smax, _extent(oa, ob, ost[q], ost[q + 1], ist[q], ist[q + 1], pa, pb,
                                     owner))  # fmt: skip
    if pooled == 0:
        smin, smax = 0.0, 0.0
    lo[n], hi[n], lo[n + 1], hi[n + 1] = smin, max(smax, smin), 0.0, gfree
    for q in range(n + 2):
        pos[2 * q] = lo[q]
        pos[2 * q + 1] = hi[q]
    srt = np.argsort(pos[: 2 * (n + 2)])
    best = -np.inf
    for ns in (0, pooled):
        for nf in (0, free):
            w[n] = float(ns)
            w[n + 1] = float(nf)
            best = max(best, _sup_w(lo, hi, w, n + 2, srt, a, b, pos))
    w[n] = 1.0
    w[n + 1] = 1.0
    return best


def split_bound(oa, ob, ost, pa, pb, ist, owner, extra, gaps, nb, lo, hi, w, n_fixed, gfree, a,
                b, pos, cut, nodes):  # fmt: skip
    """The maximum of Eq. 1 over every choice of splits of the uncertain lines (``extra > 0``),
    bounded by a branch and bound of at most ``nodes`` nodes (module doc); ``cut``: a value
    at which the caller discards the box anyway (nodes at most it are not branched)."""
    order = np.empty(nb, dtype=np.int64)
    key = np.empty(nb)
    nd, nl, free = 0, 0, 0
    for q in range(nb):  # the branched lines first (longest split group first), then the rest
        if extra[q] > 0 and 0 < gaps[q] <= MAX_GAPS:
            order[nd] = q
            key[nd] = -_extent(oa, ob, ost[q], ost[q + 1], ist[q], ist[q + 1], pa, pb, owner)
            nd += 1
    srt = np.argsort(key[:nd])
    tmp = order[:nd].copy()
    for i in range(nd):
        order[i] = tmp[srt[i]]
    nl = nd
    for q in range(nb):
        if extra[q] > 0:
            free += extra[q]
            if not (0 < gaps[q] <= MAX_GAPS):
                order[nl] = q
                nl += 1
    chosen = np.zeros(nd + 1, dtype=np.int64)
    root = _node(oa, ob, ost, pa, pb, ist, owner, extra, gaps, order, nl, 0, chosen, lo, hi, w,
                 n_fixed, free, gfree, a, b, pos)  # fmt: skip
    if nd == 0 or root <= cut:
        return root
    # a stack of nodes (depth, the choice of line order[depth - 1], bound), depth first
    cap = nd * ((1 << MAX_GAPS) + 1) + 2
    s_depth = np.empty(cap, dtype=np.int64)
    s_mask = np.empty(cap, dtype=np.int64)
    s_bound = np.empty(cap)
    top = 0
    s_depth[0], s_mask[0], s_bound[0] = 0, 0, root
    top = 1
    best, settled, used = -np.inf, -np.inf, 0
    vals = np.empty(1 << MAX_GAPS)
    while top > 0:
        top -= 1
        depth, bound = s_depth[top], s_bound[top]
        if depth > 0:
            chosen[depth - 1] = s_mask[top]
        if bound <= max(best, cut):
            settled = max(settled, bound)
            continue
        if depth == nd:  # every branched line chosen: the node is exact for them
            best = max(best, bound)
            continue
        if used >= nodes:
            top += 1  # put it back: the nodes left bound the rest
            break
        q = order[depth]
        nm = 1 << gaps[q]
        for m in range(nm):
            chosen[depth] = m
            vals[m] = _node(oa, ob, ost, pa, pb, ist, owner, extra, gaps, order, nl, depth + 1,
                            chosen, lo, hi, w, n_fixed, free, gfree, a, b, pos)  # fmt: skip
            used += 1
        for m in np.argsort(vals[:nm]):  # the best child on top of the stack
            s_depth[top], s_mask[top], s_bound[top] = depth + 1, m, vals[m]
            top += 1
    out = max(best, settled)
    for i in range(top):
        out = max(out, s_bound[i])
    return min(out, root)


def prepare() -> None:
    """Swap this module's helpers for their numba versions (before a caller compiles)."""
    kernel._compiled()
    jit_globals(globals(), ("_extent", "_line_segments", "_node", "_sup_w"))
