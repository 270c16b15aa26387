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

from ..._jit import compiled

__all__ = ["box_bounds", "eq1_at_angle", "eq1_values", "lines_range"]

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


def _g(a, b, n, ref, sx, qx, f, c, err_share):
    """Eq. 1 of ``n`` lengths: ``n - f`` fixed (sum ``sx``, sum of squares ``qx``, centred on
    ``ref``) and ``f`` equal to ``ref + c``; the std taken from below by the rounding of the
    running sums (``err_share``: their relative error), so the value is never too low."""
    mean = (sx + f * c) / n
    second = (qx + f * c * c) / n
    var = second - mean * mean - err_share * second
    return a * (mean + ref) + b * (1.0 - math.sqrt(max(var, 0.0)))


def _sup(lo, hi, j0, j1, a, b, pos):
    """The maximum of Eq. 1 over every vector with ``lo_k <= L_k <= hi_k``, ``k = j0..j1``.

    Eq. 1 is concave in the lengths; by KKT its maximiser is ``clip(c, lo, hi)`` for one
    ``c = mean + (a / b) std``, so the maximum is that of ``G(c) = Eq1(clip(c, lo, hi))``.
    Between consecutive interval ends the free lengths (``lo < c < hi``) equal ``c`` and the
    others are fixed, so ``G`` is concave there: its maximum is at an end or where
    ``a n std = b ((n - f) c - S)`` (``f`` free, ``S`` the fixed sum, centred), a quadratic
    solved in closed form. A sweep over the ``2 n`` sorted ends keeps the running sums
    (:func:`_sup_w` with every interval taken once)."""
    n = j1 - j0 + 1
    ref = 0.0
    for k in range(j0, j1 + 1):
        ref += lo[k] + hi[k]
    ref /= 2 * n
    for q in range(n):  # the ends sorted as _sup_w centres them (the same order on ties)
        pos[2 * q] = lo[j0 + q] - ref
        pos[2 * q + 1] = hi[j0 + q] - ref
    order = np.argsort(pos[: 2 * n])
    return _sup_w(lo[j0 : j1 + 1], hi[j0 : j1 + 1], np.ones(n), n, order, a, b, pos)


