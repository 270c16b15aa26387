"""Events of the angle, the work limit, and the piece structure of the offset circle."""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...errors import ProblemTooLargeError
from ...geometry import Polygon

__all__ = ["BOUND_SLACK", "EVENT_MERGE", "WORK_LIMIT", "event_angles", "global_work"]


Array = NDArray[np.float64]


#: Events closer than this (radians) are one event: exact coincidences (symmetric polygons, a
#: spacing that divides a width) computed with rounding.
EVENT_MERGE = 1e-12


#: Added to every upper bound to cover floating-point rounding in the closed forms (the computed
#: piece maxima are accurate to ~1e-15; see docs/global_optimum.md).
BOUND_SLACK = 1e-10


def event_angles(vertices: ArrayLike, spacing: float) -> Array:
    """Sorted angles in ``[0, pi]`` where the piece structure of the offset circle can change.

    ``n(theta) . (v_i - v_j) = m s`` for a pair of vertices and an integer ``m`` (``m = 0`` for an
    adjacent pair is an edge parallel to the transects). ``0`` and ``pi`` are always included, so
    consecutive entries bound event-free open intervals that tile ``[0, pi]``.

    Args:
        vertices: ``(N, 2)`` vertices in the frame of ``spacing`` (normalised for the library).
        spacing: transect spacing, > 0.
    """
    v = np.asarray(vertices, dtype=np.float64)
    i, j = _pairs(len(v))
    delta = v[i] - v[j]
    dx, dy = delta[:, 0], delta[:, 1]
    dist = np.hypot(dx, dy)
    # n(theta) . delta = -sin(theta) dx + cos(theta) dy = dist * cos(theta - alpha)
    alpha = np.arctan2(-dx, dy)
    # The multiples m of each pair with |m s / dist| <= 1 (the float test, on the range
    # |m| <= floor(dist / s) + 1 that holds them): the arc cosines of those alone, not of every
    # pair against every multiple of the widest pair (the same numbers, about a tenth of them).
    reach = np.floor(dist / spacing) + 1.0
    top: NDArray[np.int64] = np.where(np.isfinite(reach), reach, 0.0).astype(np.int64)
    counts = 2 * top + 1
    pair = np.repeat(np.arange(len(dist)), counts)
    first = np.cumsum(counts) - counts
    m = (np.arange(len(pair)) - first[pair] - top[pair]).astype(np.float64)
    ratio = m * spacing / dist[pair]
    ok = np.abs(ratio) <= 1.0
    acos = np.arccos(ratio[ok])
    base = alpha[pair[ok]]
    cand = np.concatenate([base + acos, base - acos, [0.0]])
    cand = np.sort(np.mod(cand, math.pi))
    keep = np.empty(len(cand), dtype=bool)
    keep[0] = True
    np.greater(np.diff(cand), EVENT_MERGE, out=keep[1:])
    cand = cand[keep]
    if cand[-1] > math.pi - EVENT_MERGE:  # equal to 0 modulo pi
        cand = cand[:-1]
    return np.append(cand, math.pi)


@cache
def _pairs(n: int) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """``np.triu_indices(n, k=1)``, kept (read-only) per ``n``."""
    i, j = np.triu_indices(n, k=1)
    i.flags.writeable = j.flags.writeable = False
    return i, j


#: Most work the exact optimisers take on (events x vertices^2, see :func:`global_work`): about
#: 6 s and 1 GB on one core; a regular 40-gon at 1/100 of its diameter needs 3e8.
WORK_LIMIT = 1.0e8


def global_work(vertices: ArrayLike, spacing: float) -> float:
    """Estimated work of :func:`global_optimum` (and the shortest-path optimiser): the number of
    event angles (``2 (2 floor(|v_i - v_j| / s) + 1)`` for each pair of vertices) times the
    ``n^2`` pieces x segments of the structure evaluated between events."""
    v = np.asarray(vertices, dtype=np.float64)
    i, j = np.triu_indices(len(v), k=1)
    dist = np.hypot(*(v[i] - v[j]).T)
    events = float(np.sum(2.0 * (2.0 * np.floor(dist / spacing) + 1.0)))
    return events * len(v) ** 2


