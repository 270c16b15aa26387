"""The straight connecting moves of a plan tested all at once.

:meth:`boustro.plan.routing.Router._straight` decides one move: whether the straight line from
``p`` to ``q`` may be flown (it enters no hole, and where it leaves the shell it stays within
the router's reach of it) and how much of it lies outside. A plan drives tens of moves, each
such test a dozen small numpy calls; :func:`straight_moves` runs the same arithmetic for all
of them at once (dot products rounded as numpy's matmul rounds ``r @ r``, the breakpoints of
each move sorted and deduplicated as ``np.unique`` does), so its answers equal the one-at-a-time
test bit for bit (tested).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

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
    r = q - p  # (M, 2)
    s = router._e2 - router._e1  # (E, 2)
    # dot products as numpy's matmul rounds them (as ``r @ r`` in ``Router._breaks``)
    rr = np.matmul(r[:, None, :], r[:, :, None])[:, 0, 0]
    rn = np.sqrt(rr)
    den = _cross(r[:, None], s[None])  # (M, E)
    good = np.abs(den) > 1e-15 * (rn[:, None] * np.linalg.norm(s, axis=1)[None] + 1e-300)
    safe = np.where(good, den, 1.0)
    w = router._e1[None] - p[:, None]  # (M, E, 2)
    t = _cross(w, s[None]) / safe
    u = _cross(w, r[:, None]) / safe
    eps = 1e-12
    hit = good & (t >= -eps) & (t <= 1 + eps) & (u >= -eps) & (u <= 1 + eps)
    seg_i, _ = np.nonzero(hit)
    ids, params = [seg_i], [t[hit]]
    pos = rr > 0
    if pos.any():  # vertices on the segment (collinear edges included)
        rp = r[pos]
        vp = router._e1[None] - p[pos][:, None]  # (M', E, 2)
        tv = np.matmul(vp, rp[:, :, None])[..., 0] / rr[pos][:, None]
        dist = np.abs(_cross(rp[:, None], vp)) / np.sqrt(rr[pos])[:, None]
        sel = (dist <= router.tol) & (tv > 0) & (tv < 1)
        vi, _ = np.nonzero(sel)
        ids.append(np.flatnonzero(pos)[vi])
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
