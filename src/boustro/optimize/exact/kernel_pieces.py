"""Compiled twins (numba) of the piece structure and the pieces' exact maxima, one angle a call.

The same formulas as :func:`.structure._structure`, :func:`.bounds._smith_pieces` and
:func:`.bounds._quick_excess` (docs/global_optimum.md, sections 1 and 3), written as loops over
one angle's pieces ``p`` and knot segments ``j`` so that numba compiles them: no per-angle
Python, no temporaries. They write into scratch arrays the caller allocates once
(:class:`Scratch` lists them). The operations follow the numpy code's order, so the two agree
to rounding (tests/test_exact_kernel.py checks it on seeded random polygons). Plain Python
until :func:`.kernel.compiled` compiles them.
"""

from __future__ import annotations

import math

import numpy as np

__all__: list[str] = []

_HUGE = 1e100  # as .structure._HUGE

# Columns of the per-piece moments array ``mo`` (P, _NMO).
_TOTAL, _MEAN_A, _MEAN_B, _V_AA, _V_AB, _V_BB, _X0, _RESID, _VALUE, _LAM = range(10)
_NMO = 10


def _nmax(x: float, y: float) -> float:
    """``np.maximum`` of two floats (NaN wins)."""
    if x != x or y != y:
        return math.nan
    return x if x >= y else y


def _nmin(x: float, y: float) -> float:
    """``np.minimum`` of two floats (NaN wins)."""
    if x != x or y != y:
        return math.nan
    return x if x <= y else y


def _clip01(x: float) -> float:
    """``np.clip(x, 0, 1)`` (NaN stays NaN)."""
    if x < 0.0:
        return 0.0
    if x > 1.0:
        return 1.0
    return x


def _sign(x: float) -> float:
    """``np.sign``."""
    if x > 0.0:
        return 1.0
    if x < 0.0:
        return -1.0
    return x  # 0 or NaN


def _argmax(values: np.ndarray) -> int:
    """``np.argmax`` of a 1-D array: the first maximum, or the first NaN."""
    best = 0
    for k in range(len(values)):
        if values[k] != values[k]:
            return k
        if values[k] > values[best]:
            best = k
    return best


def _order_desc(values: np.ndarray, out: np.ndarray) -> None:
    """``out``: the indices of ``values`` from the largest down, NaN first, ties in index order
    (insertion sort: a handful of pieces)."""
    n = len(values)
    for i in range(n):
        out[i] = i
    for i in range(1, n):
        k = out[i]
        key = values[k]
        j = i - 1
        while (
            j >= 0
            and not (values[out[j]] != values[out[j]])
            and (key != key or key > values[out[j]])
        ):
            out[j + 1] = out[j]
            j -= 1
        out[j + 1] = k


def _argsort_into(keys: np.ndarray, out: np.ndarray) -> None:
    """``out[:] = np.argsort(keys, kind="stable")``: insertion sort for small arrays."""
    n = len(keys)
    if n > 32:
        out[:] = np.argsort(keys, kind="mergesort")
        return
    for i in range(n):
        out[i] = i
    for i in range(1, n):
        k = out[i]
        key = keys[k]
        j = i - 1
        while j >= 0 and keys[out[j]] > key:
            out[j + 1] = out[j]
            j -= 1
        out[j + 1] = k


def _chords_through_vertices(
    h: np.ndarray, t: np.ndarray, tu_v: np.ndarray, td_v: np.ndarray
) -> None:
    """The ends ``(tu_v, td_v)`` of the chord through every vertex: the boundary points of
    every edge at its height (as the first lines of .structure._structure)."""
    n = len(h)
    for i in range(n):
        hv = h[i]
        up, dn = -np.inf, np.inf
        for e in range(n):
            e1 = e + 1 if e + 1 < n else 0  # (e + 1) % n without an integer division
            ha, hb = h[e], h[e1]
            ta, tb = t[e], t[e1]
            if not (min(ha, hb) <= hv and hv <= max(ha, hb)):
                continue
            dh = hb - ha
            if dh == 0:
                t_hi, t_lo = max(ta, tb), min(ta, tb)
            else:
                frac = _clip01((hv - ha) / dh)
                tt = tb if frac == 1.0 else ta + frac * (tb - ta)
                t_hi, t_lo = tt, tt
            up = _nmax(up, t_hi)
            dn = _nmin(dn, t_lo)
        tu_v[i], td_v[i] = up, dn