def _sup_w(lo, hi, w, m, order, a, b, pos):
    """The maximum of Eq. 1 over lengths ``lo_q <= L <= hi_q`` of ``m`` intervals, interval
    ``q`` taken ``w_q`` times (``order``: the argsort of the ends ``lo_0, hi_0, lo_1, ...``):
    the convex kernel's ``_sup`` with multiplicities (the KKT maximiser gives equal lengths
    to the copies of one interval)."""
    n = 0.0
    ref = 0.0
    for q in range(m):
        n += w[q]
        ref += w[q] * (lo[q] + hi[q])
    if n == 0.0:
        return -np.inf
    ref /= 2 * n
    for q in range(m):
        pos[2 * q] = lo[q] - ref
        pos[2 * q + 1] = hi[q] - ref
    sx, qx, f = 0.0, 0.0, 0.0
    for q in range(m):
        x = pos[2 * q]
        sx += w[q] * x
        qx += w[q] * x * x
    err_share = (8.0 * n + 16.0) * 2.3e-16
    best = _g(a, b, n, ref, sx, qx, 0.0, 0.0, err_share)
    prev = pos[order[0]]
    for e in range(2 * m):
        i = order[e]
        wq = w[i // 2]
        if wq == 0.0:
            continue
        ce = pos[i]
        if f > 0 and ce > prev:
            best = max(best, _g(a, b, n, ref, sx, qx, f, ce, err_share))
            p = n - f
            a2 = p * (a * a * f - b * b * p)
            a1 = 2.0 * sx * (b * b * p - a * a * f)
            a0 = a * a * (n * qx - sx * sx) - b * b * sx * sx
            if p > 0 and a2 != 0.0:
                disc = a1 * a1 - 4.0 * a2 * a0
                root = math.sqrt(max(disc, 0.0))
                qq = -0.5 * (a1 + root if a1 >= 0.0 else a1 - root)
                for r in (qq / a2, a0 / qq if qq != 0.0 else prev, -0.5 * a1 / a2):
                    if prev < r < ce:
                        best = max(best, _g(a, b, n, ref, sx, qx, f, r, err_share))
        x = pos[i]
        if i % 2 == 0:
            sx -= wq * x
            qx -= wq * x * x
            f += wq
        else:
            sx += wq * x
            qx += wq * x * x
            f -= wq
        prev = ce
    return best


def _upper(lo, hi, a, b, max_choices, pos):
    """An upper bound of Eq. 1 over every ``S`` whose chords satisfy ``lo <= L <= hi``.

    Lines with ``hi = 0`` are never counted, lines with ``lo > 0`` always; a convex ``S``
    counts a contiguous range of lines, so the uncertain ones are at the two ends: every range
    ``[k0, k1]`` with ``o0 <= k0 <= i0``, ``i1 <= k1 <= o1`` is tried, each with the exact
    maximum over its lengths (:func:`_sup`; uncertain lines: ``[0, hi]``)."""
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
    best = -np.inf
    for k0 in range(o0, i0 + 1):
        for k1 in range(i1, o1 + 1):
            best = max(best, _sup(lo, hi, k0, k1, a, b, pos))
    return best


def _bounds(in_xy, out_xy, cs, sn, d, s, k0, nb, a, b, max_choices, slack):
    m = cs.shape[0]
    out = np.empty(m)
    lo_t = np.empty(nb)
    hi_t = np.empty(nb)
    lo = np.empty(nb)
    hi = np.empty(nb)
    pos = np.empty(2 * nb)
    for i in range(m):
        _spans(in_xy, cs[i], sn[i], d[i], s, k0, nb, lo_t, hi_t, lo)
        _spans(out_xy, cs[i], sn[i], d[i], s, k0, nb, lo_t, hi_t, hi)
        for k in range(nb):  # rounding can only widen the intervals
            x, y = lo[k], hi[k]
            lo[k] = min(x, y)
            hi[k] = max(x, y)
        out[i] = _upper(lo, hi, a, b, max_choices, pos) + slack
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
    """``(_bounds, _values)`` compiled by numba (cached on disk), or plain Python without it
    (safe from several threads at once: :func:`boustro._jit.jit_globals`)."""
    return compiled(
        globals(), ("_bounds", "_values"), ("_spans", "_eq1", "_g", "_sup_w", "_sup", "_upper")
    )


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


def eq1_at_angle(
    v: NDArray[np.float64],
    theta: float,
    offsets: NDArray[np.float64],
    spacing: float,
    a: float,
    b: float,
) -> NDArray[np.float64]:
    """``(m,)`` Eq. 1 at one angle and many offsets over the strictly convex polygon of CCW
    vertices ``v``, in ``O(n + m lines log n)``: its boundary splits at the extreme vertices
    across the lines into two chains monotone across them, whose along-coordinates at each line
    are interpolated (lines through an extreme vertex have length 0, as in :func:`eq1_values`)."""
    h = v[:, 1] * math.cos(theta) - v[:, 0] * math.sin(theta)
    t = v[:, 0] * math.cos(theta) + v[:, 1] * math.sin(theta)
    lo, hi = int(np.argmin(h)), int(np.argmax(h))
    n = len(v)
    first = np.arange(lo, lo + ((hi - lo) % n) + 1) % n  # lo -> hi, counter-clockwise
    second = np.arange(hi, hi + ((lo - hi) % n) + 1)[::-1] % n  # lo -> hi, clockwise
    offsets = np.asarray(offsets, dtype=np.float64)
    k0 = math.floor((h[lo] - offsets.max()) / spacing)
    k = np.arange(k0, math.ceil((h[hi] - offsets.min()) / spacing) + 1)
    c = offsets[:, None] + k[None, :] * spacing
    inside = (c > h[lo]) & (c < h[hi])
    length = np.abs(np.interp(c, h[first], t[first]) - np.interp(c, h[second], t[second]))
    length = np.where(inside, length, 0.0)
    counted = length > 0.0
    count = counted.sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = length.sum(axis=1) / count
        var = np.where(counted, (length - mean[:, None]) ** 2, 0.0).sum(axis=1) / count
        value = a * mean + b * (1.0 - np.sqrt(var))
    return np.where(count > 0, value, -np.inf)
