"""Moves on traced boundaries through the router's inner domains
(:mod:`boustro.plan.route_domain`): the leg from a point to a domain, a move through a domain
with its corners pulled tight in the area."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from .route_domain import nearest_in

__all__ = ["coarse_path", "pull", "to_domains"]

#: Domain vertices tried at a time from a point whose nearest domain point is hidden.
_NEAREST = 16


def to_domains(
    router: Any, pa: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.float64]]:
    """Each anchored point's nearest point of a domain of ``router``, the domain (``-1``: none
    reached by a straight move inside the area) and the length of that leg."""
    domains = router._domains
    pd, which = nearest_in(domains, pa)
    ok = router._visible_many(pa, pd)
    which = np.where(ok, which, -1)
    blocked = np.flatnonzero(~ok)
    if len(blocked):  # the nearest point is hidden (a dent): the nearest visible vertex
        v = np.concatenate([d.vertices for d in domains])
        sizes = [len(d.vertices) for d in domains]
        owner = np.repeat(np.arange(len(domains)), sizes)
        near = np.argsort(np.linalg.norm(pa[blocked, None] - v[None], axis=-1), axis=1)
        left = np.arange(len(blocked))
        for k in range(0, len(v), _NEAREST):  # nearest vertices first, a batch at a time
            cand = near[left, k : k + _NEAREST]  # (B, <= _NEAREST), by distance
            a = np.repeat(pa[blocked[left]], cand.shape[1], axis=0)
            vis = router._visible_many(a, v[cand.ravel()]).reshape(cand.shape)
            hit = vis.any(axis=1)
            first = cand[np.arange(len(left)), np.argmax(vis, axis=1)]
            pd[blocked[left[hit]]] = v[first[hit]]
            which[blocked[left[hit]]] = owner[first[hit]]
            left = left[~hit]
            if not len(left):
                break
    return pd, which, np.linalg.norm(pd - pa, axis=1)


def coarse_path(
    router: Any, pa: NDArray[np.float64], qa: NDArray[np.float64]
) -> NDArray[np.float64] | None:
    """The move from ``pa`` to ``qa`` (both in the area) through a domain, its corners pulled
    tight in the area; ``None`` if none is found."""
    assert router._coarse is not None
    pd, which, _ = router._to_domains(np.stack([pa, qa]))
    if which[0] < 0 or which[0] != which[1]:
        return None
    sub = router._coarse[int(which[0])].path(pd[0], pd[1])
    if not sub.found:
        return None
    return pull(router, np.concatenate([pa[None], sub.points, qa[None]]))


def pull(router: Any, pts: NDArray[np.float64]) -> NDArray[np.float64]:
    """The polyline with every corner dropped that a straight move in the area skips
    (greedily, the farthest visible point first)."""
    out = [0]
    while out[-1] < len(pts) - 1:
        i = out[-1]
        later = np.arange(i + 1, len(pts))
        vis = router._visible_many(np.repeat(pts[i : i + 1], len(later), axis=0), pts[later])
        vis[0] = True  # consecutive points of a route are joined by its own moves
        out.append(int(later[np.flatnonzero(vis)[-1]]))
    return pts[out]
