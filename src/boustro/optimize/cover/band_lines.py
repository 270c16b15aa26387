"""The interval arithmetic on one band's lines, for :mod:`~boustro.optimize.cover.bands`.

Plain Python loops over flat arrays, compiled by numba with the rest of the band statistics
(:func:`jit_into`): the edges projected into a layout's frame, each band's projection as sorted,
merged intervals, the lines' crossings with the edges and the holes, interval differences and
the counted pieces of a line."""

from __future__ import annotations

import math
from collections.abc import MutableMapping
from typing import Any

import numpy as np

from ..._jit import jit_globals

__all__ = ["KERNELS", "jit_into"]

#: The helpers, in this module and in a kernel module that calls them (by these names).
KERNELS = ("_project", "_sort_pairs", "_sort_keys", "_band_intervals", "_crossings", "_overlaps",
           "_hole_chords", "_minus", "_count_pieces")  # fmt: skip


def jit_into(namespace: MutableMapping[str, Any]) -> None:
    """Swap :data:`KERNELS` for their compiled versions here (they call each other by name) and
    in ``namespace``, the globals of a kernel module that imported some of them."""
    jit_globals(globals(), KERNELS)
    namespace.update({name: globals()[name] for name in KERNELS if name in namespace})


def _project(xy, cs, sn, ox, oy):
    e = xy.shape[0]
    h1 = np.empty(e)
    h2 = np.empty(e)
    t1 = np.empty(e)
    t2 = np.empty(e)
    for i in range(e):
        x1, y1, x2, y2 = xy[i, 0] - ox, xy[i, 1] - oy, xy[i, 2] - ox, xy[i, 3] - oy
        h1[i] = -sn * x1 + cs * y1
        h2[i] = -sn * x2 + cs * y2
        t1[i] = cs * x1 + sn * y1
        t2[i] = cs * x2 + sn * y2
    return h1, h2, t1, t2


def _band_intervals(h1, h2, t1, t2, d, s, reach, k0, nb):
    """Per band: sorted, merged intervals of the projection (start index, lo, hi arrays)."""
    e = h1.shape[0]
    # pass 1: counts of clipped edges and of crossings of each band's two edge lines
    n_clip = np.zeros(nb, dtype=np.int64)
    n_x = np.zeros((nb, 2), dtype=np.int64)
    for i in range(e):
        lo, hi = min(h1[i], h2[i]), max(h1[i], h2[i])
        ka = max(math.ceil((lo - reach - d) / s), k0)
        kb = min(math.floor((hi + reach - d) / s), k0 + nb - 1)
        for k in range(ka, kb + 1):
            c = d + k * s
            if min(hi, c + reach) >= max(lo, c - reach):
                n_clip[k - k0] += 1
            for side in range(2):
                line = c - reach if side == 0 else c + reach
                if (h1[i] <= line) != (h2[i] <= line):
                    n_x[k - k0, side] += 1
    cap = n_clip + n_x[:, 0] // 2 + n_x[:, 1] // 2
    start = np.zeros(nb + 1, dtype=np.int64)
    for b in range(nb):
        start[b + 1] = start[b] + cap[b]
    xstart = np.zeros(nb * 2 + 1, dtype=np.int64)
    for b in range(nb):
        for side in range(2):
            j = 2 * b + side
            xstart[j + 1] = xstart[j] + n_x[b, side]
    ilo = np.empty(start[nb])
    ihi = np.empty(start[nb])
    xt = np.empty(xstart[2 * nb])
    fill = start[:nb].copy()
    xfill = xstart[: 2 * nb].copy()
    # pass 2: fill
    for i in range(e):
        lo, hi = min(h1[i], h2[i]), max(h1[i], h2[i])
        ka = max(math.ceil((lo - reach - d) / s), k0)
        kb = min(math.floor((hi + reach - d) / s), k0 + nb - 1)
        dh = h2[i] - h1[i]
        for k in range(ka, kb + 1):
            c = d + k * s
            a, bb = max(lo, c - reach), min(hi, c + reach)
            b = k - k0
            if bb >= a:
                if dh == 0.0:
                    ta, tb = t1[i], t2[i]
                else:
                    ta = t1[i] + (a - h1[i]) * (t2[i] - t1[i]) / dh
                    tb = t1[i] + (bb - h1[i]) * (t2[i] - t1[i]) / dh
                ilo[fill[b]] = min(ta, tb)
                ihi[fill[b]] = max(ta, tb)
                fill[b] += 1
            for side in range(2):
                line = c - reach if side == 0 else c + reach
                if (h1[i] <= line) != (h2[i] <= line):
                    xt[xfill[2 * b + side]] = t1[i] + (line - h1[i]) * (t2[i] - t1[i]) / dh
                    xfill[2 * b + side] += 1
    # chords on the band's edge lines: sorted crossings paired (even-odd rule)
    for b in range(nb):
        for side in range(2):
            j = 2 * b + side
            _sort_keys(xt, xstart[j], xstart[j + 1])
            for q in range(xstart[j], xstart[j + 1] - 1, 2):
                ilo[fill[b]] = xt[q]
                ihi[fill[b]] = xt[q + 1]
                fill[b] += 1
    # sort and merge per band, in place; mstart/mcount index the merged intervals (the union
    # does not depend on the order of intervals with equal starts)
    mcount = np.zeros(nb, dtype=np.int64)
    for b in range(nb):
        p0, p1 = start[b], fill[b]
        if p1 <= p0:
            continue
        _sort_pairs(ilo, ihi, p0, p1)
        m = 0
        for q in range(p0, p1):
            if m > 0 and ilo[q] <= ihi[p0 + m - 1]:
                ihi[p0 + m - 1] = max(ihi[p0 + m - 1], ihi[q])
            else:
                ilo[p0 + m] = ilo[q]
                ihi[p0 + m] = ihi[q]
                m += 1
        mcount[b] = m
    return start, mcount, ilo, ihi


