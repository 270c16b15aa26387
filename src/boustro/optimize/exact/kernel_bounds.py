"""Compiled twins (numba) of the second-order upper bounds of Eq. 1, one angle a call.

The same formulas as :func:`.structure._runs`, :func:`.structure._parallel_drift`,
:func:`.bounds._second_order`, :func:`.bounds._linearised` and :func:`.bounds._kink_excess`
(docs/global_optimum.md, section 3), as loops over one angle's pieces and knot segments, in the
numpy code's order of operations (equal to rounding; tests/test_exact_kernel.py). Plain Python
until :func:`.kernel.compiled` compiles them.
"""

from __future__ import annotations

import math

import numpy as np

from .kernel_pieces import (
    _HUGE,
    _LAM,
    _MEAN_A,
    _MEAN_B,
    _RESID,
    _TOTAL,
    _V_AA,
    _V_AB,
    _V_BB,
    _VALUE,
    _X0,
    _angular_growth,
    _nmax,
    _nmin,
    _weighted_row,
)

__all__: list[str] = []


def _mu_ratio(
    c: float, sn: float, pv0: float, pv1: float, qv0: float, qv1: float, big_k: float, qn: float
) -> float:
    """The position ``mu`` in ``[0, 1]`` of a chord end on its edge at the angle whose cosine
    and sine are ``c``, ``sn``."""
    num = -sn * pv0 + c * pv1 + big_k
    den = -sn * qv0 + c * qv1
    if abs(den) <= 1e-12 * qn:
        dnum = -(c * pv0 + sn * pv1)
        dden = -(c * qv0 + sn * qv1)
        mu = dnum / (1.0 if dden == 0 else dden)
    else:
        mu = num / den
    if not math.isfinite(mu):
        mu = 0.5
    return min(max(mu, 0.0), 1.0)


def _parallel_edge(
    v: np.ndarray, h: np.ndarray, x: np.ndarray, chain: int, j: int, out: np.ndarray
) -> None:
    """The edge of ``chain`` (0 upper, 1 lower) covering segment ``j`` at the centre angle, for
    :func:`_parallel_one`: ``out[:5]`` = edge index (-1: none), ``V2 - V1``, its length, its
    direction's angle. The same for every piece and end of the segment, so computed once."""
    n = v.shape[0]
    xj, xj1 = x[j], x[j + 1]
    edge = -1
    for e in range(n):
        he, hn = h[e], h[e + 1 if e + 1 < n else 0]
        rising = hn > he if chain == 0 else hn < he
        if min(he, hn) <= xj and xj1 <= max(he, hn) and rising:
            edge = e
            break
    out[0] = edge
    if edge < 0:
        return
    e2 = (edge + 1) % n
    qv0, qv1 = v[e2, 0] - v[edge, 0], v[e2, 1] - v[edge, 1]
    out[1], out[2] = qv0, qv1
    out[3] = math.hypot(qv0, qv1)
    out[4] = math.atan2(qv1, qv0)


def _parallel_one(
    v: np.ndarray,
    s: float,
    theta: float,
    dl: float,
    trig: np.ndarray,
    edge_row: np.ndarray,
    fam_v: int,
    kap: float,
) -> float:
    """Drift of one chord end on an edge within ``dl`` of parallel (as
    .structure._parallel_drift, which documents the bound). ``trig``: cosine and sine of
    ``theta``, ``theta - dl``, ``theta + dl``; ``edge_row``: the edge (:func:`_parallel_edge`)."""
    edge = int(edge_row[0])
    if edge < 0:
        return np.inf
    pv0, pv1 = v[fam_v, 0] - v[edge, 0], v[fam_v, 1] - v[edge, 1]
    qv0, qv1, qn = edge_row[1], edge_row[2], edge_row[3]
    big_k = kap * s
    mu0 = _mu_ratio(trig[0], trig[1], pv0, pv1, qv0, qv1, big_k, qn)
    span = max(
        abs(_mu_ratio(trig[2], trig[3], pv0, pv1, qv0, qv1, big_k, qn) - mu0),
        abs(_mu_ratio(trig[4], trig[5], pv0, pv1, qv0, qv1, big_k, qn) - mu0),
    )
    cross = pv0 * qv1 - pv1 * qv0
    rhs = cross / (big_k * qn)
    ok = big_k != 0 and abs(rhs) <= 1.0
    if ok:
        phase = edge_row[4]
        acos = math.acos(min(max(rhs, -1.0), 1.0))
        for sign in (1.0, -1.0):
            crit = phase + sign * acos
            crit = crit + np.rint((theta - crit) / (2 * math.pi)) * 2 * math.pi
            if abs(crit - theta) < dl:
                mu_c = _mu_ratio(math.cos(crit), math.sin(crit), pv0, pv1, qv0, qv1, big_k, qn)
                span = max(span, abs(mu_c - mu0))
    span = min(span, max(mu0, 1.0 - mu0))
    dist = math.hypot(pv0, pv1)
    return dl * dist + qn * (span + mu0 * dl)


