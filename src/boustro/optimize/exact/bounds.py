"""Upper bounds of Eq. 1 over an angle interval (first and second order)."""

from __future__ import annotations

import math

import numpy as np

from .search import _BATCH
from .structure import (
    _HUGE,
    BOUND_SLACK,
    Array,
    _edge_rate,
    _Moments,
    _Runs,
    _runs,
    _Structure,
    _structure,
    _sum_sq,
    _take,
    _weighted,
)

__all__ = []


def _smith_pieces(st: _Structure, a: float, b: float) -> _Moments:
    """Exact maximum of Eq. 1 on every piece, in closed form (concave in ``lam``)."""
    cnt = st.count
    i1 = cnt * (cnt - 1.0) * 0.5
    i2 = (cnt - 1.0) * cnt * (2.0 * cnt - 1.0) / 6.0
    total = cnt.sum(axis=-1)
    ok = total > 0
    tsafe = np.where(ok, total, 1.0)
    mean_a = (cnt * st.first + st.step * i1).sum(axis=-1) / tsafe
    mean_b = (cnt * st.slope).sum(axis=-1) / tsafe
    ca = st.first - mean_a[..., None]
    cb = np.where(cnt > 0, st.slope - mean_b[..., None], 0.0)
    v_aa = _sum_sq(ca, st.step, cnt, i1, i2) / tsafe
    v_11 = _sum_sq(ca + cb, st.step, cnt, i1, i2) / tsafe
    v_bb = (cnt * cb * cb).sum(axis=-1) / tsafe
    v_ab = (cb * (cnt * ca + st.step * i1)).sum(axis=-1) / tsafe
    pos = v_bb > 1e-300
    vbs = np.where(pos, v_bb, 1.0)
    x0 = np.where(pos, -v_ab / vbs, 0.0)
    # Residual variance, min over lam, recomputed from the centred runs (no cancellation).
    resid = np.where(pos, _sum_sq(ca + x0[..., None] * cb, st.step, cnt, i1, i2) / tsafe, v_aa)
    # Stationary point of a * mean_b * lam - b * sqrt(v_bb (lam - x0)^2 + resid).
    disc = b * b * v_bb - a * a * mean_b * mean_b
    has_stat = pos & (disc > 0)
    xs = np.sign(mean_b) * a * np.abs(mean_b) * np.sqrt(resid)
    xs = np.where(has_stat, xs / np.sqrt(np.where(has_stat, vbs * disc, 1.0)), 0.0)
    lam_s = np.where(has_stat, x0 + xs, np.where(mean_b > 0, 1.0, 0.0))
    lam_s = np.clip(lam_s, 0.0, 1.0)
    q_s = np.where(pos, v_bb * (lam_s - x0) ** 2 + resid, v_aa)
    f0 = a * mean_a + b * (1.0 - np.sqrt(np.maximum(v_aa, 0.0)))
    f1 = a * (mean_a + mean_b) + b * (1.0 - np.sqrt(np.maximum(v_11, 0.0)))
    fs = a * (mean_a + mean_b * lam_s) + b * (1.0 - np.sqrt(np.maximum(q_s, 0.0)))
    stack = np.stack([f0, fs, f1])
    pick = np.argmax(stack, axis=0)
    value = np.take_along_axis(stack, pick[None], axis=0)[0]
    lam = np.where(pick == 0, 0.0, np.where(pick == 2, 1.0, lam_s))
    value = np.where(ok, value, -np.inf)
    return _Moments(total, mean_a, mean_b, ca, cb, i1, i2, v_aa, v_ab, v_bb, x0, resid, value, lam)


