"""The straight connecting moves of a plan tested all at once.

:meth:`boustro.plan.routing.Router._straight` decides one move: whether the straight line from
``p`` to ``q`` may be flown (it enters no hole, and where it leaves the shell it stays within
the router's reach of it) and how much of it lies outside. A plan drives tens of moves, each
such test a dozen small numpy calls; :func:`straight_moves` runs the same arithmetic for all
of them at once (dot products rounded as numpy's matmul rounds ``r @ r``, the breakpoints of
each move sorted and deduplicated as ``np.unique`` does), so its answers equal the one-at-a-time
test bit for bit (tested).

The tests of every move against every edge (the crossings' parameters, and which edges' first
vertices lie within ``tol`` of a move's line) run in a compiled loop (numba, :func:`_edge_tests`)
with numpy's floating-point operations in numpy's order, element by element (numba contracts
nothing into fused multiply-adds without ``fastmath``), instead of a dozen ``(M, E)`` arrays.
The position of a vertex along its move is a dot product that numpy's ``matmul`` rounds with its
BLAS (fused multiply-adds on this machine: a plain loop differs in the last bit), so it is still
computed by ``matmul``, only for the moves with a vertex near their line (a few), each such
move's row whole as before: the same rounding.
"""

from __future__ import annotations

import math
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._jit import compiled
from ..geometry.polygon import _cross

__all__ = ["straight_moves"]


def straight_moves(
    router: Any, p: NDArray[np.float64], q: NDArray[np.float64]
) -> tuple[NDArray[np.bool_], NDArray[np.float64]]:
    """``(allowed (M,), outside length (M,))`` of the moves ``p[i] -> q[i]`` in ``router``'s
    area (a :class:`~boustro.plan.routing.Router`): ``Router._straight`` for each move."""
    m = len(p)
    ok = np.zeros(m, dtype=bool)
    outside = np.zeros(m)
    if m == 0:
        return ok, outside
    r, rn, p_seg, lo, hi, cls = _pieces(router, p, q)
    in_hole = np.bincount(p_seg[cls == 1], minlength=m) > 0
    out_piece = cls == 2
    any_out = np.bincount(p_seg[out_piece], minlength=m) > 0
    length = rn
    for i in np.flatnonzero(any_out & ~in_hole):
        sel = out_piece & (p_seg == i)
        outside[i] = float(np.sum((hi - lo)[sel])) * length[i]
    ok[~in_hole & ~any_out] = True
    outside[in_hole] = math.inf
    if router.reach <= 0:
        return ok, outside
    step = router.reach / 16
    pts, owner = [], []
    for k in np.flatnonzero(out_piece & ~in_hole[p_seg]):
        j = int(p_seg[k])
        n = max(2, math.ceil((hi[k] - lo[k]) * length[j] / step) + 1)
        pts.append(p[j] + np.linspace(lo[k], hi[k], n)[:, None] * r[j])
        owner.append(np.full(n, j))
    if pts:
        near = router._index.within(
            np.concatenate(pts), router.reach * (1 + 1e-9), len(router._shell_edges)
        )
        who = np.concatenate(owner)
        fail = np.bincount(who[~near], minlength=m) > 0
        ok[any_out & ~in_hole & ~fail] = True
    return ok, outside


def inside_moves(router: Any, p: NDArray[np.float64], q: NDArray[np.float64]) -> NDArray[np.bool_]:
    """``(M,)``: whether each straight move ``p[i] -> q[i]`` stays in ``router``'s closed area,
    ``Router.inside`` for each move (every piece between its breakpoints in the area: the same
    pieces and classes as :func:`straight_moves`, bit for bit)."""
    m = len(p)
    if m == 0:
        return np.zeros(0, dtype=bool)
    _, _, p_seg, _, _, cls = _pieces(router, p, q)
    return np.bincount(p_seg[cls != 0], minlength=m) == 0