#: Runs longer than this are sorted by numpy (a stable sort, allocating): insertion sort is
#: quadratic where the crossings come in reverse order (a review: a 4000-edge sawtooth side
#: driven against the lines' direction, 7x slower a box).
LONG_RUN = 32


def _sort_pairs(key, other, p0, p1):
    """Sort ``key[p0:p1]`` in place, ``other[p0:p1]`` along with it, stably (insertion sort: a
    band holds few intervals, and no array is allocated; above :data:`LONG_RUN` numpy's)."""
    if p1 - p0 > LONG_RUN:
        order = np.argsort(key[p0:p1], kind="mergesort")
        sorted_key, sorted_other = key[p0:p1][order], other[p0:p1][order]
        key[p0:p1] = sorted_key
        other[p0:p1] = sorted_other
        return
    for q in range(p0 + 1, p1):
        k, o = key[q], other[q]
        j = q - 1
        while j >= p0 and key[j] > k:
            key[j + 1] = key[j]
            other[j + 1] = other[j]
            j -= 1
        key[j + 1] = k
        other[j + 1] = o


def _sort_keys(key, p0, p1):
    """Sort ``key[p0:p1]`` in place (insertion sort; above :data:`LONG_RUN` numpy's)."""
    if p1 - p0 > LONG_RUN:
        key[p0:p1] = np.sort(key[p0:p1])
        return
    for q in range(p0 + 1, p1):
        k = key[q]
        j = q - 1
        while j >= p0 and key[j] > k:
            key[j + 1] = key[j]
            j -= 1
        key[j + 1] = k


def _crossings(h1, h2, t1, t2, hole, d, s, k0, nb):
    """Per band: where the line ``d + k s`` crosses the holes' edges (the half-open rule
    ``h <= line``), sorted ``(t, hole id)``: consecutive pairs are the holes' chords."""
    e = h1.shape[0]
    n_x = np.zeros(nb, dtype=np.int64)
    for i in range(e):
        if hole[i] < 0:
            continue
        lo, hi = min(h1[i], h2[i]), max(h1[i], h2[i])
        ka = max(math.ceil((lo - d) / s), k0)
        kb = min(math.floor((hi - d) / s), k0 + nb - 1)
        for k in range(ka, kb + 1):
            line = d + k * s
            if (h1[i] <= line) != (h2[i] <= line):
                n_x[k - k0] += 1
    xstart = np.zeros(nb + 1, dtype=np.int64)
    for b in range(nb):
        xstart[b + 1] = xstart[b] + n_x[b]
    xt = np.empty(xstart[nb])
    xh = np.empty(xstart[nb], dtype=np.int64)
    fill = xstart[:nb].copy()
    for i in range(e):
        if hole[i] < 0:
            continue
        lo, hi = min(h1[i], h2[i]), max(h1[i], h2[i])
        ka = max(math.ceil((lo - d) / s), k0)
        kb = min(math.floor((hi - d) / s), k0 + nb - 1)
        for k in range(ka, kb + 1):
            line = d + k * s
            if (h1[i] <= line) != (h2[i] <= line):
                b = k - k0
                xt[fill[b]] = t1[i] + (line - h1[i]) * (t2[i] - t1[i]) / (h2[i] - h1[i])
                xh[fill[b]] = hole[i]
                fill[b] += 1
    for b in range(nb):
        _sort_pairs(xt, xh, xstart[b], xstart[b + 1])
    return xstart, xt, xh


