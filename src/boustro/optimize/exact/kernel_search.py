"""The compiled branch and bound of the certified Eq. 1 optimum (numba): one call a polygon.

:func:`_evaluate` is :func:`.bounds._evaluate_smith` (the exact best value and offset at every
interval's centre, an upper bound over the interval, the bound's order) as loops over the
angles of :mod:`.kernel_pieces` and :mod:`.kernel_bounds`; :func:`_search` is
:func:`.search._branch_and_bound` around it, step for step (the same intervals, children,
discarded bounds and stopping rules), so that a whole search is one call into compiled code.
:func:`_pieces_at` gives the pieces' maxima at given angles for the candidate layouts. Plain
Python until :func:`.kernel.compiled` compiles them.
"""

from __future__ import annotations

import numpy as np

from .kernel_bounds import _NCH, _chains_one, _kink_one, _runs_piece, _second_one
from .kernel_events import _event_merge
from .kernel_pieces import (
    _LAM,
    _NMO,
    _TOTAL,
    _VALUE,
    _argmax,
    _nmax,
    _nmin,
    _order_desc,
    _pieces_one,
    _quick_one,
    _structure_one,
    _structure_scratch,
    _weighted_row,
)
from .structure import BOUND_SLACK

__all__: list[str] = []


#: A piece whose cheap bound is below the best second-order bound of the angle by more than
#: this (relative to 1 or to the bound) cannot hold the angle's bound: its cheap bound is, up to
#: rounding (about 1e-15 of it), at least its second-order one (both start from the piece's
#: exact maximum; the cheap one takes every chord end as far from its pivot as the polygon
#: allows), so :func:`_evaluate` does not compute its second-order bound.
_SKIP_MARGIN = 1e-9


def _second_bound(
    v: np.ndarray,
    s: float,
    mid: float,
    half: float,
    h: np.ndarray,
    x: np.ndarray,
    tu: np.ndarray,
    td: np.ndarray,
    pc: np.ndarray,
    fam: np.ndarray,
    rn: np.ndarray,
    mo: np.ndarray,
    cc: np.ndarray,
    qp: np.ndarray,
    a: float,
    b: float,
    chain: np.ndarray,
    edges: np.ndarray,
    d1: np.ndarray,
    trig: np.ndarray,
    porder: np.ndarray,
    pb: np.ndarray,
    f1s: np.ndarray,
    f2s: np.ndarray,
    drift: np.ndarray,
    curv: np.ndarray,
    d0: np.ndarray,
    scratch: np.ndarray,
) -> tuple[float, float]:
    """The second-order bound of the interval ``mid +- half`` and its order, from its
    structure, pieces and cheap bounds ``qp`` (the rest scratch): the largest over the pieces,
    bounded from the highest cheap bound down, skipping those below the best so far by more
    than :data:`_SKIP_MARGIN`."""
    n = v.shape[0]
    _chains_one(s, mid, half, x, tu, td, chain, edges, d1, trig)
    _order_desc(qp, porder)
    best = -np.inf
    for k in range(n):
        p = porder[k]
        q = qp[p]
        if k > 0 and q < 1e90 and q + _SKIP_MARGIN * max(1.0, abs(q)) < best:
            pb[p] = -np.inf  # below the best: not the angle's bound
            f1s[p], f2s[p] = 0.0, 0.0
            continue
        _runs_piece(
            p, v, s, mid, half, h, x, pc, fam, rn, chain, edges, trig, drift, curv, d0, scratch
        )
        total = mo[p, _TOTAL]
        f1 = _weighted_row(rn[p, :, 0], drift[p], total, a, b)
        second = _second_one(p, rn, mo, cc, curv, d0, d1, half, a, b)
        kink = _kink_one(p, rn, mo, cc, curv, d0, d1, half, a, b)
        f2 = _nmin(second, kink)
        excess = _nmax(_nmin(f1, f2), 0.0)
        pb[p] = mo[p, _VALUE] + excess if total > 0 else -np.inf
        f1s[p], f2s[p] = f1, f2
        best = pb[p] if k == 0 else _nmax(best, pb[p])
    top = _argmax(pb)
    return pb[top], (2.0 if f2s[top] < f1s[top] else 1.0)


#: Floats of the structures :func:`_evaluate` keeps from its first pass for its second (about
#: 2 MB): the intervals it will bound again are not recomputed.
_KEEP_FLOATS = 1 << 18