def _linearised(
    st: _Structure, mo: _Moments, ru: _Runs, lam: Array, a: float, b: float
) -> tuple[Array, Array, Array, Array, Array]:
    """At ``lam`` ``(K, M, P)``: Eq. 1, its ``lam``-derivative and its angle-derivatives through
    the two piece ends (``G_lo``, ``G_hi``), all from one supergradient ``g`` of the concave
    Eq. 1 (``g_k = a / N - b z_k / N``, ``z`` the standardised lengths; ``z = 0`` where the std is
    0), and ``sum_k |g_k| curv_k``, the factor of the curvature remainder."""
    assert ru.d0 is not None and ru.d1 is not None and ru.curv is not None
    tsafe = np.where(mo.total > 0, mo.total, 1.0)
    var = np.where(mo.v_bb > 1e-300, mo.v_bb * (lam - mo.x0) ** 2 + mo.resid, mo.v_aa)
    sd = np.sqrt(np.maximum(var, 0.0))
    pos = sd > 0
    inv = np.where(pos, 1.0 / np.where(pos, sd, 1.0), 0.0)
    value = a * (mo.mean_a + mo.mean_b * lam) + b * (1.0 - sd)
    slope = a * mo.mean_b - b * (mo.v_ab + mo.v_bb * lam) * inv
    cl = mo.ca + mo.cb * lam[..., None]  # (K, M, P, J) centred first lengths at lam
    cnt, step, d1 = st.count, st.step, ru.d1
    grads = []
    for e in (0, 1):
        d0 = ru.d0[e]
        mean_d = (cnt * d0 + d1 * mo.i1).sum(axis=-1) / tsafe
        cov = (cnt * cl * d0 + (cl * d1 + step * d0) * mo.i1 + step * d1 * mo.i2).sum(axis=-1)
        grads.append(a * mean_d - b * cov / tsafe * inv)
    curv = ru.curv
    with np.errstate(invalid="ignore", over="ignore"):
        mean_c = (cnt * curv).sum(axis=-1) / tsafe
        rms_c = np.sqrt((cnt * curv * curv).sum(axis=-1) / tsafe)
        last = cl + step * np.maximum(cnt - 1.0, 0.0)
        zsum = (cnt * curv * np.maximum(np.abs(cl), np.abs(last))).sum(axis=-1) / tsafe * inv
        zfac = np.where(pos & (mo.total > 1), np.minimum(rms_c, zsum), 0.0)
        remfac = a * mean_c + b * zfac
    remfac = np.where(np.isnan(remfac), np.inf, remfac)
    return value, slope, grads[0], grads[1], remfac


def _second_order(
    v: Array, st: _Structure, mo: _Moments, delta: Array, s: float, a: float, b: float
) -> tuple[Array, Array]:
    """First- and second-order excess ``(M, P)`` of every piece over its exact maximum.

    Second order: with ``L_b`` the lengths at a point ``lam_b`` of a box ``[l0, l1]`` of the piece
    where Eq. 1 is largest on the box, concavity gives
    ``f(L) <= f(L_b) + grad . (L - L_b)``; the right side is linear in ``lam`` and in the angle
    offset, plus the lengths' curvature remainder, so its maximum is at a corner. Three boxes
    around the piece's maximiser make the bound quadratic in ``delta`` near smooth maxima.
    """
    ru = _runs(v, st, delta, s, second=True)
    first = _weighted(st.count, ru.drift, mo.total, a, b)
    dl = delta[:, None]
    lam_c = mo.lam
    # |G_hi - G_lo| = |grad . Q| <= a |mean Q| + b std(Q), Q the runs' change of derivative
    assert ru.d0 is not None
    cnt = st.count
    tsafe = np.where(mo.total > 0, mo.total, 1.0)
    qv = ru.d0[1] - ru.d0[0]
    m_q = (cnt * qv).sum(axis=-1) / tsafe
    sd_q = np.sqrt(np.maximum((cnt * qv * qv).sum(axis=-1) / tsafe - m_q * m_q, 0.0))
    var_c = np.where(mo.v_bb > 1e-300, mo.v_bb * (lam_c - mo.x0) ** 2 + mo.resid, mo.v_aa)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        curv_c = b * mo.v_bb * mo.resid / np.maximum(var_c, 0.0) ** 1.5
        half = 2.0 * dl * (a * np.abs(m_q) + b * sd_q) / curv_c
    half = np.where(curv_c == 0, 1.0, np.where(np.isfinite(half), half, 0.0))
    half = np.clip(half, 1e-12, 1.0)
    lam_l, lam_r = lam_c - half, lam_c + half
    in_l, in_r = np.maximum(lam_l, 0.0), np.minimum(lam_r, 1.0)
    pts = np.stack([lam_c, in_l, in_r])
    val, slope, glo, ghi, remfac = _linearised(st, mo, ru, pts, a, b)
    box_lo = np.stack([in_l, np.zeros_like(lam_c), in_r])
    box_hi = np.stack([in_r, in_l, np.ones_like(lam_c)])
    present = np.stack([np.ones(lam_c.shape, dtype=bool), lam_l > 0, lam_r < 1])
    with np.errstate(invalid="ignore", over="ignore"):
        corner = [
            (edge - pts) * slope + dl * np.abs(glo + edge * (ghi - glo))
            for edge in (box_lo, box_hi)
        ]
        rem = remfac * 0.5 * dl**2
        boxes = np.where(present, val + np.maximum(corner[0], corner[1]) + rem, -np.inf)
        second = boxes.max(axis=0) - mo.value
    second = np.where(np.isnan(second), np.inf, second)
    kink = _kink_excess(st, mo, ru, delta, a, b)
    return first, np.minimum(second, kink)