#: Columns of a segment's chain terms ``chain (J, 2, _NCH)`` (:func:`_chains_one`).
_R, _ZC, _GROW, _DRIFT_K, _REACH, _RATE, _BIG, _C0, _C1 = range(9)
_NCH = 9


def _ends_one(
    v: np.ndarray,
    h: np.ndarray,
    x: np.ndarray,
    s: float,
    theta: float,
    dl: float,
    j: int,
    p: int,
    pc: np.ndarray,
    fam: np.ndarray,
    rn: np.ndarray,
    cj: np.ndarray,
    ej: np.ndarray,
    trig: np.ndarray,
    scratch: np.ndarray,
) -> tuple[float, float]:
    """Drift and curvature bound of the run of piece ``p`` in segment ``j`` (its ends ``q``:
    first and last transect at either piece end, on both chains ``c``); ``cj (2, _NCH)`` the
    segment's chain terms, ``ej (2, 6)`` its edges for :func:`_parallel_one` (computed here
    when first needed: column 5 says whether they are), ``trig`` the angles' cosines and sines
    (:func:`_chains_one`). Leaves the ends' offsets ``tau`` in ``scratch[14:16]``."""
    kap, rel, tfam = scratch[8], scratch[9], scratch[10]
    ed, tau = scratch[12:14], scratch[14:16]
    wx = x[j + 1] - x[j]
    wxs = wx if wx > 0 else 1.0
    last = max(rn[p, j, 0] - 1.0, 0.0)
    rel[0], rel[1] = rn[p, j, 4], rn[p, j, 4] + last * s
    rel[2], rel[3] = rn[p, j, 5], rn[p, j, 5] + last * s
    tfam[0], tfam[1], tfam[2], tfam[3] = pc[p, 2], pc[p, 2], pc[p, 3], pc[p, 3]
    kraw0, kraw1 = rn[p, j, 6], rn[p, j, 7]
    kap[0], kap[1] = abs(kraw0) * s, abs(kraw0 + last) * s
    kap[2], kap[3] = abs(kraw1) * s, abs(kraw1 + last) * s
    for c in range(2):
        grow_c, drift_kc = cj[c, _GROW], cj[c, _DRIFT_K]
        c0, c1 = cj[c, _C0], cj[c, _C1]
        for q in range(4):
            phi = rel[q] / wxs
            tq = (1.0 - phi) * c0 + phi * c1 - tfam[q]
            tau[c, q] = tq
            e = abs(tq) * grow_c + kap[q] * drift_kc
            if e >= 1e-3 and cj[c, _BIG] > 0:  # an edge near parallel: bound it on the edge
                kraw = (kraw0 if q < 2 else kraw1) + (last if q % 2 == 1 else 0.0)
                fam_v = fam[p, 0] if q < 2 else fam[p, 1]
                if ej[c, 5] == 0.0:  # the segment's edge, once per segment and chain
                    _parallel_edge(v, h, x, c, j, ej[c])
                    ej[c, 5] = 1.0
                e = _nmin(e, _parallel_one(v, s, theta, dl, trig, ej[c], fam_v, kraw))
            ed[c, q] = e
    dr = 0.0
    cv = 0.0
    for q in range(4):  # the sums over the chains, the largest over the ends (NaN wins)
        cq = 0.0
        for c in range(2):
            r_c = cj[c, _R]
            tmax = abs(tau[c, q]) * (1.0 + cj[c, _GROW]) + kap[q] * cj[c, _REACH]
            term = kap[q] * r_c + tmax * (1.0 + 2.0 * r_c**2)
            cq = term if c == 0 else cq + term
        dq = ed[0, q] + ed[1, q]
        dr = dq if q == 0 else _nmax(dr, dq)
        cv = cq if q == 0 else _nmax(cv, cq)
    return dr, cv


