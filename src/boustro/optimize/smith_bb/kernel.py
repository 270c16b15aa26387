"""The per-layout work of the Eq. 1 branch and bound (numba, compiled on first use).

For a layout ``(theta, d)`` line ``k`` is ``n . p = d + k s`` (normalised frame: the polygon's
vertex mean at the origin), ``n = (-sin theta, cos theta)``, ``u = (cos theta, sin theta)``.
:func:`_spans` finds, per line, the span along ``u`` of the crossings of a set's boundary edges
with the line, in ``O(E + crossings)``: for a convex set it is its chord. Its two uses, valid
even where rounding leaves a set slightly non-convex:

* an OUTER set (containing the moved polygon ``S``): the span of its crossings is at least the
  measure of the outer set on the line, hence at least ``S``'s chord;
* an INNER set (contained in ``S``, convex): ``S`` contains the convex hull of the inner set's
  points on the line, so ``S``'s chord is at least their span.

A crossing is counted where ``(h1 <= c) != (h2 <= c)`` (half-open: a line through a vertex is
counted once per side, an edge lying on the line not at all).

:func:`_upper` bounds Eq. 1 from above over every vector of lengths with ``lo_k <= L_k <= hi_k``
and every set of counted lines a convex ``S`` between the two sets can have (docs/global_optimum.md,
"Certified at scale").
"""

from __future__ import annotations

import math
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["box_bounds", "eq1_values", "lines_range"]

#: Most inclusion choices of the uncertain end lines enumerated per box; a box with more
#: (a large box) gets the cruder bound ``a max(hi) + b``.
MAX_CHOICES = 64
#: Added to every box bound: the closed forms' rounding (values accurate to about 1e-15).
BOUND_SLACK = 1e-10


# -- the loops (plain Python, compiled by numba on first use) ----------------------------------
def _spans(xy, cs, sn, d, s, k0, nb, lo_t, hi_t, out):
    """``out[k - k0]``: the span along the lines of the edges' crossings with line ``k``."""
    for b in range(nb):
        lo_t[b] = np.inf
        hi_t[b] = -np.inf
    for i in range(xy.shape[0]):
        x1, y1, x2, y2 = xy[i, 0], xy[i, 1], xy[i, 2], xy[i, 3]
        h1 = -sn * x1 + cs * y1
        h2 = -sn * x2 + cs * y2
        if h1 == h2:
            continue
        t1 = cs * x1 + sn * y1
        t2 = cs * x2 + sn * y2
        ka = max(math.floor((min(h1, h2) - d) / s) - 1, k0)
        kb = min(math.ceil((max(h1, h2) - d) / s) + 1, k0 + nb - 1)
        for k in range(ka, kb + 1):
            c = d + k * s
            if (h1 <= c) != (h2 <= c):
                t = t1 + (c - h1) * (t2 - t1) / (h2 - h1)
                j = k - k0
                if t < lo_t[j]:
                    lo_t[j] = t
                if t > hi_t[j]:
                    hi_t[j] = t
    for b in range(nb):
        out[b] = hi_t[b] - lo_t[b] if hi_t[b] > lo_t[b] else 0.0


def _eq1(ch, a, b):
    """Eq. 1 over the lines of positive length (``-inf`` without one)."""
    n = 0
    total = 0.0
    for k in range(ch.shape[0]):
        if ch[k] > 0.0:
            n += 1
            total += ch[k]
    if n == 0:
        return -np.inf
    m = total / n
    var = 0.0
    for k in range(ch.shape[0]):
        if ch[k] > 0.0:
            var += (ch[k] - m) ** 2
    return a * m + b * (1.0 - math.sqrt(var / n))


def _min_var(lo, hi, j0, j1):
    """The least population variance of a vector with ``lo_k <= L_k <= hi_k``, ``k = j0..j1``:
    ``min_c mean_k dist(c, [lo_k, hi_k])^2`` (the variance is ``min_c mean (L - c)^2``; the
    inner minimum over the box is the distance), a convex piecewise quadratic in ``c`` solved
    exactly by a sweep over the sorted interval ends."""
    n = j1 - j0 + 1
    ls = np.sort(lo[j0 : j1 + 1])
    hs = np.sort(hi[j0 : j1 + 1])
    if ls[n - 1] <= hs[0]:
        return 0.0  # every interval holds one point: equal lengths
    # g'(c) / 2 = (A + B) c - (SA + SB): A, SA the count and sum of ends hi < c; B, SB of lo > c
    na, sa = 0, 0.0
    nl, sl = n, 0.0
    for k in range(n):
        sl += ls[k]
    ia, il = 0, 0
    prev = -np.inf
    c = 0.0
    while True:
        if ia < n and (il >= n or hs[ia] <= ls[il]):
            nxt, kind = hs[ia], 0
        elif il < n:
            nxt, kind = ls[il], 1
        else:
            nxt, kind = np.inf, 2
        den = na + nl
        num = sa + sl
        if kind == 2 or den * nxt - num >= 0.0:
            c = num / den if den > 0 else prev
            c = min(max(c, prev), nxt)
            break
        if kind == 0:
            na += 1
            sa += hs[ia]
            ia += 1
        else:
            nl -= 1
            sl -= ls[il]
            il += 1
        prev = nxt
    var = 0.0
    for k in range(j0, j1 + 1):
        if hi[k] < c:
            var += (c - hi[k]) ** 2
        elif lo[k] > c:
            var += (lo[k] - c) ** 2
    return var / n


