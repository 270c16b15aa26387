"""Certified global optima over (angle, offset): Eq. 1 by branch and bound, and exact optima of
the fewest-transects and shortest-path objectives (layer 4). See ``docs/global_optimum.md``.

Everything runs in the normalised frame in float64 numpy (the work is many small batched array
operations, where numpy's per-call overhead is far below torch's); results come back in the
polygon's units as an :class:`~boustro.optimize.OptimizeResult`, with the fitness re-evaluated by
the library's exact model so that it is the same number :func:`~boustro.optimize.evaluate_grid`
gives for that layout.

The structure used (DESIGN.md sec. 4), with ``h_i = n(theta) . v_i`` the vertex projections on the
transects' normal and ``t_i = u(theta) . v_i`` along them:

* at a fixed angle the chord length ``L(c)`` of the line ``n . p = c`` is piecewise linear and
  concave in ``c`` on ``[min h, max h]``, with knots at the ``h_i``;
* the grid ``c_k = d + k s`` has a transect through a vertex exactly when ``d = h_i mod s``: these
  ``n`` *breakpoints* cut the offset circle ``[0, s)`` into at most ``n`` *pieces*; on a piece the
  set of crossing transects is fixed and every length is affine in ``d``, so Eq. 1 is concave
  there and its maximum has a closed form;
* the cyclic order of the breakpoints changes only at *events*, angles where
  ``n(theta) . (v_i - v_j)`` is a multiple of ``s`` (this includes edges parallel to the transects).
  Between events every quantity above is a smooth function of the angle.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
import torch
from numpy.typing import ArrayLike, NDArray

from .errors import InvalidParameterError, NoTransectError, ProblemTooLargeError, as_number
from .fitness import SmithFitness
from .geometry import Polygon, halfplanes
from .models import check_spacing, exact_chords
from .objectives import GRAZE, coverage_count, path_length
from .optimize import OptimizeResult, canonical, evaluate_grid
from .scoring import as_polygon

__all__ = [
    "best_offset",
    "event_angles",
    "fewest_transects_optimum",
    "global_optimum",
    "shortest_path_optimum",
]

Array = NDArray[np.float64]

#: Events closer than this (radians) are one event: exact coincidences (symmetric polygons, a
#: spacing that divides a width) computed with rounding.
EVENT_MERGE = 1e-12

#: Added to every upper bound to cover floating-point rounding in the closed forms (the computed
#: piece maxima are accurate to ~1e-15; see docs/global_optimum.md).
BOUND_SLACK = 1e-10


# --------------------------------------------------------------------------------------------
# Events
# --------------------------------------------------------------------------------------------
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
    i, j = np.triu_indices(len(v), k=1)
    delta = v[i] - v[j]
    dist = np.hypot(delta[:, 0], delta[:, 1])
    # n(theta) . delta = -sin(theta) dx + cos(theta) dy = dist * cos(theta - alpha)
    alpha = np.arctan2(-delta[:, 0], delta[:, 1])
    m_max = int(np.floor(dist.max() / spacing)) if len(dist) else 0
    m = np.arange(-m_max, m_max + 1, dtype=np.float64)
    ratio = m[None, :] * spacing / dist[:, None]
    ok = np.abs(ratio) <= 1.0
    acos = np.arccos(np.clip(ratio, -1.0, 1.0))
    base = np.broadcast_to(alpha[:, None], ratio.shape)
    cand = np.concatenate([(base + acos)[ok], (base - acos)[ok], [0.0]])
    cand = np.mod(cand, math.pi)
    cand = np.sort(cand)
    keep = np.concatenate([[True], np.diff(cand) > EVENT_MERGE])
    cand = cand[keep]
    if cand[-1] > math.pi - EVENT_MERGE:  # equal to 0 modulo pi
        cand = cand[:-1]
    return np.concatenate([cand, [math.pi]])


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


def _check_work(poly: Polygon, spacing: float, what: str) -> None:
    work = global_work(poly.vertices, spacing)
    if work > WORK_LIMIT:
        raise ProblemTooLargeError(
            f"{what} would need about {work:.2g} units of work ({len(poly)} vertices at spacing "
            f"{spacing:.6g}; limit {WORK_LIMIT:.0e}, minutes and gigabytes beyond it): use "
            "method='hybrid' (or --method hybrid), a larger spacing, or fewer vertices"
        )


# --------------------------------------------------------------------------------------------
# The exact structure at a batch of angles
# --------------------------------------------------------------------------------------------
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
    top = np.arctan2(np.abs(dc), wx) + dl
    bad = top >= 0.5 * math.pi
    r = np.where(bad, _HUGE, np.tan(np.where(bad, 0.0, top)))
    r = np.minimum(r, _HUGE)
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


def _weighted(cnt: Array, w: Array, total: Array, a: float, b: float) -> Array:
    """``a mean(w) + b rms(w)`` over each piece's transects ``(M, P)``: a bound on how much Eq. 1
    can gain when every length moves by at most ``w`` (``std`` is 1-Lipschitz in the rms norm);
    ``inf`` stays ``inf``."""
    tsafe = np.where(total > 0, total, 1.0)
    # the std of a single transect is 0 whatever its length
    rms = np.where(total > 1, np.sqrt((cnt * w * w).sum(axis=-1) / tsafe), 0.0)
    out = a * (cnt * w).sum(axis=-1) / tsafe + b * rms
    return np.where(np.isnan(out), np.inf, out)


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


def _take(obj: Any, rows: NDArray[np.intp]) -> Any:
    """The same dataclass with every array field restricted to ``rows`` of its first axis."""
    return type(obj)(**{f.name: getattr(obj, f.name)[rows] for f in fields(obj)})


def _quick_excess(st: _Structure, mo: _Moments, delta: Array, a: float, b: float) -> Array:
    """A cheap, looser first-order excess ``(M, P)``: every chord end is within the polygon's
    extent along the transects of its pivot's foot, and every pivot within its width."""
    x = st.x
    wx = (x[:, 1:] - x[:, :-1])[:, None, :]
    chains = np.stack([st.tu, st.td])
    dc = chains[:, :, None, 1:] - chains[:, :, None, :-1]
    dl = delta[None, :, None, None]
    top = np.arctan2(np.abs(dc), wx) + dl
    bad = top >= 0.5 * math.pi
    r = np.where(bad, _HUGE, np.tan(np.where(bad, 0.0, top)))
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


