"""The branch and bound of the certified cover search (:func:`~.search.cover_optimum`): bound,
plan, discard or retire, and halve boxes of layouts; the 1-tree's multipliers follow the boxes
(docs/mission_time.md, "The 1-tree's CPU")."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from .boxes import Boxes as _Boxes
from .boxes import box_radius, split_boxes, split_parents
from .one_tree import Multipliers
from .plans import try_plans

__all__ = [
    "CERTIFY_FIRST",
    "CUT_OFF",
    "FINE_BOXES",
    "FINE_LEVELS",
    "PARTIAL_ROUND",
    "POINT_TOURS_BELOW_MODEL",
    "REOPEN",
    "SETTLE_SHARE",
    "Limits",
    "branch_and_bound",
    "certifying",
    "discard_at",
    "joined_parts",
    "partial_round",
    "retire_at",
    "take_multipliers",
]

#: A box whose bound is within this share of (best plan - lowest model) and ``rtol`` of the best
#: plan (``rtol`` alone where it is larger) below the lowest model is retired (the certificate's
#: gap cannot get much below that difference anyway; :func:`retire_at`). 0.25 before the
#: piece-ends bound; 0.15 cut the random areas' median gap by a tenth for 4% more CPU.
SETTLE_SHARE = 0.15


#: Whether boxes are only discarded (never resolved or settled below the discard value) when
#: the lowest model, less :data:`CERTIFY_SHARE` of its distance to the best plan, is at or
#: above that value: the certificate is then within reach (:func:`certifying`).
CERTIFY_FIRST = True


#: The share of (best plan - lowest model) kept below the lowest model by :func:`certifying`:
#: :data:`SETTLE_SHARE` (0.15) before :data:`REOPEN`; with the boxes settled before then
#: reopened, a margin only delays certifying (the benchmark's random area 21: its lowest model
#: 0.15 s above the discard value, 0.03 s short of that margin; docs/mission_time.md, "Where the
#: certificates are lost, and the search's last boxes").
CERTIFY_SHARE = 0.0


#: Whether a round computes the 1-tree at a box centre only where the bound without it is
#: below the lowest model (plus ``resolve - rtol`` of the best plan): elsewhere it cannot
#: change which boxes are kept, so the same search for less CPU (the points' 1-trees were
#: half of the 1-tree's CPU; docs/mission_time.md, "The 1-tree's CPU").
POINT_TOURS_BELOW_MODEL = True


#: Whether the boxes retired below the discard value (settled or resolved) come back into the
#: search once it is certifying (:func:`certifying`): retired in the first rounds, before the
#: lowest model rose (or the best plan fell) into the certificate's reach, they held its floor
#: below the discard value for good. Any box may be bounded again: only the search's work
#: changes.
REOPEN = True


#: Halvings past the smallest radius (``min_eps``) for the boxes left once the certificate is
#: within reach (:func:`certifying`: every box is only discarded), when at most
#: :data:`FINE_BOXES` are left: a box straddling a layout where the plan changes (random area 4
#: of ``benchmarks/mission_time.py``: one box of radius 5.2 mm held the floor 0.05 s below
#: the certificate) loses less to the sandwich at a smaller radius. Any box's bound is a lower
#: bound, whatever its radius: only the search's work changes.
FINE_LEVELS = 4
FINE_BOXES = 32


#: Whether a search whose next round would pass its work budget (``max_work``) halves the
#: boxes of the lowest bounds that the budget still allows (:meth:`~.search.CoverSearch.
#: boxes_within`), best first, before it stops; the other boxes leave with their bounds, in the
#: certificate's floor as every box left at the budget's end. On searches with simplified
#: sandwiches (areas of more than ``SIMPLIFY_EDGES`` edges), not with keep-inside: the other
#: searches keep their path (not measured with it). Issue 21's 2000-vertex field: the budget
#: stopped the search after 3 rounds with 1440 boxes of radius 3.1 m, where the budget still
#: allowed 1126 of them at 1.6 m (docs/scale.md, "A partial last round").
PARTIAL_ROUND = True


def partial_round(search: Any) -> bool:
    """Whether ``search`` ends on a partial round (:data:`PARTIAL_ROUND`)."""
    return PARTIAL_ROUND and not search.keep_inside and search.sandwich.tolerance > 0


#: Why a search with a ``cutoff`` stopped once its lower bound reached it (``info["stopped"]``).
CUT_OFF = "the lower bound reached the cutoff"


class Limits(NamedTuple):
    """The tolerances and budgets of :func:`cover_optimum` (see its arguments)."""

    rtol: float
    resolve: float
    min_eps: float
    max_work: float
    max_seconds: float | None
    t0: float
    cutoff: float | None = None  # stop once the lower bound reaches it (cover_optimum's)


def take_multipliers(mult: Multipliers | None, index: NDArray[Any]) -> Multipliers | None:
    """The multipliers of the boxes ``index`` selects (a mask or indices)."""
    if mult is None:
        return None
    return Multipliers(mult.values[index], mult.warm[index], mult.k0)


def discard_at(best: float, lim: Limits) -> float:
    """The discard value: a box whose bound is at or above it cannot beat the best plan
    ``best`` by more than ``rtol`` (cost units)."""
    return best - lim.rtol * abs(best)


def certifying(best: float, model_min: float, lim: Limits) -> bool:
    """Whether boxes are only discarded (:data:`CERTIFY_FIRST`): the lowest model less
    :data:`CERTIFY_SHARE` of its distance to the best plan is at or above the discard value."""
    discard = discard_at(best, lim)
    return CERTIFY_FIRST and model_min - CERTIFY_SHARE * max(best - model_min, 0.0) >= discard


def retire_at(
    points: NDArray[np.float64], best: float, model_min: float, lim: Limits
) -> NDArray[np.float64]:
    """The bound at which each box (``points``: the model at its centre) leaves the search:
    discarded at ``best - rtol |best|`` (it cannot beat the best plan by more than ``rtol``),
    resolved within ``resolve`` of its centre's model, settled within :data:`SETTLE_SHARE` of
    (best plan - lowest model) plus ``rtol |best|`` below the lowest model, or within ``rtol
    |best|`` alone where the share is smaller (the resolved boxes stop there anyway; the sum
    took another ``rtol`` off the floor: Fields2Cover's ``test_2_cell.json#1``, 0.05% of its
    gap; where the share is larger the sum stays, the CPU of a wide gap's boxes: random area 9
    of ``benchmarks/mission_time.py`` took 1.3x with the larger of the two).
    Where :func:`certifying`, no box is resolved or settled: one retired below the discard
    value leaves the certificate's floor there (unless :data:`REOPEN` brings it back),
    uncertified however far the others go (Fields2Cover's ``test1.xml``: boxes settled at
    3987.54 s, where the plan of 3991.70 s certifies at 3987.70 s)."""
    discard = discard_at(best, lim)
    unavoidable = SETTLE_SHARE * max(best - model_min, 0.0)
    if certifying(best, model_min, lim):
        return np.full(len(points), discard)
    near = unavoidable < lim.rtol * abs(best)  # the share alone would settle above resolution
    settle = model_min - lim.rtol * abs(best) - (0.0 if near else unavoidable)
    return np.minimum(np.minimum(discard, points - lim.resolve * abs(best)), settle)


_Part = tuple[_Boxes, NDArray[np.float64], NDArray[np.float64], Multipliers | None]


def joined_parts(parts: list[_Part]) -> _Part:
    """Boxes, bounds, certificate's bounds and multipliers of several parts, concatenated."""
    boxes = _Boxes(*(np.concatenate([p[0][f] for p in parts]) for f in range(4)))
    bounds = np.concatenate([p[1] for p in parts])
    tight = np.concatenate([p[2] for p in parts])
    kept = [p[3] for p in parts if p[3] is not None]
    mult = None
    if len(kept) == len(parts):
        values = np.concatenate([m.values for m in kept])
        mult = Multipliers(values, np.concatenate([m.warm for m in kept]), kept[0].k0)
    return boxes, bounds, tight, mult


