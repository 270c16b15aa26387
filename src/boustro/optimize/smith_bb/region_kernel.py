"""The per-box work of the Eq. 1 branch and bound on a region (shell and holes; numba).

Lines and layouts as in :mod:`.kernel`. A line meets a set of closed rings in intervals found
by pairing its sorted crossings even-odd (:func:`_intervals`, ``O(E + crossings log)``); the
exact value of a layout is Eq. 1 over the real region's intervals (its segments).

For a box, the rigidly moved region ``S`` lies between the inner set ``I`` and the outer set
``O`` of the sandwich; per line (docs/global_optimum.md, "Concave areas and holes"):

* every S-segment lies in one O-component ``o``; every I-piece lies in one S-segment, so the
  segment count is at least ``r`` = the O-components holding I-length;
* the count is at most half the boundary points of ``S`` on the line, and each h-monotone
  chain of the real boundary (edges whose direction stays on one side of the lines for every
  angle of the box) meets the line at most once after the motion, if its h-range grown by
  ``eps`` holds the line (:func:`_chain_counts`): ``u``;
* with ``u = r`` each ``o`` holding pieces holds one segment, of length between the span of
  its pieces and ``|o|``; otherwise the pieces of each ``o`` are grouped by the segments
  (every split point between two pieces tried, at most ``u - r`` splits), a group's length lies
  between its pieces' span and the gap to its neighbours, and up to ``u - r - splits`` free
  segments (holding no piece) lie in gaps, of length at most the longest gap ``G``.

Eq. 1 with ``f`` free segments of one length ``y``: their share ``t = f / (n + f)`` moves the
mean linearly and the variance concavely (``(1 - t) V + t (1 - t) (m - y)^2``), so Eq. 1 is
convex in ``t`` and the best count of free segments is none or all of them.

Eq. 1 is concave in the lengths for a fixed count: each choice is maximised exactly
(:func:`_sup_w`, the convex kernel's closed form with multiplicities), the bound is the largest;
beyond :data:`MAX_CHOICES` choices they are pooled and branched (:mod:`.region_splits`).
"""

from __future__ import annotations

import math
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..._jit import compiled
from . import kernel, region_splits, region_strips
from .kernel import _sup_w, lines_range
from .region_chains import _chains, chain_bound, edge_lengths, prepare
from .region_splits import _line_segments, split_bound, split_nodes
from .region_strips import strip_intervals

__all__ = ["region_bounds", "region_nodes", "region_values", "ring_starts"]

#: Most split choices enumerated per box (2^gaps), beyond it :func:`.region_splits.split_bound`.
MAX_CHOICES = 8
#: A sure line's segment whose length interval is wider than this many ``eps`` (the sandwich
#: gives about 4 to 8) is left to the chain bound (:mod:`.region_chains`).
LOOSE = 16.0
#: Inner pieces of a strip shorter than this many strip half widths are dropped (but the
#: longest of each outer component; :func:`.region_strips._prune`).
KEEP = 4.0
#: Added to every box bound (rounding of the closed forms).
BOUND_SLACK = 1e-10


def _first_line(lo, d, s, k0):
    """The first line ``k >= k0`` with ``d + k s >= lo`` (exactly, as the crossing rule
    ``(h1 <= c) != (h2 <= c)`` holds for ``min(h1, h2) <= c < max(h1, h2)``)."""
    k = max(math.ceil((lo - d) / s), k0)
    while k > k0 and d + (k - 1) * s >= lo:
        k -= 1
    while d + k * s < lo:
        k += 1
    return k