def _check_work(poly: Polygon, spacing: float, what: str) -> float:
    """The :func:`global_work` of the problem, refused beyond :data:`WORK_LIMIT`; below
    ``WORK_LIMIT / 10`` possibly an upper bound of it instead (every pair of vertices is at
    most the diameter apart), which small polygons settle without the ``O(n^2)`` sum."""
    n = len(poly)
    bound = n * (n - 1) * (2.0 * math.floor(poly.diameter / spacing) + 1.0) * n**2
    if bound <= WORK_LIMIT / 10:
        return bound
    work = global_work(poly.vertices, spacing)
    if work > WORK_LIMIT:
        raise ProblemTooLargeError(
            f"{what} would need about {work:.2g} units of work ({len(poly)} vertices at spacing "
            f"{spacing:.6g}; limit {WORK_LIMIT:.0e}, minutes and gigabytes beyond it): use "
            "method='hybrid' (or --method hybrid), a larger spacing, or fewer vertices"
        )
    return work


@dataclass
class _Structure:
    """Pieces x segments at ``M`` angles; arrays ``(M, P, J)`` unless stated.

    ``P = n`` pieces of the offset circle, ``J = n - 1`` segments between sorted knots. For piece
    ``p`` and segment ``j``, ``count`` transects lie in the segment; the first, at ``lam = 0``, has
    length ``first`` and the others follow with step ``step``; all move by ``slope * lam``.
    """

    theta: Array  # (M,)
    beta: Array  # (M, P) lower breakpoint of each piece
    width: Array  # (M, P) width of each piece (>= 0)
    count: Array  # (M, P, J) float
    first: Array
    step: Array
    slope: Array
    # pieces' end families and positions, for bounds
    rel_lo: Array  # (M, P, J) position of the first transect at lam=0 minus x_j
    rel_hi: Array  # (M, P, J) position of the first transect at lam=1 minus x_j
    tfam_lo: Array  # (M, P, 1) t of the lower family vertex
    tfam_hi: Array  # (M, P, 1)
    kap_lo: Array  # (M, P, J) index of the first transect relative to the lower family vertex
    kap_hi: Array  # (M, P, J) the same relative to the upper family vertex
    x: Array  # (M, n) sorted knots
    tu: Array  # (M, n) upper chain t at knots
    td: Array  # (M, n) lower chain t at knots
    fam_lo: NDArray[np.intp]  # (M, P) vertex index of the lower breakpoint
    fam_hi: NDArray[np.intp]  # (M, P)


def _next(a: NDArray[Any]) -> NDArray[Any]:
    """``a`` rotated one place left along axis 1 (``np.roll(a, -1, 1)``, cheaper)."""
    return np.concatenate([a[:, 1:], a[:, :1]], axis=1)


