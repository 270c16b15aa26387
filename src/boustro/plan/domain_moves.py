"""Moves on traced boundaries through the router's inner domains
(:mod:`boustro.plan.route_domain`): the leg from a point to a domain, a move through a domain
with its corners pulled tight in the area.

A point in a pocket of the boundary (a slot narrower than the erosion, bent so that no domain
point is in sight) reaches a domain along the boundary instead (:func:`walk_to_domain`): the
straight leg to its nearest boundary point stays in the area (the open disc of that radius
lies inside it), the ring's edges are part of the closed area, and the walk ends at the
first ring vertex, either way round, that sees its nearest domain point (if none of that
ring does, a hole in the pocket, from the next nearest ring whose nearest point is in sight).
Where the two ends reach different domains (a pocket's own small domain), one end walks on
to a vertex in sight of the other's. The move is then pulled tight in the area like any
other."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .nearest_edge import pair_feet
from .route_domain import nearest_in

__all__ = ["coarse_path", "pull", "through_domains", "to_domains", "walk_to_domain"]

#: Domain vertices tried at a time from a point whose nearest domain point is hidden.
_NEAREST = 16


def to_domains(
    router: Any, pa: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.float64]]:
    """Each anchored point's nearest point of a domain of ``router`` if in sight, else the
    nearer of its nearest domain vertex in sight and the end of its :func:`walk_to_domain`;
    the domain (``-1``: none reached) and the length of that leg (of the walk for a walk)."""
    domains = router._domains
    pd, which = nearest_in(domains, pa)
    ok = router._visible_many(pa, pd)
    which = np.where(ok, which, -1)
    leg = np.linalg.norm(pd - pa, axis=1)
    blocked = np.flatnonzero(~ok)
    if not len(blocked):
        return pd, which, leg
    # the nearest point is hidden (a dent): the walk, unless a domain vertex nearer than the
    # walk's length is in sight
    walks = [walk_to_domain(router, pa[i]) for i in blocked]
    bound = np.array([math.inf if w is None else _length(w[0]) for w in walks])
    v = np.concatenate([d.vertices for d in domains])
    owner = np.repeat(np.arange(len(domains)), [len(d.vertices) for d in domains])
    dist = np.linalg.norm(pa[blocked, None] - v[None], axis=-1)
    near = np.argsort(dist, axis=1)
    seen = np.zeros(len(blocked), dtype=bool)
    left = np.arange(len(blocked))
    for k in range(0, len(v), _NEAREST):  # nearest vertices first, a batch at a time
        cand = near[left, k : k + _NEAREST]  # (B, <= _NEAREST), by distance
        nearer = np.take_along_axis(dist[left], cand, axis=1) < bound[left, None]
        a = np.repeat(pa[blocked[left]], cand.shape[1], axis=0)
        vis = router._visible_many(a, v[cand.ravel()]).reshape(cand.shape) & nearer
        hit = vis.any(axis=1)
        first = cand[np.arange(len(left)), np.argmax(vis, axis=1)]
        pd[blocked[left[hit]]] = v[first[hit]]
        which[blocked[left[hit]]] = owner[first[hit]]
        seen[left[hit]] = True
        left = left[~hit & nearer[:, -1]]  # points with nearer vertices still to try
        if not len(left):
            break
    leg[blocked] = np.linalg.norm(pd[blocked] - pa[blocked], axis=1)
    for j in np.flatnonzero(~seen):  # no domain vertex in sight nearer than the walk
        walk = walks[j]
        if walk is not None:
            i = blocked[j]
            pd[i], which[i], leg[i] = walk[0][-1], walk[1], bound[j]
    return pd, which, leg


def _length(line: NDArray[np.float64]) -> float:
    return float(np.linalg.norm(np.diff(line, axis=0), axis=1).sum())


def _sights(router: Any) -> list[tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.bool_]]]:
    """Per ring of ``router``'s area: each vertex's nearest domain point, its domain and
    whether the vertex sees it (computed once per router)."""
    if router._sights is None:
        out = []
        for ring in router.region.rings:
            pd, which = nearest_in(router._domains, ring)
            out.append((pd, which, (which >= 0) & router._visible_many(ring, pd)))
        router._sights = out
    return router._sights


def walk_to_domain(
    router: Any, point: NDArray[np.float64], domain: int | None = None
) -> tuple[NDArray[np.float64], int] | None:
    """``(polyline, domain)``: from ``point`` (in the closed area) straight to its nearest
    boundary point, along that ring to the first vertex, either way round, that sees its
    nearest domain point, and there; the shorter way. If no vertex of that ring sees one (a
    hole in the pocket), the same from the next nearest ring whose nearest point ``point``
    sees. Only vertices whose nearest domain is ``domain``, if given. ``None`` if none does."""
    feet = []
    for ri, ring in enumerate(router.region.rings):
        foot, dist = pair_feet(np.repeat(point[None], len(ring), 0), ring, np.roll(ring, -1, 0))
        e = int(np.argmin(dist))
        feet.append((float(dist[e]), ri, e, foot[e]))
    feet.sort(key=lambda f: f[0])
    for k, (_, ri, e, foot) in enumerate(feet):
        if k and not router._visible_many(point[None], foot[None])[0]:
            continue  # the nearest ring's leg is inside (the open disc); others are tested
        walk = _walk_ring(router, point, ri, e, foot, domain)
        if walk is not None:
            return walk
    return None


def _walk_ring(
    router: Any,
    point: NDArray[np.float64],
    ri: int,
    e: int,
    foot: NDArray[np.float64],
    domain: int | None,
) -> tuple[NDArray[np.float64], int] | None:
    """:func:`walk_to_domain` along ring ``ri`` from ``foot`` on its edge ``e``."""
    ring = router.region.rings[ri]
    pd, which, sees = _sights(router)[ri]
    if domain is not None:
        sees = sees & (which == domain)
    n = len(ring)
    out: tuple[NDArray[np.float64], int] | None = None
    for way in (np.arange(e + 1, e + 1 + n) % n, np.arange(e, e - n, -1) % n):
        hit = np.flatnonzero(sees[way])
        if not len(hit):
            return None
        vs = way[: hit[0] + 1]
        line = np.concatenate([point[None], foot[None], ring[vs], pd[vs[-1]][None]])
        if out is None or _length(line) < _length(out[0]):
            out = (line, int(which[vs[-1]]))
    return out


def coarse_path(
    router: Any, pa: NDArray[np.float64], qa: NDArray[np.float64]
) -> NDArray[np.float64] | None:
    """The move from ``pa`` to ``qa`` (both in the area) through a domain, its corners pulled
    tight in the area; ``None`` if none is found."""
    assert router._coarse is not None
    ends = np.stack([pa, qa])
    pd, which, _ = router._to_domains(ends)
    pd, which = pd.copy(), which.copy()  # (the router's remembered rows)
    lead = [e[None] for e in ends]
    if which[0] != which[1]:  # one end walks on to the other's domain (a pocket's own domain)
        for i in (0, 1):
            other = int(which[1 - i])
            walk = None if other < 0 else walk_to_domain(router, ends[i], other)
            if walk is not None:
                lead[i], pd[i], which[i] = walk[0][:-1], walk[0][-1], walk[1]
                break
    if which[0] < 0 or which[0] != which[1]:
        return None
    sub = router._coarse[int(which[0])].path(pd[0], pd[1])
    if not sub.found:
        return None
    # a leg out of sight is a walk along the boundary (its length says too little: a walk
    # past a spike 0.4 mm across the chord is within 1e-9 of the diameter of the chord's)
    for k in np.flatnonzero(~router._visible_many(ends, pd)):
        if len(lead[k]) == 1:
            walk = walk_to_domain(router, ends[k])
            assert walk is not None
            lead[k] = walk[0][:-1]
    return pull(router, np.concatenate([lead[0], sub.points, lead[1][::-1]]))


def through_domains(router: Any, pa: NDArray[np.float64], qa: NDArray[np.float64]) -> None:
    """Route at once, in each inner domain's router, the moves that :func:`coarse_path` asks
    it for between anchored points ``pa[i]``, ``qa[i]`` whose legs reach the same domain
    (their domain points, :meth:`~boustro.plan.routing.Router._to_domains`): the domain's
    router remembers each, and :meth:`~boustro.plan.routing.Router.paths` routes a batch as
    its ``path`` routes each move alone (tested), so ``coarse_path`` then finds what it would
    have routed. Moves whose ends reach different domains (a walk) are left to it."""
    m = len(pa)
    pd, which, _ = router._to_domains(np.concatenate([pa, qa]))
    for k, sub in enumerate(router._coarse):
        idx = np.flatnonzero((which[:m] == k) & (which[m:] == k))
        if len(idx):
            sub.paths(pd[:m][idx], pd[m:][idx])


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