def _pieces(
    router: Any, p: NDArray[np.float64], q: NDArray[np.float64]
) -> tuple[NDArray[Any], ...]:
    """``(r, |r|, move of each piece, its parameters lo and hi, its class)`` of the moves
    ``p[i] -> q[i] = p[i] + r[i]`` (``Router._pieces`` of each move, all at once; ``M >= 1``)."""
    m = len(p)
    r = q - p  # (M, 2)
    s = router._e2 - router._e1  # (E, 2)
    # dot products as numpy's matmul rounds them (as ``r @ r`` in ``Router._breaks``)
    rr = np.matmul(r[:, None, :], r[:, :, None])[:, 0, 0]
    rn = np.sqrt(rr)
    seg_i, t_hit, near = _tests(p, r, rn, rr > 0, router._e1, s, router.tol)
    ids, params = [seg_i], [t_hit]
    if near.any():  # vertices on the segment (collinear edges included)
        rp = r[near]
        vp = router._e1[None] - p[near][:, None]  # (M', E, 2)
        tv = np.matmul(vp, rp[:, :, None])[..., 0] / rr[near][:, None]
        dist = np.abs(_cross(rp[:, None], vp)) / np.sqrt(rr[near])[:, None]
        sel = (dist <= router.tol) & (tv > 0) & (tv < 1)
        vi, _ = np.nonzero(sel)
        ids.append(np.flatnonzero(near)[vi])
        params.append(tv[sel])
    ids += [np.arange(m), np.arange(m)]
    params += [np.zeros(m), np.ones(m)]
    seg = np.concatenate(ids)
    par = np.clip(np.concatenate(params), 0.0, 1.0)
    order = np.lexsort((par, seg))
    seg, par = seg[order], par[order]
    first = np.ones(len(par), dtype=bool)
    first[1:] = (seg[1:] != seg[:-1]) | (par[1:] != par[:-1])
    seg, par = seg[first], par[first]  # per move: its sorted distinct breakpoints
    same = seg[1:] == seg[:-1]
    p_seg, lo, hi = seg[1:][same], par[:-1][same], par[1:][same]  # the pieces
    keep = hi - lo > 1e-12
    cls = np.zeros(len(p_seg), dtype=np.int64)
    if keep.any():
        mids = (lo[keep] + hi[keep]) / 2
        cls[keep] = router.classify(p[p_seg[keep]] + mids[:, None] * r[p_seg[keep]])
    return r, rn, p_seg, lo, hi, cls


def _edge_tests(p, r, rn, pos, e1, s, snorm, tol, seg, par, near):
    """Every move ``p[i] -> p[i] + r[i]`` against every edge ``e1[e] -> e1[e] + s[e]``, with
    the arithmetic of the dense ``(M, E)`` arrays it replaces: the crossings' ``(move, t)``
    written to ``seg``, ``par`` (their count returned, ``-1`` when those are full) and
    ``near[i]`` set where a first vertex lies within ``tol`` of the line of a move of positive
    length (``pos``)."""
    eps = 1e-12
    k = 0
    for i in range(p.shape[0]):
        px, py, rx, ry = p[i, 0], p[i, 1], r[i, 0], r[i, 1]
        for e in range(e1.shape[0]):
            sx, sy = s[e, 0], s[e, 1]
            wx, wy = e1[e, 0] - px, e1[e, 1] - py
            den = rx * sy - ry * sx
            if abs(den) > 1e-15 * (rn[i] * snorm[e] + 1e-300):
                t = (wx * sy - wy * sx) / den
                u = (wx * ry - wy * rx) / den
                if t >= -eps and t <= 1 + eps and u >= -eps and u <= 1 + eps:
                    if k == seg.shape[0]:
                        return -1
                    seg[k] = i
                    par[k] = t
                    k += 1
            if pos[i] and not near[i] and abs(rx * wy - ry * wx) / rn[i] <= tol:
                near[i] = True
    return k


@cache
def _compiled() -> Any:
    return compiled(globals(), "_edge_tests")


def _tests(
    p: NDArray[np.float64],
    r: NDArray[np.float64],
    rn: NDArray[np.float64],
    pos: NDArray[np.bool_],
    e1: NDArray[np.float64],
    s: NDArray[np.float64],
    tol: float,
) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.bool_]]:
    """``(move of each crossing, its parameter t, whether a move has a vertex near its line)``
    (:func:`_edge_tests`), the crossings in move order, then edge order."""
    snorm = np.linalg.norm(s, axis=1)
    f64 = [np.ascontiguousarray(x, dtype=np.float64) for x in (p, r, rn)]
    e1, s = np.ascontiguousarray(e1, dtype=np.float64), np.ascontiguousarray(s, dtype=np.float64)
    cap = 8 * len(p) + 64
    while True:
        seg = np.empty(cap, dtype=np.int64)
        par = np.empty(cap, dtype=np.float64)
        near = np.zeros(len(p), dtype=np.bool_)
        k = _compiled()(*f64, np.ascontiguousarray(pos), e1, s, snorm, float(tol), seg, par, near)
        if k >= 0:
            return seg[:k], par[:k], near
        cap *= 4
