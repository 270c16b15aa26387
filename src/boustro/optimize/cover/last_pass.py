"""The certified cover search's last pass (:func:`settle_branched`): the boxes the branch and
bound retired below the discard value of the best plan, bounded again with the 1-tree branched
(:mod:`~.one_tree_branch`) and halved, the lowest first, within a budget of boxes.

It runs after every plan, so the plans are the same; each box's bound only rises (a box's
halves keep its bound where higher: they hold fewer layouts), so the certificate's floor too
(docs/mission_time.md, "Branching on the 1-tree").
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .boxes import Boxes as _Boxes
from .boxes import split_boxes, split_parents
from .branch import joined_parts, take_multipliers
from .one_tree import Multipliers
from .one_tree_branch import BRANCH_NODES

__all__ = ["settle_branched"]

#: Whether an uncertified search's last pass branches on the 1-trees of the boxes it retired
#: below the discard value (:func:`settle_branched`, :mod:`~.one_tree_branch`):
#: after every plan, so the same plans; the certificate's floor can only rise.
BRANCH_TOUR = True
#: ... only where those boxes' bounds are within this share of the best plan below the discard
#: value, and a layout's 1-tree is branched only where it is within as much of its target.
BRANCH_RTOL = 3e-3
#: ... halving the boxes still below it at most this many times, the :data:`BRANCH_CHUNK`
#: lowest retired boxes first (if they stay below it the others are left as they are).
BRANCH_LEVELS = 4
BRANCH_CHUNK = 4
#: ... then the others in chunks, each this many times the one before (4, 16, 64, ...), the
#: lowest first, the pass stopping at the first chunk that stays below (the chunks after it
#: keep their bounds): each box is bounded in one chunk or keeps its bound, so where the pass
#: certifies it bounds the same boxes as one chunk of all of them, and where it cannot it
#: spends less (eighteenth round: random area 39 of ``benchmarks/mission_time.py``, 8,019 boxes
#: and 6.3 s of CPU in one chunk, 1,904 and 1.7 s so).
BRANCH_GROWTH = 4
#: ... bounding at most this many boxes in all (a level that would pass it is not bounded: its
#: boxes keep the bounds they have, which hold). Random areas 7, 9, 22 and 24 of
#: ``benchmarks/mission_time.py`` are certified by the pass within 800-9,200; without a budget
#: random 35 bounded 207,631 boxes (133 s of CPU, not certified) and random 77 51,314 (22 s).
BRANCH_BUDGET = 12_000
#: ... bounding a level's boxes this many at a time, lowest first, so that the last level
#: stops once no box left can lower its least bound (:func:`_level_bounds`).
BRANCH_SLICE = 256
#: The window class (nineteenth round): the pass also runs where the lowest retired box is
#: below the discard value by more than :data:`BRANCH_RTOL` of the best plan, up to this share
#: of it (boxes retired at radii of 0.04-1.4 m by the settling margin, 3.7-16 s below on the
#: benchmark's random areas), with three changes that only decide what is bounded and where
#: the 1-tree branches (a box not bounded keeps its bound, which holds; the branching is sound
#: for any window, :mod:`~.one_tree_branch`): the 1-tree is branched wherever a layout is short
#: of the target by at most the lowest box's distance to it (every box of the pass, whose
#: halves' bounds are at least their box's, is within it); the lowest box alone is the first
#: chunk (if it stays below, the pass stops after one box's levels: the cheap early stop); and
#: at most :data:`BRANCH_REACH_BUDGET` boxes in all (docs/mission_time.md, "The window class").
BRANCH_REACH = 1.5e-2
#: ... bounding at most this many boxes in all there (:data:`BRANCH_BUDGET` elsewhere); the
#: pass stops before a chunk where more boxes below the discard value are left than boxes in
#: the budget (the exact early fail: a box left unbounded keeps its bound below the discard
#: value, and each box takes at least one of the budget, so the pass could no longer certify;
#: random 38 and 16 of ``benchmarks/mission_time.py``, 6,333 and 5,915 such boxes, before any
#: chunk, random 20 after three: docs/mission_time.md, "The window class").
BRANCH_REACH_BUDGET = 4_000


def settle_branched(search: Any, lower: float, value: float, rtol: float) -> float:
    """The certificate's lower bound ``lower`` raised by a last pass (:data:`BRANCH_TOUR`)
    over the boxes the branch and bound retired below the discard value of the best plan
    ``value``, the :data:`BRANCH_CHUNK` lowest first, then the others in chunks growing by
    :data:`BRANCH_GROWTH`, the lowest first: their bounds with
    the 1-tree branched (:mod:`~.one_tree_branch`), the boxes still below it halved (each
    half keeps its box's bound where higher: it holds fewer layouts), :data:`BRANCH_LEVELS`
    times at most; the chunks after one that stays below it are left as they are. Only where
    it can decide: the rest of the floor at or above the discard value, every retired box
    within :data:`BRANCH_RTOL` of the best plan below it, or within :data:`BRANCH_REACH` (the
    window class: the lowest box alone first, the branching's window its distance to the
    discard value, :data:`BRANCH_REACH_BUDGET` boxes). Plans only before, so the same
    plans; each box's bound only rises, so the floor too. The floor of the boxes not
    deferred: the deferred boxes join it after (:meth:`~.search.CoverSearch.settle_deferred`)."""
    target = value - rtol * abs(value)
    retired, search.retired = search.retired, []
    if not (BRANCH_TOUR and search.ends and search.tour) or lower >= target:
        return lower
    if min(search.rest_floor, value) < target or not retired:
        return lower
    window = BRANCH_RTOL * abs(value)
    boxes, bounds, _, mult = joined_parts(retired)
    lowest = float(bounds.min())
    if lowest < target - max(window, BRANCH_REACH * abs(value)):
        return lower
    wide = lowest < target - window  # the window class (BRANCH_REACH)
    order = np.argsort(bounds, kind="stable")
    order = order[bounds[order] < target]
    above = float(bounds[bounds >= target].min(initial=math.inf))  # kept as they are
    floor = min(search.rest_floor, value, above)
    work, evaluations = search.work, search.bound_evaluations  # not the search's work
    search.branch = (BRANCH_NODES, target - lowest if wide else window)
    search.branch_left = BRANCH_REACH_BUDGET if wide else BRANCH_BUDGET
    start, stop = 0, 1 if wide else BRANCH_CHUNK
    while start < len(order):  # the lowest first: the pass stops where a chunk stays low
        if wide and len(order) - start > search.branch_left:  # cannot certify: the early fail
            floor = min(floor, float(bounds[order[start:]].min()))
            break
        pick = order[start:stop]
        got = _branched_boxes(
            search, boxes.take(pick), bounds[pick], take_multipliers(mult, pick), target
        )
        floor = min(floor, got)
        if got < target:  # the chunks after it keep their bounds
            rest = order[stop:]
            floor = min(floor, float(bounds[rest].min(initial=math.inf)))
            break
        start, stop = stop, stop + (stop - start) * BRANCH_GROWTH
    search.branch = None
    search.work, search.bound_evaluations = work, evaluations
    return max(lower, floor)


def _branched_boxes(
    search: Any,
    boxes: _Boxes,
    bounds: NDArray[np.float64],
    mult: Multipliers | None,
    target: float,
) -> float:
    """The least bound over ``boxes`` (``bounds`` their bounds so far) with the 1-tree
    branched, the boxes below ``target`` halved :data:`BRANCH_LEVELS` times at most, within
    what is left of the budget (``branch_left``: :data:`BRANCH_BUDGET`, or
    :data:`BRANCH_REACH_BUDGET` in the window class; a level past it is not bounded
    and its boxes keep their bounds so far, each at most its layouts' values)."""
    low_min = math.inf
    for level in range(BRANCH_LEVELS + 1):
        if len(bounds) > search.branch_left:  # over the budget: the bounds they have hold
            break
        search.branch_left -= len(bounds)
        got, last_min = _level_bounds(search, boxes, bounds, mult, target, level)
        if got is None:  # the pass's last level: its least bound is all that counts
            return last_min
        bounds = np.maximum(bounds, got)
        low = bounds < target
        low_min = min(low_min, float(bounds[~low].min(initial=math.inf)))
        if not low.any() or level == BRANCH_LEVELS:
            break
        boxes, bounds, mult = boxes.take(low), bounds[low], take_multipliers(mult, low)
        parents = split_parents(boxes, search.radius)
        bounds, mult = bounds[parents], take_multipliers(mult, parents)
        boxes = split_boxes(boxes, search.radius)
    return min(low_min, float(bounds.min()))


def _level_bounds(
    search: Any,
    boxes: _Boxes,
    bounds: NDArray[np.float64],
    mult: Multipliers | None,
    target: float,
    level: int,
) -> tuple[NDArray[np.float64] | None, float]:
    """One level of :func:`_branched_boxes`: the boxes' bounds with the 1-tree branched
    (``mult`` updated), bounded :data:`BRANCH_SLICE` at a time, lowest ``bounds`` first (a
    box's bound does not depend on the others bounded with it). ``(None, least)`` once the
    level is the pass's last (:data:`BRANCH_LEVELS`, or its boxes below ``target`` so far
    would halve into more than the budget left) and no box left can lower ``least``, the
    least of the bounds so far: each box left keeps at least its bound so far, so ``least``
    is the least bound the whole level would give, all that :func:`_branched_boxes` returns
    after its last level (docs/mission_time.md, "The plans' CPU, eighteenth round"): it
    stops only at a box left whose bound so far is below the target, so ``least`` is below
    it too, under every box of the levels before that reached it. Else ``(bounds, inf)``,
    every box bounded."""
    order = np.argsort(bounds, kind="stable")
    got = np.empty(len(bounds))
    least, children = math.inf, 0
    for start in range(0, len(order), BRANCH_SLICE):
        idx = order[start : start + BRANCH_SLICE]
        last = level == BRANCH_LEVELS or children > search.branch_left
        if last and not float(bounds[idx[0]]) < least:
            return None, least
        part = take_multipliers(mult, idx)
        got[idx] = search.box_bounds(boxes.take(idx), tour_below=target, multipliers=part)
        if mult is not None and part is not None:
            mult.values[idx], mult.warm[idx] = part.values, part.warm
        now = np.maximum(bounds[idx], got[idx])
        least = min(least, float(now.min()))
        low = idx[now < target]
        children += len(split_parents(boxes.take(low), search.radius))
    return got, math.inf