def _intervals(xy, cs, sn, d, s, k0, nb):
    """``(start (nb + 1,), lo, hi)``: the intervals of the rings ``xy`` on each line (line
    ``k0 + b`` holds intervals ``start[b]:start[b + 1]``, sorted)."""
    cnt = np.zeros(nb + 1, dtype=np.int64)
    ne = xy.shape[0]
    hit = np.empty(ne, dtype=np.int64)  # the edges crossing a line, and their first line
    first = np.empty(ne, dtype=np.int64)
    nh = 0
    inv = 1.0 / s
    for i in range(ne):
        h1 = -sn * xy[i, 0] + cs * xy[i, 1]
        h2 = -sn * xy[i, 2] + cs * xy[i, 3]
        # most edges cross no line: no whole number within a margin (far above the rounding
        # of d + k s, relative to the line index: raw UTM coordinates reach 1e8) of
        # [(min - d) / s, (max - d) / s]
        lo, hi = (min(h1, h2) - d) * inv, (max(h1, h2) - d) * inv
        margin = 1e-9 + 1e-14 * (abs(lo) + abs(hi))
        if math.ceil(lo - margin) > hi + margin:
            continue
        k = _first_line(min(h1, h2), d, s, k0)
        if k < k0 + nb and (h1 <= d + k * s) != (h2 <= d + k * s):
            hit[nh], first[nh] = i, k
            nh += 1
        while k < k0 + nb and (h1 <= d + k * s) != (h2 <= d + k * s):
            cnt[k - k0 + 1] += 1
            k += 1
    for q in range(nb):
        cnt[q + 1] += cnt[q]
    t = np.empty(cnt[nb])
    fill = cnt[:nb].copy()
    for e in range(nh):
        i = hit[e]
        x1, y1, x2, y2 = xy[i, 0], xy[i, 1], xy[i, 2], xy[i, 3]
        h1 = -sn * x1 + cs * y1
        h2 = -sn * x2 + cs * y2
        t1 = cs * x1 + sn * y1
        t2 = cs * x2 + sn * y2
        k = first[e]
        while k < k0 + nb and (h1 <= d + k * s) != (h2 <= d + k * s):
            c = d + k * s
            j = k - k0
            t[fill[j]] = t1 + (c - h1) * (t2 - t1) / (h2 - h1)
            fill[j] += 1
            k += 1
    start = np.zeros(nb + 1, dtype=np.int64)
    for q in range(nb):
        start[q + 1] = start[q] + (cnt[q + 1] - cnt[q]) // 2
    lo = np.empty(start[nb])
    hi = np.empty(start[nb])
    for q in range(nb):
        for i in range(cnt[q] + 1, cnt[q + 1]):  # insertion sort: few crossings a line
            x = t[i]
            j = i - 1
            while j >= cnt[q] and t[j] > x:
                t[j + 1] = t[j]
                j -= 1
            t[j + 1] = x
        for j in range(start[q + 1] - start[q]):
            lo[start[q] + j] = t[cnt[q] + 2 * j]
            hi[start[q] + j] = t[cnt[q] + 2 * j + 1]
    return start, lo, hi


def _values(xy, cs, sn, d, s, k0, nb, a, b, tiny):
    """Eq. 1 over the segments longer than ``tiny`` of each layout (``-inf`` without one)."""
    m = cs.shape[0]
    out = np.empty(m)
    for i in range(m):
        _, lo, hi = _intervals(xy, cs[i], sn[i], d[i], s, k0, nb)
        n, s1, s2 = 0, 0.0, 0.0
        for j in range(lo.shape[0]):
            length = hi[j] - lo[j]
            if length > tiny:
                n += 1
                s1 += length
                s2 += length * length
        if n == 0:
            out[i] = -np.inf
        else:
            mean = s1 / n
            out[i] = a * mean + b * (1.0 - math.sqrt(max(s2 / n - mean * mean, 0.0)))
    return out


def _chain_counts(xy, rings, cs, sn, sdelta, d, s, eps, k0, nb, cnt):
    """``cnt[b]``: h-monotone chains of the real rings (or single edges that may turn parallel
    to the lines; :func:`.region_chains._chains`) whose h-range grown by ``eps`` holds line
    ``k0 + b`` (:func:`_count_chains`)."""
    ci = np.empty((xy.shape[0], 4), dtype=np.int64)
    cf = np.empty((xy.shape[0], 2))
    nch = _chains(xy, rings, cs, sn, sdelta, edge_lengths(xy), ci, cf)
    _count_chains(cf, nch, d, s, eps, k0, nb, cnt)


def _count_chains(cf, nch, d, s, eps, k0, nb, cnt):
    """``cnt[b]``: the chains (h-ranges ``cf[:nch]``) whose h-range grown by ``eps`` holds line
    ``k0 + b``: at least the crossings of every moved region's boundary with the line (the
    half-open rule crosses a monotone chain at most once, a straight edge at most once, an edge
    along the line never)."""
    for q in range(nb):
        cnt[q] = 0
    for m in range(nch):
        lo_h, hi_h = cf[m, 0], cf[m, 1]
        ka = max(math.floor((lo_h - eps - d) / s), k0)
        kb = min(math.ceil((hi_h + eps - d) / s), k0 + nb - 1)
        for k in range(ka, kb + 1):
            c = d + k * s
            if lo_h - eps <= c <= hi_h + eps:
                cnt[k - k0] += 1