def _kink_excess(
    st: _Structure, mo: _Moments, ru: _Runs, delta: Array, a: float, b: float
) -> Array:
    """Excess ``(M, P)`` from the exact split of Eq. 1 at the piece's maximiser ``L*``.

    ``std(L* + D) >= std(D) - std(L*)`` gives ``f(L* + D) <= f* + 2 b std(L*) + a mean(D) -
    b std(D)``. With ``D = tau P + mu B + tau mu Q + rho`` (``P``: the lengths' angle-derivative
    at ``lam*``, ``B``: their ``lam``-slope, ``Q``: the change of ``P`` across the piece, ``rho``:
    curvature remainder), ``a mean(tau P + mu B) - b std(tau P + mu B) + |tau mu| c_Q`` is concave
    and positively homogeneous on each half-plane ``mu >= 0``, ``mu <= 0``, so its supremum over
    ``|tau| <= delta`` is ``delta`` times its supremum at ``tau = +-1``, in closed form. This keeps
    the bound second order where the maximum is a kink (all lengths equal), as for rectangles.
    """
    assert ru.d0 is not None and ru.d1 is not None and ru.curv is not None
    cnt, d1 = st.count, ru.d1
    i1, i2 = mo.i1, mo.i2
    lam = mo.lam[..., None]
    tsafe = np.where(mo.total > 0, mo.total, 1.0)
    p0 = (1.0 - lam) * ru.d0[0] + lam * ru.d0[1]  # P_i = p0 + d1 i
    qv = ru.d0[1] - ru.d0[0]  # Q per run
    bv = st.slope  # B per run
    m_p = (cnt * p0 + d1 * i1).sum(axis=-1) / tsafe
    m_b = (cnt * bv).sum(axis=-1) / tsafe
    m_q = (cnt * qv).sum(axis=-1) / tsafe
    cp = np.where(cnt > 0, p0 - m_p[..., None], 0.0)
    cb = np.where(cnt > 0, bv - m_b[..., None], 0.0)
    cq = np.where(cnt > 0, qv - m_q[..., None], 0.0)
    v_pp = _sum_sq(cp, d1, cnt, i1, i2) / tsafe
    v_pb = (cb * (cnt * cp + d1 * i1)).sum(axis=-1) / tsafe
    v_bb = (cnt * cb * cb).sum(axis=-1) / tsafe
    c_q = a * np.abs(m_q) + b * np.sqrt((cnt * cq * cq).sum(axis=-1) / tsafe)
    dl = delta[:, None]
    best = np.zeros(m_p.shape)
    pos_b = v_bb > 1e-300
    vbs = np.where(pos_b, v_bb, 1.0)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for tau in (1.0, -1.0):
            x0 = -tau * v_pb / vbs
            r = np.maximum(v_pp - v_pb * v_pb / vbs, 0.0)
            for half in (1.0, -1.0):
                alpha = a * m_b + half * dl * c_q
                disc = b * b * v_bb - alpha * alpha
                bounded = pos_b & (disc > 0)
                mu_s = x0 + np.sign(alpha) * np.abs(alpha) * np.sqrt(r) / np.sqrt(
                    np.where(bounded, vbs * disc, 1.0)
                )
                mu = np.where(half > 0, np.maximum(mu_s, 0.0), np.minimum(mu_s, 0.0))
                # without curvature in mu the half-line is bounded only if alpha points back
                flat_ok = ~pos_b & (half * alpha <= 0)
                mu = np.where(bounded, mu, 0.0)
                q = np.maximum(v_pp + 2.0 * tau * v_pb * mu + v_bb * mu * mu, 0.0)
                h = tau * a * m_p + alpha * mu - b * np.sqrt(q)
                h = np.where(bounded | flat_ok, h, np.inf)
                best = np.maximum(best, h)
        sd = np.sqrt(
            np.maximum(
                np.where(mo.v_bb > 1e-300, mo.v_bb * (mo.lam - mo.x0) ** 2 + mo.resid, mo.v_aa), 0.0
            )
        )
        rem = _weighted(cnt, ru.curv, mo.total, a, b) * 0.5 * dl**2
        out = 2.0 * b * sd + dl * best + rem
    return np.where(np.isnan(out), np.inf, out)


