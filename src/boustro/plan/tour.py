"""The tour: chains of lanes, passes around holes, their order (greedy, 2-opt, DP), the drive."""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..geometry import Polygon
from .cells import _frame
from .lanes import Lanes
from .order_kernel import improve_order
from .routing import Router
from .tour_exact import EXACT_TOUR_PASSES, exact_nodes
from .types import KINDS

__all__ = [
    "ORDER_BUDGET",
]


# -- passes and their order -------------------------------------------------------------------
@dataclass
class _Pass:
    """A chain of lane segments driven back and forth, or a loop around a hole.

    ``options``: ``(entry point, exit point, points in driving order, transect roles)`` for each
    way of driving it; the transects of a chain are consecutive pairs of ``points``.
    """

    kind: str  # "chain" or "hole"
    cell: int
    angle: float
    options: list[tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], float]]


def _chains(lanes: Lanes, tol: float) -> list[list[int]]:
    """Segments on consecutive lines that overlap one-to-one, chained."""
    idx_by_k: dict[int, list[int]] = {}
    for i, kk in enumerate(lanes.k):
        idx_by_k.setdefault(int(kk), []).append(i)
    nxt: dict[int, int] = {}
    has_prev: set[int] = set()
    for kk, here in idx_by_k.items():
        there = idx_by_k.get(kk + 1)
        if not there:
            continue
        a0, a1 = lanes.t0[here], lanes.t1[here]
        b0, b1 = lanes.t0[there], lanes.t1[there]
        ov = np.minimum(a1[:, None], b1[None]) - np.maximum(a0[:, None], b0[None]) > -tol
        for i, j in zip(*np.nonzero(ov), strict=True):
            if ov[i].sum() == 1 and ov[:, j].sum() == 1:
                nxt[here[i]] = there[j]
                has_prev.add(there[j])
    chains = []
    for i in range(len(lanes.k)):
        if i in has_prev:
            continue
        chain = [i]
        while chain[-1] in nxt:
            chain.append(nxt[chain[-1]])
        chains.append(chain)
    return chains


def _chain_pass(lanes: Lanes, chain: list[int], cell: int) -> _Pass:
    seg = lanes.segments[chain]  # (m, 2, 2) from t0 to t1
    options = []
    for order in (seg, seg[::-1]):
        for first_forward in (True, False):
            pts = []
            for i, sg in enumerate(order):
                forward = first_forward if i % 2 == 0 else not first_forward
                pts.extend(sg if forward else sg[::-1])
            arr = np.asarray(pts)
            internal = float(np.linalg.norm(np.diff(arr, axis=0), axis=1).sum())
            options.append((arr[0], arr[-1], arr, internal))
        if len(seg) == 1:
            break
    return _Pass("chain", cell, lanes.angle, options)


def _hole_pass(hole: Polygon, max_options: int = 8) -> _Pass:
    v = hole.vertices
    starts = np.unique(np.linspace(0, len(v), max_options, endpoint=False).astype(int))
    perimeter = float(np.linalg.norm(np.roll(v, -1, axis=0) - v, axis=1).sum())
    options = []
    for i in starts:
        ring = np.roll(v, -int(i), axis=0)
        arr = np.concatenate([ring, ring[:1]])
        options.append((arr[0], arr[-1], arr, perimeter))
    return _Pass("hole", -1, 0.0, options)


def _boundary_pass(pts: NDArray[np.float64], max_options: int = 8) -> _Pass:
    """A boundary pass (:mod:`boustro.plan.inside`): a polyline driven either way, or a closed
    contour entered at up to ``max_options`` of its corners, either way round."""
    length = float(np.linalg.norm(np.diff(pts, axis=0), axis=1).sum())
    closed = len(pts) > 3 and bool(np.allclose(pts[0], pts[-1], rtol=0.0, atol=1e-12))
    if not closed:
        ways = [(pts[0], pts[-1], pts, length), (pts[-1], pts[0], pts[::-1], length)]
        return _Pass("boundary", -1, 0.0, ways)
    ring = pts[:-1]
    starts = np.unique(np.linspace(0, len(ring), max_options, endpoint=False).astype(int))
    options = []
    for way in (ring, ring[::-1]):
        for i in starts:
            r = np.roll(way, -int(i), axis=0)
            arr = np.concatenate([r, r[:1]])
            options.append((arr[0], arr[-1], arr, length))
    return _Pass("boundary", -1, 0.0, options)


#: Orders the 2-opt improvement of a tour evaluates at most (about 0.25 s for 60 passes on the
#: project's machine): a count, not a time, so that plans do not depend on the machine's load.
ORDER_BUDGET = 4000