def _chains_one(
    s: float,
    theta: float,
    dl: float,
    x: np.ndarray,
    tu: np.ndarray,
    td: np.ndarray,
    chain: np.ndarray,
    edges: np.ndarray,
    d1: np.ndarray,
    trig: np.ndarray,
) -> None:
    """The terms of every segment's edges on the upper and lower chain, the same for every
    piece (as .structure._runs): ``chain (J, 2, _NCH)``, ``d1 (J,)``; ``trig (6,)`` the
    cosine and sine of ``theta``, ``theta - dl`` and ``theta + dl``; ``edges (J, 2, 6)``
    marked not computed yet."""
    n_j = len(x) - 1
    trig[0], trig[1] = math.cos(theta), math.sin(theta)
    th_lo, th_hi = theta - dl, theta + dl
    trig[2], trig[3] = math.cos(th_lo), math.sin(th_lo)
    trig[4], trig[5] = math.cos(th_hi), math.sin(th_hi)
    tan_dl = math.tan(dl)
    for j in range(n_j):
        wx = x[j + 1] - x[j]
        wxs = wx if wx > 0 else 1.0
        dsum = 0.0
        for c in range(2):  # the segment's edges on the upper and lower chain
            cj = chain[j, c]
            c0, c1 = (tu[j], tu[j + 1]) if c == 0 else (td[j], td[j + 1])
            cj[_C0], cj[_C1] = c0, c1
            dc = c1 - c0
            r, zc, grow, drift_k, big_c = _angular_growth(dc, wx, dl, tan_dl)
            cj[_R], cj[_ZC], cj[_GROW], cj[_DRIFT_K] = r, zc, grow, drift_k
            cj[_BIG] = 1.0 if big_c else 0.0
            rs = r if zc > 0 else 1.0
            cj[_REACH] = _HUGE if big_c else (grow / rs if zc > 0 else dl)
            rate = -dc / wxs
            cj[_RATE] = rate
            sign = -1.0 if c == 0 else 1.0
            dsum += sign * (-s) * rate * rate
            edges[j, c, 5] = 0.0
        d1[j] = dsum


def _runs_piece(
    p: int,
    v: np.ndarray,
    s: float,
    theta: float,
    dl: float,
    h: np.ndarray,
    x: np.ndarray,
    pc: np.ndarray,
    fam: np.ndarray,
    rn: np.ndarray,
    chain: np.ndarray,
    edges: np.ndarray,
    trig: np.ndarray,
    drift: np.ndarray,
    curv: np.ndarray,
    d0: np.ndarray,
    scratch: np.ndarray,
) -> None:
    """Derivative data of piece ``p``'s runs (as .structure._runs with ``second=True``):
    ``drift[p], curv[p] (J,)``, ``d0[:, p] (2, J)``, the segments' terms from
    :func:`_chains_one`; ``scratch (16, 4)``."""
    tau = scratch[14:16]
    for j in range(rn.shape[1]):
        if not rn[p, j, 0] > 0:  # no transect: the numpy code's np.where(has, ..., 0)
            drift[p, j] = 0.0
            curv[p, j] = 0.0
            d0[0, p, j] = 0.0
            d0[1, p, j] = 0.0
            continue
        cj = chain[j]
        dr, cv = _ends_one(v, h, x, s, theta, dl, j, p, pc, fam, rn, cj, edges[j], trig, scratch)
        drift[p, j] = np.inf if dr >= _HUGE else dr
        curv[p, j] = np.inf if cv >= _HUGE else cv
        for e_ in range(2):
            d0[e_, p, j] = (-1.0 * tau[0, 2 * e_]) * cj[0, _RATE] + (tau[1, 2 * e_]) * cj[1, _RATE]