def _owners(oa, ob, o0, o1, pa, pb, p0, p1, tiny, owner):
    """``owner[p]``: the O-component holding piece ``p`` (``-1``: a piece of length ``<= tiny``,
    ignored), components widened to hold their pieces; ``False`` if one has none (rounding)."""
    j = o0
    for p in range(p0, p1):
        owner[p] = -1
        if pb[p] - pa[p] <= tiny:
            continue
        mid = 0.5 * (pa[p] + pb[p])
        while j < o1 and ob[j] < mid:
            j += 1
        if j >= o1 or oa[j] > mid:
            return False
        owner[p] = j
        oa[j] = min(oa[j], pa[p])
        ob[j] = max(ob[j], pb[p])
    return True


def _bound(in_xy, out_xy, real_xy, rings, ln, cs, sn, sdelta, eta, d, s, eps, k0, nb, a, b,
           tiny, margin, cut, pos, radius, nodes):  # fmt: skip
    """The bound of one box: from the strips of the real boundary if ``radius >= 0``
    (:mod:`.region_strips`; lengths in ``t``, so ``(a + b) (1 / cos delta - 1) top`` is added,
    and the cut is lowered by it), else from the sandwich ``in_xy, out_xy``."""
    if radius >= 0:
        ost, oa, ob, ist, pa, pb = strip_intervals(real_xy, cs, sn, d, s, k0, nb, radius,
                                                   sdelta, eta, KEEP)  # fmt: skip
    else:
        ost, oa, ob = _intervals(out_xy, cs, sn, d, s, k0, nb)
        ist, pa, pb = _intervals(in_xy, cs, sn, d, s, k0, nb)
    top = 0.0
    for j in range(oa.shape[0]):
        top = max(top, ob[j] - oa[j])
    if oa.shape[0] == 0:
        return -np.inf
    if pos.shape[0] < 2 * (pa.shape[0] + 8):
        pos = np.empty(2 * (pa.shape[0] + 8))
    stretch = 0.0
    if radius >= 0:
        # a layout's lengths are the t-lengths times 1 / cos(alpha): mean and std (the chain
        # bound mixes t-lengths with its own) move by at most (1 / cos(delta) - 1) top each
        stretch = (a + b) * top * (1.0 / math.sqrt(max(1.0 - sdelta * sdelta, 1e-300)) - 1.0)
    return stretch + _bound_of(oa, ob, ost, pa, pb, ist, real_xy, rings, ln, cs, sn, sdelta, eta,
                               d, s, eps, k0, nb, a, b, tiny, margin, cut - stretch, pos,
                               top, nodes)  # fmt: skip


def _bound_of(oa, ob, ost, pa, pb, ist, real_xy, rings, ln, cs, sn, sdelta, eta, d, s, eps, k0,
              nb, a, b, tiny, margin, cut, pos, top, nodes):  # fmt: skip
    """The bound of one box from its lines' outer and inner intervals (module doc); ``ln``:
    the real edges' lengths (:func:`.region_chains.edge_lengths`); ``nodes``: of the split
    choices' branch and bound (:func:`.region_splits.split_bound`)."""
    crude = a * top + b
    cnt = np.empty(nb, dtype=np.int64)
    ci = np.empty((real_xy.shape[0], 4), dtype=np.int64)  # the chains, for the counts and
    cf = np.empty((real_xy.shape[0], 2))  # the chain bound
    nch = _chains(real_xy, rings, cs, sn, sdelta, ln, ci, cf)
    _count_chains(cf, nch, d, s, eps, k0, nb, cnt)
    owner = np.empty(pa.shape[0], dtype=np.int64)
    extra = np.zeros(nb, dtype=np.int64)
    gaps = np.zeros(nb, dtype=np.int64)
    size = pa.shape[0] + 3
    lo = np.empty(size)
    hi = np.empty(size)
    w = np.ones(size)
    n_fixed, total_gaps, gfree = 0, 0, 0.0
    unc = np.empty(nb, dtype=np.int64)  # the lines left to the chain bound
    clo = np.empty(size)  # and the segments of the others (a sure line's, if tight)
    chi = np.empty(size)
    n_unc, n_sure = 0, 0
    for q in range(nb):
        if not _owners(oa, ob, ost[q], ost[q + 1], pa, pb, ist[q], ist[q + 1], tiny, owner):
            return crude
        r, held, prev_o = 0, 0, -1
        for p in range(ist[q], ist[q + 1]):
            if owner[p] >= 0:
                held += 1
                if owner[p] != prev_o:
                    r += 1
                    prev_o = owner[p]
        u = cnt[q] // 2
        if u <= r:  # one segment per component holding pieces
            n0 = n_fixed
            n_fixed, _, _ = _line_segments(
                oa, ob, ost[q], ost[q + 1], pa, pb, ist[q], ist[q + 1], owner, 0, 0, lo, hi,
                n_fixed)  # fmt: skip
            loose = False
            for j in range(n0, n_fixed):
                loose = loose or hi[j] - lo[j] > LOOSE * eps
            if loose:  # e.g. a line along an edge: the chains may fix its segments
                unc[n_unc] = q
                n_unc += 1
            else:
                for j in range(n0, n_fixed):
                    clo[n_sure], chi[n_sure] = lo[j], hi[j]
                    n_sure += 1
            continue
        extra[q] = u - r
        unc[n_unc] = q
        n_unc += 1
        gaps[q] = held - r
        total_gaps += held - r
        # the longest gap on the line: between pieces, or a component's ends and its pieces
        for o in range(ost[q], ost[q + 1]):
            left = oa[o]
            for p in range(ist[q], ist[q + 1]):
                if owner[p] == o:
                    gfree = max(gfree, pa[p] - left)
                    left = pb[p]
            gfree = max(gfree, ob[o] - left)
    if total_gaps > 30 or (1 << total_gaps) > MAX_CHOICES:  # branched (.region_splits)
        old = split_bound(oa, ob, ost, pa, pb, ist, owner, extra, gaps, nb, lo, hi, w, n_fixed,
                          gfree, a, b, pos, cut, nodes)  # fmt: skip
    else:
        old = _enumerated(oa, ob, ost, pa, pb, ist, owner, extra, total_gaps, gfree, nb, lo, hi,
                          w, n_fixed, a, b, pos)  # fmt: skip
    if cut == np.inf:  # the chain bound alone (tests)
        old = np.inf
    elif old <= cut:  # the box is discarded anyway
        return old
    # the chain bound (segment ends tied to the chains, .region_chains) where it applies
    return min(old, chain_bound(real_xy, ci, cf, nch, cs, sn, sdelta, eta, d, s, eps, k0, unc,
                                n_unc, clo, chi, n_sure, a, b, tiny, margin))  # fmt: skip