def _orders(
    passes: list[_Pass],
    start: NDArray[np.float64],
    router: Router,
    budget: int = ORDER_BUDGET,
    *,
    force_start: bool = True,
) -> list[tuple[list[int], list[int]]]:
    """Orders and driving options of every pass, the shortest first: the exact one where it
    is shorter than the heuristic's, then the heuristic's (only the latter where the exact
    order is not solved or not shorter). With ``force_start`` the first is the pass and
    option whose entry (a lane end) is nearest ``start``; without, ``start`` only seeds the
    greedy order and the tour begins where it is shortest. The rest greedy, then 2-opt (at most
    ``budget`` orders evaluated) with the options chosen by dynamic programming; for at most
    :data:`~.tour_exact.EXACT_TOUR_PASSES` passes the exact order where it is shorter."""
    pts, entry_idx, exit_idx = [start], [], []
    for p in passes:
        e_i, x_i = [], []
        for entry, exit_, _, _ in p.options:
            e_i.append(len(pts))
            pts.append(entry)
            x_i.append(len(pts))
            pts.append(exit_)
        entry_idx.append(np.array(e_i))
        exit_idx.append(np.array(x_i))
    dist = router.distances(np.asarray(pts))
    internal = [np.array([o[3] for o in p.options]) for p in passes]
    # The first pass and its option: the entry nearest the start (ties: the first found).
    first_pass, first_option = min(
        ((k, j) for k in range(len(passes)) for j in range(len(entry_idx[k]))),
        key=lambda kj: dist[0, entry_idx[kj[0]][kj[1]]],
    )
    forced = np.full(len(entry_idx[first_pass]), math.inf)
    forced[first_option] = 0.0

    blocks: dict[tuple[int, int], NDArray[np.float64]] = {}

    def block(prev: int, cur: int) -> NDArray[np.float64]:
        """The moves from ``prev``'s exits to ``cur``'s entries (computed once)."""
        b = blocks.get((prev, cur))
        if b is None:
            b = blocks[(prev, cur)] = dist[np.ix_(exit_idx[prev], entry_idx[cur])]
        return b

    def head(first: int) -> NDArray[np.float64]:
        acc = dist[0, entry_idx[first]] + internal[first]
        return acc + forced if force_start else acc

    def cost(order: list[int]) -> tuple[float, list[int]]:
        acc = head(order[0])
        back = []
        for prev, cur in itertools.pairwise(order):
            trans = block(prev, cur) + acc[:, None]
            arg = np.argmin(trans, axis=0)
            back.append(arg)
            acc = trans[arg, np.arange(trans.shape[1])] + internal[cur]
        choice = [int(np.argmin(acc))]
        for arg in reversed(back):
            choice.append(int(arg[choice[-1]]))
        return float(acc.min()), choice[::-1]

    order = _greedy(dist, entry_idx, exit_idx, first_pass, first_option)
    best_cost, _ = cost(order)
    # 2-opt within a budget of evaluated orders, not of seconds, so that the same input gives
    # the same plan on a busy machine and an idle one (compiled: the same orders and costs)
    first_cost = [dist[0, entry_idx[k]] + internal[k] for k in range(len(passes))]
    if force_start:
        first_cost[first_pass] = first_cost[first_pass] + forced
    order = improve_order(
        order, best_cost, budget, int(force_start), first_cost, dist, entry_idx, exit_idx, internal
    )
    _, choice = cost(order)
    if 1 < len(passes) <= EXACT_TOUR_PASSES:
        pin = forced if force_start else None
        exact = _exact(order, choice, dist, entry_idx, exit_idx, internal, pin, first_pass)
        if exact is not None:
            return [exact, (order, choice)]
    return [(order, choice)]


def _greedy(
    dist: NDArray[np.float64],
    entry_idx: list[NDArray[np.int64]],
    exit_idx: list[NDArray[np.int64]],
    first_pass: int,
    first_option: int,
) -> list[int]:
    """The greedy order of the passes from ``first_pass`` (left by ``first_option``'s exit):
    each step the pass with the nearest entry from the last exit (its first nearest option;
    ties: the first pass in the set's order), all passes' moves from that exit at once."""
    remaining = set(range(len(entry_idx))) - {first_pass}
    order: list[int] = [first_pass]
    here = int(exit_idx[first_pass][first_option])
    entries = _padded(entry_idx)
    while remaining:
        row = dist[here, entries]  # (passes, options), the last option repeated past the end
        near, option = row.min(axis=1).tolist(), row.argmin(axis=1).tolist()
        best = (math.inf, -1, -1)
        for candidate in remaining:
            if near[candidate] < best[0]:
                best = (near[candidate], candidate, option[candidate])
        order.append(best[1])
        remaining.discard(best[1])
        here = int(exit_idx[best[1]][best[2]])
    return order