# --------------------------------------------------------------------------------------------
# Branch and bound over the angle
# --------------------------------------------------------------------------------------------
#: Angles evaluated per batch (bounds the memory of the (M, n, n - 1) arrays).
_BATCH = 2048
#: Most children an interval is cut into in one round.
_MAX_CHILDREN = 16
#: Intervals narrower than this (radians) are not cut further.
_MIN_WIDTH = 1e-13


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


@dataclass
class _Search:
    """Outcome of a branch and bound in the normalised frame."""

    theta: float
    lo: float  # the event-free interval of the best centre angle
    hi: float
    offset: float
    value: float
    upper_bound: float
    evaluations: int
    rounds: int
    events: int
    converged: bool


def _branch_and_bound(
    v: Array,
    s: float,
    evaluate: Any,
    tol: float,
    max_evaluations: int,
) -> _Search:
    """Maximise over the angle: ``evaluate(lo, hi, threshold) -> (value, offset, upper_bound,
    order)`` on intervals ``[lo, hi]`` (see :func:`_evaluate_smith`)."""
    edges = event_angles(v, s)
    lo, hi = edges[:-1].copy(), edges[1:].copy()
    g, d, ub, order = evaluate(lo, hi, -math.inf)
    evaluations = len(lo)
    k = int(np.argmax(g))
    best, best_theta, best_d = float(g[k]), 0.5 * (lo[k] + hi[k]), float(d[k])
    best_iv = (float(lo[k]), float(hi[k]))
    closed = -math.inf  # largest bound of the intervals already discarded
    rounds = 0
    converged = True
    while True:
        keep = ub > best + tol
        if np.any(~keep):
            closed = max(closed, float(ub[~keep].max()))
        lo, hi, g, ub, order = lo[keep], hi[keep], g[keep], ub[keep], order[keep]
        if len(lo) == 0:
            break
        width = hi - lo
        stuck = width < _MIN_WIDTH
        if np.any(stuck):
            closed = max(closed, float(ub[stuck].max()))
            keep = ~stuck
            lo, hi, g, ub, order, width = (x[keep] for x in (lo, hi, g, ub, order, width))
            converged = False
            if len(lo) == 0:
                break
        if evaluations >= max_evaluations:
            closed = max(closed, float(ub.max()))
            converged = False
            break
        rounds += 1
        err = ub - g
        with np.errstate(invalid="ignore", over="ignore"):
            # first-order bounds shrink like the width, second-order ones like its square
            parts = np.where(np.isfinite(err), np.ceil((err / tol) ** (1.0 / order)), _MAX_CHILDREN)
        parts = np.clip(parts, 2, _MAX_CHILDREN).astype(np.int64)
        idx = np.repeat(np.arange(len(lo)), parts)
        j = np.arange(len(idx)) - np.repeat(np.cumsum(parts) - parts, parts)
        kk = parts[idx]
        clo = lo[idx] + width[idx] * (j / kk)
        chi = np.where(j + 1 == kk, hi[idx], lo[idx] + width[idx] * ((j + 1) / kk))
        lo, hi = clo, chi
        g, d, ub, order = evaluate(lo, hi, best + tol)
        evaluations += len(lo)
        k = int(np.argmax(g))
        if g[k] > best:
            best, best_theta, best_d = float(g[k]), 0.5 * (lo[k] + hi[k]), float(d[k])
            best_iv = (float(lo[k]), float(hi[k]))
    upper = max(closed, best)
    return _Search(
        best_theta, *best_iv, best_d, best, upper, evaluations, rounds, len(edges) - 1, converged
    )


