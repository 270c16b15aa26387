"""The layouts a certified cover search plans (upper bounds: :func:`try_plans`), and which:
each round's most promising box centres (:mod:`~.branch`), the longest edges' directions before
the search (:func:`try_edges`), the best layout of each degree and more offsets at the best
angle after it (:func:`polish`, :func:`refine_offsets`), and a 1-degree brute force's layouts
(:mod:`~.centred`, offsets from :func:`centred_offsets`). A layout whose own bound is above
the best plan is not planned (:func:`bounds_rule_out`). ``search`` is the
:class:`~.search.CoverSearch` whose best plan, seen layouts and counts these update."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...geometry.region import Region
from .boxes import Boxes as _Boxes

__all__ = [
    "EDGE_OFFSETS",
    "EDGE_PLANS",
    "FIRST_PLANS",
    "FIRST_SEPARATION",
    "PLANS_PER_ROUND",
    "POLISH_PLANS",
    "REFINE_OFFSETS",
    "RULE_OUT_TOL",
    "SKIP_RULED_OUT",
    "bounds_rule_out",
    "centred_offsets",
    "layout_bounds",
    "plan_value",
    "polish",
    "refine_offsets",
    "rules_out",
    "try_edges",
    "try_plans",
]

#: Plans evaluated per round at most (the layouts with the lowest point bound).
PLANS_PER_ROUND = 3
#: Plans evaluated at the first round, at angles this far apart (radians) at least.
FIRST_PLANS = 16
FIRST_SEPARATION = math.radians(3.0)
#: Edge directions (longest edges first) whose best offsets are planned before the search,
#: and offsets scanned at each.
EDGE_PLANS = 12
EDGE_OFFSETS = 64
#: Plans of the best modelled layouts (one per degree) after the search of a routed plan.
POLISH_PLANS = 32
#: Offsets planned at the best angle after the search of a routed plan.
REFINE_OFFSETS = 8
#: Whether a layout whose own bound (the exact area, the 1-tree) is above the best plan is not
#: planned (:func:`try_plans`): its plan cannot beat the best one; it still counts
#: as tried, so the search plans the same layouts otherwise and finds the same plan
#: (docs/mission_time.md, "The 1-tree's CPU").
SKIP_RULED_OUT = True
#: A bound must be above the best plan by this share of it to rule a layout out (rounding).
RULE_OUT_TOL = 1e-9


def bounds_rule_out(search: Any) -> bool:
    """Whether a layout's own bound (:meth:`~.search.CoverSearch.point_values` on the exact
    area, the 1-tree where computed) is a lower bound of its plan's cost here, so that a layout
    whose bound is above the best plan need not be planned (:data:`SKIP_RULED_OUT`): with real
    plans, not with keep-inside (its bound at a layout is 5-20% below its plans: it would rule
    out next to nothing, and is tested in boxes only). On areas searched with simplified
    sandwiches the search's own point values are of the simplified area (a model, not a
    bound): there :func:`try_plans` computes the exact bound of each layout it is about to plan
    (:func:`_exact_bound`)."""
    return SKIP_RULED_OUT and search.evaluate is not None and not search.keep_inside


def _exact_bound(search: Any, boxes: _Boxes, i: int) -> float:
    """The bound at box ``i``'s centre on the exact area (:func:`layout_bounds`), where
    :func:`bounds_rule_out` on a search with simplified sandwiches; else ``-inf``. One layout
    against the area's edges (about 0.5 ms on issue 21's 2120 edges, against 20-100 ms a
    plan)."""
    one = _Boxes(boxes.theta[i : i + 1], np.zeros(1), boxes.d[i : i + 1], np.zeros(1))
    out = layout_bounds(search, one)
    return -math.inf if out is None else float(out[0])


def layout_bounds(search: Any, boxes: _Boxes) -> NDArray[np.float64] | None:
    """The bound at each box's centre (:meth:`~.search.CoverSearch.point_values`, exact, the
    1-tree up to the best plan) without touching the search's state (its work, ranks, lowest
    model), where :func:`bounds_rule_out`; else ``None``."""
    if not bounds_rule_out(search) or not len(boxes.theta):
        return None
    state = (
        search.ranks,
        len(search.points),
        search.model_min,
        search.work,
        search.bound_evaluations,
    )
    out = search.point_values(boxes, exact=True)
    search.ranks, n, search.model_min, search.work, search.bound_evaluations = state
    del search.points[n:]
    return out


def try_plans(
    search: Any,
    boxes: _Boxes,
    points: NDArray[np.float64],
    first: bool = False,
    limit: int | None = None,
    bounds: NDArray[np.float64] | None = None,
) -> None:
    """Evaluate the plans of the boxes' centres with the lowest point values (upper
    bounds), where they could beat the best plan: :data:`PLANS_PER_ROUND`, or at the first
    round :data:`FIRST_PLANS` at angles at least :data:`FIRST_SEPARATION` apart.

    ``bounds`` (per box, where :func:`bounds_rule_out`): lower bounds of the plans at the
    centres; a layout whose bound is above the best plan is not planned (its plan cannot
    beat it) but counts as tried, so the same plans win as without ``bounds``
    (:attr:`~.search.CoverSearch.ruled_out` counts them); so is a layout whose floor
    (``search.screen``, a keep-inside plan's) is above it (counted in ``screened``)."""
    # the exact bounds: given (exact sandwiches), or of each layout planned (simplified ones,
    # whose point values model the simplified area)
    lazy = bounds_rule_out(search) and search.sandwich.tolerance > 0
    if bounds is not None and (lazy or not bounds_rule_out(search)):
        bounds = None
    order = np.argsort(points)
    if limit is None:
        limit = FIRST_PLANS if first else PLANS_PER_ROUND
    tried, taken = 0, list[float]()
    for i in order:
        if tried >= limit or points[i] >= search.best[0]:
            break
        key = boxes.centre_key(int(i))
        if key in search.seen:
            continue
        if first and any(
            abs((float(boxes.theta[i]) - t + math.pi / 2) % math.pi - math.pi / 2)
            < FIRST_SEPARATION
            for t in taken
        ):
            continue
        taken.append(float(boxes.theta[i]))
        search.seen.add(key)
        floor = float(bounds[i]) if bounds is not None else -math.inf
        if lazy and math.isfinite(search.best[0]):
            floor = _exact_bound(search, boxes, int(i))
        if rules_out(floor, search.best[0]):
            search.ruled_out += 1
            tried += 1
            continue
        theta, d = float(boxes.theta[i]), float(boxes.d[i])
        if _screened_out(search, theta, d):
            search.screened += 1
            tried += 1
            continue
        value = plan_value(search, boxes, int(i), points)
        search.plans += 1
        tried += 1
        if value < search.best[0]:
            search.best = (value, theta, d)


def _screened_out(search: Any, theta: float, d: float) -> bool:
    """Whether the layout's floor (``search.screen``: a lower bound of its plan's cost,
    cheaper than the plan, told the best plan's cost: it may stop at a cheaper floor already
    above it) is above the best plan: then the plan cannot beat it and is not made;
    it still counts as tried, as a layout ruled out by its bound, so the search makes the same
    other plans and finds the same best one."""
    if search.screen is None or not math.isfinite(search.best[0]):
        return False
    return rules_out(search.screen(theta, d, search.best[0]), search.best[0])


def rules_out(floor: float, best: float) -> bool:
    """Whether a layout whose cost is at least ``floor`` (a lower bound, or a screen's floor)
    cannot beat the ``best`` plan: ``floor`` above it by more than :data:`RULE_OUT_TOL` of it
    (room for the rounding of the two sums)."""
    return bool(floor > best + RULE_OUT_TOL * abs(best))


def plan_value(search: Any, boxes: _Boxes, i: int, points: NDArray[np.float64]) -> float:
    """The cost of the plan at box ``i``'s centre (``evaluate``, or the exact model)."""
    theta, d = float(boxes.theta[i]), float(boxes.d[i])
    if search.evaluate is not None:
        return float(search.evaluate(theta, d))
    if search.sandwich.tolerance <= 0 and not search.keep_inside:
        return float(points[i])
    one = _Boxes(*(a[i : i + 1] for a in boxes))
    return float(search.point_values(one, exact=True)[0])


def try_edges(search: Any, angles: list[float] | None = None) -> None:
    """Plan the best offset (by the model) along each of the longest edges' directions:
    areas with parallel sides often have their optimum exactly there. With the lane-ends
    bound, also the best offset by the lines' span alone where it differs: both are lower
    bounds of a routed tour, and either may rank a layout's real tour better (on areas of at
    most :data:`~.search.SIMPLIFY_EDGES` edges, where a plan costs milliseconds). ``angles``: these
    directions instead (a fixed-angle search)."""
    for a in _edge_angles(search.region, EDGE_PLANS) if angles is None else angles:
        d = (np.arange(EDGE_OFFSETS, dtype=np.float64) + 0.5) * (search.s / EDGE_OFFSETS)
        if not search.keep_inside:
            # and the lanes laid from either extreme: where the area's width is a whole
            # number of spacings (a 100 x 60 m rectangle at 10 m), the fewest lanes need
            # exactly that offset, a single point no box centre hits (the search planned 7
            # lanes, 212 s, where 6 fly it in 180 s). Not with keep_inside: there its model
            # ranks them first and the real plans came out up to 0.57% longer (a review)
            ends = np.array([a, a + math.pi])
            d = np.concatenate([d, centred_offsets(search.region, ends, search.s, search.reach)])
            d[-1] = (-d[-1]) % search.s  # the line reach inside the highest extreme
        boxes = _Boxes(np.full(len(d), a), np.zeros(len(d)), d, np.zeros(len(d)))
        bounds = search.point_values(boxes)
        try_plans(search, boxes, search.ranks, limit=1, bounds=bounds)
        if search.ends and search.evaluate is not None and search.sandwich.tolerance <= 0:
            span = search.point_values(boxes, span_only=True)
            try_plans(search, boxes, span, limit=1, bounds=bounds)


def polish(search: Any) -> None:
    """Plan the best modelled layout of each degree of angle whose model beats the best
    plan, lowest model first, :data:`POLISH_PLANS` at most, and the lanes centred on the
    area at those whole degrees: a routed plan's tour differs between layouts whose bounds
    are close, so the plans decide."""
    v, theta, d = np.concatenate(search.points, axis=1)
    ok = v < search.best[0]
    v, theta, d = v[ok], theta[ok], d[ok]
    bins = np.floor(np.degrees(theta % math.pi)).astype(np.int64)
    order = np.lexsort((v, bins))
    first = np.ones(len(order), dtype=bool)
    first[1:] = bins[order][1:] != bins[order][:-1]
    pick = order[first]
    pick = pick[np.argsort(v[pick])][:POLISH_PLANS]
    boxes = _Boxes(theta[pick], np.zeros(len(pick)), d[pick], np.zeros(len(pick)))
    try_plans(search, boxes, v[pick], limit=len(pick), bounds=layout_bounds(search, boxes))
    # the first lane half a spacing inside the area's extreme: the layout a person, or a
    # brute force over degrees, would fly
    angles = np.radians(bins[pick].astype(np.float64))
    centred = centred_offsets(search.region, angles, search.s, search.reach)
    boxes = _Boxes(angles, np.zeros(len(pick)), centred, np.zeros(len(pick)))
    bounds = search.point_values(boxes)
    try_plans(search, boxes, search.ranks, limit=len(pick), bounds=bounds)


def refine_offsets(search: Any) -> None:
    """Plan :data:`REFINE_OFFSETS` more offsets at the best angle: a routed plan's moves
    differ between offsets that the bound (lanes, turns) cannot tell apart."""
    theta = search.best[1]
    d = (np.arange(REFINE_OFFSETS, dtype=np.float64) + 0.5) * (search.s / REFINE_OFFSETS)
    boxes = _Boxes(np.full(len(d), theta), np.zeros(len(d)), d, np.zeros(len(d)))
    bounds = search.point_values(boxes)
    try_plans(search, boxes, search.ranks, limit=REFINE_OFFSETS, bounds=bounds)


def centred_offsets(
    region: Region, angles: NDArray[Any], spacing: float, reach: float
) -> NDArray[np.float64]:
    """The offsets (from the shell's vertex mean, in ``[0, spacing)``) that put the first line
    ``reach`` inside the area's lowest extreme across the lines at each of ``angles``: lanes
    laid from the edge, as a person (or a brute force over angles) would."""
    verts = region.shell.vertices - region.centre
    normal = np.stack([-np.sin(angles), np.cos(angles)], axis=1)
    return np.mod((normal @ verts.T).min(axis=1) + reach, spacing)


def _edge_angles(region: Region, count: int) -> list[float]:
    """The directions of the shell's longest edges, distinct by 0.1 degree, at most ``count``."""
    v = region.shell.vertices
    e = np.roll(v, -1, axis=0) - v
    order = np.argsort(-np.hypot(e[:, 0], e[:, 1]))
    out: list[float] = []
    for i in order:
        a = math.atan2(e[i, 1], e[i, 0]) % math.pi
        if all(abs((a - b + math.pi / 2) % math.pi - math.pi / 2) > math.radians(0.1) for b in out):
            out.append(a)
        if len(out) >= count:
            break
    return out
