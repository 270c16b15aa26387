"""Connecting moves inside an area with holes: a visibility graph and shortest paths.

A move is straight where that line enters no hole and stays within the router's reach of the
shell; else it is routed through the area's reflex vertices, or, with a reach, through those of
the shell grown by it where that is shorter and every segment passes the straight test
(:mod:`~boustro.plan.route_grown`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import lru_cache
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..geometry.polygon import _cross
from ..geometry.region import Region, as_region
from .domain_moves import coarse_path, pull, through_domains, to_domains
from .edge_index import EdgeIndex
from .min_plus import min_plus
from .nearest_edge import DENSE_ANCHOR, index_feet, nearest_feet
from .route_cache import remembered_rows
from .route_distances import coarse_distances, distances
from .route_domain import MAX_NODES, inner_domains
from .route_grown import grown_region
from .route_visibility import visible_many
from .straight_moves import straight_moves

__all__ = ["Route", "Router", "router_for"]

#: Routed moves a :class:`Router` remembers (about 100 bytes each plus their corners).
_ROUTES = 1 << 16

#: Points whose rows (:meth:`Router._rows`) a :class:`Router` remembers, per computation.
_ROWS = 1 << 14

#: A detour's anchored ends and whether the straight move between them stays in the area.
_Ends = tuple[NDArray[np.float64], NDArray[np.float64], bool]


class Route(NamedTuple):
    """A connecting move: ``points (L, 2)`` from start to end, its ``length``, the part of it
    ``outside`` the area (length; within ``reach`` of the area unless ``found`` is false),
    whether it is the straight move, and whether a move inside the area was ``found`` (if
    not, the move is the straight line, through whatever is in the way)."""

    points: NDArray[np.float64]
    length: float
    outside: float
    straight: bool
    found: bool = True


class Router:
    """Shortest connecting moves in a region (module docstring).

    Args:
        region: the area (shell and holes), plan units.
        reach: how far outside the shell a straight move may pass (plan units, >= 0).
    """

    def __init__(self, region: Region, reach: float = 0.0) -> None:
        self.region = as_region(region)
        self.reach = float(reach)
        self.tol = 1e-9 * self.region.diameter
        e = self.region.edges
        self._e1, self._e2 = e[:, 0], e[:, 1]
        n_shell = len(self.region.shell)
        self._shell_edges = e[:n_shell]
        self._index = EdgeIndex(self.region, self.tol)
        # Vertices where the free space is reflex: a right turn along rings with the area on
        # their left (the shell CCW, holes CW).
        nodes = []
        for ring in self.region.rings:
            turn = _cross(ring - np.roll(ring, 1, axis=0), np.roll(ring, -1, axis=0) - ring)
            nodes.append(ring[turn < 0])
        self.nodes = np.concatenate(nodes) if nodes else np.zeros((0, 2))
        # Too many reflex vertices (a traced boundary): route through the reflex vertices of
        # inner simplified domains instead (:mod:`boustro.plan.route_domain`).
        self._coarse: list[Router] | None = None
        self._sights: list[Any] | None = None  # the rings' sights of the domains, on use
        if len(self.nodes) > MAX_NODES:
            self._domains = inner_domains(self.region, self.reach)
            if self._domains:  # else (eroded away: a sliver) the exact graph, however slow
                self._coarse = [Router(d) for d in self._domains]
                self.nodes = np.zeros((0, 2))
        self._graph()
        # with a reach: moves that are not straight also routed in the shell grown by it
        # (:mod:`boustro.plan.route_grown`), kept where shorter
        grown = grown_region(self.region, self.reach) if self._coarse is None else None
        self._grown = Router(grown) if grown is not None else None
        # moves already routed, by their ends' bytes: a move depends on its ends and the
        # router only, and a plan flies its tour's moves after the refinement measured them,
        # and plans of nearby layouts share moves (the hole passes' ends, the start)
        self._routes: dict[bytes, Route] = {}
        self._row_cache: dict[str, dict[bytes, tuple[Any, ...]]] = {}

    # -- membership --------------------------------------------------------------------------
    def classify(self, points: ArrayLike) -> NDArray[np.int64]:
        """``(P,)``: 0 in the closed area, 1 strictly inside a hole, 2 strictly outside the
        shell (within ``1e-9`` of the diameter of a ring counts as on it, i.e. in the area)."""
        return self._index.classify(np.asarray(points, dtype=np.float64).reshape(-1, 2))

    def anchor(self, points: ArrayLike) -> NDArray[np.float64]:
        """Each point if it lies in the closed area, else the nearest point of the area's
        boundary (of the shell for a point outside, of the hole for a point in a hole)."""
        p = np.asarray(points, dtype=np.float64).reshape(-1, 2).copy()
        where = self.classify(p)
        bad = np.flatnonzero(where != 0)
        if len(bad) and len(self._e1) <= DENSE_ANCHOR:
            p[bad] = nearest_feet(p[bad], self._e1, self._e2)
        elif len(bad):  # the same arithmetic on the edges that can be nearest (an STRtree)
            p[bad] = index_feet(self._index, p[bad])
        return p

    # -- segments ----------------------------------------------------------------------------
    def _breaks(self, p: NDArray[np.float64], q: NDArray[np.float64]) -> NDArray[np.float64]:
        """Sorted parameters in [0, 1] where segment ``p -> q`` meets any ring edge or vertex."""
        r = q - p
        s = self._e2 - self._e1
        den = _cross(r, s)
        ok = np.abs(den) > 1e-15 * (np.linalg.norm(r) * np.linalg.norm(s, axis=1) + 1e-300)
        safe = np.where(ok, den, 1.0)
        w = self._e1 - p
        t = _cross(w, s) / safe
        u = _cross(w, r) / safe
        eps = 1e-12
        hit = ok & (t >= -eps) & (t <= 1 + eps) & (u >= -eps) & (u <= 1 + eps)
        params = [t[hit]]
        # Vertices on the segment (collinear edges included).
        rr = float(r @ r)
        if rr > 0:
            v = self._e1
            tv = ((v - p) @ r) / rr
            dist = np.abs(_cross(np.broadcast_to(r, v.shape), v - p)) / math.sqrt(rr)
            params.append(tv[(dist <= self.tol) & (tv > 0) & (tv < 1)])
        out = np.clip(np.concatenate([*params, np.array([0.0, 1.0])]), 0.0, 1.0)
        return np.unique(out)

    def _pieces(self, p: NDArray[np.float64], q: NDArray[np.float64]):
        """``(params, classes)``: the breakpoints and the class of each piece between them."""
        br = self._breaks(p, q)
        mids = (br[:-1] + br[1:]) / 2
        keep = br[1:] - br[:-1] > 1e-12
        cls = np.zeros(len(mids), dtype=np.int64)
        if keep.any():
            cls[keep] = self.classify(p + mids[keep, None] * (q - p))
        return br, cls

    def inside(self, p: ArrayLike, q: ArrayLike) -> bool:
        """Whether the straight move ``p -> q`` stays in the closed area."""
        p, q = np.asarray(p, float), np.asarray(q, float)
        _, cls = self._pieces(p, q)
        return bool(np.all(cls == 0))

    def _straight(self, p: NDArray[np.float64], q: NDArray[np.float64]) -> tuple[bool, float]:
        """``(allowed, outside length)`` for the straight move (module docstring)."""
        br, cls = self._pieces(p, q)
        if np.any(cls == 1):
            return False, math.inf
        length = float(np.linalg.norm(q - p))
        out = cls == 2
        outside = float(np.sum((br[1:] - br[:-1])[out])) * length
        if not out.any():
            return True, 0.0
        if self.reach <= 0:
            return False, outside
        step = self.reach / 16
        for a, b in zip(br[:-1][out], br[1:][out], strict=True):
            n = max(2, math.ceil((b - a) * length / step) + 1)
            pts = p + np.linspace(a, b, n)[:, None] * (q - p)
            if not self._index.within(pts, self.reach * (1 + 1e-9), len(self._shell_edges)).all():
                return False, outside
        return True, outside

    def _straight_many(
        self, p: NDArray[np.float64], q: NDArray[np.float64]
    ) -> tuple[NDArray[np.bool_], NDArray[np.float64]]:
        """:meth:`_straight` of the moves ``p[i] -> q[i]`` at once
        (:func:`~boustro.plan.straight_moves.straight_moves`)."""
        return straight_moves(self, p, q)

    def _visible_many(self, a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.bool_]:
        """Whether each segment ``a[i] -> b[i]`` stays in the closed area, ``(M,)``
        (:func:`~boustro.plan.route_visibility.visible_many`)."""
        return visible_many(self, a, b)

    # -- the graph ---------------------------------------------------------------------------
    def _graph(self) -> None:
        nodes = self.nodes
        n = len(nodes)
        dist = np.full((n, n), math.inf)
        if n:
            i, j = np.triu_indices(n, k=1)
            vis = self._visible_many(nodes[i], nodes[j])
            d = np.linalg.norm(nodes[i] - nodes[j], axis=1)
            dist[i[vis], j[vis]] = d[vis]
            dist[j[vis], i[vis]] = d[vis]
            np.fill_diagonal(dist, 0.0)
        nxt = np.tile(np.arange(n), (n, 1))
        for k in range(n):
            via = dist[:, k, None] + dist[None, k, :]
            better = via < dist
            dist = np.where(better, via, dist)
            nxt = np.where(better, nxt[:, k, None], nxt)
        self._dist, self._next = dist, nxt

    def _node_path(self, i: int, j: int) -> list[int]:
        out = [i]
        while i != j:
            i = int(self._next[i, j])
            out.append(i)
        return out

    def _to_nodes(self, p: NDArray[np.float64]) -> NDArray[np.float64]:
        """Distances ``(P, N)`` from anchored points to the visible nodes (inf if hidden);
        each point's row computed once (:meth:`_rows`)."""
        return self._rows("nodes", p, lambda x: (self._to_nodes_now(x),))[0]

    def _via_nodes(self, p: NDArray[np.float64]) -> tuple[NDArray[np.float64], ...]:
        """``(v, w)``, each ``(P, N)``: :meth:`_to_nodes` and the shortest lengths from each
        point through its visible nodes to every node; each point's rows computed once."""
        return self._rows("via", p, self._via_nodes_now)

    def _via_nodes_now(self, p: NDArray[np.float64]) -> tuple[NDArray[np.float64], ...]:
        """:meth:`_via_nodes`, computed (:func:`~boustro.plan.min_plus.min_plus`)."""
        v = self._to_nodes(p)
        return v, min_plus(v, self._dist)

    def _to_nodes_now(self, p: NDArray[np.float64]) -> NDArray[np.float64]:
        """:meth:`_to_nodes`, computed."""
        n = len(self.nodes)
        if n == 0 or len(p) == 0:
            return np.full((len(p), n), math.inf)
        a = np.repeat(p, n, axis=0)
        b = np.tile(self.nodes, (len(p), 1))
        vis = self._visible_many(a, b).reshape(len(p), n)
        d = np.linalg.norm(p[:, None] - self.nodes[None], axis=-1)
        return np.where(vis, d, math.inf)

    # -- queries -----------------------------------------------------------------------------
    def path(self, p: ArrayLike, q: ArrayLike) -> Route:
        """The connecting move from ``p`` to ``q`` (module docstring)."""
        p = np.asarray(p, dtype=np.float64).reshape(2)
        q = np.asarray(q, dtype=np.float64).reshape(2)
        key = p.tobytes() + q.tobytes()
        route = self._routes.get(key)
        if route is None:
            ok, outside = self._straight(p, q)
            if ok:
                route = Route(np.stack([p, q]), float(np.linalg.norm(q - p)), outside, True)
            else:
                route = self._detour(p, q)
            self._keep(key, route)
        return route

    def paths(self, p: ArrayLike, q: ArrayLike) -> list[Route]:
        """``[path(p[i], q[i]) ...]``, the straight moves tested all at once, then the detours'
        ends anchored, their straight moves tested and (traced boundaries) their moves through
        the inner domains routed all at once (:func:`~.domain_moves.through_domains`)."""
        p = np.ascontiguousarray(p, dtype=np.float64).reshape(-1, 2)
        q = np.ascontiguousarray(q, dtype=np.float64).reshape(-1, 2)
        keys = [a.tobytes() + b.tobytes() for a, b in zip(p, q, strict=True)]
        # the answers kept here: remembering one may forget the others (_keep)
        out: list[Route | None] = [self._routes.get(k) for k in keys]
        new = [i for i, r in enumerate(out) if r is None]
        if new:
            pn, qn = p[new], q[new]
            ok, outside = self._straight_many(pn, qn)
            # the detours' ends anchored and their straight moves tested all at once (each
            # answer depends on its own points only: the same as one by one)
            bad = np.flatnonzero(~ok)
            if len(bad):
                ends = self.anchor(np.concatenate([pn[bad], qn[bad]]))
                pa, qa = ends[: len(bad)], ends[len(bad) :]
                seen = self._visible_many(pa, qa)
                if self._coarse is not None and not seen.all():
                    through_domains(self, pa[~seen], qa[~seen])
            k = 0  # the detours' position in bad
            for i, a, b, good, o in zip(new, pn, qn, ok, outside, strict=True):
                if good:
                    route = Route(np.stack([a, b]), float(np.linalg.norm(b - a)), float(o), True)
                else:
                    route = self._detour(a, b, (pa[k], qa[k], bool(seen[k])))
                    k += 1
                self._keep(keys[i], route)
                out[i] = route
        return [r for r in out if r is not None]

    def _keep(self, key: bytes, route: Route) -> None:
        """Remember a routed move (read-only; forgotten all at once past :data:`_ROUTES`)."""
        if len(self._routes) >= _ROUTES:
            self._routes.clear()
        route.points.flags.writeable = False
        self._routes[key] = route

    def _detour(
        self, p: NDArray[np.float64], q: NDArray[np.float64], ends: _Ends | None = None
    ) -> Route:
        """The move from ``p`` to ``q`` where the straight one is not allowed: inside the
        area, or in the grown domain where that is shorter (:meth:`_grown_detour`); ``ends``:
        :meth:`_inside_detour`'s anchored ends and their straight test, if computed."""
        route = self._inside_detour(p, q, ends)
        if self._grown is not None:
            grown = self._grown_detour(p, q)
            if grown is not None and (grown.length < route.length or not route.found):
                return grown
        return route

    def _grown_detour(self, p: NDArray[np.float64], q: NDArray[np.float64]) -> Route | None:
        """The move from ``p`` to ``q`` routed in the grown domain, if every segment of it
        passes this router's straight test (within the reach, no hole; else ``None``).

        ``None`` at once where an end lies outside the shell farther than the reach (a run-in's
        end, up to the reach plus the run-in out): the test samples a segment's ends, so the
        move's first or last segment would fail it; not routing it spares the grown domain's
        search (with a 6 m run-in and 10 m lanes 94% of these moves, 2026-11-28)."""
        assert self._grown is not None
        if not self._grown_ends(np.stack([p, q])).all():
            return None
        route = self._grown.path(p, q)
        if not route.found:
            return None
        pts = np.ascontiguousarray(route.points)
        ok, outside = self._straight_many(pts[:-1], pts[1:])
        if not ok.all():
            return None
        return Route(pts, route.length, float(outside.sum()), False)

    def _grown_ends(self, points: NDArray[np.float64]) -> NDArray[np.bool_]:
        """``(P,)``: whether a move from or to each point may be routed in the grown domain:
        not strictly inside a hole, not outside the shell farther than the reach
        (:meth:`_grown_detour`). From either, the grown route's first or last segment (to the
        grown domain's nearest point) fails the straight test, so the move is flown inside
        the area and :meth:`distances` must not take the grown length for it."""
        where = self.classify(points)
        ok = where == 0
        out = np.flatnonzero(where == 2)
        if len(out):
            ok[out] = self._index.within(
                points[out], self.reach * (1 + 1e-9), len(self._shell_edges)
            )
        return ok

    def _inside_detour(
        self, p: NDArray[np.float64], q: NDArray[np.float64], ends: _Ends | None = None
    ) -> Route:
        """The move from ``p`` to ``q`` inside the area (its legs to it excepted); ``ends``:
        ``(anchor(p), anchor(q), whether the straight move between them stays in the area)``,
        if computed (:meth:`paths`: the same answers for many moves at once)."""
        if ends is None:
            pa, qa = self.anchor(np.stack([p, q]))
            ends = (pa, qa, bool(self._visible_many(pa[None], qa[None])[0]))
        pa, qa, seen = ends
        legs = float(np.linalg.norm(pa - p) + np.linalg.norm(qa - q))
        if seen:
            middle = [pa, qa]
        elif self._coarse is not None:
            through = self._coarse_path(pa, qa)
            if through is None:
                length = float(np.linalg.norm(q - p))
                return Route(np.stack([p, q]), length, length, True, False)
            middle = list(through)
        else:
            dp, dq = self._to_nodes(pa[None])[0], self._to_nodes(qa[None])[0]
            total = dp[:, None] + self._dist + dq[None, :]
            if total.size == 0 or not np.isfinite(total.min()):
                length = float(np.linalg.norm(q - p))
                return Route(np.stack([p, q]), length, length, True, False)
            else:
                i, j = np.unravel_index(int(np.argmin(total)), total.shape)
                middle = [pa, *self.nodes[self._node_path(int(i), int(j))], qa]
        pts = [p, *middle, q]
        clean = [pts[0]]
        for x in pts[1:]:
            if np.linalg.norm(x - clean[-1]) > self.tol:
                clean.append(x)
        if len(clean) == 1:
            clean.append(q)
        arr = np.asarray(clean)
        length = float(np.linalg.norm(np.diff(arr, axis=0), axis=1).sum())
        return Route(arr, length, legs, False)

    def distances(self, points: ArrayLike, *, nearest: int = 24) -> NDArray[np.float64]:
        """Lengths ``(P, P)`` of the connecting moves between points, for ordering
        (:func:`~boustro.plan.route_distances.distances`).

        The straight move is tested only towards each point's ``nearest`` neighbours (by
        straight-line distance); other pairs are measured through the visibility graph (exact
        where the straight move is blocked, an upper bound otherwise), or the straight line
        where no move inside the area is found. Points outside the area are measured from their
        nearest point of it, plus that leg.
        """
        return distances(self, points, nearest)

    def _rows(
        self,
        name: str,
        p: NDArray[np.float64],
        compute: Callable[[NDArray[np.float64]], tuple[NDArray[Any], ...]],
    ) -> tuple[NDArray[Any], ...]:
        """``compute(p)`` for a computation whose answer for each point depends on that point
        only (its rows), each point's rows remembered by the point's bytes
        (:func:`~boustro.plan.route_cache.remembered_rows`, at most :data:`_ROWS` points)."""
        return remembered_rows(self._row_cache.setdefault(name, {}), p, compute, _ROWS)

    # -- traced boundaries: routes through the inner domains ---------------------------------
    def _to_domains(
        self, pa: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.float64]]:
        """Each anchored point's domain point, its domain (``-1``: none reached) and the
        length of the leg there (:func:`~boustro.plan.domain_moves.to_domains`: straight, or
        a walk along the boundary); each point's answer computed once (:meth:`_rows`)."""
        pd, which, leg = self._rows("domains", pa, self._to_domains_now)
        return pd, which, leg

    def _to_domains_now(
        self, pa: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.float64]]:
        """:meth:`_to_domains`, computed (:func:`~boustro.plan.domain_moves.to_domains`)."""
        return to_domains(self, pa)

    def _coarse_path(
        self, pa: NDArray[np.float64], qa: NDArray[np.float64]
    ) -> NDArray[np.float64] | None:
        """:func:`~boustro.plan.domain_moves.coarse_path`."""
        return coarse_path(self, pa, qa)

    def _pull(self, pts: NDArray[np.float64]) -> NDArray[np.float64]:
        """:func:`~boustro.plan.domain_moves.pull`."""
        return pull(self, pts)

    def _coarse_distances(self, pa: NDArray[np.float64]) -> NDArray[np.float64]:
        """:func:`~boustro.plan.route_distances.coarse_distances`."""
        return coarse_distances(self, pa)


@lru_cache(maxsize=8)
def router_for(region: Region, reach: float) -> Router:
    """The :class:`Router` of ``region`` (by identity) and ``reach``, built once: a search
    plans many layouts of one area, and the graph depends on the area only."""
    return Router(region, reach=reach)