# --------------------------------------------------------------------------------------------
# Public API: Eq. 1
# --------------------------------------------------------------------------------------------
def _check_count(name: str, value: int) -> int:
    if int(value) != value or value < 1:
        raise InvalidParameterError(f"{name} must be an integer >= 1, got {value!r}")
    return int(value)


#: Smallest certified gap asked for: below it float64 rounding in the bounds (about 1e-12 of the
#: fitness) could make a certificate claim more than it proves.
MIN_TOL = 1e-10


def _check_tol(tol: float) -> float:
    t = as_number("tol", tol)
    if not (t >= MIN_TOL and math.isfinite(t)):
        raise InvalidParameterError(
            f"tol must be a finite number >= {MIN_TOL:g} (float64 rounding), got {tol!r}"
        )
    return t


def _weights(a: float, b: float, fitness: SmithFitness | None) -> tuple[float, float]:
    if fitness is not None:
        if not isinstance(fitness, SmithFitness):
            raise InvalidParameterError(
                "the global optimiser of Eq. 1 takes a SmithFitness (a, b), got "
                f"{type(fitness).__name__}; use fewest_transects_optimum or "
                "shortest_path_optimum for the other objectives"
            )
        return float(fitness.a), float(fitness.b)
    SmithFitness(a=a, b=b)  # validates a, b >= 0 and finite
    return float(a), float(b)


def _attained(
    poly: Polygon, v: Array, s_n: float, thetas: Array, a: float, b: float
) -> tuple[float, float, float]:
    """The best layout near the closed-form optimum, scored by the exact model.

    The closed-form maximum of a piece can sit at its end, where a transect passes a vertex, or
    at an event angle: the supremum then belongs to a limit (a transect of length -> 0 counted,
    or not). The candidates are, at every angle of ``thetas``, the maximisers of the three best
    pieces, as they are and nudged into the pieces' interiors; the best exact score wins.

    Returns:
        ``(fitness, angle, offset)`` in the normalised frame.
    """
    thetas = np.asarray(thetas, dtype=np.float64)
    st = _structure(v, s_n, thetas)
    mo = _smith_pieces(st, a, b)
    best = (-math.inf, float(thetas[0]), 0.0)
    hp = halfplanes(poly)
    fit = SmithFitness(a=a, b=b)
    for row, theta in enumerate(thetas):
        order = np.argsort(-mo.value[row])[: min(3, mo.value.shape[1])]
        cands = []
        for p in order:
            if not np.isfinite(mo.value[row, p]):
                continue
            for eta in (0.0, 1e-9, 1e-6, 1e-3):
                lam_p = min(max(mo.lam[row, p], eta), 1.0 - eta)
                cands.append(st.beta[row, p] + lam_p * st.width[row, p])
        if not cands:
            continue
        offsets = torch.tensor(cands, dtype=torch.float64)
        values = evaluate_grid(
            hp, torch.tensor([float(theta)], dtype=torch.float64), offsets, s_n, fitness=fit
        )[0]
        k = int(torch.argmax(values))
        if float(values[k]) > best[0]:
            best = (float(values[k]), float(theta), float(offsets[k]))
    return best


def best_offset(
    polygon: Polygon | ArrayLike,
    spacing: float,
    angle: float,
    *,
    a: float = 0.5,
    b: float = 0.5,
    fitness: SmithFitness | None = None,
) -> tuple[float, float]:
    """The exact best offset for Eq. 1 at a fixed angle, in closed form.

    Solves every piece of the offset circle (at most one per vertex) exactly: Eq. 1 is concave
    on a piece and its maximum has a closed form (docs/global_optimum.md).

    Args:
        polygon: convex polygon, user units.
        spacing: transect spacing, user units, > 0.
        angle: transect direction, radians.
        a, b: weights of Eq. 1 (ignored when ``fitness`` is given).
        fitness: a :class:`~boustro.fitness.SmithFitness` to take ``a`` and ``b`` from.

    Returns:
        ``(offset, fitness)``: offset in user units in ``[0, spacing)``, fitness by the exact
        model.
    """
    poly = as_polygon(polygon).require_convex("the exact offset optimiser")
    spacing = check_spacing(spacing, extent=poly.diameter)
    a, b = _weights(a, b, fitness)
    angle = float(angle)
    if not math.isfinite(angle):
        raise InvalidParameterError(f"angle must be a finite number, got {angle!r}")
    frame = poly.frame
    v = frame.to_normalised(poly.vertices)
    s_n = spacing / frame.scale
    with np.errstate(all="ignore"):
        value, _, d = _attained(poly, v, s_n, np.array([angle]), a, b)
    if not math.isfinite(value):
        raise NoTransectError(f"no transect crosses the polygon at spacing {spacing:g}")
    offset = float(np.mod(d * frame.scale, spacing))  # for ``angle`` as given, not mod pi
    return (0.0 if offset >= spacing else offset), value


