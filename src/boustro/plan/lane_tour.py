"""The tour refined lane by lane: the chains split, 2-opt and or-opt with directions (issue 16).

:func:`boustro.plan.tour._orders` orders passes: chains of lanes (lanes on consecutive lines
that overlap one-to-one, driven as one unit), hole and boundary passes. A chain keeps its lanes
together even where the tour would do better to leave one and come back for the rest (a chain
that a hole ends, two chains side by side on either side of a hole). :func:`refine_tour` takes
that tour, splits every chain into its lanes, and improves the sequence of lanes and other
passes (each a unit driven either way) by 2-opt (a stretch of the tour driven in reverse, a
unit turned round) and or-opt (one to :data:`~.order_kernel.OR_OPT_UNITS` consecutive units
moved elsewhere, either way round) on the moves between them
(:func:`~boustro.plan.order_kernel.improve_lanes`, compiled). The tour it returns is never
longer than the one it was given: the given one is kept unless the new one is shorter by the
router's distances and by the moves the two tours do not share, flown as the driver flies them
(:meth:`~boustro.plan.routing.Router.paths`, in their directions). Not where a vehicle's turns
or headland passes are added to the order afterwards (:func:`refinement`).

The local search's tour is a local optimum of those moves; an iterated local search goes on
from it (:func:`_kicked`, seventeenth round): :data:`LANE_TOUR_KICKS` kicks, each a double
bridge of the units (three cut points drawn from a generator seeded by the tour's points)
followed by the same 2-opt and or-opt, all within :data:`KICK_BUDGET` evaluations (counts, not
a time: the same input gives the same plan on any machine). A kick's tour replaces the best so
far only where it is shorter by the distances and by the moves the two do not share as flown,
so the refined tour is never longer than the one the kicks start from. The turns are the units
less one whatever their order, so the plan's time (metres / speed + turns x turn time) is
shorter exactly where the moves flown are.

Then each closed pass (a hole pass, a closed boundary contour) is entered at the point of its
ring whose moves from the unit before and to the unit after are shortest as flown
(:func:`ring_starts`, on :func:`refine_best`'s tour): the order chose among 8 corners, this
among every corner and the points of each edge nearest the neighbours' ends. The same loop
is driven the same way round (one more vertex where it starts mid-edge); a start is changed
only where its two moves are shorter as flown, so the tour is never longer.

A local search's result depends on where it starts: refined, the exact order of a few passes
was sometimes longer than the greedy 2-opt order refined. :func:`refine_best` refines both and
keeps the shorter as flown, so the exact order's plan is never longer than the heuristic's.
"""

from __future__ import annotations

import contextlib
import zlib
from collections.abc import Callable, Iterator
from contextvars import ContextVar
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from .order_kernel import improve_lanes, kick_lanes
from .routing import Router
from .tour import _extension_end, _Pass

__all__ = [
    "LANE_TOUR_BUDGET",
    "LANE_TOUR_KICKS",
    "LANE_TOUR_UNITS",
    "refine_best",
    "refine_tour",
    "refinement",
    "ring_starts",
]

#: Units (lanes and other passes) above which the tour is not refined (the distances between
#: their ends: a matrix of ``(2 units + 1)^2`` moves).
LANE_TOUR_UNITS = 500
#: Moves the refinement evaluates at most: a count, not a time, so that plans do not depend on
#: the machine's load.
LANE_TOUR_BUDGET = 5_000_000
#: Kicks of the iterated local search after the refinement (:func:`_kicked`), and the
#: evaluations they spend in all at most (counts, not a time: reproducible plans).
LANE_TOUR_KICKS = 30
KICK_BUDGET = 20_000_000
#: Units after the fixed ones below which the tour is not kicked.
KICK_UNITS = 8
#: Points of a closed pass's ring whose moves are routed when its start is chosen.
RING_CANDIDATES = 2

_Unit = tuple[_Pass, NDArray[np.float64]]

_REFINE: ContextVar[bool] = ContextVar("boustro_refine_tour", default=True)


@contextlib.contextmanager
def refinement(enabled: bool) -> Iterator[None]:
    """Tours planned inside the block are refined (:func:`refine_tour`) only if ``enabled``.
    Off where the order is driven with a vehicle's turns or joined to headland passes
    (:func:`boustro.mission.plan_area`): the refinement compares the moves between lane ends,
    not the turns of a turn radius nor the move to the headland, and could lengthen those."""
    token = _REFINE.set(bool(enabled))
    try:
        yield
    finally:
        _REFINE.reset(token)