def _padded(idx: list[NDArray[np.int64]]) -> NDArray[np.int64]:
    """``(passes, options)``: each pass's points, the last one repeated past its options
    (a minimum over a row and its first position are the pass's own)."""
    width = max(len(i) for i in idx)
    return np.array([np.concatenate([i, np.full(width - len(i), i[-1])]) for i in idx])


def _exact(
    order: list[int],
    choice: list[int],
    dist: NDArray[np.float64],
    entry_idx: list[NDArray[np.int64]],
    exit_idx: list[NDArray[np.int64]],
    internal: list[NDArray[np.float64]],
    forced: NDArray[np.float64] | None,
    first_pass: int,
) -> tuple[list[int], list[int]] | None:
    """The exact order of few passes (:mod:`.tour_exact`), or ``None`` where it is not
    shorter than ``order, choice``. The tour's cost is the driven one: its passes and the
    moves between them, plus with a forced start (``forced``: the first pass's options, 0 for
    the forced one) the approach from the start (the greedy + 2-opt order also counts that
    approach without one)."""
    pass_of = np.concatenate([np.full(len(e), k) for k, e in enumerate(entry_idx)])
    option = np.concatenate([np.arange(len(e)) for e in entry_idx])
    entries, exits = np.concatenate(entry_idx), np.concatenate(exit_idx)
    own = np.concatenate(internal)
    move = dist[np.ix_(exits, entries)] + own[None, :]
    first = own.copy()
    if forced is not None:  # the forced pass and option only, with the approach
        first = np.full(len(own), math.inf)
        sel = np.flatnonzero(pass_of == first_pass)
        first[sel] = dist[0, entries[sel]] + own[sel] + forced
    node = {(int(k), int(c)): a for a, (k, c) in enumerate(zip(pass_of, option, strict=True))}
    base = [node[(k, c)] for k, c in zip(order, choice, strict=True)]
    base_cost = float(first[base[0]]) + sum(float(move[a, b]) for a, b in itertools.pairwise(base))
    nodes, cost = exact_nodes(pass_of, first, move)
    if not cost < base_cost * (1 - 1e-12):
        return None
    return [int(pass_of[a]) for a in nodes], [int(option[a]) for a in nodes]


# -- driving the tour ------------------------------------------------------------------------
def _extension_end(
    router: Router, p: NDArray[np.float64], q: NDArray[np.float64], inside: bool = False
) -> NDArray[np.float64]:
    """``q``, or the point where ``p -> q`` first enters a hole (run-ins never enter holes), or
    with ``inside`` first leaves the area."""
    br, cls = router._pieces(p, q)
    bad = np.flatnonzero(cls != 0 if inside else cls == 1)
    if len(bad) == 0:
        return q
    return p + br[bad[0]] * (q - p)


class _Path(NamedTuple):
    """Step 5: the waypoints and transects of the tour (plan units)."""

    waypoints: NDArray[np.float64]
    kinds: tuple[str, ...]
    lane: NDArray[np.int64]
    transects: NDArray[np.float64]
    angles: NDArray[np.float64]
    roles: tuple[str, ...]
    cells: NDArray[np.int64]
    positions: NDArray[np.float64]
    outside: float
    hole_length: float
    blocked: list[tuple[NDArray[np.float64], NDArray[np.float64]]]
    boundary_length: float = 0.0