def _structure(v: Array, s: float, theta: Array) -> _Structure:
    """Knots, pieces and per-(piece, segment) transect runs at every angle of ``theta``."""
    cos, sin = np.cos(theta)[:, None], np.sin(theta)[:, None]
    h = v[:, 1] * cos - v[:, 0] * sin  # (M, n) projections on n(theta)
    t = v[:, 0] * cos + v[:, 1] * sin  # along u(theta)
    hb, tb = _next(h), _next(t)
    # Chord through each vertex: boundary points of every edge at that height.
    lo_e, hi_e = np.minimum(h, hb)[:, None, :], np.maximum(h, hb)[:, None, :]
    hv = h[:, :, None]
    inr = (lo_e <= hv) & (hv <= hi_e)
    dh = (hb - h)[:, None, :]
    flat = dh == 0
    frac = (hv - h[:, None, :]) / np.where(flat, 1.0, dh)
    frac = np.clip(np.where(flat, 0.0, frac), 0.0, 1.0)
    ta, tbb = t[:, None, :], tb[:, None, :]
    tt = np.where(frac == 1.0, tbb, ta + frac * (tbb - ta))
    t_hi = np.where(flat, np.maximum(ta, tbb), tt)
    t_lo = np.where(flat, np.minimum(ta, tbb), tt)
    tu_v = np.where(inr, t_hi, -np.inf).max(axis=2)  # (M, n)
    td_v = np.where(inr, t_lo, np.inf).min(axis=2)
    rows = np.arange(len(theta))[:, None]
    order = np.argsort(h, axis=1, kind="stable")
    x, tu, td = h[rows, order], tu_v[rows, order], td_v[rows, order]
    y = tu - td
    # Breakpoints of the offset circle.
    mult = np.floor(h / s)
    bp = h - mult * s
    fam_lo = np.argsort(bp, axis=1, kind="stable")
    fam_hi = _next(fam_lo)
    beta = bp[rows, fam_lo]  # (M, P)
    beta_hi = _next(beta)
    beta_hi[:, -1] += s
    width = beta_hi - beta
    m_lo, m_hi = mult[rows, fam_lo], mult[rows, fam_hi]
    m_hi[:, -1] -= 1.0  # the wrap piece ends at beta_0 + s
    h_lo, h_hi = h[rows, fam_lo], h[rows, fam_hi]
    # Runs of transects per (piece, segment), positions relative to the lower family vertex.
    x0, x1 = x[:, None, :-1], x[:, None, 1:]  # (M, 1, J)
    wx = x1 - x0
    hl = h_lo[:, :, None]
    half = 0.5 * width[:, :, None]
    k_lo = np.floor((x0 - hl - half) / s) + 1.0
    k_hi = np.ceil((x1 - hl - half) / s) - 1.0
    count = np.maximum(k_hi - k_lo + 1.0, 0.0)
    has = count > 0
    wx_safe = np.where(has, wx, 1.0)
    rel_lo = (hl - x0) + k_lo * s  # first transect at lam = 0, minus x_j
    k_hi_fam = k_lo + (m_lo - m_hi)[:, :, None]
    rel_hi = (h_hi[:, :, None] - x0) + k_hi_fam * s  # first transect at lam = 1, minus x_j
    y0, dy = y[:, None, :-1], (y[:, 1:] - y[:, :-1])[:, None, :]
    first = np.where(has, y0 + (rel_lo / wx_safe) * dy, 0.0)
    step = np.where(has, dy * (s / wx_safe), 0.0)
    slope = np.where(has, dy * (width[:, :, None] / wx_safe), 0.0)
    tfam_lo = t[rows, fam_lo][:, :, None]
    tfam_hi = t[rows, fam_hi][:, :, None]
    return _Structure(
        theta,
        beta,
        width,
        count,
        first,
        step,
        slope,
        rel_lo,
        rel_hi,
        tfam_lo,
        tfam_hi,
        k_lo,
        k_hi_fam,
        x,
        tu,
        td,
        fam_lo,
        fam_hi,
    )


def _sum_sq(c: Array, step: Array, count: Array, i1: Array, i2: Array) -> Array:
    """``sum_{i < count} (c + step i)^2`` summed over the last axis."""
    return (count * c * c + 2.0 * c * step * i1 + step * step * i2).sum(axis=-1)


@dataclass
class _Moments:
    """Eq. 1 on every piece as a function of ``lam``; arrays ``(M, P)`` unless stated.

    ``mean(lam) = mean_a + mean_b lam`` and ``var(lam) = v_bb (lam - x0)^2 + resid``; ``ca`` and
    ``cb`` ``(M, P, J)`` are the runs' first lengths and slopes minus ``mean_a`` and ``mean_b``.
    """

    total: Array
    mean_a: Array
    mean_b: Array
    ca: Array
    cb: Array
    i1: Array  # (M, P, J)
    i2: Array  # (M, P, J)
    v_aa: Array
    v_ab: Array
    v_bb: Array
    x0: Array
    resid: Array
    value: Array  # exact maximum over lam in [0, 1] (-inf without transects)
    lam: Array  # its argument


