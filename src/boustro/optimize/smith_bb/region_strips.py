"""A region's inner and outer intervals on a box's lines from strips of the real boundary
(numba), tighter than the buffered sandwich's (docs/global_optimum.md, section 10, "Strips").

A box's layout ``theta + alpha`` (``|alpha| <= delta``), offset ``d + eta'`` (``|eta'| <=
eta``) seen in the centre's frame (``t`` along, ``h`` across the centre's lines, the vertex
mean at 0): its line ``k`` is the set ``h = c + (c (1 - cos alpha) + eta' + t sin alpha) /
cos alpha`` (``c = d + k s``), a straight line that, wherever a point of the region can lie
(``|t| <= T``), stays within the strip ``|h - c| <= A = (|c| (1 - cos delta) + eta + T sin
delta) / cos delta``. Parametrised by ``t`` (exact: the layout's own along coordinate is ``t /
cos alpha`` plus a constant), the line's intersection with the region therefore lies in

* the outer set: the ``t`` where the vertical segment ``{t} x [c - A, c + A]`` meets the
  region, the projection of the boundary of ``region ∩ strip``: the region's intervals on the
  strip's two edges ``h = c +- A`` and the ``t``-ranges of the boundary's edges clipped to the
  strip;

and holds

* the inner set: the ``t`` where that segment lies in the region: both ends in it and no
  boundary edge crossing it (the region's intervals on both strip edges, intersected, less the
  clipped edges' ``t``-ranges).

A disc of radius ``eps = delta R + eta`` (the sandwich) holds the vertical segment (``A <=
eps`` up to ``O(delta^2)``), so these intervals lie within the sandwich's; where a line crosses
the boundary at a right angle the outer and inner ends meet up to the boundary's wiggle in the
strip, where the sandwich's lie ``2 eps`` apart. Lengths in ``t`` are the layout's times
``cos alpha``: the caller adds ``a (1 / cos delta - 1)`` times the longest outer interval.
``T`` per line: every vertex lies within ``R`` of the vertex mean, so ``T = sqrt(R^2 -
max(|c| - A0, 0)^2)`` with ``A0`` the strip of ``T = R``.
"""

from __future__ import annotations

import math

import numpy as np

from ..._jit import jit_globals

__all__ = ["prepare", "strip_halfwidths", "strip_intervals"]


def strip_halfwidths(c, radius, sdelta, eta, out):
    """``out[q]``: the strip's half width ``A`` of the line at offset ``c[q]`` (module doc)."""
    cd = math.sqrt(max(1.0 - sdelta * sdelta, 0.0))
    for q in range(c.shape[0]):
        a0 = (abs(c[q]) * (1.0 - cd) + eta + radius * sdelta) / cd
        near = max(abs(c[q]) - a0, 0.0)
        t = math.sqrt(max(radius * radius - near * near, 0.0))
        out[q] = ((abs(c[q]) * (1.0 - cd) + eta + t * sdelta) / cd) * (1.0 + 1e-9) + 1e-12


def _crossings(ha, hb, ta, tb, h, nb, cnt_out):
    """``t``: the sorted ``t`` of the rings' crossings with each line ``h[q]`` (``h`` sorted
    ascending; edges from ``(ta, ha)`` to ``(tb, hb)``; half-open rule ``(h1 <= c) != (h2 <=
    c)``), line ``q``'s from ``cnt_out[q]`` to ``cnt_out[q + 1]``."""
    cnt = np.zeros(nb + 1, dtype=np.int64)
    first = np.empty(ha.shape[0], dtype=np.int64)
    for i in range(ha.shape[0]):
        h1, h2 = ha[i], hb[i]
        q = np.searchsorted(h, min(h1, h2))
        first[i] = q
        while q < nb and (h1 <= h[q]) != (h2 <= h[q]):
            cnt[q + 1] += 1
            q += 1
    for q in range(nb):
        cnt[q + 1] += cnt[q]
    t = np.empty(cnt[nb])
    fill = cnt[:nb].copy()
    for i in range(ha.shape[0]):
        h1, h2 = ha[i], hb[i]
        if h1 == h2:
            continue
        t1, t2 = ta[i], tb[i]
        q = first[i]
        while q < nb and (h1 <= h[q]) != (h2 <= h[q]):
            t[fill[q]] = t1 + (h[q] - h1) * (t2 - t1) / (h2 - h1)
            fill[q] += 1
            q += 1
    for q in range(nb):
        t[cnt[q] : cnt[q + 1]] = np.sort(t[cnt[q] : cnt[q + 1]])
    cnt_out[:] = cnt
    return t