def _upper(lo, hi, a, b, max_choices, prefix):
    """An upper bound of Eq. 1 over every ``S`` whose chords satisfy ``lo <= L <= hi``.

    Lines with ``hi = 0`` are never counted, lines with ``lo > 0`` always; a convex ``S``
    counts a contiguous range of lines, so the uncertain ones are at the two ends: every range
    ``[k0, k1]`` with ``o0 <= k0 <= i0``, ``i1 <= k1 <= o1`` is tried, bounding the mean by
    that of ``hi`` and the std from below by :func:`_min_var` (uncertain lines: ``[0, hi]``)."""
    nb = lo.shape[0]
    o0, o1, i0, i1 = -1, -1, -1, -1
    top = 0.0
    for k in range(nb):
        if hi[k] > 0.0:
            if o0 < 0:
                o0 = k
            o1 = k
            top = max(top, hi[k])
        if lo[k] > 0.0:
            if i0 < 0:
                i0 = k
            i1 = k
    if o0 < 0:
        return -np.inf  # no line meets the outer set: no layout of the box has a transect
    if i0 < 0 or (i0 - o0 + 1) * (o1 - i1 + 1) > max_choices:
        return a * top + b
    prefix[0] = 0.0
    for k in range(nb):
        prefix[k + 1] = prefix[k] + hi[k]
    best = -np.inf
    for k0 in range(o0, i0 + 1):
        for k1 in range(i1, o1 + 1):
            n = k1 - k0 + 1
            mean = (prefix[k1 + 1] - prefix[k0]) / n
            std = math.sqrt(_min_var(lo, hi, k0, k1))
            best = max(best, a * mean + b * (1.0 - std))
    return best


def _bounds(in_xy, out_xy, cs, sn, d, s, k0, nb, a, b, max_choices, slack):
    m = cs.shape[0]
    out = np.empty(m)
    lo_t = np.empty(nb)
    hi_t = np.empty(nb)
    lo = np.empty(nb)
    hi = np.empty(nb)
    prefix = np.empty(nb + 1)
    for i in range(m):
        _spans(in_xy, cs[i], sn[i], d[i], s, k0, nb, lo_t, hi_t, lo)
        _spans(out_xy, cs[i], sn[i], d[i], s, k0, nb, lo_t, hi_t, hi)
        for k in range(nb):  # rounding can only widen the intervals
            x, y = lo[k], hi[k]
            lo[k] = min(x, y)
            hi[k] = max(x, y)
        out[i] = _upper(lo, hi, a, b, max_choices, prefix) + slack
    return out


def _values(xy, cs, sn, d, s, k0, nb, a, b):
    m = cs.shape[0]
    out = np.empty(m)
    lo_t = np.empty(nb)
    hi_t = np.empty(nb)
    ch = np.empty(nb)
    for i in range(m):
        _spans(xy, cs[i], sn[i], d[i], s, k0, nb, lo_t, hi_t, ch)
        out[i] = _eq1(ch, a, b)
    return out


@cache
def _compiled() -> tuple[Any, Any]:
    """``(_bounds, _values)`` compiled by numba (cached on disk), or plain Python without it."""
    try:
        import numba
    except ImportError:  # pragma: no cover - numba is a dependency
        return _bounds, _values
    jit = numba.njit(cache=True)
    g = globals()
    for name in ("_spans", "_eq1", "_min_var", "_upper"):
        g[name] = jit(g[name])
    return jit(_bounds), jit(_values)


def lines_range(xy: NDArray[np.float64], spacing: float) -> tuple[int, int]:
    """``(k0, count)``: every line ``k`` of a layout with offset in ``[-s, 2 s]`` that can meet
    the set of edges ``xy`` (normalised frame, origin at the vertex mean)."""
    far = float(np.hypot(xy[:, 0], xy[:, 1]).max()) if len(xy) else 0.0
    k0 = math.floor(-far / spacing) - 3
    k1 = math.ceil(far / spacing) + 2
    return k0, k1 - k0 + 1


def _args(theta: NDArray[np.float64], d: NDArray[np.float64]) -> tuple[Any, Any, Any]:
    theta = np.ascontiguousarray(theta, dtype=np.float64)
    return np.cos(theta), np.sin(theta), np.ascontiguousarray(d, dtype=np.float64)


def box_bounds(
    inner: NDArray[np.float64],
    outer: NDArray[np.float64],
    theta: NDArray[np.float64],
    d: NDArray[np.float64],
    spacing: float,
    a: float,
    b: float,
) -> NDArray[np.float64]:
    """``(m,)`` an upper bound of Eq. 1 for every convex set between the edge sets ``inner``
    and ``outer`` (``(E, 4)`` rows ``x1, y1, x2, y2``), seen by the lines of layout ``i``."""
    k0, nb = lines_range(outer, spacing)
    cs, sn, dd = _args(theta, d)
    fn = _compiled()[0]
    inner, outer = np.ascontiguousarray(inner), np.ascontiguousarray(outer)
    return fn(inner, outer, cs, sn, dd, float(spacing), k0, nb, float(a), float(b), MAX_CHOICES,
              BOUND_SLACK)  # fmt: skip


def eq1_values(
    xy: NDArray[np.float64],
    theta: NDArray[np.float64],
    d: NDArray[np.float64],
    spacing: float,
    a: float,
    b: float,
) -> NDArray[np.float64]:
    """``(m,)`` Eq. 1 of the layouts over the convex polygon of edges ``xy`` (``-inf`` where
    no line crosses it)."""
    k0, nb = lines_range(xy, spacing)
    cs, sn, dd = _args(theta, d)
    fn = _compiled()[1]
    return fn(np.ascontiguousarray(xy), cs, sn, dd, float(spacing), k0, nb, float(a), float(b))