def _refined(n: int) -> bool:
    """Whether a tour of ``n`` units is refined (:func:`refine_tour`)."""
    return 3 <= n <= LANE_TOUR_UNITS and _REFINE.get()


def _units(passes: list[_Pass], order: list[int], choice: list[int]) -> list[_Unit]:
    """The tour's lanes and other passes in driving order, each with its points as driven."""
    out: list[_Unit] = []
    for pi, oi in zip(order, choice, strict=True):
        p = passes[pi]
        pts = p.options[oi][2]
        if p.kind != "chain":
            out.append((p, pts))
            continue
        for j in range(0, len(pts), 2):
            out.append((p, pts[j : j + 2]))
    return out


def _ends(
    units: list[_Unit], router: Router, turnaround: float, inside: bool
) -> NDArray[np.float64]:
    """``(2 units, 2)``: where each unit's connecting moves begin and end, as
    :class:`~boustro.plan.tour._Driver` flies them: a lane's ends run out by ``turnaround``
    along it (cut where they would enter a hole, or leave the area with ``inside``; the same
    point whichever way the lane is driven), another pass's first and last points."""
    out = []
    for p, pts in units:
        a, b = pts[0], pts[-1]
        d = b - a
        length = float(np.linalg.norm(d))
        if p.kind == "chain" and turnaround and length > 0:
            step = turnaround * d / length
            a = _extension_end(router, a, a - step, inside)
            b = _extension_end(router, b, b + step, inside)
        out += [a, b]
    return np.asarray(out, dtype=np.float64).reshape(-1, 2)


def _moves(dist: NDArray[np.float64], seq: NDArray[np.int64], flip: NDArray[np.int64]) -> float:
    """The moves of the tour ``seq``/``flip`` (from the start: ``dist[0]``)."""
    entry = 1 + 2 * seq + flip
    exit_ = 2 + 2 * seq - flip
    return float(dist[0, entry[0]] + dist[exit_[:-1], entry[1:]].sum())


def _flown(
    router: Router, pts: NDArray[np.float64], a: NDArray[np.int64], b: NDArray[np.int64]
) -> float:
    """The total of the moves ``pts[a] -> pts[b]`` as the driver flies them
    (:meth:`Router.paths`, each in its direction: a detour through a simplified domain is not
    always the same both ways, nor as long as :meth:`Router.distances` says)."""
    if len(a) == 0:
        return 0.0
    return float(sum(r.length for r in router.paths(pts[a], pts[b])))


