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
from ..cover.band_lines import _sort_keys, _sort_pairs, jit_into

__all__ = ["prepare", "strip_halfwidths", "strip_intervals"]


def strip_halfwidths(c, radius, sdelta, eta, out):
    """``out[q]``: the strip's half width ``A`` of the line at offset ``c[q]`` (module doc)."""
    cd = math.sqrt(max(1.0 - sdelta * sdelta, 0.0))
    for q in range(c.shape[0]):
        a0 = (abs(c[q]) * (1.0 - cd) + eta + radius * sdelta) / cd
        near = max(abs(c[q]) - a0, 0.0)
        t = math.sqrt(max(radius * radius - near * near, 0.0))
        out[q] = ((abs(c[q]) * (1.0 - cd) + eta + t * sdelta) / cd) * (1.0 + 1e-9) + 1e-12


def _first_strip(c, nb, at, d, s, k0):
    """The first line ``q`` with ``c[q] >= at`` (``c[q] = d + (k0 + q) s``, ascending; ``nb``
    if none): ``searchsorted(c, at)`` by arithmetic, fixed against ``c`` itself."""
    x = (at - d) / s - k0
    if not x < nb:  # also NaN
        return nb
    q = min(max(math.ceil(x), 0), nb)
    while q > 0 and c[q - 1] >= at:
        q -= 1
    while q < nb and c[q] < at:
        q += 1
    return q


def _sweep(xy, cs, sn, c, low, high, widest, d, s, k0, nb):
    """One pass over the edges ``xy`` seen in the box centre's frame (``h`` across, ``t``
    along): per line ``q`` the ``t`` of the boundary's crossings with the strip's lower edge
    ``h = low[q]`` and its upper edge ``high[q]`` (sorted; half-open rule ``(h1 <= h) != (h2
    <= h)``), and the ``t``-ranges of the edges clipped to the strip ``[low[q], high[q]]``
    (closed; in edge order, padded by ``1e-12 (1 + |u0| + |u1|)``). Only the lines whose
    strip can meet an edge (``c[q] - widest <= max h``, ``c[q] + widest >= min h``) are
    visited, found by arithmetic (:func:`_first_strip`), and an edge meeting none costs its
    two ``h`` only. Returns ``(lcnt, lt, hcnt, ht, pcnt, plo, phi)``, line ``q``'s entries
    from ``cnt[q]`` to ``cnt[q + 1]``."""
    ne = xy.shape[0]
    lcnt = np.zeros(nb + 1, dtype=np.int64)
    hcnt = np.zeros(nb + 1, dtype=np.int64)
    pcnt = np.zeros(nb + 1, dtype=np.int64)
    hit = np.empty(ne, dtype=np.int64)  # the edges meeting a strip, and their first line
    first = np.empty(ne, dtype=np.int64)
    ha = np.empty(ne)
    hb = np.empty(ne)
    nh = 0
    inv = 1.0 / s
    for i in range(ne):
        h1 = -sn * xy[i, 0] + cs * xy[i, 1]
        h2 = -sn * xy[i, 2] + cs * xy[i, 3]
        a, b = min(h1, h2), max(h1, h2)
        # most edges meet no strip: no whole number within a margin (far above the rounding
        # of c = d + k s, relative to the line index as in region_kernel._intervals) of
        # [(a - widest - d) / s, (b + widest - d) / s]
        lo, hi = (a - widest - d) * inv, (b + widest - d) * inv
        margin = 1e-9 + 1e-14 * (abs(lo) + abs(hi))
        if math.ceil(lo - margin) > hi + margin:
            continue
        q = _first_strip(c, nb, a - widest, d, s, k0)
        if q >= nb or c[q] - widest > b:
            continue
        hit[nh], first[nh], ha[nh], hb[nh] = i, q, h1, h2
        nh += 1
        while q < nb and c[q] - widest <= b:
            if low[q] <= b and high[q] >= a:
                pcnt[q + 1] += 1
                if a <= low[q] < b:
                    lcnt[q + 1] += 1
                if a <= high[q] < b:
                    hcnt[q + 1] += 1
            q += 1
    for q in range(nb):
        lcnt[q + 1] += lcnt[q]
        hcnt[q + 1] += hcnt[q]
        pcnt[q + 1] += pcnt[q]
    lt = np.empty(lcnt[nb])
    ht = np.empty(hcnt[nb])
    plo = np.empty(pcnt[nb])
    phi = np.empty(pcnt[nb])
    lfill = lcnt[:nb].copy()
    hfill = hcnt[:nb].copy()
    pfill = pcnt[:nb].copy()
    for e in range(nh):
        i = hit[e]
        h1, h2 = ha[e], hb[e]
        t1 = cs * xy[i, 0] + sn * xy[i, 1]
        t2 = cs * xy[i, 2] + sn * xy[i, 3]
        a, b = min(h1, h2), max(h1, h2)
        q = first[e]
        while q < nb and c[q] - widest <= b:
            if low[q] > b or high[q] < a:
                q += 1
                continue
            if a <= low[q] < b:
                lt[lfill[q]] = t1 + (low[q] - h1) * (t2 - t1) / (h2 - h1)
                lfill[q] += 1
            if a <= high[q] < b:
                ht[hfill[q]] = t1 + (high[q] - h1) * (t2 - t1) / (h2 - h1)
                hfill[q] += 1
            if h1 == h2:
                u0, u1 = t1, t2
            else:  # the edge's t at the strip's edges, clamped to the edge
                ua = min(max((low[q] - h1) / (h2 - h1), 0.0), 1.0)
                ub = min(max((high[q] - h1) / (h2 - h1), 0.0), 1.0)
                u0 = t1 + ua * (t2 - t1)
                u1 = t1 + ub * (t2 - t1)
            pad = 1e-12 * (1.0 + abs(u0) + abs(u1))
            plo[pfill[q]] = min(u0, u1) - pad
            phi[pfill[q]] = max(u0, u1) + pad
            pfill[q] += 1
            q += 1
    for q in range(nb):
        _sort_keys(lt, lcnt[q], lcnt[q + 1])
        _sort_keys(ht, hcnt[q], hcnt[q + 1])
    return lcnt, lt, hcnt, ht, pcnt, plo, phi


