"""The segments a box forces on its lines: crossings of the strips by the real boundary (numba).

With the strips of :mod:`.region_strips` (lines ``t``-parametrised in the box centre's frame,
line ``k`` of every layout of the box inside the strip ``c - A <= h <= c + A`` wherever a point
of the region can lie), a stretch of a ring that runs from a point strictly above the strip to
one strictly below it (or back) without leaving the strip in between, a *traversal*, is crossed
by every layout's line an odd number of times (half-open rule: the sides of its two ends
differ), so at least once, at a ``t`` within the stretch's ``t``-range (the ``t``-ranges of its
edges clipped to the strip). Distinct traversals share no edge, so they hold distinct crossings,
and each crossing ends one of the line's segments (the evaluator pairs the sorted crossings).
That range is connected and lies in the outer set (the clipped edges' ranges are part of it),
so in one outer component ``o``, and it meets no inner piece (the pieces leave out the clipped
ranges). Along a line the region's membership is "out" just outside ``o`` and "in" on each
piece, so the crossings in a gap of ``o`` (docs/global_optimum.md, section 10, "Forced
segments") number

* in a component without pieces: an even count, at least ``k`` (its traversals), i.e. at
  least ``ceil(k / 2)`` segments, each inside ``o``;
* before its first piece or after its last: an odd count at least ``k``, i.e. one end of the
  piece's segment and at least ``k // 2`` segments holding no piece, inside that gap;
* between two pieces: an even count at least ``k``; if ``k >= 1`` the two pieces lie in
  different segments (a forced split) and at least ``(k - 1) // 2`` segments lie in the gap.

Those free segments are *forced*: :mod:`.region_kernel` adds them with a length in ``[0, gap]``
(their own gap, not the line's longest) and takes them off the line's ``u - r``; the forced
splits restrict the split choices (:mod:`.region_splits`).

Uncounted segments: the evaluator drops segments of at most ``tiny``. Such a segment has two
ends within ``tiny``, on two edges that share a vertex ``v`` (the region's minimum clearance is
above ``2 tiny``), so the line passes within ``2 tiny / f_v`` of ``v`` (``f_v`` the sine of its
angle if acute; :func:`.region_chains.near_margin`), a layout the bound leaves out when that is
at most :data:`.region_chains.MARGIN_CAP`. A traversal with an edge at a vertex sharper than that
(``sharp``: :func:`.region_chains.sharp_edges`) forces nothing.
"""

from __future__ import annotations

import numpy as np

from ..._jit import jit_globals
from .region_strips import _first_strip, meets_no_strip

__all__ = ["forced_segments", "prepare", "traversals"]


def _side(h, low, high):
    """``+1`` strictly above the strip ``[low, high]``, ``-1`` strictly below, 0 in it."""
    if h > high:
        return 1
    if h < low:
        return -1
    return 0


def _cut(h1, h2, t1, t2, at):
    """The ``t`` where the edge from ``(h1, t1)`` to ``(h2, t2)`` reaches ``h = at``."""
    return t1 + (at - h1) * (t2 - t1) / (h2 - h1)