def _structure_scratch(n: int) -> tuple:
    """The scratch arrays of :func:`_structure_one` and :func:`_pieces_one` for ``n``
    vertices: ``h, t, x, tu, td, pc, fam, rn, mo, cc, work, iwork``."""
    n_j = n - 1
    h, t, x, tu, td = np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    pc = np.empty((n, 5))
    fam = np.empty((n, 2), dtype=np.int64)
    rn = np.empty((n, n_j, 8))
    mo = np.empty((n, _NMO))
    cc = np.empty((n, n_j, 4))
    work, iwork = np.empty((4, n)), np.empty((2, n), dtype=np.int64)
    return h, t, x, tu, td, pc, fam, rn, mo, cc, work, iwork


def _structure_one(
    v: np.ndarray,
    s: float,
    theta: float,
    h: np.ndarray,
    t: np.ndarray,
    x: np.ndarray,
    tu: np.ndarray,
    td: np.ndarray,
    pc: np.ndarray,
    fam: np.ndarray,
    rn: np.ndarray,
    work: np.ndarray,
    iwork: np.ndarray,
) -> None:
    """The structure at one angle, written into the scratch arrays (``work (4, n)`` and
    ``iwork (2, n)`` are scratch).

    ``h, t, x, tu, td (n,)``; ``pc (P, 5)``: beta, width, tfam_lo, tfam_hi, h_lo; ``fam (P, 2)``:
    lower and upper family vertex; ``rn (P, J, 8)``: count, first, step, slope, rel_lo, rel_hi,
    kap_lo (k_lo), kap_hi (k_hi_fam).
    """
    n = v.shape[0]
    cos, sin = math.cos(theta), math.sin(theta)
    for i in range(n):
        h[i] = v[i, 1] * cos - v[i, 0] * sin
        t[i] = v[i, 0] * cos + v[i, 1] * sin
    tu_v, td_v, mult, bp = work[0], work[1], work[2], work[3]
    order, fam_lo = iwork[0], iwork[1]
    _chords_through_vertices(h, t, tu_v, td_v)
    _argsort_into(h, order)
    for k in range(n):
        x[k], tu[k], td[k] = h[order[k]], tu_v[order[k]], td_v[order[k]]
    for i in range(n):
        mult[i] = np.floor(h[i] / s)
        bp[i] = h[i] - mult[i] * s
    _argsort_into(bp, fam_lo)
    for p in range(n):
        lo_f, hi_f = fam_lo[p], fam_lo[p + 1 if p + 1 < n else 0]
        fam[p, 0], fam[p, 1] = lo_f, hi_f
        beta, beta_hi = bp[lo_f], bp[hi_f]
        m_lo, m_hi = mult[lo_f], mult[hi_f]
        if p == n - 1:
            beta_hi += s
            m_hi -= 1.0
        width = beta_hi - beta
        hl, hh = h[lo_f], h[hi_f]
        pc[p, 0], pc[p, 1], pc[p, 2], pc[p, 3], pc[p, 4] = beta, width, t[lo_f], t[hi_f], hl
        half = 0.5 * width
        # (x_j - hl - half) / s ends segment j - 1 and starts segment j: one division each
        q_lo = (x[0] - hl - half) / s
        for j in range(n - 1):
            x0, x1 = x[j], x[j + 1]
            wx = x1 - x0
            q_hi = (x1 - hl - half) / s
            k_lo = np.floor(q_lo) + 1.0
            k_hi = np.ceil(q_hi) - 1.0
            q_lo = q_hi
            count = max(k_hi - k_lo + 1.0, 0.0)
            rel_lo = (hl - x0) + k_lo * s
            k_hi_fam = k_lo + (m_lo - m_hi)
            rn[p, j, 0] = count
            rn[p, j, 4] = rel_lo
            rn[p, j, 5] = (hh - x0) + k_hi_fam * s
            rn[p, j, 6], rn[p, j, 7] = k_lo, k_hi_fam
            if count > 0:
                y0 = tu[j] - td[j]
                dy = (tu[j + 1] - td[j + 1]) - y0
                rn[p, j, 1] = y0 + (rel_lo / wx) * dy
                rn[p, j, 2] = dy * (s / wx)
                rn[p, j, 3] = dy * (width / wx)
            else:
                rn[p, j, 1], rn[p, j, 2], rn[p, j, 3] = 0.0, 0.0, 0.0