def _enumerated(oa, ob, ost, pa, pb, ist, owner, extra, total_gaps, gfree, nb, lo, hi, w, n_fixed,
                a, b, pos):  # fmt: skip
    """The bound with every choice of splits on the uncertain lines (module doc)."""
    best = -np.inf
    for mask in range(1 << total_gaps):
        n, g, free, ok = n_fixed, 0, 0, True
        for q in range(nb):
            if extra[q] == 0:
                continue
            n, g, splits = _line_segments(
                oa, ob, ost[q], ost[q + 1], pa, pb, ist[q], ist[q + 1], owner, mask, g, lo, hi,
                n)  # fmt: skip
            if splits > extra[q]:
                ok = False
                break
            free += extra[q] - splits
        if not ok:
            continue
        lo[n] = 0.0
        hi[n] = gfree
        for q in range(n + 1):
            pos[2 * q] = lo[q]
            pos[2 * q + 1] = hi[q]
        order = np.argsort(pos[: 2 * (n + 1)])
        for f in (0, free):  # the best count of free segments is none or all (module doc)
            w[n] = float(f)
            best = max(best, _sup_w(lo, hi, w, n + 1, order, a, b, pos))
        w[n] = 1.0
    return best


def _bounds(in_xy, out_xy, real_xy, rings, cs, sn, sdelta, eta, d, s, eps, k0, nb, a, b, tiny,
            margin, cut, slack, radius, nodes):  # fmt: skip
    m = cs.shape[0]
    out = np.empty(m)
    pos = np.empty(2 * (max(in_xy.shape[0], 2 * real_xy.shape[0]) + 4) * nb + 8)
    ln = edge_lengths(real_xy)
    for i in range(m):
        v = _bound(in_xy, out_xy, real_xy, rings, ln, cs[i], sn[i], sdelta[i], eta[i], d[i], s,
                   eps[i], k0, nb, a, b, tiny, margin, cut - 2.0 * slack, pos, radius,
                   nodes)  # fmt: skip
        out[i] = v + slack
    return out


@cache
def _compiled() -> tuple[Any, Any]:
    """``(_bounds, _values)`` compiled by numba (cached on disk), or plain Python without it."""
    # first _sup_w's own helpers (kernel's _g) compiled where it looks them up, and those of
    # chain_bound (.region_chains), split_bound and strip_intervals
    before = (kernel._compiled, prepare, region_splits.prepare, region_strips.prepare)
    helpers = ("_first_line", "_intervals", "_chains", "edge_lengths", "_count_chains",
               "_chain_counts", "_sup_w", "_owners",
               "_line_segments", "_enumerated", "chain_bound",
               "split_bound", "strip_intervals", "_bound_of", "_bound")  # fmt: skip
    return compiled(globals(), ("_bounds", "_values"), helpers, before)