def _overlaps(lo, hi, xt, p0, p1):
    """Whether ``[lo, hi]`` overlaps (by more than a point) a chord ``xt[p0:p1]`` (pairs)."""
    for q in range(p0, p1 - 1, 2):
        if min(hi, xt[q + 1]) > max(lo, xt[q]):
            return True
    return False


def _hole_chords(h1, h2, t1, t2, hole, d, s, k0, nb, tau):
    """Per band: the chords of the holes on the band's centre line, sorted ``(lo, hi, hole
    id)`` pairs, each kept only where the lines ``tau`` either side cross the hole too (as the
    planner cuts a lane, :func:`boustro.plan.lanes._cut_holes`): a line along a hole's edge,
    or through its extreme vertex, gets no chord there."""
    c0, ct, ch = _crossings(h1, h2, t1, t2, hole, d, s, k0, nb)
    l0, lt, _lh = _crossings(h1, h2, t1, t2, hole, d - tau, s, k0, nb)
    u0, ut, _uh = _crossings(h1, h2, t1, t2, hole, d + tau, s, k0, nb)
    xstart = np.zeros(nb + 1, dtype=np.int64)
    xt = np.empty(ct.shape[0])
    xh = np.empty(ct.shape[0], dtype=np.int64)
    n = 0
    for b in range(nb):
        for q in range(c0[b], c0[b + 1] - 1, 2):
            lo, hi = ct[q], ct[q + 1]
            if _overlaps(lo, hi, lt, l0[b], l0[b + 1]) and _overlaps(lo, hi, ut, u0[b], u0[b + 1]):
                xt[n], xt[n + 1] = lo, hi
                xh[n], xh[n + 1] = ch[q], ch[q]
                n += 2
        xstart[b + 1] = n
    return xstart, xt[:n], xh[:n]


def _minus(lo, hi, n, glo, ghi, tol, out_lo, out_hi):
    """Sorted disjoint intervals minus sorted disjoint gaps (pieces longer than ``tol``),
    written to ``out_lo, out_hi`` (room for ``n + len(glo) + 1``); returns their number."""
    m = 0
    g = 0
    ng = glo.shape[0]
    for q in range(n):
        a, b = lo[q], hi[q]
        while g < ng and ghi[g] <= a:
            g += 1
        gg = g
        cur = a
        while gg < ng and glo[gg] < b:
            if glo[gg] - cur > tol:
                out_lo[m] = cur
                out_hi[m] = glo[gg]
                m += 1
            cur = max(cur, ghi[gg])
            gg += 1
        if b - cur > tol:
            out_lo[m] = cur
            out_hi[m] = b
            m += 1
    return m


def _count_pieces(slo, shi, llo, lhi, n, plo, phi, n_p, tol, row):
    """The pieces ``[slo, shi]`` (sorted, disjoint) holding inner length (``[plo, phi]``, ``n_p``
    pieces), and in ``row`` (:attr:`BandStats.pieces`) the loose ends ``llo, lhi`` of the first,
    second, last and the one before the last of them; returns their number."""
    row[:] = math.nan
    c = 0
    j = 0
    before = math.nan  # the end of the counted piece before the last one
    for q in range(n):
        while j < n_p and phi[j] <= slo[q] + tol:
            j += 1
        if j < n_p and plo[j] < shi[q] - tol:
            c += 1
            if c == 1:
                row[0] = lhi[q]
            elif c == 2:
                row[1] = llo[q]
            if c >= 2:
                row[2] = llo[q]
                row[3] = before
            before = lhi[q]
    return c
