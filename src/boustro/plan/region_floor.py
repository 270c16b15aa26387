"""A floor of a ``keep_inside`` plan's path, from its lanes and boundary passes alone (and of a
plan without it, from its lanes: :func:`_open_floor`).

A search over layouts (:func:`boustro.optimize.cover.cover_optimum`) plans hundreds of
``keep_inside`` layouts of one area, most of them longer than its best plan. The lanes cut
inside the area and the boundary passes (:func:`~boustro.plan.inside.inside_layout`) are a
third of a plan's CPU; the tour, the routing and the driven path the rest. :func:`plan_floor`
lays the lanes and passes exactly as :func:`~boustro.plan.region.plan_region` does (the same
steps, the same options) and bounds every path through them from below
(:func:`tour_floor`): a layout whose floor costs more than the best plan
need not be planned (docs/keep_inside.md, "The search's screen"). ``inside_layout`` keeps its
last results, so a layout that passes the screen is not laid twice.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..geometry.region import Region, as_region
from .inside import MARGINS, margin_floor
from .lanes import Lanes
from .region import (
    _check_options,
    _flown_holes,
    _laid_lanes,
    _plan_cells,
    _plan_lanes,
    plan_region,
)
from .tour import _hole_pass

__all__ = ["CHEAP_ROOM", "lanes_floor", "plan_floor", "screen_floor", "tour_floor"]

#: ``plan_region``'s signature, read once (``inspect.signature`` per call was 5% of a floor),
#: and its keywords' defaults (binding the arguments per call was 2% of a floor).
_SIGNATURE = inspect.signature(plan_region)
_DEFAULTS = {
    name: p.default
    for name, p in _SIGNATURE.parameters.items()
    if p.kind is inspect.Parameter.KEYWORD_ONLY
}


def plan_floor(region: Any, spacing: float, **kw: Any) -> tuple[float, int] | None:
    """A lower bound ``(path length, turns)`` (plan units) of the plan
    ``plan_region(region, spacing, **kw)``, from its cut lanes and boundary passes (without
    ``keep_inside``: its lanes, :func:`_open_floor`); ``None`` unless it is a plan of the
    guaranteed layout over one cell (``decompose_area=False``). Raises what ``plan_region``
    raises for its lanes, not what its tour stage raises (``order="exact"`` over too many
    passes: the mission's screen never sets ``order``)."""
    parsed = _parsed(region, spacing, kw)
    if parsed is None:
        return None
    r, opts = parsed
    if not opts.keep_inside:
        return _open_floor(r, opts)
    lanes = _plan_lanes(r, _plan_cells(r, opts, []), opts)
    return tour_floor(lanes.lanes, lanes.boundary or [])


def _open_floor(r: Region, opts: Any) -> tuple[float, int]:
    """:func:`plan_floor` of a plan without ``keep_inside``: :func:`tour_floor` of its lanes as laid
    (the plan flies them as they are, :func:`~boustro.plan.region._plan_lanes`) and, with hole
    passes on, the closed ring of every hole that cuts a lane (the hole pass the plan flies,
    :func:`~boustro.plan.tour._hole_pass`'s first way round: the hole's own ring, the same
    length from any of its corners). Why it is below the plan (docs/keep_inside.md, "Eighteenth
    round"): the path drives every lane whole from one end to the other (a chain's lanes too;
    run-ins and run-outs only lengthen the path between lane ends, never below the straight
    line) and every hole pass round from a corner to it, so :func:`tour_floor`'s argument holds,
    and the plan's turns are its lanes and hole passes less one
    (:func:`~boustro.plan.region._assemble`)."""
    lanes = _laid_lanes(r, _plan_cells(r, opts, []), opts).lanes
    rings = [_hole_pass(r.holes[i]).options[0][2] for i in _flown_holes(lanes, opts)]
    return tour_floor(lanes, rings)


def screen_floor(
    region: Any,
    spacing: float,
    cost_of: Callable[[float, int], float],
    beyond: Callable[[float], bool],
    **kw: Any,
) -> float:
    """``cost_of(*plan_floor(region, spacing, **kw))`` (``-inf`` where that is ``None``), or a
    lower floor of the plan's cost that is already ``beyond`` (the search's test: above its
    best plan), from the lanes alone (:func:`lanes_floor`): then the lanes are not cut to the
    area by their passes, their residual not computed (most of a floor's cost). Whatever it
    returns, ``beyond`` of it holds exactly where it holds of the plan floor's cost (``beyond``
    an upper set), so a search screens out the same layouts. ``cost_of`` as
    :meth:`~boustro.optimize.cover.CoverCost.of`: non-decreasing in both."""
    cheap = lanes_floor(region, spacing, cost_of, beyond, **kw)
    if cheap is not None and beyond(cheap):
        return cheap
    floor = plan_floor(region, spacing, **kw)
    return -math.inf if floor is None else cost_of(*floor)


#: Relative room :func:`lanes_floor` leaves below the plan floor's cost: the sums of its parts
#: in another order than :func:`tour_floor`'s (rounding, ~1e-15 of them).
CHEAP_ROOM = 1e-9


def lanes_floor(
    region: Any,
    spacing: float,
    cost_of: Callable[[float, int], float],
    beyond: Callable[[float], bool] | None = None,
    **kw: Any,
) -> float | None:
    """A floor of ``cost_of(*plan_floor(region, spacing, **kw))`` (``None`` where that is
    ``None``, and for a plan without ``keep_inside``) from the lanes cut at each margin and a
    floor of their passes (:func:`~boustro.plan.inside.margin_floor`), without their residual:
    the smallest over the margins of ``min_p cost_of(L + P + max(M - H(p), 0), n + p - 1)``,
    ``L`` the cut lanes' length, ``P`` the passes' floor, ``n`` the lanes, ``M`` the moves'
    floor of the lanes alone (:func:`tour_floor`'s ``by_lanes`` without passes) and ``H(p)``
    the ``2 p`` largest of the lane ends' ``nn_lane / 2``, over the passes' count ``p`` (at
    least 1 where ``P > 0``).

    Why it is below the plan floor (docs/keep_inside.md, "Cheap screen"): the plan keeps one
    margin's lanes with ``p`` passes at least ``P`` long (some pass where ``P > 0``: its
    stretches), and its floor (:func:`tour_floor`) counts ``L`` plus the passes, ``n + p - 1``
    turns and moves of at least ``max(by_lanes, 0)``; ``by_lanes`` sums the lane ends'
    ``nn_lane / 2`` (passes change no lane end's nearest lane end) and the passes' ends'
    ``nn / 2 >= 0`` less the two largest (adding non-negative terms never lowers a sum less its
    two largest), so at least ``M``, less at most ``2 p`` lane ends' ``(nn_lane - nn) / 2 <=
    nn_lane / 2``: at least ``M - H(p)``. ``cost_of`` is non-decreasing in both, so the
    floor's cost is at least the term of its ``p``; the terms are convex in ``p`` (``H``'s
    steps shrink), the smallest found where they stop falling. :data:`CHEAP_ROOM` for
    rounding. With ``beyond``, it stops at the first margin (1/2 first) whose floor is not
    ``beyond``: then it returns that margin's floor, not below the smallest but not
    ``beyond`` either."""
    parsed = _parsed(region, spacing, kw)
    if parsed is None or not parsed[1].keep_inside:
        return None
    r, opts = parsed
    laid = _laid_lanes(r, _plan_cells(r, opts, []), opts).lanes
    out = math.inf
    for margin in sorted(MARGINS, reverse=True):  # 1/2 first: its floor is the lower one
        cut, passes = margin_floor(r, laid, opts.spacing, opts.reach, margin)
        length, n, moves, halves = _lane_moves(cut)
        lost = np.concatenate([[0.0], np.cumsum(halves)])  # the 2 p largest halves: lost[2 p]
        floor = math.inf
        for p in range(1 if passes > 0 else 0, n + 2):  # convex in p: stop where it rises
            floor_p = cost_of(length + passes + max(moves - lost[min(2 * p, 2 * n)], 0.0),
                              max(n + p - 1, 0))  # fmt: skip
            if floor_p >= floor:
                break
            floor = floor_p
        out = min(out, floor - CHEAP_ROOM * abs(floor))
        if beyond is not None and not beyond(out):
            break  # the smallest is not beyond: the other margin need not be cut
    return out


def _parsed(region: Any, spacing: float, kw: dict[str, Any]) -> tuple[Region, Any] | None:
    """The region and ``plan_region``'s checked options of :func:`plan_floor`'s call, ``None``
    unless it is a plan of the guaranteed layout over one cell."""
    unknown = kw.keys() - _DEFAULTS.keys()
    if unknown:  # plan_region's own error
        _SIGNATURE.bind(region, spacing, **kw)
    args = {**_DEFAULTS, **kw}
    r = as_region(region)
    del args["progress"]
    cells = args.pop("cells")
    opts = _check_options(r, spacing, cells=None if cells is None else tuple(cells), **args)
    if opts.layout != "guaranteed" or opts.decompose_area is not False:
        return None
    return r, opts


def _lane_moves(lanes: list[Lanes]) -> tuple[float, int, float, NDArray[np.float64]]:
    """The cut ``lanes``' length, their number, :func:`tour_floor`'s ``by_lanes`` of the lanes
    alone (no passes) and the halves of each lane end's distance to another lane's end
    (``nn_lane / 2``), largest first."""
    ends, labels, length, units = _lane_ends(lanes)
    if units < 2:
        return length, units, 0.0, np.zeros(2 * units)
    xy, lab = np.concatenate(ends), np.concatenate(labels)
    _, nn_lane = _nearest(xy, lab, xy, lab, 2 * units)
    halves = np.sort(nn_lane / 2)
    return length, units, float(halves[:-2].sum()), halves[::-1]


def _lane_ends(
    lanes: list[Lanes],
) -> tuple[list[NDArray[np.float64]], list[NDArray[np.int64]], float, int]:
    """The lanes' ends (two a lane), their lanes' numbers, their length and number."""
    ends, labels = [], []
    length, units = 0.0, 0
    for ls in lanes:
        if len(ls.k):
            ends.append(ls.segments.reshape(-1, 2))
            labels.append(np.repeat(np.arange(units, units + len(ls.k)), 2))
            length += float(np.sum(ls.t1 - ls.t0))
            units += len(ls.k)
    return ends, labels, length, units


def _nearest(
    every: NDArray[np.float64],
    every_lab: NDArray[np.int64],
    xy: NDArray[np.float64],
    lab: NDArray[np.int64],
    n_lane: int,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Per end ``xy`` (of unit ``lab``), the distance to the nearest point of ``every`` (of unit
    ``every_lab``) of another unit, and to the nearest of its first ``n_lane`` (the lanes'
    ends; where none, the former), 0 where none."""
    nn, nn_lane = np.full(len(xy), np.inf), np.full(len(xy), np.inf)
    for lo in range(0, len(every), 512):  # the ends' nearest other unit, 512 points at a time
        d = np.hypot(every[lo : lo + 512, None, 0] - xy[None, :, 0],
                     every[lo : lo + 512, None, 1] - xy[None, :, 1])  # fmt: skip
        d[every_lab[lo : lo + 512, None] == lab[None, :]] = np.inf
        nn = np.minimum(nn, d.min(axis=0))
        if lo < n_lane:  # the nearest other lane's end
            nn_lane = np.minimum(nn_lane, d[: n_lane - lo].min(axis=0))
    nn = np.where(np.isfinite(nn), nn, 0.0)
    return nn, np.where(np.isfinite(nn_lane), nn_lane, nn)


def tour_floor(lanes: list[Lanes], passes: list[NDArray[np.float64]]) -> tuple[float, int]:
    """A lower bound ``(length, turns)`` of the path and turns of every tour of the cut
    ``lanes`` and boundary ``passes`` (:func:`inside_layout`), however ordered, routed and
    driven: the lanes' and passes' own length plus a floor of the moves between them, and the
    turns (one fewer than the lanes and passes: a plan's count, with or without ``keep_inside``,
    :mod:`boustro.plan.region`).

    The path drives each *unit* (a lane, a pass) whole, from an entry to an exit: a lane or an
    open pass from one end to the other (either way), a closed pass from one of its corners
    round to it. Between consecutive units it goes from the exit of one to the entry of the
    next (a move, routed or turned: never shorter than the straight line). With ``nn(p)`` the
    distance from a unit's end ``p`` to the nearest end or corner of any *other* unit, the
    move from ``x`` to ``y`` is at least ``max(nn(x), nn(y)) >= (nn(x) + nn(y)) / 2``; summed
    over the moves, every lane's and open pass's two ends count half once each (whichever way
    it is driven) except the first unit's entry and the last one's exit (the two largest
    halves are taken off), and a closed pass counts 0. Also, every unit but the first is
    entered by a move of at least ``min(nn)`` over its ends (0 for a closed pass); the larger
    of the two floors is returned. The search's screen (:mod:`boustro.optimize.cover`) skips
    a layout whose floor is above its best plan."""
    ends, labels, length, units = _lane_ends(lanes)
    rings, ring_labels = [], []
    n_lanes = units
    for p in passes:
        length += float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())
        if len(p) > 3 and bool(np.allclose(p[0], p[-1], rtol=0.0, atol=1e-12)):  # closed
            rings.append(p)
            ring_labels.append(np.full(len(p), units))
        else:
            ends.append(p[[0, -1]])
            labels.append(np.array([units, units]))
        units += 1
    if units < 2 or not ends:
        return length, max(units - 1, 0)
    xy, lab = np.concatenate(ends), np.concatenate(labels)
    every, every_lab = np.concatenate([xy, *rings]), np.concatenate([lab, *ring_labels])
    n_lane = 2 * n_lanes  # the lanes' ends come first
    nn, nn_lane = _nearest(every, every_lab, xy, lab, n_lane)
    half = np.sort(nn / 2)
    by_halves = float(half[:-2].sum())
    # a move between two lanes' ends is at least half of each one's nn_lane; at most two moves
    # per pass reach a lane's end from it (in and out), each losing half of nn_lane - nn there
    charge = np.concatenate([nn_lane[:n_lane], nn[n_lane:]]) / 2
    loss = np.sort((nn_lane[:n_lane] - nn[:n_lane]) / 2)[::-1][: 2 * len(passes)]
    by_lanes = float(np.sort(charge)[:-2].sum() - loss.sum())
    entered = np.full(units, np.inf)
    np.minimum.at(entered, lab, nn)
    entered = np.where(np.isfinite(entered), entered, 0.0)  # closed passes
    by_entries = float(entered.sum() - entered.max())
    return length + max(by_halves, by_lanes, by_entries, 0.0), units - 1