def _union(lt, l0, l1, ht, h0, h1, cut_lo, cut_hi, ncut, out_lo, out_hi, m):
    """Append to ``out`` from ``m`` the union of three sorted runs of intervals: the pairs of
    crossings ``lt[l0:l1]`` and ``ht[h0:h1]`` and the ``ncut`` cuts (touching ones merged, as
    :func:`_merge`); returns the new count."""
    i, j, k = l0, h0, 0
    have = False
    a, b = 0.0, 0.0
    while True:
        x, y, which = np.inf, np.inf, -1
        if i < l1 - 1 and lt[i] < x:
            x, y, which = lt[i], lt[i + 1], 0
        if j < h1 - 1 and ht[j] < x:
            x, y, which = ht[j], ht[j + 1], 1
        if k < ncut and cut_lo[k] < x:
            x, y, which = cut_lo[k], cut_hi[k], 2
        if which < 0:
            break
        if which == 0:
            i += 2
        elif which == 1:
            j += 2
        else:
            k += 1
        if have and x <= b:
            b = max(b, y)
        else:
            if have:
                out_lo[m], out_hi[m] = a, b
                m += 1
            a, b, have = x, y, True
    if have:
        out_lo[m], out_hi[m] = a, b
        m += 1
    return m


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
    low = c - half
    high = c + half
    lcnt, lt, hcnt, ht, pcnt, plo, phi = _sweep(xy, cs, sn, c, low, high, half.max(), d, s, k0,
                                                nb)  # fmt: skip
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
        l0, l1 = lcnt[q], lcnt[q + 1]
        h0, h1 = hcnt[q], hcnt[q + 1]
        p0, p1 = pcnt[q], pcnt[q + 1]
        # the clipped edges' ranges, sorted and merged: the inner set's cuts
        _sort_pairs(plo, phi, p0, p1)
        ncut = _merge(plo[p0:p1], phi[p0:p1], p1 - p0, buf_lo, buf_hi, 0)
        # outer: the union of both edges' intervals and the cuts (three sorted runs)
        mo = _union(lt, l0, l1, ht, h0, h1, buf_lo, buf_hi, ncut, oa, ob, mo)
        ost[q + 1] = mo
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
    jit_into(globals())  # the insertion sorts of cover's band lines
    helpers = ("strip_halfwidths", "_first_strip", "_sweep", "_union", "_merge", "_inner",
               "_prune")  # fmt: skip
    jit_globals(globals(), helpers)