def _piece_max(
    mean_a: float,
    mean_b: float,
    v_aa: float,
    v_11: float,
    v_bb: float,
    x0: float,
    resid: float,
    a: float,
    b: float,
) -> tuple[float, float]:
    """The maximum of ``a mean(lam) + b (1 - sqrt(var(lam)))`` over ``lam`` in ``[0, 1]`` and
    its argument: the stationary point in closed form, or an end (as .bounds._smith_pieces)."""
    pos = v_bb > 1e-300
    vbs = v_bb if pos else 1.0
    disc = b * b * v_bb - a * a * mean_b * mean_b
    if pos and disc > 0:
        xs = _sign(mean_b) * a * abs(mean_b) * math.sqrt(resid)
        lam_s = x0 + xs / math.sqrt(vbs * disc)
    else:
        lam_s = 1.0 if mean_b > 0 else 0.0
    lam_s = _clip01(lam_s)
    q_s = v_bb * (lam_s - x0) ** 2 + resid if pos else v_aa
    f0 = a * mean_a + b * (1.0 - math.sqrt(_nmax(v_aa, 0.0)))
    f1 = a * (mean_a + mean_b) + b * (1.0 - math.sqrt(_nmax(v_11, 0.0)))
    fs = a * (mean_a + mean_b * lam_s) + b * (1.0 - math.sqrt(_nmax(q_s, 0.0)))
    pick, value = 0, f0  # np.argmax of (f0, fs, f1): the first maximum, or the first NaN
    if not (f0 != f0):
        if fs != fs or fs > value:
            pick, value = 1, fs
        if not (value != value) and (f1 != f1 or f1 > value):
            pick, value = 2, f1
    return value, (0.0 if pick == 0 else (1.0 if pick == 2 else lam_s))


def _pieces_one(rn: np.ndarray, a: float, b: float, mo: np.ndarray, cc: np.ndarray) -> None:
    """The exact maximum of Eq. 1 on every piece (as .bounds._smith_pieces).

    Writes ``mo (P, _NMO)`` and ``cc (P, J, 4)``: i1, i2, ca, cb. Segments without transects
    add exact zeros to the sums and are skipped.
    """
    n_p, n_j = rn.shape[0], rn.shape[1]
    for p in range(n_p):
        total = 0.0
        sa = 0.0
        sb = 0.0
        for j in range(n_j):
            c = rn[p, j, 0]
            if c > 0:
                i1 = c * (c - 1.0) * 0.5
                cc[p, j, 0] = i1
                cc[p, j, 1] = (c - 1.0) * c * (2.0 * c - 1.0) / 6.0
                total += c
                sa += c * rn[p, j, 1] + rn[p, j, 2] * i1
                sb += c * rn[p, j, 3]
            else:  # the same formulas at c = 0: -0.0 and 0.0
                cc[p, j, 0], cc[p, j, 1] = -0.0, 0.0
        ok = total > 0
        tsafe = total if ok else 1.0
        mean_a, mean_b = sa / tsafe, sb / tsafe
        vbb = 0.0
        vab = 0.0
        vaa = 0.0
        v11 = 0.0
        for j in range(n_j):
            c = rn[p, j, 0]
            ca = rn[p, j, 1] - mean_a
            cc[p, j, 2] = ca
            cc[p, j, 3] = 0.0
            if c > 0:
                step, i1, i2 = rn[p, j, 2], cc[p, j, 0], cc[p, j, 1]
                cb = rn[p, j, 3] - mean_b
                cc[p, j, 3] = cb
                vbb += c * cb * cb
                vab += cb * (c * ca + step * i1)
                vaa += c * ca * ca + 2.0 * ca * step * i1 + step * step * i2
                c1 = ca + cb
                v11 += c * c1 * c1 + 2.0 * c1 * step * i1 + step * step * i2
        v_aa, v_11 = vaa / tsafe, v11 / tsafe
        v_bb, v_ab = vbb / tsafe, vab / tsafe
        pos = v_bb > 1e-300
        vbs = v_bb if pos else 1.0
        x0 = -v_ab / vbs if pos else 0.0
        if pos:
            rs = 0.0
            for j in range(n_j):
                c = rn[p, j, 0]
                if c > 0:
                    step, i1, i2 = rn[p, j, 2], cc[p, j, 0], cc[p, j, 1]
                    cr = cc[p, j, 2] + x0 * cc[p, j, 3]
                    rs += c * cr * cr + 2.0 * cr * step * i1 + step * step * i2
            resid = rs / tsafe
        else:
            resid = v_aa
        value, lam = _piece_max(mean_a, mean_b, v_aa, v_11, v_bb, x0, resid, a, b)
        m = mo[p]
        m[_TOTAL], m[_MEAN_A], m[_MEAN_B] = total, mean_a, mean_b
        m[_V_AA], m[_V_AB], m[_V_BB], m[_X0], m[_RESID] = v_aa, v_ab, v_bb, x0, resid
        m[_VALUE] = value if ok else -np.inf
        m[_LAM] = lam