def ring_starts(rings: list[NDArray[np.float64]]) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """``(xy (E, 4), starts (R + 1,))``: the edges of closed rings and where each ring starts."""
    rows = [np.concatenate([r, np.roll(r, -1, axis=0)], axis=1) for r in rings]
    starts = np.cumsum([0] + [len(r) for r in rings]).astype(np.int64)
    return np.ascontiguousarray(np.concatenate(rows)), starts


def region_bounds(
    inner: NDArray[np.float64],
    outer: NDArray[np.float64],
    real: tuple[NDArray[np.float64], NDArray[np.int64]],
    theta: NDArray[np.float64],
    delta: NDArray[np.float64],
    d: NDArray[np.float64],
    eps: NDArray[np.float64],
    spacing: float,
    a: float,
    b: float,
    tiny: float,
    eta: NDArray[np.float64] | None = None,
    margin: float = -1.0,
    cut: float = math.inf,
    radius: float = -1.0,
) -> NDArray[np.float64]:
    """``(m,)`` an upper bound of Eq. 1 over the segments of every rigid image of the region
    ``real`` (:func:`ring_starts`) moved by at most ``eps[i]`` (rotation at most ``delta[i]``,
    shift across the lines at most ``eta[i]``, default ``eps[i]``) that lies between the edge
    sets ``inner`` and ``outer``, seen by the lines of layout ``i``. ``margin``: how near a
    vertex a line passes where it cuts a segment of length at most ``tiny``
    (:func:`.region_chains.near_margin`; negative: unknown). A box whose first bound is at most
    ``cut`` (it will be discarded) skips the chain bound; ``cut = inf``: the chain bound alone
    (``inf`` where it does not apply; for tests). ``radius >= 0`` (every vertex of ``real``
    within it of 0): the lines' intervals from strips of the real boundary
    (:mod:`.region_strips`), ``inner`` and ``outer`` unread. The split choices are branched
    (:func:`.region_splits.split_nodes`) unless more lines cross ``real``."""
    th = np.ascontiguousarray(theta, dtype=np.float64)
    sdelta = np.sin(np.minimum(np.asarray(delta, dtype=np.float64), math.pi / 2))
    eta = eps if eta is None else np.minimum(eta, eps)
    nodes = region_nodes(real[0], spacing)
    if radius >= 0:  # the lines that a strip of the real region can reach
        k0, nb = lines_range(real[0], spacing)
        cd = np.sqrt(np.maximum(1.0 - sdelta * sdelta, 1e-300))
        half = float(np.max((radius * (1 - cd) + eta + radius * sdelta) / cd, initial=0.0))
        grow = math.ceil(half / spacing) + 1
        k0, nb = k0 - grow, nb + 2 * grow
        inner = outer = np.zeros((0, 4))
    else:
        k0, nb = lines_range(outer, spacing)
    fn = _compiled()[0]
    return fn(np.ascontiguousarray(inner), np.ascontiguousarray(outer), real[0], real[1],
              np.cos(th), np.sin(th), sdelta, np.ascontiguousarray(eta, dtype=np.float64),
              np.ascontiguousarray(d, dtype=np.float64),
              float(spacing), np.ascontiguousarray(eps, dtype=np.float64), k0, nb, float(a),
              float(b), float(tiny), float(margin), float(cut), BOUND_SLACK,
              float(radius), nodes)  # fmt: skip


def region_nodes(real_xy: NDArray[np.float64], spacing: float) -> int:
    """The nodes of the split choices' branch and bound in every box of the region of edges
    ``real_xy`` (normalised frame) at ``spacing`` (same units):
    :func:`.region_splits.split_nodes` of the lines across it (0: the pooled bound)."""
    return split_nodes(lines_range(real_xy, spacing)[1])


def region_values(
    xy: NDArray[np.float64],
    theta: NDArray[np.float64],
    d: NDArray[np.float64],
    spacing: float,
    a: float,
    b: float,
    tiny: float,
) -> NDArray[np.float64]:
    """``(m,)`` Eq. 1 over the segments (longer than ``tiny``) of the region of edges ``xy``."""
    k0, nb = lines_range(xy, spacing)
    th = np.ascontiguousarray(theta, dtype=np.float64)
    fn = _compiled()[1]
    return fn(np.ascontiguousarray(xy), np.cos(th), np.sin(th),
              np.ascontiguousarray(d, dtype=np.float64), float(spacing), k0, nb, float(a),
              float(b), float(tiny))  # fmt: skip