#: Stands for "no finite bound" in the derivative bounds (kept finite so that 0 * it is 0).
_HUGE = 1e100


@dataclass
class _Runs:
    """Per-run derivative data of the breakpoint chords at both ends of every piece.

    For end ``e`` (0: ``lam = 0``, 1: ``lam = 1``) transect ``i`` of a run has the chord-length
    derivative ``d0[e] + d1 * i`` at the centre angle; over the interval its length moves by at
    most ``drift`` and its second derivative is at most ``curv`` (``>= _HUGE``: no bound).
    """

    drift: Array  # (M, P, J)
    end_drift: Array | None = None  # (2, M, P, J) per chain (upper, lower), first order only
    d0: Array | None = None  # (2, M, P, J)
    d1: Array | None = None  # (M, 1, J)
    curv: Array | None = None  # (M, P, J)


def _parallel_drift(
    v: Array, st: _Structure, delta: Array, s: float, flag: NDArray[np.bool_]
) -> Array:
    """Drift of chord ends on an edge within ``delta`` of parallel to the transects, where the
    bound through the angular speed fails (entries of ``flag`` ``(2, 4, M, P, J)``).

    The end is ``P = V1 + mu (V2 - V1)`` on the edge ``V1 V2``; within an event-free interval it
    stays on the edge, so ``0 <= mu <= 1``, and ``mu = N / D`` with
    ``N = n . (v_f - V1) + kappa s``, ``D = n . (V2 - V1)`` (``v_f`` the family vertex).
    ``mu`` is monotone between the angles where
    ``u . (V2 - V1) = ((v_f - V1) x (V2 - V1)) / (kappa s)``, so its range over the interval is
    reached at the interval's ends (the limit ``N' / D'`` where the edge is parallel) or there.
    The end's distance ``tau`` from the pivot then moves by at most
    ``delta |V1 - v_f| + |V2 - V1| (|mu - mu_0| + mu_0 delta)``.
    """
    c_idx, q_idx, m_idx, p_idx, j_idx = np.nonzero(flag)
    theta = st.theta[m_idx]
    dl = delta[m_idx]
    end_hi = q_idx >= 2
    fam = np.where(end_hi, st.fam_hi[m_idx, p_idx], st.fam_lo[m_idx, p_idx])
    kap0 = np.where(end_hi, st.kap_hi[m_idx, p_idx, j_idx], st.kap_lo[m_idx, p_idx, j_idx])
    kap = kap0 + np.where(q_idx % 2 == 1, np.maximum(st.count[m_idx, p_idx, j_idx] - 1.0, 0.0), 0.0)
    big_k = kap * s
    # the edge of chain c covering segment j at the centre angle
    cos, sin = np.cos(theta)[:, None], np.sin(theta)[:, None]
    h = v[:, 1] * cos - v[:, 0] * sin
    hn = np.roll(h, -1, axis=1)
    xj = st.x[m_idx, j_idx][:, None]
    xj1 = st.x[m_idx, j_idx + 1][:, None]
    up = hn > h
    down = hn < h
    lo_e, hi_e = np.minimum(h, hn), np.maximum(h, hn)
    cover = (lo_e <= xj) & (xj1 <= hi_e) & np.where(c_idx[:, None] == 0, up, down)
    edge = np.argmax(cover, axis=1)
    found = cover[np.arange(len(edge)), edge]
    v1 = v[edge]
    v2 = v[(edge + 1) % len(v)]
    pv = v[fam] - v1
    qv = v2 - v1
    qn = np.hypot(qv[:, 0], qv[:, 1])

    def ratio(th: Array) -> Array:
        c, sn = np.cos(th), np.sin(th)
        num = -sn * pv[:, 0] + c * pv[:, 1] + big_k
        den = -sn * qv[:, 0] + c * qv[:, 1]
        dnum = -(c * pv[:, 0] + sn * pv[:, 1])
        dden = -(c * qv[:, 0] + sn * qv[:, 1])
        flat = np.abs(den) <= 1e-12 * qn
        with np.errstate(divide="ignore", invalid="ignore"):
            mu = np.where(
                flat, dnum / np.where(dden == 0, 1.0, dden), num / np.where(flat, 1.0, den)
            )
        return np.clip(np.where(np.isfinite(mu), mu, 0.5), 0.0, 1.0)

    mu0 = ratio(theta)
    span = np.maximum(np.abs(ratio(theta - dl) - mu0), np.abs(ratio(theta + dl) - mu0))
    cross = pv[:, 0] * qv[:, 1] - pv[:, 1] * qv[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        rhs = cross / (big_k * qn)
    ok = (big_k != 0) & (np.abs(rhs) <= 1.0)
    phase = np.arctan2(qv[:, 1], qv[:, 0])
    acos = np.arccos(np.clip(np.where(ok, rhs, 0.0), -1.0, 1.0))
    for sign in (1.0, -1.0):
        crit = phase + sign * acos
        crit = crit + np.round((theta - crit) / (2 * math.pi)) * 2 * math.pi
        inside = ok & (np.abs(crit - theta) < dl)
        span = np.where(inside, np.maximum(span, np.abs(ratio(crit) - mu0)), span)
    span = np.minimum(span, np.maximum(mu0, 1.0 - mu0))
    dist = np.hypot(pv[:, 0], pv[:, 1])
    out = dl * dist + qn * (span + mu0 * dl)
    return np.where(found, out, np.inf)


def _runs(v: Array, st: _Structure, delta: Array, s: float, second: bool) -> _Runs:
    """Derivative data of every run over the angle interval of half-width ``delta`` ``(M,)``.

    The chord at a piece end passes at signed distance ``kappa s`` from its family vertex ``v``;
    as the angle turns it rolls on the circle of radius ``|kappa| s`` about ``v``, i.e. it rotates
    about the tangent point ``q``. An end of the chord at signed distance ``tau`` from ``q`` on an
    edge with ``R = across / along`` obeys ``tau' = kappa s - tau R`` and ``R' = -(1 + R^2)``;
    ``|R| <= r = tan(psi + delta)`` on the interval, ``psi`` the edge's angle to the normal now.
    Hence ``|tau| <= |tau_0| e^z + K (e^z - 1) / r`` (``z = r delta``, ``K = |kappa| s``), the
    chord end moves by at most ``|tau_0| (e^z - 1) + K (e^z - 1 - z) / r`` and
    ``|tau''| <= K r + max|tau| (1 + 2 r^2)``. The chord length is the difference of its ends.
    """
    x = st.x
    wx = (x[:, 1:] - x[:, :-1])[:, None, :]  # (M, 1, J)
    wxs = np.where(wx > 0, wx, 1.0)
    chains = np.stack([st.tu, st.td])  # (2, M, n): upper and lower boundary t at the knots
    c0, c1 = chains[:, :, None, :-1], chains[:, :, None, 1:]  # (2, M, 1, J)
    dc = c1 - c0
    dl = delta[None, :, None, None]
    r, bad = _edge_rate(dc, wx, dl)
    z = r * dl
    big = bad | (z > 600.0)
    zc = np.where(big, 0.0, z)
    grow = np.where(big, _HUGE, np.expm1(zc))
    rs = np.where(zc > 0, r, 1.0)
    drift_k = np.where(big, _HUGE, np.where(zc > 0, np.maximum(grow - zc, 0.5 * zc * zc) / rs, 0.0))
    last = np.maximum(st.count - 1.0, 0.0)
    rel = np.stack([st.rel_lo, st.rel_lo + last * s, st.rel_hi, st.rel_hi + last * s])
    tfam = np.stack([st.tfam_lo, st.tfam_lo, st.tfam_hi, st.tfam_hi])
    kap = np.abs(np.stack([st.kap_lo, st.kap_lo + last, st.kap_hi, st.kap_hi + last])) * s
    phi = rel / wxs  # (4, M, P, J)
    tau = (1.0 - phi) * c0[:, None] + phi * c1[:, None] - tfam  # (2, 4, M, P, J)
    atau = np.abs(tau)
    has = st.count > 0
    ends_drift = atau * grow[:, None] + kap * drift_k[:, None]  # (2, 4, M, P, J)
    flag = (ends_drift >= 1e-3) & big[:, None] & has
    if np.any(flag):
        ends_drift = ends_drift.copy()
        ends_drift[flag] = np.minimum(ends_drift[flag], _parallel_drift(v, st, delta, s, flag))
    drift = ends_drift.sum(axis=0).max(axis=0)
    drift = np.where(has, np.where(drift >= _HUGE, np.inf, drift), 0.0)
    if not second:
        end_drift = ends_drift.max(axis=1)  # (2, M, P, J): how far each end of a chord moves
        end_drift = np.where(has, np.where(end_drift >= _HUGE, np.inf, end_drift), 0.0)
        return _Runs(drift, end_drift=end_drift)
    reach_k = np.where(big, _HUGE, np.where(zc > 0, grow / rs, dl))
    tmax = atau * (1.0 + grow[:, None]) + kap * reach_k[:, None]
    curv = (kap * r[:, None] + tmax * (1.0 + 2.0 * r[:, None] ** 2)).sum(axis=0).max(axis=0)
    curv = np.where(has, np.where(curv >= _HUGE, np.inf, curv), 0.0)
    rate = -dc / wxs  # signed R of each chain's edge at the centre angle (2, M, 1, J)
    sign = np.array([-1.0, 1.0])[:, None, None, None]
    # chord derivative -tau_U R_U + tau_D R_D at the first transect of each end
    d0 = (sign[:, None] * tau[:, 0::2] * rate[:, None]).sum(axis=0)  # (2, M, P, J)
    d1 = (sign * (-s) * rate * rate).sum(axis=0)  # (M, 1, J)
    return _Runs(drift, None, np.where(has, d0, 0.0), d1, curv)


def _edge_rate(dc: Array, wx: Array, dl: Array) -> tuple[Array, NDArray[np.bool_]]:
    """``(r, bad)``: ``r = tan(atan2(|dc|, wx) + dl)``, the largest ``|across / along|`` of an
    edge rising ``dc`` over ``wx`` within ``dl`` of the centre angle, by the addition formula
    ``(m + tan dl) / (1 - m tan dl)`` (``m = |dc| / wx``; one tangent per angle instead of an
    arctangent and a tangent per edge, as the compiled kernels compute it), and ``_HUGE``
    where that angle reaches a right angle (``bad``)."""
    tan_dl = np.tan(dl)
    with np.errstate(divide="ignore", invalid="ignore"):
        pos = wx > 0
        slope = np.where(pos, np.abs(dc) / np.where(pos, wx, 1.0), np.where(dc == 0, 0.0, np.inf))
        den = 1.0 - slope * tan_dl
        bad = ~(den > 0) | (dl >= 0.5 * math.pi)
        r = np.where(bad, _HUGE, (slope + tan_dl) / np.where(bad, 1.0, den))
    return np.minimum(r, _HUGE), bad


def _weighted(cnt: Array, w: Array, total: Array, a: float, b: float) -> Array:
    """``a mean(w) + b rms(w)`` over each piece's transects ``(M, P)``: a bound on how much Eq. 1
    can gain when every length moves by at most ``w`` (``std`` is 1-Lipschitz in the rms norm);
    ``inf`` stays ``inf``."""
    tsafe = np.where(total > 0, total, 1.0)
    # the std of a single transect is 0 whatever its length
    rms = np.where(total > 1, np.sqrt((cnt * w * w).sum(axis=-1) / tsafe), 0.0)
    out = a * (cnt * w).sum(axis=-1) / tsafe + b * rms
    return np.where(np.isnan(out), np.inf, out)


def _take(obj: Any, rows: NDArray[np.intp]) -> Any:
    """The same dataclass with every array field restricted to ``rows`` of its first axis."""
    return type(obj)(**{f.name: getattr(obj, f.name)[rows] for f in fields(obj)})