class _Driver:
    """Collects the waypoints and transects while the tour is driven pass by pass."""

    def __init__(self, router: Router, turnaround: float, inside: bool = False) -> None:
        self.router = router
        self.turnaround = turnaround
        self.inside = inside  # run-ins and run-outs end at the boundary
        self.points: list[NDArray[np.float64]] = []
        self.kinds: list[str] = []
        self.lane_of: list[int] = []
        self.transects: list[NDArray[np.float64]] = []
        self.angles: list[float] = []
        self.roles: list[str] = []
        self.cells: list[int] = []
        self.positions: list[float] = []
        self.outside = 0.0
        self.hole_length = 0.0
        self.boundary_length = 0.0
        self.blocked: list[tuple[NDArray[np.float64], NDArray[np.float64]]] = []
        # connecting moves, routed together at the end: (waypoint index, target, transect)
        self.moves: list[tuple[int, NDArray[np.float64], int]] = []

    def point(self, p: NDArray[np.float64], kind: str, transect: int) -> None:
        self.points.append(p)
        self.kinds.append(kind)
        self.lane_of.append(transect)

    def transect(
        self,
        a: NDArray[np.float64],
        b: NDArray[np.float64],
        angle: float,
        role: str,
        cell: int,
        position: float,
    ) -> None:
        self.transects.append(np.stack([a, b]))
        self.angles.append(angle)
        self.roles.append(role)
        self.cells.append(cell)
        self.positions.append(position)

    def move_to(self, target: NDArray[np.float64], next_transect: int) -> None:
        """The connecting move from the last waypoint (its corners become ``via`` points,
        inserted by :meth:`_route_moves`: a move starts at a waypoint, never at a corner)."""
        if not self.points:
            return
        self.moves.append((len(self.points), target, next_transect))

    def _route_moves(self) -> None:
        """Route every recorded move at once (:meth:`Router.paths`) and insert its corners."""
        if not self.moves:
            return
        starts = np.array([self.points[i - 1] for i, _, _ in self.moves])
        targets = np.array([t for _, t, _ in self.moves])
        routes = self.router.paths(starts, targets)
        points, kinds, lane_of = self.points, self.kinds, self.lane_of
        self.points, self.kinds, self.lane_of = [], [], []
        at = 0
        for (i, target, ti), route in zip(self.moves, routes, strict=True):
            for j in range(at, i):
                self.point(points[j], kinds[j], lane_of[j])
            at = i
            self.outside += route.outside
            if not route.found:
                self.blocked.append((points[i - 1], target))
            for p in route.points[1:-1]:
                self.point(p, "via", ti)
        for j in range(at, len(points)):
            self.point(points[j], kinds[j], lane_of[j])
        self.moves = []

    def chain(
        self,
        pts: NDArray[np.float64],
        angle: float,
        cell: int,
        origin: NDArray[np.float64],
    ) -> None:
        """A chain of lanes driven back and forth, with run-in and run-out."""
        u, n = _frame(angle)
        t = self.turnaround
        for j in range(0, len(pts), 2):
            a, b = pts[j], pts[j + 1]
            ti = len(self.transects)
            d = b - a
            length = float(np.linalg.norm(d))
            direction = d / length if length > 0 else (u if j % 4 == 0 else -u)
            run_in = _extension_end(self.router, a, a - t * direction, self.inside) if t else a
            self.move_to(run_in, ti)
            if t and self._extends(run_in, a):
                self.point(run_in, "run_in", ti)
            self.point(a, "start", ti)
            self.point(b, "end", ti)
            if t:
                out = _extension_end(self.router, b, b + t * direction, self.inside)
                if self._extends(out, b):
                    self.point(out, "run_out", ti)
            self.transect(a, b, angle, "lane", cell, float((a - origin) @ n))

    def _extends(self, p: NDArray[np.float64], end: NDArray[np.float64]) -> bool:
        """Whether a run-in or run-out ending at ``p`` is kept: always, except a run-in or
        run-out of a ``keep_inside`` plan that the boundary cut to nothing."""
        return not self.inside or float(np.linalg.norm(p - end)) > self.router.tol

    def hole(self, pts: NDArray[np.float64]) -> None:
        """A pass around a hole: one transect per edge of the loop."""
        ti = len(self.transects)
        self.move_to(pts[0], ti)
        self.hole_length += self._edges(pts, "hole")
        self.point(pts[0], "start", ti)
        for j in range(1, len(pts) - 1):
            self.point(pts[j], "loop", ti + j)
        self.point(pts[-1], "end", ti + len(pts) - 2)

    def boundary(self, pts: NDArray[np.float64]) -> None:
        """A boundary pass: one transect (role ``boundary``) per edge, every waypoint of kind
        ``contour``."""
        ti = len(self.transects)
        self.move_to(pts[0], ti)
        self.boundary_length += self._edges(pts, "boundary")
        for j in range(len(pts)):
            self.point(pts[j], "contour", ti + min(j, len(pts) - 2))

    def _edges(self, pts: NDArray[np.float64], role: str) -> float:
        """One transect per edge of the polyline ``pts``, of ``role``; their total length."""
        total = 0.0
        for j in range(len(pts) - 1):
            a, b = pts[j], pts[j + 1]
            d = b - a
            self.transect(a, b, math.atan2(d[1], d[0]), role, -1, math.nan)
            total += float(np.linalg.norm(d))
        return total

    def result(self) -> _Path:
        self._route_moves()
        assert set(self.kinds) <= set(KINDS)
        return _Path(
            waypoints=np.asarray(self.points),
            kinds=tuple(self.kinds),
            lane=np.asarray(self.lane_of, dtype=np.int64),
            transects=np.asarray(self.transects),
            angles=np.asarray(self.angles),
            roles=tuple(self.roles),
            cells=np.asarray(self.cells, dtype=np.int64),
            positions=np.asarray(self.positions),
            outside=self.outside,
            hole_length=self.hole_length,
            blocked=self.blocked,
            boundary_length=self.boundary_length,
        )