def global_optimum(
    polygon: Polygon | ArrayLike,
    spacing: float,
    *,
    a: float = 0.5,
    b: float = 0.5,
    fitness: SmithFitness | None = None,
    tol: float = 1e-6,
    max_evaluations: int = 2_000_000,
    progress: bool | None = None,
) -> OptimizeResult:
    """The global maximum of Eq. 1 over every angle and offset, with a certified upper bound.

    Branch and bound over the angle (docs/global_optimum.md): the angle range ``[0, pi]`` is cut
    at every *event* (where the piece structure of the offset circle changes); on each interval
    the exact best offset at its centre is a lower bound, and a rigorous bound on how far the
    pieces' maxima can move over the interval (first order from the chords' angular speed,
    second order from a supergradient of the concave Eq. 1 and the chords' curvature) gives an
    upper bound. Intervals whose bound exceeds the best value found by more than ``tol`` are cut,
    until none is left.

    Args:
        polygon: convex polygon, user units (a :class:`~boustro.geometry.Polygon` or vertices).
        spacing: transect spacing, user units, > 0.
        a, b: weights of Eq. 1, any finite values >= 0 (ignored when ``fitness`` is given).
        fitness: a :class:`~boustro.fitness.SmithFitness` to take ``a`` and ``b`` from.
        tol: absolute optimality gap to certify (Eq. 1 lies in ``[b/2, a + b]``).
        max_evaluations: cap on angle evaluations; if reached, the bound is still valid but the
            gap may exceed ``tol`` (``info["converged"]`` is False).
        progress: accepted for the common optimiser interface; the search shows no bar.

    Returns:
        :class:`~boustro.optimize.OptimizeResult` with ``method="global"``, the fitness of the
        returned layout by the exact model, ``upper_bound`` >= the fitness of every layout
        (``gap = upper_bound - fitness``), ``evaluations`` = angles solved exactly over the
        offset, and ``info`` with ``events``, ``rounds``, ``converged``, ``tol``.

    Raises:
        NonConvexPolygonError, InvalidPolygonError, InvalidParameterError: bad input.
    """
    t0 = time.perf_counter()
    del progress
    poly = as_polygon(polygon).require_convex("the global optimiser")
    spacing = check_spacing(spacing, extent=poly.diameter)
    _check_work(poly, spacing, "the global optimiser")
    a, b = _weights(a, b, fitness)
    tol = _check_tol(tol)
    frame = poly.frame
    v = frame.to_normalised(poly.vertices)
    s_n = spacing / frame.scale

    def evaluate(lo: Array, hi: Array, threshold: float) -> tuple[Array, Array, Array, Array]:
        return _evaluate_smith(v, s_n, lo, hi, a, b, threshold)

    cap = _check_count("max_evaluations", max_evaluations)
    with np.errstate(all="ignore"):  # infinities are meant: they mark missing bounds
        search = _branch_and_bound(v, s_n, evaluate, tol, cap)
        angles = np.array([search.theta, search.lo, search.hi])
        value, theta, d = _attained(poly, v, s_n, angles, a, b)
    upper = search.upper_bound
    if not search.converged and not math.isfinite(upper):
        upper = a + b  # every length is at most the diameter (1) and std >= 0
    # An independent spot check, exact fitness on a coarse grid: in degenerate configurations
    # (a symmetric polygon whose width is a multiple of the spacing, to the last bits) the
    # search's best value can be a limit that no layout attains, or float64 can misplace an
    # event; the check then finds a better layout, and the result says it is not certified.
    check_theta, check_d, check_value = _spot_check(poly, v, s_n, a, b)
    notes = []
    if check_value > value + 1e-12:
        with np.errstate(all="ignore"):
            better, theta_b, d_b = _attained(poly, v, s_n, np.array([check_theta]), a, b)
        if better >= check_value:
            value, theta, d = better, theta_b, d_b
        else:
            value, theta, d = check_value, check_theta, check_d
        notes.append("a spot check found a better layout than the search")
    if value > upper + 1e-12:
        notes.append(
            "the upper bound is not valid here (float64 cannot resolve this degenerate "
            "configuration)"
        )
        upper = value
    elif upper - value > tol * (1 + 1e-9) and search.converged:
        notes.append(
            "the search's best value is a limit no layout attains (a transect grazing "
            "a vertex); the layout returned is the best attained one found"
        )
    converged = search.converged and not notes
    angle, offset = canonical(theta, d * frame.scale, spacing)
    info: dict[str, Any] = {
        "events": search.events,
        "rounds": search.rounds,
        "converged": converged,
        "tol": tol,
        "a": a,
        "b": b,
        "closed_form_value": search.value,
    }
    if notes:
        info["note"] = "; ".join(notes)
    return OptimizeResult(
        angle=angle,
        offset=offset,
        fitness=value,
        spacing=spacing,
        method="global",
        evaluations=search.evaluations,
        seconds=time.perf_counter() - t0,
        upper_bound=max(upper, value),
        info=info,
    )