def _pieces(ha, hb, ta, tb, c, half, nb):
    """``(start (nb + 1,), lo, hi)``: per line ``q``, the ``t``-ranges of the edges clipped to
    its strip ``|h - c[q]| <= half[q]`` (unsorted; ``c`` ascending)."""
    lo_h = c - half
    hi_h = c + half
    widest = half.max()
    cnt = np.zeros(nb + 1, dtype=np.int64)
    first = np.empty(ha.shape[0], dtype=np.int64)
    for i in range(ha.shape[0]):
        a, b = min(ha[i], hb[i]), max(ha[i], hb[i])
        q = np.searchsorted(c, a - widest)  # strips in c order, their widths vary
        first[i] = q
        while q < nb and c[q] - widest <= b:
            if lo_h[q] <= b and hi_h[q] >= a:
                cnt[q + 1] += 1
            q += 1
    for q in range(nb):
        cnt[q + 1] += cnt[q]
    lo = np.empty(cnt[nb])
    hi = np.empty(cnt[nb])
    fill = cnt[:nb].copy()
    for i in range(ha.shape[0]):
        h1, h2, t1, t2 = ha[i], hb[i], ta[i], tb[i]
        a, b = min(h1, h2), max(h1, h2)
        q = first[i]
        while q < nb and c[q] - widest <= b:
            if lo_h[q] > b or hi_h[q] < a:
                q += 1
                continue
            if h1 == h2:
                u0, u1 = t1, t2
            else:  # the edge's t at the strip's edges, clamped to the edge
                ua = min(max((lo_h[q] - h1) / (h2 - h1), 0.0), 1.0)
                ub = min(max((hi_h[q] - h1) / (h2 - h1), 0.0), 1.0)
                u0 = t1 + ua * (t2 - t1)
                u1 = t1 + ub * (t2 - t1)
            pad = 1e-12 * (1.0 + abs(u0) + abs(u1))
            lo[fill[q]] = min(u0, u1) - pad
            hi[fill[q]] = max(u0, u1) + pad
            fill[q] += 1
            q += 1
    return cnt, lo, hi


def _merge(lo, hi, n, out_lo, out_hi, m):
    """Append the union of the intervals ``lo/hi[:n]`` (sorted by ``lo``) to ``out`` from
    ``m``; returns the new count."""
    j = 0
    while j < n:
        a, b = lo[j], hi[j]
        j += 1
        while j < n and lo[j] <= b:
            b = max(b, hi[j])
            j += 1
        out_lo[m] = a
        out_hi[m] = b
        m += 1
    return m