def _weighted_row(cnt: np.ndarray, w: np.ndarray, total: float, a: float, b: float) -> float:
    """``a mean(w) + b rms(w)`` over one piece's transects (as .structure._weighted)."""
    tsafe = total if total > 0 else 1.0
    s1 = 0.0
    s2 = 0.0
    for j in range(len(cnt)):
        if cnt[j] > 0:  # where there is no transect, w is 0 (never inf)
            s1 += cnt[j] * w[j]
            s2 += cnt[j] * w[j] * w[j]
    rms = math.sqrt(s2 / tsafe) if total > 1 else 0.0
    out = a * s1 / tsafe + b * rms
    return np.inf if out != out else out


def _angular_growth(
    dc: float, wx: float, dl: float, tan_dl: float
) -> tuple[float, float, float, float, bool]:
    """For an edge rising ``dc`` over ``wx`` and half-width ``dl`` (``tan_dl = tan(dl)``):
    ``(r, zc, grow, drift_k, big)`` of the chord-end bounds (see .structure._runs).

    ``r = tan(atan2(|dc|, wx) + dl)`` by the addition formula, ``(m + tan dl) / (1 - m tan
    dl)`` with ``m = |dc| / wx``, infinite (``_HUGE``) where the sum reaches a right angle
    (``m tan dl >= 1``): the same number to rounding (a few units in the last place, far inside
    :data:`.structure.BOUND_SLACK`) without two of the three transcendental functions, which
    took 40% of the cheap bound's time."""
    if wx > 0:
        slope = abs(dc) / wx
    else:  # atan2(|dc|, 0): a right angle, or 0 for dc = 0
        slope = 0.0 if dc == 0 else np.inf
    den = 1.0 - slope * tan_dl
    bad = not (den > 0) or dl >= 0.5 * math.pi
    r = _HUGE if bad else (slope + tan_dl) / den
    r = min(r, _HUGE)
    z = r * dl
    big = bad or z > 600.0
    zc = 0.0 if big else z
    grow = _HUGE if big else math.expm1(zc)
    rs = r if zc > 0 else 1.0
    if big:
        drift_k = _HUGE
    elif zc > 0:
        drift_k = max(grow - zc, 0.5 * zc * zc) / rs
    else:
        drift_k = 0.0
    return r, zc, grow, drift_k, big


def _quick_one(
    x: np.ndarray,
    tu: np.ndarray,
    td: np.ndarray,
    rn: np.ndarray,
    mo: np.ndarray,
    dl: float,
    a: float,
    b: float,
    work: np.ndarray,
    qp: np.ndarray,
) -> float:
    """The cheap first-order bound of the angle (as .bounds._quick_excess): the largest
    ``value + excess`` over the pieces (``-inf`` without transects, NaN wins); each piece's
    into ``qp (P,)``."""
    n = len(x)
    n_j = n - 1
    extent = tu.max() - td.min()
    width = x[n - 1] - x[0]
    drift, w = work[0], work[1]
    tan_dl = math.tan(dl)
    for j in range(n_j):
        wx = x[j + 1] - x[j]
        acc = 0.0
        for c in range(2):
            dc = (tu[j + 1] - tu[j]) if c == 0 else (td[j + 1] - td[j])
            _, _, grow, drift_k, _ = _angular_growth(dc, wx, dl, tan_dl)
            acc += extent * grow + width * drift_k
        drift[j] = np.inf if acc >= _HUGE else acc
    best = -np.inf
    for p in range(rn.shape[0]):
        for j in range(n_j):
            w[j] = drift[j] if rn[p, j, 0] > 0 else 0.0
        total = mo[p, _TOTAL]
        val = mo[p, _VALUE] + _weighted_row(rn[p, :, 0], w, total, a, b) if total > 0 else -np.inf
        qp[p] = val
        if p == 0:
            best = val
        else:
            best = _nmax(best, val)
    return best