def _linearised_one(
    p: int,
    lam: float,
    rn: np.ndarray,
    mo: np.ndarray,
    cc: np.ndarray,
    curv: np.ndarray,
    d0: np.ndarray,
    d1: np.ndarray,
    a: float,
    b: float,
) -> tuple[float, float, float, float, float]:
    """Eq. 1 at ``lam``, its ``lam``-slope, its angle-derivatives through the piece's two ends
    and the curvature factor (as .bounds._linearised)."""
    n_j = rn.shape[1]
    total = mo[p, _TOTAL]
    tsafe = total if total > 0 else 1.0
    v_bb = mo[p, _V_BB]
    var = v_bb * (lam - mo[p, _X0]) ** 2 + mo[p, _RESID] if v_bb > 1e-300 else mo[p, _V_AA]
    sd = math.sqrt(max(var, 0.0))
    pos = sd > 0
    inv = 1.0 / sd if pos else 0.0
    value = a * (mo[p, _MEAN_A] + mo[p, _MEAN_B] * lam) + b * (1.0 - sd)
    slope = a * mo[p, _MEAN_B] - b * (mo[p, _V_AB] + v_bb * lam) * inv
    sm0 = 0.0
    sc0 = 0.0
    sm1 = 0.0
    sc1 = 0.0
    s1 = 0.0
    s2 = 0.0
    s3 = 0.0
    for j in range(n_j):
        cnt = rn[p, j, 0]
        if cnt == 0:  # exact zeros in every sum (d0 and curv are 0 there)
            continue
        step, i1, i2, cv = rn[p, j, 2], cc[p, j, 0], cc[p, j, 1], curv[p, j]
        cl = cc[p, j, 2] + cc[p, j, 3] * lam
        e0, e1, dj = d0[0, p, j], d0[1, p, j], d1[j]
        sm0 += cnt * e0 + dj * i1
        sc0 += cnt * cl * e0 + (cl * dj + step * e0) * i1 + step * dj * i2
        sm1 += cnt * e1 + dj * i1
        sc1 += cnt * cl * e1 + (cl * dj + step * e1) * i1 + step * dj * i2
        last = cl + step * max(cnt - 1.0, 0.0)
        s1 += cnt * cv
        s2 += cnt * cv * cv
        s3 += cnt * cv * max(abs(cl), abs(last))
    g0 = a * (sm0 / tsafe) - b * sc0 / tsafe * inv
    g1 = a * (sm1 / tsafe) - b * sc1 / tsafe * inv
    mean_c = s1 / tsafe
    rms_c = math.sqrt(s2 / tsafe)
    zsum = s3 / tsafe * inv
    zfac = _nmin(rms_c, zsum) if (pos and total > 1) else 0.0
    remfac = a * mean_c + b * zfac
    if remfac != remfac:
        remfac = np.inf
    return value, slope, g0, g1, remfac


def _second_one(
    p: int,
    rn: np.ndarray,
    mo: np.ndarray,
    cc: np.ndarray,
    curv: np.ndarray,
    d0: np.ndarray,
    d1: np.ndarray,
    dl: float,
    a: float,
    b: float,
) -> float:
    """Second-order excess of piece ``p`` (as .bounds._second_order, its ``second``)."""
    n_j = rn.shape[1]
    total = mo[p, _TOTAL]
    tsafe = total if total > 0 else 1.0
    lam_c = mo[p, _LAM]
    sq = 0.0
    sqq = 0.0
    for j in range(n_j):
        qv = d0[1, p, j] - d0[0, p, j]
        sq += rn[p, j, 0] * qv
        sqq += rn[p, j, 0] * qv * qv
    m_q = sq / tsafe
    sd_q = math.sqrt(max(sqq / tsafe - m_q * m_q, 0.0))
    v_bb, resid = mo[p, _V_BB], mo[p, _RESID]
    var_c = v_bb * (lam_c - mo[p, _X0]) ** 2 + resid if v_bb > 1e-300 else mo[p, _V_AA]
    curv_c = b * v_bb * resid / max(var_c, 0.0) ** 1.5
    half = 2.0 * dl * (a * abs(m_q) + b * sd_q) / curv_c
    if curv_c == 0:
        half = 1.0
    elif not math.isfinite(half):
        half = 0.0
    half = min(max(half, 1e-12), 1.0)
    lam_l, lam_r = lam_c - half, lam_c + half
    in_l, in_r = max(lam_l, 0.0), min(lam_r, 1.0)
    best = -np.inf
    for k in range(3):
        if k == 0:
            pt, blo, bhi = lam_c, in_l, in_r
        elif k == 1:
            pt, blo, bhi = in_l, 0.0, in_l
        else:
            pt, blo, bhi = in_r, in_r, 1.0
        val, slope, glo, ghi, remfac = _linearised_one(p, pt, rn, mo, cc, curv, d0, d1, a, b)
        present = True if k == 0 else (lam_l > 0 if k == 1 else lam_r < 1)
        c_lo = (blo - pt) * slope + dl * abs(glo + blo * (ghi - glo))
        c_hi = (bhi - pt) * slope + dl * abs(glo + bhi * (ghi - glo))
        rem = remfac * 0.5 * dl**2
        box = val + _nmax(c_lo, c_hi) + rem if present else -np.inf
        best = box if k == 0 else _nmax(best, box)
    second = best - mo[p, _VALUE]
    return np.inf if second != second else second


