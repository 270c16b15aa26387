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

A local search's result depends on where it starts: refined, the exact order of a few passes
was sometimes longer than the greedy 2-opt order refined. :func:`refine_best` refines both and
keeps the shorter as flown, so the exact order's plan is never longer than the heuristic's.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from contextvars import ContextVar

import numpy as np
from numpy.typing import NDArray

from .order_kernel import improve_lanes
from .routing import Router
from .tour import _extension_end, _Pass

__all__ = ["LANE_TOUR_BUDGET", "LANE_TOUR_UNITS", "refine_best", "refine_tour", "refinement"]

#: Units (lanes and other passes) above which the tour is not refined (the distances between
#: their ends: a matrix of ``(2 units + 1)^2`` moves).
LANE_TOUR_UNITS = 500
#: Moves the refinement evaluates at most: a count, not a time, so that plans do not depend on
#: the machine's load.
LANE_TOUR_BUDGET = 5_000_000

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
) -> tuple[list[_Pass], list[int], list[int]]:
    """The tour ``order``/``choice`` of ``passes`` with its chains split into lanes and the
    lanes and other passes reordered where that shortens the moves: ``(passes, order,
    choice)``, the given ones where it does not (or above :data:`LANE_TOUR_UNITS` units, or
    outside :func:`refinement`'s ``enabled``). With
    ``force_start`` the first lane stays first (the approach from ``start`` counted), without
    the tour begins where it is shortest. ``turnaround``, ``inside``: the lanes' run-ins and
    run-outs (:class:`~boustro.plan.tour._Driver`), from whose ends the moves are flown."""
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
    seq, flip = improve_lanes(seq0, flip0, int(force_start), dist, budget)
    if not _moves(dist, seq, flip) < _moves(dist, seq0, flip0) - 1e-9:
        return passes, order, choice
    # the moves of both tours as flown (straight moves may pass within the router's reach
    # outside the shell, which ``distances`` does not count; the first lane is the same with a
    # forced start, no approach is flown without): the given tour stays unless the new one is
    # shorter. Only the moves one tour flies and the other does not (in that direction) are
    # measured.
    new, old = _edges(seq, flip), _edges(seq0, flip0)
    key_new, key_old = new[0] * len(pts) + new[1], old[0] * len(pts) + old[1]  # directed
    only_new, only_old = ~np.isin(key_new, key_old), ~np.isin(key_old, key_new)
    gain = _flown(router, pts, old[0][only_old], old[1][only_old]) - _flown(
        router, pts, new[0][only_new], new[1][only_new]
    )
    if not gain > 1e-9:
        return passes, order, choice
    out = []
    for u, f in zip(seq, flip, strict=True):
        p, pts = units[u]
        pts = pts[::-1].copy() if f else pts
        length = p.options[0][3] if p.kind != "chain" else float(np.linalg.norm(pts[1] - pts[0]))
        out.append(_Pass(p.kind, p.cell, p.angle, [(pts[0], pts[-1], pts, length)]))
    return out, list(range(n)), [0] * n


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
        return best
    best_moves = _tour_moves(*best, start, router, force_start, *run)
    for order, choice in tours[1:]:
        other = refine(passes, order, choice, start, router, force_start, *run)
        moves = _tour_moves(*other, start, router, force_start, *run)
        if moves < best_moves - 1e-9:
            best, best_moves = other, moves
    return best


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