def strip_intervals(xy, cs, sn, d, s, k0, nb, radius, sdelta, eta, keep):
    """``(ost, oa, ob, ist, pa, pb)``: the outer and inner intervals (module doc) of lines
    ``k0 .. k0 + nb - 1`` of a box (centre ``cs, sn, d``; rotation at most ``asin(sdelta)``,
    shift at most ``eta``) of the region of edges ``xy`` whose vertices lie within ``radius``
    of 0, as :func:`.region_kernel._intervals` gives them (per line sorted, disjoint); inner
    pieces shorter than ``keep`` strip half widths dropped (:func:`_prune`)."""
    c = np.empty(nb)
    for q in range(nb):
        c[q] = d + (k0 + q) * s
    half = np.empty(nb)
    strip_halfwidths(c, radius, sdelta, eta, half)
    # the strips' edges, sorted (the widths vary: an edge of a strip may pass its neighbour's)
    low = c - half
    high = c + half
    lorder = np.argsort(low)
    horder = np.argsort(high)
    ne = xy.shape[0]
    ha = np.empty(ne)
    hb = np.empty(ne)
    ta = np.empty(ne)
    tb = np.empty(ne)
    for i in range(ne):
        ha[i] = -sn * xy[i, 0] + cs * xy[i, 1]
        hb[i] = -sn * xy[i, 2] + cs * xy[i, 3]
        ta[i] = cs * xy[i, 0] + sn * xy[i, 1]
        tb[i] = cs * xy[i, 2] + sn * xy[i, 3]
    lcnt = np.empty(nb + 1, dtype=np.int64)
    hcnt = np.empty(nb + 1, dtype=np.int64)
    lt = _crossings(ha, hb, ta, tb, low[lorder], nb, lcnt)
    ht = _crossings(ha, hb, ta, tb, high[horder], nb, hcnt)
    lrow = np.empty(nb, dtype=np.int64)
    hrow = np.empty(nb, dtype=np.int64)
    for i in range(nb):
        lrow[lorder[i]] = i
        hrow[horder[i]] = i
    pcnt, plo, phi = _pieces(ha, hb, ta, tb, c, half, nb)
    size = lt.shape[0] + ht.shape[0] + plo.shape[0] + 1
    oa = np.empty(size)
    ob = np.empty(size)
    pa = np.empty(size)
    pb = np.empty(size)
    ost = np.zeros(nb + 1, dtype=np.int64)
    ist = np.zeros(nb + 1, dtype=np.int64)
    buf_lo = np.empty(size)
    buf_hi = np.empty(size)
    mo, mi = 0, 0
    for q in range(nb):
        l0, l1 = lcnt[lrow[q]], lcnt[lrow[q] + 1]
        h0, h1 = hcnt[hrow[q]], hcnt[hrow[q] + 1]
        p0, p1 = pcnt[q], pcnt[q + 1]
        # outer: the union of both edges' intervals and the clipped edges' ranges
        n = 0
        for j in range(l0, l1 - 1, 2):
            buf_lo[n], buf_hi[n] = lt[j], lt[j + 1]
            n += 1
        for j in range(h0, h1 - 1, 2):
            buf_lo[n], buf_hi[n] = ht[j], ht[j + 1]
            n += 1
        for j in range(p0, p1):
            buf_lo[n], buf_hi[n] = plo[j], phi[j]
            n += 1
        order = np.argsort(buf_lo[:n])
        sl = buf_lo[:n][order]
        sh = buf_hi[:n][order]
        mo = _merge(sl, sh, n, oa, ob, mo)
        ost[q + 1] = mo
        porder = np.argsort(plo[p0:p1])
        ncut = _merge(plo[p0:p1][porder], phi[p0:p1][porder], p1 - p0, buf_lo, buf_hi, 0)
        mi = _inner(lt, l0, l1, ht, h0, h1, buf_lo, buf_hi, ncut, pa, pb, mi)
        mi = _prune(oa, ob, ost[q], ost[q + 1], pa, pb, ist[q], mi, keep * half[q])
        ist[q + 1] = mi
    return ost, oa[:mo], ob[:mo], ist, pa[:mi], pb[:mi]


def _inner(lt, l0, l1, ht, h0, h1, cut_lo, cut_hi, ncut, pa, pb, m):
    """Append to ``pa, pb`` from ``m`` the inner set of one line: the intervals of the strip's
    two edges (crossings ``lt[l0:l1]``, ``ht[h0:h1]``, paired) intersected, less the cuts (the
    clipped edges' ranges, merged and sorted); returns the new end."""
    i, j = l0, h0
    while i < l1 - 1 and j < h1 - 1:
        a = max(lt[i], ht[j])
        b = min(lt[i + 1], ht[j + 1])
        if a < b:  # [a, b] less the cuts
            left = a
            for k in range(ncut):
                if cut_hi[k] <= left or cut_lo[k] >= b:
                    continue
                if cut_lo[k] > left:
                    pa[m], pb[m] = left, cut_lo[k]
                    m += 1
                left = max(left, cut_hi[k])
            if left < b:
                pa[m], pb[m] = left, b
                m += 1
        if lt[i + 1] < ht[j + 1]:
            i += 2
        else:
            j += 2
    return m


def _prune(oa, ob, o0, o1, pa, pb, p0, p1, short):
    """Drop the inner pieces ``p0:p1`` shorter than ``short`` except the longest of each outer
    component (a subset of an inner set is one: the bound only loosens by their span, while
    every gap between pieces is a split the bound must try); returns the new end."""
    m = p0
    j = o0
    for p in range(p0, p1):
        mid = 0.5 * (pa[p] + pb[p])
        while j < o1 - 1 and ob[j] < mid:
            j += 1
        longest = 0.0
        for r in range(p0, p1):
            if oa[j] <= 0.5 * (pa[r] + pb[r]) <= ob[j]:
                longest = max(longest, pb[r] - pa[r])
        length = pb[p] - pa[p]
        if length >= short or length >= longest:
            pa[m], pb[m] = pa[p], pb[p]
            m += 1
    return m


def prepare() -> None:
    """Swap this module's helpers for their numba versions (before a caller compiles)."""
    jit_globals(
        globals(), ("strip_halfwidths", "_crossings", "_pieces", "_merge", "_inner", "_prune")
    )