def _spot_check(
    poly: Polygon, v: Array, s: float, a: float, b: float
) -> tuple[float, float, float]:
    """``(angle, offset, fitness)``, normalised frame (``v``: ``poly``'s vertices in it): the
    best of the exact fitness over 90 angles, every edge's direction and its normal, and 9
    offsets (0 included)."""
    edges = np.roll(v, -1, axis=0) - v
    edge_angles = np.mod(np.arctan2(edges[:, 1], edges[:, 0]), math.pi)
    angles = np.concatenate(
        [np.arange(90) * (math.pi / 90), edge_angles, np.mod(edge_angles + math.pi / 2, math.pi)]
    )
    offsets = np.arange(9) * (s / 9)
    hp = halfplanes(poly)  # normalised frame, as v
    values = evaluate_grid(
        hp,
        torch.as_tensor(angles, dtype=hp.normals.dtype),
        torch.as_tensor(offsets, dtype=hp.normals.dtype),
        s,
        fitness=SmithFitness(a=a, b=b),
    ).numpy()
    i, j = np.unravel_index(int(np.argmax(values)), values.shape)
    return float(angles[i]), float(offsets[j]), float(values[i, j])


# --------------------------------------------------------------------------------------------
# Shortest path: per-transect pieces, convex in the offset
# --------------------------------------------------------------------------------------------
@dataclass
class _PathPieces:
    """Every piece's transects and their ends as affine functions of ``lam`` ``(M, P, K)``."""

    valid: NDArray[np.bool_]
    run: NDArray[np.intp]  # run (segment) of each transect
    u0: Array  # upper end t at lam = 0
    ub: Array  # its slope in lam
    d0: Array
    db: Array
    pos: Array  # position of each transect at lam = 0


def _path_pieces(st: _Structure, s: float) -> _PathPieces:
    """Expand every piece's runs into its transects, in order of position."""
    cnt = st.count
    j_count = cnt.shape[-1]
    total = cnt.sum(axis=-1)
    k_count = max(int(total.max()) if total.size else 0, 1)
    cum = np.cumsum(cnt, axis=-1)
    start = cum - cnt
    t = np.arange(k_count, dtype=np.float64)
    run = (t[:, None] >= cum[..., None, :]).sum(axis=-1)  # (M, P, K)
    valid = t < total[..., None]
    run = np.minimum(run, j_count - 1)

    def gather(arr: Array) -> Array:
        return np.take_along_axis(np.broadcast_to(arr, cnt.shape), run, axis=-1)

    i = t - gather(start)
    x0 = st.x[:, None, :-1]
    wx = st.x[:, None, 1:] - x0
    wxs = gather(np.where(wx > 0, wx, 1.0))
    rel = gather(st.rel_lo) + i * s
    phi = rel / wxs
    scale = st.width[..., None] / wxs
    out = []
    for chain in (st.tu, st.td):
        c0 = gather(chain[:, None, :-1])
        c1 = gather(chain[:, None, 1:])
        out.append(((1.0 - phi) * c0 + phi * c1, (c1 - c0) * scale))
    pos = gather(x0) + rel
    zero = np.zeros_like(phi)
    return _PathPieces(
        valid,
        run,
        np.where(valid, out[0][0], zero),
        np.where(valid, out[0][1], zero),
        np.where(valid, out[1][0], zero),
        np.where(valid, out[1][1], zero),
        np.where(valid, pos, zero),
    )


def _path_minimise(pp: _PathPieces, s: float) -> tuple[Array, Callable[[Array], Array]]:
    """Unconstrained minimiser ``lam*`` in ``[0, 1]`` of the (convex) path length of every piece
    and start side ``(2, M, P)``, and a function evaluating the length at any ``lam``."""
    length0 = ((pp.u0 - pp.d0) * pp.valid).sum(axis=-1)
    length1 = ((pp.ub - pp.db) * pp.valid).sum(axis=-1)
    pair = pp.valid[..., 1:] & pp.valid[..., :-1]
    du0, dub = np.diff(pp.u0, axis=-1), np.diff(pp.ub, axis=-1)
    dd0, ddb = np.diff(pp.d0, axis=-1), np.diff(pp.db, axis=-1)
    even = (np.arange(du0.shape[-1]) % 2) == 0
    # start 0: first move on the upper side; start 1: on the lower side
    x0 = np.stack([np.where(even, du0, dd0), np.where(even, dd0, du0)]) * pair
    x1 = np.stack([np.where(even, dub, ddb), np.where(even, ddb, dub)]) * pair
    s2 = s * s

    def value(lam: Array) -> Array:
        z = x0 + x1 * lam[..., None]
        moves = (np.sqrt(s2 + z * z) * pair).sum(axis=-1)
        return length0 + length1 * lam + moves

    def slope(lam: Array) -> tuple[Array, Array]:
        z = x0 + x1 * lam[..., None]
        r = np.sqrt(s2 + z * z)
        d1 = length1 + (z * x1 / r * pair).sum(axis=-1)
        d2 = (s2 * x1 * x1 / r**3 * pair).sum(axis=-1)
        return d1, d2

    shape = x0.shape[:-1]
    lo, hi = np.zeros(shape), np.ones(shape)
    g0, _ = slope(lo)
    g1, _ = slope(hi)
    lam = np.full(shape, 0.5)
    for _ in range(40):
        g, h = slope(lam)
        lo = np.where(g > 0, lo, lam)
        hi = np.where(g > 0, lam, hi)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = lam - g / h
        inside = np.isfinite(step) & (step > lo) & (step < hi)
        new = np.where(inside, step, 0.5 * (lo + hi))
        if np.all(np.abs(new - lam) <= 1e-15):
            lam = new
            break
        lam = new
    lam = np.where(g0 >= 0, 0.0, np.where(g1 <= 0, 1.0, lam))
    return lam, value