def _edges(
    seq: NDArray[np.int64], flip: NDArray[np.int64]
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """The points (indices into the distances) each move of the tour leaves and reaches."""
    entry = 1 + 2 * seq + flip
    exit_ = 2 + 2 * seq - flip
    return exit_[:-1], entry[1:]


def refine_tour(
    passes: list[_Pass],
    order: list[int],
    choice: list[int],
    start: NDArray[np.float64],
    router: Router,
    force_start: bool,
    turnaround: float = 0.0,
    inside: bool = False,
    *,
    budget: int = LANE_TOUR_BUDGET,
    kicks: int | None = None,
    kick_budget: int | None = None,
) -> tuple[list[_Pass], list[int], list[int]]:
    """The tour ``order``/``choice`` of ``passes`` with its chains split into lanes and the
    lanes and other passes reordered where that shortens the moves: ``(passes, order,
    choice)``, the given ones where it does not (or above :data:`LANE_TOUR_UNITS` units, or
    outside :func:`refinement`'s ``enabled``). With
    ``force_start`` the first lane stays first (the approach from ``start`` counted), without
    the tour begins where it is shortest. ``turnaround``, ``inside``: the lanes' run-ins and
    run-outs (:class:`~boustro.plan.tour._Driver`), from whose ends the moves are flown.
    ``kicks``, ``kick_budget``: the iterated local search's (:func:`_kicked`; default
    :data:`LANE_TOUR_KICKS`, :data:`KICK_BUDGET`)."""
    units = _units(passes, order, choice)
    n = len(units)
    if not _refined(n):
        return passes, order, choice
    ends = _ends(units, router, turnaround, inside)
    pts = np.vstack([np.asarray(start, dtype=np.float64)[None], ends])
    dist = router.distances(pts)  # exact where the straight move is blocked
    if not force_start:
        dist[0] = 0.0
    seq0, flip0 = np.arange(n, dtype=np.int64), np.zeros(n, dtype=np.int64)
    tour = (seq0, flip0)
    found = improve_lanes(seq0, flip0, int(force_start), dist, budget)
    if _shorter(router, pts, dist, tour, found):
        tour = found
    kicks = LANE_TOUR_KICKS if kicks is None else kicks
    kick_budget = KICK_BUDGET if kick_budget is None else kick_budget
    tour = _kicked(router, pts, dist, tour, int(force_start), kicks, kick_budget)
    if tour[0] is seq0:
        return passes, order, choice
    return _as_passes([_turned(units[u], int(f)) for u, f in zip(*tour, strict=True)])


def _as_passes(units: list[_Unit]) -> tuple[list[_Pass], list[int], list[int]]:
    """``(passes, order, choice)`` of the units in driving order, each one pass of one option."""
    out = []
    for p, pts in units:
        length = p.options[0][3] if p.kind != "chain" else float(np.linalg.norm(pts[1] - pts[0]))
        out.append(_Pass(p.kind, p.cell, p.angle, [(pts[0], pts[-1], pts, length)]))
    return out, list(range(len(out))), [0] * len(out)


def _turned(unit: _Unit, flip: int) -> _Unit:
    """The unit driven backwards where ``flip``."""
    p, pts = unit
    return (p, pts[::-1].copy()) if flip else unit


_Tour = tuple[NDArray[np.int64], NDArray[np.int64]]


def _shorter(
    router: Router, pts: NDArray[np.float64], dist: NDArray[np.float64], old: _Tour, new: _Tour
) -> bool:
    """Whether the tour ``new`` is shorter than ``old`` by the distances and by its moves as
    flown: only the moves one tour flies and the other does not (in that direction) are
    measured (straight moves may pass within the router's reach outside the shell, which
    ``distances`` does not count; the first lane is the same with a forced start, no approach
    is flown without)."""
    if not _moves(dist, *new) < _moves(dist, *old) - 1e-9:
        return False
    a, b = _edges(*new), _edges(*old)
    key_new, key_old = a[0] * len(pts) + a[1], b[0] * len(pts) + b[1]  # directed
    only_new, only_old = ~np.isin(key_new, key_old), ~np.isin(key_old, key_new)
    gain = _flown(router, pts, b[0][only_old], b[1][only_old]) - _flown(
        router, pts, a[0][only_new], a[1][only_new]
    )
    return gain > 1e-9


def _kicked(
    router: Router,
    pts: NDArray[np.float64],
    dist: NDArray[np.float64],
    tour: _Tour,
    fixed: int,
    kicks: int,
    budget: int,
) -> _Tour:
    """The tour after an iterated local search: ``kicks`` double bridges, each followed by
    2-opt and or-opt (:func:`~.order_kernel.kick_lanes`, ``budget`` evaluations in all), each
    kick's result kept only where it is :func:`_shorter` (by the distances and as flown) than
    the best tour so far. The kicks' cuts are drawn from a generator seeded by the tour's
    points: the same input, the same plan."""
    seq, flip = tour
    if kicks <= 0 or len(seq) - fixed < KICK_UNITS:
        return tour
    state = zlib.crc32(pts.tobytes())
    for _ in range(kicks):
        s, f, _, budget, state = kick_lanes(seq, flip, fixed, dist, budget, state)
        if _shorter(router, pts, dist, (seq, flip), (s, f)):
            seq, flip = s, f
        if budget <= 0:
            break
    return seq, flip


def ring_starts(
    passes: list[_Pass],
    order: list[int],
    choice: list[int],
    start: NDArray[np.float64],
    router: Router,
    force_start: bool,
    turnaround: float = 0.0,
    inside: bool = False,
) -> tuple[list[_Pass], list[int], list[int]]:
    """The tour with its closed passes (hole passes, closed boundary contours) each entered
    at the point of its ring whose moves from the unit before and to the unit after are
    shortest as flown (:func:`_ring_start`), in driving order (a ring's new start is the next
    one's unit before); the given tour where none is shorter. Where :func:`refinement` is on
    and the tour has :data:`LANE_TOUR_UNITS` units at most. Each change shortens the moves it
    touches as flown, so the tour is never longer.

    The rings whose neighbours are not rings decided before them (every ring that does not
    follow another in the tour, then the second of each run of rings, ...) have their moves
    routed in one :meth:`Router.paths` call (:func:`_ring_waves`): a route depends on its
    ends only, so each ring's start is the one it gets alone, in driving order."""
    units = _units(passes, order, choice)
    n = len(units)
    rings = [k for k, (p, pts) in enumerate(units) if p.kind != "chain" and _closed(pts)]
    if not rings or not _refined(n):
        return passes, order, choice

    def end(k: int, which: int) -> NDArray[np.float64]:  # 0: where unit k is entered, 1: left
        return _ends(units[k : k + 1], router, turnaround, inside)[which]

    start = np.asarray(start, dtype=np.float64)
    changed = False
    for wave in _ring_waves(rings):
        found = []
        for k in wave:
            before = end(k - 1, 1) if k else start if force_start else None
            after = end(k + 1, 0) if k + 1 < n else None
            found.append((k, _ring_candidates(units[k][1], before, after)))
        asked = [c for _, c in found if c is not None]
        flown = iter(_flown_many(asked, router))
        for k, c in found:
            ring = None if c is None else _ring_pick(c, next(flown))
            if ring is not None:
                units[k], changed = (units[k][0], ring), True
    return _as_passes(units) if changed else (passes, order, choice)


def _ring_waves(rings: list[int]) -> list[list[int]]:
    """The tour positions of closed passes in waves: the ``i``-th of each run of consecutive
    positions in wave ``i`` (a ring's unit before is decided in an earlier wave, its unit
    after in a later one or not a ring)."""
    waves: list[list[int]] = []
    run = 0
    for i, k in enumerate(rings):
        run = run + 1 if i and rings[i - 1] == k - 1 else 0
        if run == len(waves):
            waves.append([])
        waves[run].append(k)
    return waves


def _closed(ring: NDArray[np.float64]) -> bool:
    """Whether the pass's points are a closed loop (its first point again last)."""
    return len(ring) > 3 and bool(np.array_equal(ring[0], ring[-1]))


def _ring_start(
    ring: NDArray[np.float64],
    before: NDArray[np.float64] | None,
    after: NDArray[np.float64] | None,
    router: Router,
) -> NDArray[np.float64] | None:
    """The closed loop ``ring`` entered (and left) at the point of least flown moves
    ``before -> it -> after`` (either ``None``: no such move), the same loop the same way
    round; ``None`` where no point is shorter than its present start. Candidates: its vertices
    and on each edge the points nearest ``before`` and ``after``; the
    :data:`RING_CANDIDATES` with the shortest straight moves are routed with the present
    start (:meth:`Router.paths`, as the driver flies them, in one call). Where no
    candidate's straight moves are shorter than the present start's, nothing is routed (a
    heuristic's cut: the present start is kept)."""
    c = _ring_candidates(ring, before, after)
    return None if c is None else _ring_pick(c, _flown_many([c], router)[0])


class _RingChoice(NamedTuple):
    """:func:`_ring_start`'s points to route (``at``: the present start first) and moves."""

    ring: NDArray[np.float64]
    at: NDArray[np.float64]
    edge: NDArray[np.int64]  # the ring's edge of each candidate (``at[1:]``)
    starts: NDArray[np.float64]
    targets: NDArray[np.float64]
    legs: int  # moves per point (1 or 2)


def _ring_candidates(
    ring: NDArray[np.float64],
    before: NDArray[np.float64] | None,
    after: NDArray[np.float64] | None,
) -> _RingChoice | None:
    """:func:`_ring_start`'s candidates and the moves to route, ``None`` where nothing is
    routed (no end, or no candidate nearer than the present start by the straight lines)."""
    ends = [q for q in (before, after) if q is not None]
    if not ends:
        return None
    v = ring[:-1]
    e = np.roll(v, -1, axis=0) - v
    ee = (e * e).sum(axis=1)
    cand, edge = [v], [np.arange(len(v))]
    for q in ends:
        t = np.clip(((q - v) * e).sum(axis=1) / np.where(ee > 0, ee, 1.0), 0.0, 1.0)
        cand.append(v + t[:, None] * e)
        edge.append(np.arange(len(v)))
    c, j = np.concatenate(cand), np.concatenate(edge)
    _, first = np.unique(c, axis=0, return_index=True)  # a point once (projections at corners)
    keep = np.sort(first)
    c, j = c[keep], j[keep]
    straight = sum(np.hypot(*(c - q).T) for q in ends)

    near = np.argsort(straight, kind="stable")[:RING_CANDIDATES]
    if not straight[near[0]] < sum(np.hypot(*(v[0] - q)) for q in ends) - 1e-9:
        return None  # no point nearer than the present start by the straight lines: not routed
    at = np.vstack([v[:1], c[near]])  # the present start first: kept on ties
    starts, targets = [], []
    if before is not None:
        starts.append(np.repeat(before[None], len(at), axis=0))
        targets.append(at)
    if after is not None:
        starts.append(at)
        targets.append(np.repeat(after[None], len(at), axis=0))
    return _RingChoice(ring, at, j[near], np.vstack(starts), np.vstack(targets), len(starts))


def _flown_many(choices: list[_RingChoice], router: Router) -> list[NDArray[np.float64]]:
    """Per choice, its points' moves as flown (summed per point), every move of every choice
    routed in one :meth:`Router.paths` call."""
    if not choices:
        return []
    routes = router.paths(
        np.vstack([c.starts for c in choices]), np.vstack([c.targets for c in choices])
    )
    lengths = np.array([r.length for r in routes])
    out, lo = [], 0
    for c in choices:
        hi = lo + c.legs * len(c.at)
        out.append(lengths[lo:hi].reshape(c.legs, len(c.at)).sum(axis=0))
        lo = hi
    return out


def _ring_pick(choice: _RingChoice, flown: NDArray[np.float64]) -> NDArray[np.float64] | None:
    """The ring entered at the choice's point of least ``flown`` moves (the present start on
    ties), ``None`` where that is the present start or not shorter than it."""
    best = int(np.argmin(flown))
    if not flown[best] < flown[0] - 1e-9:
        return None
    v = choice.ring[:-1]
    at, i = choice.at[best], int(choice.edge[best - 1])
    body = np.roll(v, -(i + 1), axis=0)  # v[i + 1], ..., v[i]: the loop after edge i
    if np.array_equal(at, body[0]):
        return np.vstack([body, body[:1]])
    if np.array_equal(at, body[-1]):
        return np.vstack([body[-1:], body])
    return np.vstack([at[None], body, at[None]])


def refine_best(
    passes: list[_Pass],
    tours: list[tuple[list[int], list[int]]],
    start: NDArray[np.float64],
    router: Router,
    force_start: bool,
    turnaround: float = 0.0,
    inside: bool = False,
    refine: Callable[..., tuple[list[_Pass], list[int], list[int]]] | None = None,
) -> tuple[list[_Pass], list[int], list[int]]:
    """The shortest of the ``tours`` (``(order, choice)`` each, the shortest unrefined first:
    :func:`~boustro.plan.tour._orders`) each refined (:func:`refine_tour`): the refinement
    is a local search, so the shortest tour refined is not always the shortest refined tour
    (two layouts of ``tests/test_cover_pieces.py``: the exact order refined 2270.9 m, the
    greedy 2-opt one 2263.8 m). Compared by their moves as flown (:func:`_tour_moves`; the
    passes and run-ins are the same in every tour); the first on ties. Without refinement
    (:func:`refinement`, or outside :data:`LANE_TOUR_UNITS`) the first tour as it is.
    ``refine``: :func:`refine_tour` (the caller's, which its tests replace)."""
    refine = refine or refine_tour
    run = (turnaround, inside)
    best = refine(passes, *tours[0], start, router, force_start, *run)
    if len(tours) == 1 or not _refined(len(_units(passes, *tours[0]))):
        return ring_starts(*best, start, router, force_start, *run)
    best_moves = _tour_moves(*best, start, router, force_start, *run)
    for order, choice in tours[1:]:
        other = refine(passes, order, choice, start, router, force_start, *run)
        moves = _tour_moves(*other, start, router, force_start, *run)
        if moves < best_moves - 1e-9:
            best, best_moves = other, moves
    return ring_starts(*best, start, router, force_start, *run)


def _tour_moves(
    passes: list[_Pass],
    order: list[int],
    choice: list[int],
    start: NDArray[np.float64],
    router: Router,
    force_start: bool,
    turnaround: float,
    inside: bool,
) -> float:
    """The total of a tour's connecting moves as the driver flies them (the approach from
    ``start`` with ``force_start`` only, as :class:`~boustro.plan.tour._Driver` flies it)."""
    ends = _ends(_units(passes, order, choice), router, turnaround, inside)
    pts = np.vstack([np.asarray(start, dtype=np.float64)[None], ends])
    n = len(ends) // 2
    seq, flip = np.arange(n, dtype=np.int64), np.zeros(n, dtype=np.int64)
    a, b = _edges(seq, flip)
    if force_start:
        a, b = np.concatenate([[0], a]), np.concatenate([[1], b])
    return _flown(router, pts, a, b)
