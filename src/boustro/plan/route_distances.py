"""The lengths of the connecting moves between many points (a tour's distance matrix).

:func:`distances` tests the straight move only towards each point's ``nearest`` neighbours and
measures the other pairs through the router's graph (its visibility graph, or the inner
domains' routers on traced boundaries). A tour asks for two matrices a plan (the order of its
chains, then the lane-by-lane refinement) and a search plans hundreds of nearby layouts: each
point's rows of shortest lengths to the graph's nodes are remembered by the router
(:meth:`~boustro.plan.routing.Router._rows`); every matrix equals the one computed from
scratch, bit for bit.

With a grown domain (:mod:`~boustro.plan.route_grown`) a pair's length is the shorter of the
move inside the area and the grown router's :func:`distances` (the same visibility-graph
lengths its :meth:`~boustro.plan.routing.Router.path` flies), between the points from which
:meth:`~boustro.plan.routing.Router._detour` may take a grown move
(:meth:`~boustro.plan.routing.Router._grown_ends`): the lengths the router flies. A grown
move's segments lie in the grown domain, within the reach of the shell, so the router's segment
test keeps it (the test is a safety net; if it rejected one, the matrix would be shorter than
that move as flown). A straight move allowed outside the shell within the reach is measured
straight by the grown router where the pair is among the nearest (else through its graph,
an upper bound, as inside the area).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .min_plus import min_plus

__all__ = ["coarse_distances", "distances"]


def distances(router: Any, points: Any, nearest: int = 24) -> NDArray[np.float64]:
    """:meth:`Router.distances <boustro.plan.routing.Router.distances>` of ``router``.

    Points given more than once (a pass's driving options share their ends) are anchored,
    tested and measured once, by their bytes: every answer depends on the points' coordinates
    only, so the matrix is the one computed point by point, bit for bit (the pairs tested
    straight are still chosen among all ``points``, as before)."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    m = len(p)
    first, back = _distinct(p)
    pa_u = router.anchor(p[first])
    pa = pa_u[back]
    legs = np.linalg.norm(pa - p, axis=1)
    euclid = np.linalg.norm(pa_u[:, None] - pa_u[None], axis=-1)[np.ix_(back, back)]
    direct = np.full((m, m), math.inf)
    if m > 1:
        k = min(nearest, m - 1)
        near = np.argsort(euclid, axis=1)[:, 1 : k + 1]
        i = np.repeat(np.arange(m), k)
        j = near.ravel()
        keep = i < j
        keep |= ~np.isin(j * m + i, i[i < j] * m + j[i < j])
        i, j = i[keep], j[keep]
        vis = _visible(router, pa_u, back[i], back[j])
        direct[i[vis], j[vis]] = euclid[i[vis], j[vis]]
        direct[j[vis], i[vis]] = euclid[i[vis], j[vis]]
    np.fill_diagonal(direct, 0.0)
    if router._coarse is not None:
        direct = np.minimum(direct, coarse_distances(router, pa))
    elif len(router.nodes):
        v, w = router._via_nodes(pa_u)  # (U, N) each
        via = min_plus(v, w.T).T  # via[i, j] = min_n w[i, n] + v[j, n] (v: mostly inf)
        direct = np.minimum(direct, via[np.ix_(back, back)])
    else:  # a convex shell without holes: every straight move stays inside
        direct = euclid
    # no move inside the area found (a pocket no route reaches): the straight line, as
    # :meth:`path` then flies it
    direct = np.where(np.isfinite(direct), direct, euclid)
    out = direct + legs[:, None] + legs[None, :]
    if router._grown is not None:  # the moves routed in the grown domain where shorter
        idx = np.flatnonzero(router._grown_ends(p[first])[back])
        if len(idx) > 1:
            block = np.ix_(idx, idx)
            out[block] = np.minimum(out[block], router._grown.distances(p[idx]))
    np.fill_diagonal(out, 0.0)
    return out


def _distinct(p: NDArray[np.float64]) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """``(first, back)``: the index of each distinct point of ``p`` (by its bytes) and, for
    each point, its distinct point's position in ``first`` (``p[first][back]`` is ``p``)."""
    rows = np.ascontiguousarray(p).view(np.dtype((np.void, 16))).ravel()
    _, first, back = np.unique(rows, return_index=True, return_inverse=True)
    return first, back.ravel()


def _visible(
    router: Any, pts: NDArray[np.float64], a: NDArray[np.int64], b: NDArray[np.int64]
) -> NDArray[np.bool_]:
    """Whether each segment ``pts[a[i]] -> pts[b[i]]`` stays in the area, each distinct one
    (in its direction) tested once (:meth:`~boustro.plan.routing.Router._visible_many`)."""
    key = a * len(pts) + b
    pairs, back = np.unique(key, return_inverse=True)
    vis = router._visible_many(pts[pairs // len(pts)], pts[pairs % len(pts)])
    return vis[back.ravel()]


def coarse_distances(router: Any, pa: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(M, M)`` lengths of the moves through ``router``'s inner domains (``inf`` between
    domains) from anchored points."""
    assert router._coarse is not None
    uniq, back = np.unique(pa, axis=0, return_inverse=True)  # passes share their ends
    if len(uniq) < len(pa):
        return coarse_distances(router, uniq)[np.ix_(back.ravel(), back.ravel())]
    m = len(pa)
    out = np.full((m, m), math.inf)
    pd, which, leg = router._to_domains(pa)
    for k, sub in enumerate(router._coarse):
        idx = np.flatnonzero(which == k)
        if len(idx):
            d = sub.distances(pd[idx]) + leg[idx, None] + leg[None, idx]
            out[np.ix_(idx, idx)] = d
    return out