def _evaluate_path(
    v: Array, s: float, lo: Array, hi: Array, coverage: bool
) -> tuple[Array, Array, Array, Array]:
    """Negated shortest path (to maximise) at every interval's centre, the offset attaining it,
    the negated lower bound over the interval, and the bound's order (1), as
    :func:`_branch_and_bound` wants them."""
    g = np.full(len(lo), -np.inf)
    d = np.zeros(len(lo))
    ub = np.full(len(lo), -np.inf)
    batch = max(16, _BATCH // 8)
    for start in range(0, len(lo), batch):
        sl = slice(start, start + batch)
        mid = 0.5 * (lo[sl] + hi[sl])
        half = 0.5 * (hi[sl] - lo[sl])
        st = _structure(v, s, mid)
        pp = _path_pieces(st, s)
        lam, value = _path_minimise(pp, s)  # (2, M, P)
        width = st.width
        has = st.count.sum(axis=-1) > 0
        wsafe = np.where(width > 0, width, 1.0)
        if coverage:
            total = st.count.sum(axis=-1).astype(np.intp)
            last = np.maximum(total - 1, 0)[..., None]
            first_pos = pp.pos[..., 0]
            last_pos = np.take_along_axis(pp.pos, last, axis=-1)[..., 0]
            hmin, hmax = st.x[:, :1], st.x[:, -1:]
            lam_hi = (hmin + 0.5 * s - first_pos) / wsafe
            lam_lo = (hmax - 0.5 * s - last_pos) / wsafe
            # a margin moves by at most 2 (two t-differences, each <= the diameter 1) per radian
            slack = 2.0 * half[:, None] / wsafe
        else:
            lam_lo = np.zeros(width.shape)
            lam_hi = np.ones(width.shape)
            slack = np.zeros(width.shape)
        a_lo, a_hi = np.maximum(lam_lo, 0.0), np.minimum(lam_hi, 1.0)
        feasible = has & (a_lo <= a_hi) & (width > 0)
        exact_lam = np.clip(lam, a_lo, a_hi)
        exact = np.where(feasible, value(exact_lam), np.inf)  # (2, M, P)
        r_lo, r_hi = np.maximum(lam_lo - slack, 0.0), np.minimum(lam_hi + slack, 1.0)
        relaxed_ok = has & (r_lo <= r_hi)
        relaxed = np.where(relaxed_ok, value(np.clip(lam, r_lo, r_hi)), np.inf)
        # first-order drift of the whole path over the interval
        ru = _runs(v, st, half, s, second=False)
        assert ru.end_drift is not None
        ends = np.maximum(ru.end_drift[0], ru.end_drift[1])
        drift = (st.count * (ru.drift + 2.0 * ends)).sum(axis=-1)
        drift = np.where(np.isnan(drift), np.inf, drift)
        lower = np.where(relaxed_ok, relaxed - drift, np.inf).min(axis=0)  # over start sides
        flat = exact.reshape(2, len(mid), -1)
        best = np.argmin(flat.transpose(1, 0, 2).reshape(len(mid), -1), axis=1)
        side_k, piece = np.divmod(best, flat.shape[2])
        rows = np.arange(len(mid))
        g[sl] = -flat[side_k, rows, piece]
        d[sl] = st.beta[rows, piece] + exact_lam[side_k, rows, piece] * width[rows, piece]
        ub[sl] = -lower.min(axis=1)
    return g, d, ub, np.ones(len(lo))


def _layout_path(
    v: Array, s_n: float, theta: float, offsets: Array, coverage: bool
) -> tuple[Array, Array]:
    """Exact path length (normalised frame) of layouts at one angle and several offsets, ``inf``
    where the swaths fail to cover the polygon (if ``coverage``), and their transect counts."""
    hp = halfplanes(Polygon(v), normalise=False)
    ch = exact_chords(
        hp,
        torch.tensor(float(theta), dtype=torch.float64),
        torch.as_tensor(offsets, dtype=torch.float64),
        s_n,
    )
    total = path_length(ch).numpy().copy()
    lengths = ch.lengths.numpy()
    pos = ch.positions.numpy()
    shown = lengths > GRAZE
    count = shown.sum(axis=1)
    total = np.where(count > 0, total, np.inf)
    if coverage:
        h = v[:, 1] * math.cos(theta) - v[:, 0] * math.sin(theta)
        first = np.where(shown, pos, np.inf).min(axis=1)
        last = np.where(shown, pos, -np.inf).max(axis=1)
        slack = 1e-9 * s_n
        ok = (first - h.min() <= 0.5 * s_n + slack) & (h.max() - last <= 0.5 * s_n + slack)
        total = np.where(ok, total, np.inf)
    return total, count


def shortest_path_optimum(
    polygon: Polygon | ArrayLike,
    spacing: float,
    *,
    coverage: bool = True,
    rtol: float = 1e-6,
    max_evaluations: int = 500_000,
) -> OptimizeResult:
    """The layout with the shortest boustrophedon path, with a certified lower bound.

    The path (:class:`~boustro.objectives.ShortestPath`) is every transect plus the straight
    move between consecutive transects' ends, alternating sides, starting on the better side. On
    a piece of the offset circle the transects and the sides of the moves are fixed and every
    end moves linearly, so the path is convex in the offset: it is minimised exactly (safeguarded
    Newton). Branch and bound over the angle as for Eq. 1, with a first-order bound on how far
    every transect end can move over an angle interval.

    Args:
        polygon: convex polygon, user units.
        spacing: transect spacing, user units, > 0.
        coverage: only layouts whose swaths cover the polygon (first and last transects within
            half a spacing of its extremes), as a planner needs; False: any layout.
        rtol: relative optimality gap to certify (of the area / spacing, the path's scale).
        max_evaluations: cap on angle evaluations (the bound stays valid, ``converged`` False).

    Returns:
        :class:`~boustro.optimize.OptimizeResult` with ``method="shortest_path"``, ``fitness`` =
        the path length in the polygon's units (minimised: ``upper_bound`` is None), and
        ``info["lower_bound"]`` (polygon units) <= every layout's path, ``info["gap"]``,
        ``info["n_transects"]``, ``info["converged"]``.
    """
    t0 = time.perf_counter()
    poly = as_polygon(polygon).require_convex("the shortest-path optimiser")
    spacing = check_spacing(spacing, extent=poly.diameter)
    _check_work(poly, spacing, "the shortest-path optimiser")
    rtol = _check_tol(rtol)
    frame = poly.frame
    v = frame.to_normalised(poly.vertices)
    s_n = spacing / frame.scale
    tol = rtol * (poly.area / frame.scale**2) / s_n

    def evaluate(lo: Array, hi: Array, threshold: float) -> tuple[Array, Array, Array, Array]:
        return _evaluate_path(v, s_n, lo, hi, coverage)

    with np.errstate(all="ignore"):  # infinities are meant: they mark missing bounds
        search = _branch_and_bound(
            v, s_n, evaluate, tol, _check_count("max_evaluations", max_evaluations)
        )
    best = (math.inf, search.theta, search.offset, 0)
    for theta in (search.theta, search.lo, search.hi):
        offsets = search.offset + s_n * np.array([0.0, 1e-9, -1e-9, 1e-6, -1e-6])
        total, count = _layout_path(v, s_n, float(theta), offsets, coverage)
        k = int(np.argmin(total))
        if total[k] < best[0]:
            best = (float(total[k]), float(theta), float(offsets[k]), int(count[k]))
    value, theta, d, n_transects = best
    if not math.isfinite(value):
        raise NoTransectError("no layout found (this is a bug: please report the polygon)")
    lower = -search.upper_bound
    angle, offset = canonical(theta, d * frame.scale, spacing)
    return OptimizeResult(
        angle=angle,
        offset=offset,
        fitness=value * frame.scale,
        spacing=spacing,
        method="shortest_path",
        evaluations=search.evaluations,
        seconds=time.perf_counter() - t0,
        upper_bound=None,
        info={
            "objective": "shortest_path",
            "maximise": False,
            "lower_bound": min(lower, value) * frame.scale,
            "gap": max(value - lower, 0.0) * frame.scale,
            "n_transects": n_transects,
            "coverage": coverage,
            "events": search.events,
            "rounds": search.rounds,
            "converged": search.converged,
            "rtol": rtol,
        },
    )


# --------------------------------------------------------------------------------------------
# Fewest transects: closed form
# --------------------------------------------------------------------------------------------
def _width_pieces(v: Array) -> tuple[Array, Array, Array]:
    """The width ``w(theta) = max h - min h`` on ``[0, pi]`` as ``|n(theta) . (v_i - v_j)|`` for
    a fixed pair between consecutive angles where an edge is parallel to the transects.

    Returns the breakpoints ``(B + 1,)`` and for each of the ``B`` arcs the pair's difference
    vector ``(B, 2)``.
    """
    e = np.roll(v, -1, axis=0) - v
    cuts = np.mod(np.arctan2(e[:, 1], e[:, 0]), math.pi)
    cuts = np.unique(np.concatenate([[0.0, math.pi], cuts]))
    mids = 0.5 * (cuts[:-1] + cuts[1:])
    h = v[:, 1] * np.cos(mids)[:, None] - v[:, 0] * np.sin(mids)[:, None]
    top, bottom = np.argmax(h, axis=1), np.argmin(h, axis=1)
    return cuts, v[top] - v[bottom], mids


def _width(v: Array, theta: Array) -> Array:
    h = v[:, 1] * np.cos(theta)[:, None] - v[:, 0] * np.sin(theta)[:, None]
    return h.max(axis=1) - h.min(axis=1)


def fewest_transects_optimum(polygon: Polygon | ArrayLike, spacing: float) -> OptimizeResult:
    """The layout with the fewest transects that covers the polygon, in closed form.

    At angle ``theta`` full coverage (every point within half a spacing of a transect) needs
    ``ceil(width(theta) / spacing)`` transects and that many suffice with a free offset, so the
    optimum is the minimum-width direction, which for a convex polygon is parallel to one of its
    edges (the width is ``|n . (v_i - v_j)|`` for a fixed antipodal pair between edge
    directions, a concave arc, so its minimum is at an arc's end). The offset centres the
    transects: equal margins ``(width - (N - 1) s) / 2 <= s / 2`` on both sides.

    Every angle with ``width(theta) <= N s`` ties; ``info["optimal_angles"]`` lists them as
    closed intervals (radians, in ``[0, pi]``), computed in closed form per arc.

    Returns:
        :class:`~boustro.optimize.OptimizeResult` with ``method="fewest_transects"``,
        ``fitness`` = the number of transects (minimised: ``upper_bound`` is None; it is exact,
        ``info["gap"] = 0``), ``info["width"]`` (polygon units), ``info["optimal_angles"]``.
    """
    t0 = time.perf_counter()
    poly = as_polygon(polygon).require_convex("the fewest-transects optimiser")
    spacing = check_spacing(spacing, extent=poly.diameter)
    v = poly.vertices - poly.centre  # user units, centred: offsets relative to the vertex mean
    e = np.roll(v, -1, axis=0) - v
    edge_angle = np.mod(np.arctan2(e[:, 1], e[:, 0]), math.pi)
    widths = _width(v, edge_angle)
    k = int(np.argmin(widths))
    theta, width = float(edge_angle[k]), float(widths[k])
    count = coverage_count(width, spacing)
    h = v[:, 1] * math.cos(theta) - v[:, 0] * math.sin(theta)
    margin = 0.5 * (width - (count - 1) * spacing)
    first = float(h.min()) + margin
    angle, offset = canonical(theta, first, spacing)
    # the tie set {theta : width(theta) <= count * spacing}, arc by arc
    cuts, diff, _ = _width_pieces(v)
    limit = count * spacing
    intervals: list[list[float]] = []
    for lo, hi, dv in zip(cuts[:-1], cuts[1:], diff, strict=True):
        amp = float(np.hypot(dv[0], dv[1]))
        alpha = math.atan2(-dv[0], dv[1])  # width = amp * |cos(theta - alpha)| on the arc
        if amp <= limit:
            pieces = [(lo, hi)]
        else:
            gap = math.acos(
                limit / amp
            )  # |cos| <= limit / amp  <=>  theta - alpha in [gap, pi - gap] mod pi
            pieces = []
            for base in (
                alpha + gap - 2 * math.pi,
                alpha + gap - math.pi,
                alpha + gap,
                alpha + gap + math.pi,
            ):
                a0, a1 = max(lo, base), min(hi, base + math.pi - 2 * gap)
                if a0 <= a1:
                    pieces.append((a0, a1))
        for a0, a1 in pieces:
            if intervals and a0 <= intervals[-1][1] + 1e-15:
                intervals[-1][1] = max(intervals[-1][1], a1)
            else:
                intervals.append([float(a0), float(a1)])
    return OptimizeResult(
        angle=angle,
        offset=offset,
        fitness=float(count),
        spacing=spacing,
        method="fewest_transects",
        evaluations=len(edge_angle),
        seconds=time.perf_counter() - t0,
        upper_bound=None,
        info={
            "objective": "fewest_transects",
            "maximise": False,
            "lower_bound": float(count),
            "gap": 0.0,
            "width": width,
            "margin": margin,
            "optimal_angles": intervals,
        },
    )