def _kink_one(
    p: int,
    rn: np.ndarray,
    mo: np.ndarray,
    cc: np.ndarray,
    curv: np.ndarray,
    d0: np.ndarray,
    d1: np.ndarray,
    dl: float,
    a: float,
    b: float,
) -> float:
    """Excess of piece ``p`` from the split of Eq. 1 at its maximiser (as
    .bounds._kink_excess, which documents the bound)."""
    n_j = rn.shape[1]
    total = mo[p, _TOTAL]
    tsafe = total if total > 0 else 1.0
    lam = mo[p, _LAM]
    s_p = 0.0
    s_b = 0.0
    s_q = 0.0
    for j in range(n_j):
        cnt = rn[p, j, 0]
        p0 = (1.0 - lam) * d0[0, p, j] + lam * d0[1, p, j]
        s_p += cnt * p0 + d1[j] * cc[p, j, 0]
        s_b += cnt * rn[p, j, 3]
        s_q += cnt * (d0[1, p, j] - d0[0, p, j])
    m_p, m_b, m_q = s_p / tsafe, s_b / tsafe, s_q / tsafe
    v_pp = 0.0
    v_pb = 0.0
    v_bb = 0.0
    vqq = 0.0
    for j in range(n_j):
        cnt, i1, i2 = rn[p, j, 0], cc[p, j, 0], cc[p, j, 1]
        p0 = (1.0 - lam) * d0[0, p, j] + lam * d0[1, p, j]
        cp = p0 - m_p if cnt > 0 else 0.0
        cb = rn[p, j, 3] - m_b if cnt > 0 else 0.0
        cq = (d0[1, p, j] - d0[0, p, j]) - m_q if cnt > 0 else 0.0
        v_pp += cnt * cp * cp + 2.0 * cp * d1[j] * i1 + d1[j] * d1[j] * i2
        v_pb += cb * (cnt * cp + d1[j] * i1)
        v_bb += cnt * cb * cb
        vqq += cnt * cq * cq
    v_pp, v_pb, v_bb = v_pp / tsafe, v_pb / tsafe, v_bb / tsafe
    c_q = a * abs(m_q) + b * math.sqrt(vqq / tsafe)
    best = 0.0
    pos_b = v_bb > 1e-300
    vbs = v_bb if pos_b else 1.0
    for tau in (1.0, -1.0):
        x0 = -tau * v_pb / vbs
        r = max(v_pp - v_pb * v_pb / vbs, 0.0)
        for half in (1.0, -1.0):
            alpha = a * m_b + half * dl * c_q
            disc = b * b * v_bb - alpha * alpha
            bounded = pos_b and disc > 0
            sgn = 1.0 if alpha > 0 else (-1.0 if alpha < 0 else alpha)
            mu_s = x0 + sgn * abs(alpha) * math.sqrt(r) / math.sqrt(vbs * disc if bounded else 1.0)
            mu = _nmax(mu_s, 0.0) if half > 0 else _nmin(mu_s, 0.0)
            flat_ok = (not pos_b) and (half * alpha <= 0)
            if not bounded:
                mu = 0.0
            q = _nmax(v_pp + 2.0 * tau * v_pb * mu + v_bb * mu * mu, 0.0)
            h = tau * a * m_p + alpha * mu - b * math.sqrt(q)
            if not (bounded or flat_ok):
                h = np.inf
            best = _nmax(best, h)
    vb_mo = mo[p, _V_BB]
    var = vb_mo * (lam - mo[p, _X0]) ** 2 + mo[p, _RESID] if vb_mo > 1e-300 else mo[p, _V_AA]
    sd = math.sqrt(max(var, 0.0))
    rem = _weighted_row(rn[p, :, 0], curv[p], total, a, b) * 0.5 * dl**2
    out = 2.0 * b * sd + dl * best + rem
    return np.inf if out != out else out