def _evaluate(
    v: np.ndarray,
    s: float,
    lo: np.ndarray,
    hi: np.ndarray,
    a: float,
    b: float,
    threshold: float,
    batch: int,
    g: np.ndarray,
    d: np.ndarray,
    ub: np.ndarray,
    order: np.ndarray,
) -> None:
    """:func:`.bounds._evaluate_smith` as loops; writes ``g, d, ub, order``.

    The second-order bound of an angle is the largest over its pieces; the pieces are bounded
    from the highest cheap bound down, and those whose cheap bound falls below the best so far
    by more than :data:`_SKIP_MARGIN` are skipped (they cannot be the largest: the same
    bound, the same order, less work).

    The first pass keeps the structure of the intervals whose cheap bound is above the
    threshold as it stands then (a superset of those the second pass bounds, up to
    :data:`_KEEP_FLOATS` of them), so the second pass reads it instead of computing it again:
    the same functions of the same inputs, so the same numbers."""
    n = v.shape[0]
    n_j = n - 1
    per = 21 * n + 12 * n * n_j
    cap = min(min(batch, len(lo)), _KEEP_FLOATS // per)
    # slot ``cap`` is the scratch of the intervals that are not kept
    k_h, k_x = np.empty((cap + 1, n)), np.empty((cap + 1, n))
    k_tu, k_td = np.empty((cap + 1, n)), np.empty((cap + 1, n))
    k_pc, k_fam = np.empty((cap + 1, n, 5)), np.empty((cap + 1, n, 2), dtype=np.int64)
    k_rn, k_mo = np.empty((cap + 1, n, n_j, 8)), np.empty((cap + 1, n, _NMO))
    k_cc, k_qp = np.empty((cap + 1, n, n_j, 4)), np.empty((cap + 1, n))
    slot = np.empty(min(batch, len(lo)), dtype=np.int64)
    t, work, iwork = np.empty(n), np.empty((4, n)), np.empty((2, n), dtype=np.int64)
    drift, curv = np.empty((n, n_j)), np.empty((n, n_j))
    d0, d1 = np.empty((2, n, n_j)), np.empty(n_j)
    chain, edges, trig = np.empty((n_j, 2, _NCH)), np.empty((n_j, 2, 6)), np.empty(6)
    pb, f1s, f2s = np.empty(n), np.empty(n), np.empty(n)
    porder = np.empty(n, dtype=np.int64)
    scratch = np.empty((16, 4))
    bound = np.empty(len(lo))
    for start in range(0, len(lo), batch):
        stop = min(start + batch, len(lo))
        gmax = -np.inf
        used = 0
        for m in range(start, stop):
            mid = 0.5 * (lo[m] + hi[m])
            half = 0.5 * (hi[m] - lo[m])
            k = used if used < cap else cap
            h, x, tu, td, pc = k_h[k], k_x[k], k_tu[k], k_td[k], k_pc[k]
            fam, rn, mo, cc, qp = k_fam[k], k_rn[k], k_mo[k], k_cc[k], k_qp[k]
            _structure_one(v, s, mid, h, t, x, tu, td, pc, fam, rn, work, iwork)
            _pieces_one(rn, a, b, mo, cc)
            ip = _argmax(mo[:, _VALUE])
            g[m] = mo[ip, _VALUE]
            d[m] = pc[ip, 0] + mo[ip, _LAM] * pc[ip, 1]
            gmax = g[m] if m == start else _nmax(gmax, g[m])
            bound[m] = _quick_one(x, tu, td, rn, mo, half, a, b, work, qp)
            order[m] = 1.0
            slot[m - start] = -1
            now = gmax if gmax > threshold else threshold
            if k < cap and not (bound[m] + BOUND_SLACK <= now):  # may be bounded again
                slot[m - start] = k
                used += 1
        thr = gmax if gmax > threshold else threshold  # Python's max(threshold, gmax)
        for m in range(start, stop):
            if bound[m] + BOUND_SLACK > thr:
                mid = 0.5 * (lo[m] + hi[m])
                half = 0.5 * (hi[m] - lo[m])
                k = slot[m - start]
                kept = k >= 0
                k = k if kept else cap
                h, x, tu, td, pc = k_h[k], k_x[k], k_tu[k], k_td[k], k_pc[k]
                fam, rn, mo, cc, qp = k_fam[k], k_rn[k], k_mo[k], k_cc[k], k_qp[k]
                if not kept:
                    _structure_one(v, s, mid, h, t, x, tu, td, pc, fam, rn, work, iwork)
                    _pieces_one(rn, a, b, mo, cc)
                    _quick_one(x, tu, td, rn, mo, half, a, b, work, qp)
                bound[m], order[m] = _second_bound(
                    v, s, mid, half, h, x, tu, td, pc, fam, rn, mo, cc, qp, a, b, chain, edges,
                    d1, trig, porder, pb, f1s, f2s, drift, curv, d0, scratch
                )  # fmt: skip
            ub[m] = bound[m] + BOUND_SLACK


def _max_into(current: float, values: np.ndarray, mask: np.ndarray) -> float:
    """Python's ``max(current, float(values[mask].max()))`` (the numpy max propagates NaN, and
    Python's max keeps ``current`` against NaN)."""
    top = np.nan
    first = True
    for i in range(len(values)):
        if mask[i]:
            top = values[i] if first else _nmax(top, values[i])
            first = False
    return top if top > current else current


def _search(
    v: np.ndarray,
    s: float,
    alpha: np.ndarray,
    pair: np.ndarray,
    acos: np.ndarray,
    a: float,
    b: float,
    tol: float,
    max_evaluations: int,
    batch: int,
    min_width: float,
    max_children: int,
    out: np.ndarray,
) -> None:
    """:func:`.search._branch_and_bound` with :func:`_evaluate`, step for step, over the
    event angles of :func:`.kernel_events._event_merge` (``alpha, pair, acos``: the pairs'
    angles, the multiples' pairs and arc cosines). Writes ``out``: theta, lo, hi, offset,
    value, upper bound, evaluations, rounds, converged (1.0 or 0.0), number of intervals
    between events."""
    edges = _event_merge(alpha, pair, acos)
    out[9] = len(edges) - 1
    lo, hi = edges[:-1].copy(), edges[1:].copy()
    m = len(lo)
    g, d, ub, order = np.empty(m), np.empty(m), np.empty(m), np.empty(m)
    _evaluate(v, s, lo, hi, a, b, -np.inf, batch, g, d, ub, order)
    evaluations = m
    k = _argmax(g)
    best, best_theta, best_d = g[k], 0.5 * (lo[k] + hi[k]), d[k]
    best_lo, best_hi = lo[k], hi[k]
    closed = -np.inf
    rounds = 0
    converged = True
    while True:
        keep = ub > best + tol
        if not np.all(keep):
            closed = _max_into(closed, ub, ~keep)
        lo, hi, g, ub, order = lo[keep], hi[keep], g[keep], ub[keep], order[keep]
        if len(lo) == 0:
            break
        width = hi - lo
        stuck = width < min_width
        if np.any(stuck):
            closed = _max_into(closed, ub, stuck)
            keep = ~stuck
            lo, hi, g, ub, order, width = (
                lo[keep],
                hi[keep],
                g[keep],
                ub[keep],
                order[keep],
                width[keep],
            )
            converged = False
            if len(lo) == 0:
                break
        if evaluations >= max_evaluations:
            closed = _max_into(closed, ub, np.ones(len(ub), dtype=np.bool_))
            converged = False
            break
        rounds += 1
        parts = np.empty(len(lo), dtype=np.int64)
        for i in range(len(lo)):
            err = ub[i] - g[i]
            q = np.ceil((err / tol) ** (1.0 / order[i])) if np.isfinite(err) else max_children
            parts[i] = int(min(max(q, 2.0), float(max_children)))
        total = int(parts.sum())
        clo, chi = np.empty(total), np.empty(total)
        c = 0
        for i in range(len(lo)):
            kk = parts[i]
            for j in range(kk):
                clo[c] = lo[i] + width[i] * (j / kk)
                chi[c] = hi[i] if j + 1 == kk else lo[i] + width[i] * ((j + 1) / kk)
                c += 1
        lo, hi = clo, chi
        g, d, ub, order = np.empty(total), np.empty(total), np.empty(total), np.empty(total)
        _evaluate(v, s, lo, hi, a, b, best + tol, batch, g, d, ub, order)
        evaluations += total
        k = _argmax(g)
        if g[k] > best:
            best, best_theta, best_d = g[k], 0.5 * (lo[k] + hi[k]), d[k]
            best_lo, best_hi = lo[k], hi[k]
    upper = closed if closed > best else best
    out[0], out[1], out[2], out[3], out[4] = best_theta, best_lo, best_hi, best_d, best
    out[5], out[6], out[7] = upper, evaluations, rounds
    out[8] = 1.0 if converged else 0.0


def _pieces_at(
    v: np.ndarray, s: float, thetas: np.ndarray, a: float, b: float, out: np.ndarray
) -> None:
    """Every piece's exact maximum at each angle: ``out (M, P, 4)`` = lower breakpoint, width,
    value, ``lam`` (as ``_structure`` and ``_smith_pieces`` give them)."""
    n = v.shape[0]
    h, t, x, tu, td, pc, fam, rn, mo, cc, work, iwork = _structure_scratch(n)
    for i in range(len(thetas)):
        _structure_one(v, s, thetas[i], h, t, x, tu, td, pc, fam, rn, work, iwork)
        _pieces_one(rn, a, b, mo, cc)
        for p in range(n):
            out[i, p, 0], out[i, p, 1] = pc[p, 0], pc[p, 1]
            out[i, p, 2], out[i, p, 3] = mo[p, _VALUE], mo[p, _LAM]