def _quick_excess(st: _Structure, mo: _Moments, delta: Array, a: float, b: float) -> Array:
    """A cheap, looser first-order excess ``(M, P)``: every chord end is within the polygon's
    extent along the transects of its pivot's foot, and every pivot within its width."""
    x = st.x
    wx = (x[:, 1:] - x[:, :-1])[:, None, :]
    chains = np.stack([st.tu, st.td])
    dc = chains[:, :, None, 1:] - chains[:, :, None, :-1]
    dl = delta[None, :, None, None]
    r, bad = _edge_rate(dc, wx, dl)
    z = r * dl
    big = bad | (z > 600.0)
    zc = np.where(big, 0.0, z)
    grow = np.where(big, _HUGE, np.expm1(zc))
    rs = np.where(zc > 0, r, 1.0)
    drift_k = np.where(big, _HUGE, np.where(zc > 0, np.maximum(grow - zc, 0.5 * zc * zc) / rs, 0.0))
    extent = (st.tu.max(axis=1) - st.td.min(axis=1))[:, None, None]
    width = (x[:, -1] - x[:, 0])[:, None, None]
    drift = (extent * grow + width * drift_k).sum(axis=0)  # (M, 1, J)
    drift = np.where(drift >= _HUGE, np.inf, drift)
    return _weighted(st.count, np.where(st.count > 0, drift, 0.0), mo.total, a, b)


def _evaluate_smith(
    v: Array, s: float, lo: Array, hi: Array, a: float, b: float, threshold: float = -math.inf
) -> tuple[Array, Array, Array, Array]:
    """At the midpoint of every interval: the exact best value over the offset, the offset that
    attains it, an upper bound over the whole (event-free) interval, and the order (1 or 2) of
    the bound that decided it.

    Intervals whose first-order bound is already at most ``threshold`` (or the best value found
    in this batch) skip the second-order bound: they will be discarded anyway.
    """
    g = np.empty(len(lo))
    d = np.empty(len(lo))
    ub = np.empty(len(lo))
    order = np.ones(len(lo))
    for start in range(0, len(lo), _BATCH):
        sl = slice(start, start + _BATCH)
        mid = 0.5 * (lo[sl] + hi[sl])
        half = 0.5 * (hi[sl] - lo[sl])
        st = _structure(v, s, mid)
        mo = _smith_pieces(st, a, b)
        rows = np.arange(len(mid))
        ip = np.argmax(mo.value, axis=1)
        gs = mo.value[rows, ip]
        g[sl] = gs
        d[sl] = st.beta[rows, ip] + mo.lam[rows, ip] * st.width[rows, ip]
        ok = mo.total > 0
        bound = np.where(ok, mo.value + _quick_excess(st, mo, half, a, b), -np.inf).max(axis=1)
        thr = max(threshold, float(gs.max()))
        need = np.flatnonzero(bound + BOUND_SLACK > thr)
        if len(need):
            st2, mo2 = _take(st, need), _take(mo, need)
            f1, f2 = _second_order(v, st2, mo2, half[need], s, a, b)
            excess = np.maximum(np.minimum(f1, f2), 0.0)
            pb = np.where(mo2.total > 0, mo2.value + excess, -np.inf)
            top = np.argmax(pb, axis=1)
            r2 = np.arange(len(need))
            bound[need] = pb[r2, top]
            order[sl][need] = np.where(f2[r2, top] < f1[r2, top], 2.0, 1.0)
        ub[sl] = bound + BOUND_SLACK
    return g, d, ub, order