def traversals(xy, rings, sharp, cs, sn, c, low, high, widest, d, s, k0, nb):
    """``(fst, flo, fhi)``: per line ``q`` the ``t``-ranges ``flo/fhi[fst[q]:fst[q + 1]]`` of
    the traversals (module doc) of the strips ``[low[q], high[q]]`` (lines at ``c[q] = d + (k0
    + q) s``, half widths at most ``widest``) by the rings of edges ``xy`` (ring ``r``: edges
    ``rings[r]:rings[r + 1]``, edge ``i`` from vertex ``i`` to the next), in the box centre's
    frame ``cs, sn``; those with a ``sharp`` edge left out. Each ring is walked once from its
    highest vertex (strictly above every strip it can traverse)."""
    ne = xy.shape[0]
    inv = 1.0 / s
    cap = ne + 8
    fq = np.empty(cap, dtype=np.int64)
    ft = np.empty((cap, 2))
    nf = 0
    st = np.zeros(nb, dtype=np.int64)  # the side of the last point strictly outside; 0: skip
    tmn = np.empty(nb)
    tmx = np.empty(nb)
    bad = np.zeros(nb, dtype=np.bool_)
    for r in range(rings.shape[0] - 1):
        r0, r1 = rings[r], rings[r + 1]
        if r1 <= r0:
            continue
        top, hmax = r0, -np.inf
        for i in range(r0, r1):
            h = -sn * xy[i, 0] + cs * xy[i, 1]
            if h > hmax:
                top, hmax = i, h
        for q in range(nb):
            st[q] = 1 if high[q] < hmax else 0
        for j in range(r1 - r0):
            i = r0 + (top - r0 + j) % (r1 - r0)
            h1 = -sn * xy[i, 0] + cs * xy[i, 1]
            h2 = -sn * xy[i, 2] + cs * xy[i, 3]
            a, b = min(h1, h2), max(h1, h2)
            if meets_no_strip(a, b, widest, d, inv):  # most edges: their lines keep their state
                continue
            q = _first_strip(c, nb, a - widest, d, s, k0)
            while q < nb and c[q] - widest <= b:
                if st[q] == 0 or low[q] > b or high[q] < a:
                    q += 1
                    continue
                t1 = cs * xy[i, 0] + sn * xy[i, 1]
                t2 = cs * xy[i, 2] + sn * xy[i, 3]
                s1 = _side(h1, low[q], high[q])
                s2 = _side(h2, low[q], high[q])
                if s1 != 0:  # a stretch starts: the edge enters the strip
                    x = _cut(h1, h2, t1, t2, high[q] if s1 > 0 else low[q])
                    tmn[q], tmx[q], bad[q] = x, x, sharp[i]
                else:
                    bad[q] = bad[q] or sharp[i]
                if s2 != 0:  # it leaves the strip
                    x = _cut(h1, h2, t1, t2, high[q] if s2 > 0 else low[q])
                    tmn[q], tmx[q] = min(tmn[q], x), max(tmx[q], x)
                    if s2 != st[q] and not bad[q]:
                        if nf == cap:  # grow
                            cap *= 2
                            fq2 = np.empty(cap, dtype=np.int64)
                            ft2 = np.empty((cap, 2))
                            fq2[:nf], ft2[:nf] = fq[:nf], ft[:nf]
                            fq, ft = fq2, ft2
                        fq[nf], ft[nf, 0], ft[nf, 1] = q, tmn[q], tmx[q]
                        nf += 1
                    st[q] = s2
                else:
                    tmn[q], tmx[q] = min(tmn[q], t2), max(tmx[q], t2)
                q += 1
    fst = np.zeros(nb + 1, dtype=np.int64)
    for e in range(nf):
        fst[fq[e] + 1] += 1
    for q in range(nb):
        fst[q + 1] += fst[q]
    flo = np.empty(nf)
    fhi = np.empty(nf)
    fill = fst[:nb].copy()
    for e in range(nf):
        q = fq[e]
        flo[fill[q]], fhi[fill[q]] = ft[e, 0], ft[e, 1]
        fill[q] += 1
    return fst, flo, fhi


def _inside(flo, fhi, f0, f1, left, right):
    """How many of the ranges ``flo/fhi[f0:f1]`` lie in ``[left, right]``."""
    k = 0
    for f in range(f0, f1):
        if left <= flo[f] and fhi[f] <= right:
            k += 1
    return k


def forced_segments(oa, ob, o0, o1, pa, pb, p0, p1, owner, flo, fhi, f0, f1, lo, hi, n):
    """The forced segments of one line (module doc) from its traversals ``flo/fhi[f0:f1]``:
    the free ones appended to ``lo, hi`` from ``n`` (length in ``[0, their gap]``); returns
    ``(n, count, need)``, ``need`` the forced splits as a mask of the line's split points
    (bit ``g``: the ``g``-th gap between two pieces of one component, as
    :func:`.region_splits._line_segments` counts them)."""
    count, need, g = 0, 0, 0
    if f1 <= f0:
        return n, count, need
    for o in range(o0, o1):
        prev = -1
        for p in range(p0, p1):
            if owner[p] != o:
                continue
            if prev < 0:  # before the first piece: k // 2 free segments
                k = _inside(flo, fhi, f0, f1, oa[o], pa[p]) // 2
            else:  # between two pieces: a split, and (k - 1) // 2 free segments
                k = _inside(flo, fhi, f0, f1, pb[prev], pa[p])
                if k > 0:
                    need |= 1 << g
                    k = (k - 1) // 2
                g += 1
            for _ in range(k):
                lo[n], hi[n] = 0.0, pa[p] - (oa[o] if prev < 0 else pb[prev])
                n += 1
            count += k
            prev = p
        if prev < 0:  # no piece: ceil(k / 2) segments
            k = (_inside(flo, fhi, f0, f1, oa[o], ob[o]) + 1) // 2
            gap = ob[o] - oa[o]
        else:  # after the last piece: k // 2
            k = _inside(flo, fhi, f0, f1, pb[prev], ob[o]) // 2
            gap = ob[o] - pb[prev]
        for _ in range(k):
            lo[n], hi[n] = 0.0, gap
            n += 1
        count += k
    return n, count, need


def prepare() -> None:
    """Swap this module's helpers for their numba versions (before a caller compiles)."""
    helpers = ("meets_no_strip", "_first_strip", "_side", "_cut", "traversals", "_inside",
               "forced_segments")  # fmt: skip
    jit_globals(globals(), helpers)