def branch_and_bound(
    search: Any,
    boxes: _Boxes,
    lim: Limits,
    progress: Callable[[float], None] | None,
) -> tuple[float, int, str]:
    """Bound, plan, discard or retire, and halve the boxes until none is left or a limit is
    reached: ``(the lowest bound of a box taken out, rounds, why it stopped early or "")``;
    the boxes are kept by :meth:`box_bounds`' values, the bound returned is of the
    certificate's (``search.tight``, at least those: the same search, a higher floor)."""
    floor = math.inf  # the lowest bound of a discarded box
    certified = math.inf  # the same with the certificate's bounds (search.tight): not lower
    rounds, stopped = 0, ""
    mult = search.multipliers(len(boxes.theta))
    retired: list[_Part] = []  # boxes taken out below the discard value (REOPEN)
    while len(boxes.theta):
        rounds += 1
        # a point's 1-tree changes keep_at below only where its bound without it is below
        # the lowest model plus (resolve - rtol) of the best plan (the resolve term is above
        # settle elsewhere, docs/mission_time.md "The 1-tree's CPU"): the same boxes go
        tour_keep = None
        if POINT_TOURS_BELOW_MODEL and math.isfinite(search.model_min + search.best[0]):
            tour_keep = search.model_min + (lim.resolve - lim.rtol) * abs(search.best[0])
        points = search.point_values(boxes, multipliers=mult, tour_keep=tour_keep)
        try_plans(search, boxes, search.ranks, first=rounds == 1, bounds=points)
        best = search.best[0]
        # discarded: cannot beat the best plan; resolved: the bound is within rtol of the
        # model at the box's centre, so halving cannot raise it further than the model
        model_min = search.model_min
        # settled: the bound is near the lowest model value (the certificate's gap cannot get
        # much smaller than the best plan's distance to it)
        keep_at = retire_at(points, best, model_min, lim)
        # the 1-tree only where the other bounds keep the box: a box taken out without it
        # joins the certificate's floor later (settle_deferred), with it where it matters
        bounds = search.box_bounds(boxes, keep_at if search.defer else None, multipliers=mult)
        keep = bounds < keep_at
        # the certificate's bounds (search.tight: keep-inside's moves on top of its passes),
        # at least the bounds the boxes are kept by: the same boxes, a higher floor
        tight = search.tight
        skipped = search.skipped
        if skipped.any():
            later = (boxes.take(skipped), bounds[skipped], take_multipliers(mult, skipped))
            search.deferred.append(later)
        done = ~keep & ~search.skipped
        if REOPEN:  # settled or resolved below the discard value: back once certifying
            low_done = done & (bounds < discard_at(best, lim))
            if low_done.any():
                retired.append((boxes.take(low_done), bounds[low_done], tight[low_done],
                                take_multipliers(mult, low_done)))  # fmt: skip
            done &= ~low_done
        if done.any():
            floor = min(floor, float(bounds[done].min()))
            certified = min(certified, float(tight[done].min()))
        boxes, bounds, mult = boxes.take(keep), bounds[keep], take_multipliers(mult, keep)
        tight = tight[keep]
        if retired and certifying(best, model_min, lim):
            boxes, bounds, tight, mult = joined_parts([(boxes, bounds, tight, mult), *retired])
            retired = []
        low = min(floor, search.deferred_min(), float(bounds.min()) if len(bounds) else math.inf)
        low = min([low, *(float(r[1].min()) for r in retired)])
        if progress is not None and math.isfinite(best):
            progress(max(0.0, min(1.0, 1.0 - (best - low) / max(abs(best), 1e-300))))
        if not len(boxes.theta):
            break
        if lim.cutoff is not None and low >= lim.cutoff:  # no layout is below the cutoff
            certified = min(certified, search.deferred_min(), float(tight.min()))
            stopped = CUT_OFF
            break
        eps = box_radius(boxes, search.radius)
        smallest = lim.min_eps  # smaller for the last few boxes once certifying (FINE_LEVELS)
        if len(boxes.theta) <= FINE_BOXES and certifying(best, model_min, lim):
            smallest = lim.min_eps / 2.0**FINE_LEVELS
        fine = eps <= smallest
        if fine.any():
            floor = min(floor, float(bounds[fine].min()))
            certified = min(certified, float(tight[fine].min()))
            stopped = stopped or "the boxes reached the smallest radius"
            boxes, mult = boxes.take(~fine), take_multipliers(mult, ~fine)
            bounds, tight = bounds[~fine], tight[~fine]
            if not len(boxes.theta):
                break
        if search.work_spent(len(boxes.theta)) > lim.max_work:
            spent = f"the work budget ({lim.max_work:.0e} box edges) was spent"
            fit = search.boxes_within(lim.max_work) if partial_round(search) else 0
            if fit < 1:
                certified = min(certified, float(tight.min()))
                stopped = spent
                break
            # a partial round (PARTIAL_ROUND): the lowest boxes the budget still allows are
            # halved, the others leave with their bounds (the floor, as at the budget's end)
            stopped = stopped or spent
            chosen = np.zeros(len(bounds), dtype=bool)
            chosen[np.argsort(bounds, kind="stable")[:fit]] = True
            if not chosen.all():
                floor = min(floor, float(bounds[~chosen].min()))
                certified = min(certified, float(tight[~chosen].min()))
            boxes, mult = boxes.take(chosen), take_multipliers(mult, chosen)
            bounds, tight = bounds[chosen], tight[chosen]
        if lim.max_seconds is not None and time.perf_counter() - lim.t0 > lim.max_seconds:
            certified = min(certified, float(tight.min()))
            stopped = f"{lim.max_seconds} s passed"
            break
        if mult is not None:  # the halves start from their box's multipliers
            mult = take_multipliers(mult, split_parents(boxes, search.radius))
        boxes = split_boxes(boxes, search.radius)
    # the floor's parts for a last pass (search.settle_branched): the retired boxes, the rest
    search.retired, search.rest_floor = retired, certified
    return min([certified, *(float(r[2].min()) for r in retired)]), rounds, stopped
