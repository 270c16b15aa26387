"""Certified minimum over (angle, offset) of a flown plan's cost, on any region: branch and
bound over boxes of layouts with sandwich lower bounds and plans as upper bounds."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...errors import InvalidParameterError
from ...geometry import Polygon
from ...geometry.region import Region, as_region
from ...models import check_spacing
from ..result import OptimizeResult, canonical
from . import last_pass
from .bands import RigidBoxes, band_stats
from .bounds import lower_bounds
from .boxes import Boxes as _Boxes
from .boxes import box_radius, initial_boxes, level_radius
from .branch import CUT_OFF, Limits, branch_and_bound, take_multipliers
from .centred import CENTRED_SEEDS, try_centred
from .cost import CoverCost
from .ends import HoleBoxes, hole_boxes
from .inside_bound import contour_edges, inside_box_bounds, path_floor
from .one_tree import MAX_LANES, POINT_TREE_STEPS, Multipliers
from .plans import polish, refine_offsets, try_edges
from .rigid import split_rings
from .sandwich import Level, Sandwich
from .walls import WallCache

__all__ = ["CoverSearch", "cover_optimum"]

#: Regions with more edges than this are searched with simplified sandwiches
#: (:class:`Sandwich` with a tolerance of :data:`SIMPLIFY_SPACING` spacings).
SIMPLIFY_EDGES = 256
SIMPLIFY_SPACING = 0.1
#: Work budget of a search: boxes bounded (and modelled) times the area's edges (about 0.25 s
#: per million on the project's machine): a count, not a time, so that plans do not depend on
#: the machine's load.
MAX_WORK = 4e6


#: Relative distance between a box's bound and the model at its centre at which a box of a
#: routed (non-boustrophedon) plan is not halved further (at least ``rtol``): 1e-2 while the
#: bound took the tour's moves as the lines' span only; the lanes' ends bring the model within
#: 1e-3 of the plans on Fields2Cover's fields.
RESOLVE_RTOL = 1e-3
#: Smallest box radius (relative to the spacing) of a routed plan's search.
RESOLVE_EPS = 1e-3
#: Whether a routed tour's moves are also bounded by the 1-tree of its lanes' ends, on areas
#: with holes (and :data:`TOUR_PLAIN`) of at most :data:`SIMPLIFY_EDGES` edges
#: (docs/mission_time.md, "The tour's 1-tree").
TOUR_BOUND = True
#: The largest box radius (in spacings) whose boxes get the 1-tree bound: wider boxes give
#: their lanes' ends wide ranges, where it adds little, and are halved anyway.
TOUR_EPS = 0.25
#: Whether the 1-tree bound is also computed on areas without holes (a concave area's routed
#: tour), in boxes of radius at most :data:`TOUR_PLAIN_EPS` spacings, in a search over every
#: angle with the brute-force sweep (``centred``; not a decomposition's cells): the lanes' ends
#: bounds take off the two largest charges for the path's free ends, which a notched side's
#: long moves make large (Fields2Cover's ``test_2_cell.json``: 101 m of 631 m of moves missed;
#: docs/mission_time.md, "The certificate on Fields2Cover's fields").
TOUR_PLAIN = True
TOUR_PLAIN_EPS = 0.125
#: ... on areas of at most this many edges: on the 100-vertex traced field (issue 17) the points'
#: 1-trees raised the lowest model, and with it the settling value, so more boxes were halved
#: and the work budget ran out: a plan 3.2 s longer, gap 50.1 -> 80.3 s, 1.37x the CPU.
TOUR_PLAIN_EDGES = 32
#: Whether a box taken out by its other bounds gets its 1-tree only after the search, and only
#: if it could lower the certificate's floor (:meth:`CoverSearch.settle_deferred`): the same
#: certificate for less CPU (docs/mission_time.md, "The 1-tree's CPU").
DEFER_TOUR = True
#: Whether a box's 1-tree is computed (and its steps go on) only until its bound passes the
#: value at which the search takes it out (``keep_at``) by :data:`STOP_SHARE` of the way to the
#: best plan, not until the best plan: a box taken out joins the floor with the bound reached
#: (any steps give a valid bound), not deferred (this replaces :data:`DEFER_TOUR`'s deferral;
#: docs/mission_time.md, "The 1-tree's CPU").
STOP_TOUR_AT_KEEP = True
#: That share: at 0 the certificate's floor came out up to 0.3 s lower on 8 of 30 random areas
#: (its lowest boxes stopped right at the take-out value); at 0.1 as at 1 on the areas tried.
STOP_SHARE = 0.1
#: Whether a box's 1-tree starts from its parent box's best multipliers (and its centre's
#: from its box's), not from zero.
WARM_TOUR = True
#: Whether a box's lines crossed by every rigid image of a hole count the hole's split of their
#: lanes (:func:`~.rigid._split_gaps`): a hole thinner than the box's radius, eroded away by its
#: outer set, still splits every such line (issue 16: random areas 9 and 92's slivers).
SPLIT_GAPS = True
#: What a keep-inside search decides by with the moves on top of its passes
#: (:mod:`~.inside_moves`): ``"certificate"`` the certificate's floor only (the same plans),
#: ``"boxes"`` also which boxes it keeps, ``"all"`` also the layouts' bounds (docs/mission_time.md,
#: "Keep-inside: moves on top of passes").
MOVES_DECIDE = "certificate"
#: The values :data:`MOVES_DECIDE` may take.
MOVES_DECIDE_VALUES = ("certificate", "boxes", "all")
#: Offset boxes at the first round of a fixed-angle search.
FIXED_OFFSETS = 64


def moves_decide() -> str:
    """:data:`MOVES_DECIDE`, read where a keep-inside search decides by it; a value not in
    :data:`MOVES_DECIDE_VALUES` raises :class:`InvalidParameterError` (rather than silently
    deciding as ``"boxes"``)."""
    if MOVES_DECIDE not in MOVES_DECIDE_VALUES:
        raise InvalidParameterError(
            f"search.MOVES_DECIDE must be one of {', '.join(map(repr, MOVES_DECIDE_VALUES))}, "
            f"got {MOVES_DECIDE!r}"
        )
    return MOVES_DECIDE


class CoverSearch:
    """The state of one search (see :func:`cover_optimum`)."""

    def __init__(
        self,
        region: Region,
        spacing: float,
        reach: float,
        cost: CoverCost,
        evaluate: Callable[[float, float], float] | None,
        boustrophedon: bool,
        keep_inside: bool = False,
        screen: Callable[[float, float, float], float] | None = None,
        outside: float | None = None,
    ) -> None:
        self.region, self.s, self.reach, self.cost = region, spacing, reach, cost
        self.screen = screen if evaluate is not None else None  # a floor of a layout's plan
        self.screened = 0  # layouts not planned: their floor (screen) is above the best plan
        self.evaluate, self.boustrophedon = evaluate, boustrophedon and not keep_inside
        # lanes cut to the area or to the area shrunk by half a spacing (keep_inside): the
        # bound takes the lines' chords (reach 0) through the shrunk inner set
        self.keep_inside = keep_inside
        self.shrink = spacing / 2 if keep_inside else 0.0
        self.contour = contour_edges(region, spacing, reach) if keep_inside else None
        self.floor = path_floor(region, reach) if keep_inside else 0.0
        self.band = 0.0 if keep_inside else reach
        simplify = len(region.edges) > SIMPLIFY_EDGES
        self.sandwich = Sandwich(region, SIMPLIFY_SPACING * spacing if simplify else 0.0)
        self.origin = region.centre
        self.radius = float(np.linalg.norm(region.shell.vertices - self.origin, axis=1).max())
        self.n_holes = len(region.holes)
        rings = [h.vertices for h in region.holes]
        self.hole_xy = np.concatenate(rings) if rings else np.zeros((0, 2))
        self.hole_start = np.concatenate([[0], np.cumsum([len(h) for h in rings])]).astype(np.int64)
        self.tol = 1e-9 * region.diameter
        # the holes eroded past the planner's eps: rigid cuts, split gaps (rigid.split_rings)
        self.split_rings = split_rings(
            rings, spacing, self.tol, region.shell.vertices, 0.0 if keep_inside else reach
        )
        # the lane-ends bound on a routed tour's moves (not with boundary or headland passes)
        self.ends = not self.boustrophedon and not keep_inside and cost.fixed == 0
        # the 1-tree bound on the moves (optimize/cover/one_tree.py)
        plain = TOUR_PLAIN and len(region.edges) <= TOUR_PLAIN_EDGES
        self.tour = TOUR_BOUND and (self.n_holes > 0 or plain) and not simplify
        self.tour_eps = (TOUR_EPS if self.n_holes else TOUR_PLAIN_EPS) * spacing
        self.walls = WallCache(outside)
        self.defer = DEFER_TOUR  # read by the branch and bound (optimize/cover/branch.py)
        self.skipped: NDArray[np.bool_] = np.zeros(0, dtype=bool)  # see box_bounds
        self.tight: NDArray[np.float64] = np.zeros(0)  # see box_bounds
        #: keep-inside's moves on top of its passes in the certificate (cover_optimum's
        #: ``moves_on_passes``)
        self.moves_on_passes = True
        # boxes taken out before their 1-tree, their bounds and multipliers (settle_deferred)
        self.deferred: list[tuple[_Boxes, NDArray[np.float64], Multipliers | None]] = []
        # the 1-tree's branching (nodes, window in cost units), where on (last_pass)
        self.branch: tuple[int, float] | None = None
        self.branch_left = 0  # boxes the last pass may still bound (last_pass.BRANCH_BUDGET)
        # the boxes retired below the discard value and the rest of the floor (branch.py)
        self.retired: list[Any] = []
        self.rest_floor = math.inf
        self.top_eps = 0.0
        self.best = (math.inf, 0.0, 0.0)
        self.plans = 0
        self.ruled_out = 0  # layouts not planned: their bound is above the best plan
        self.bound_evaluations = 0
        self.work = 0.0  # layouts bounded times the edges of the sandwich level used
        self.seen: set[tuple[float, float]] = set()
        self.model_min = math.inf  # the lowest model value at a layout seen
        self.points: list[NDArray[Any]] = []  # (value, theta, d) of every layout modelled
        self.ranks: NDArray[np.float64] = np.zeros(0)  # the last point values, for the plans
        self.centred_plans = 0  # plans of the final sweep of centred layouts (centred.py)
        self.centred_complete: bool | None = None  # whether the sweep planned every one below

    def work_spent(self, n_boxes: int) -> float:
        """The work after the next round of ``n_boxes`` boxes (8 layouts each at most: four
        halves, box and point): layouts bounded times the area's edges, or with simplified
        sandwiches (whose levels have from a tenth to one and a half times the area's edges)
        times the edges of the levels they used so far."""
        if self.sandwich.tolerance <= 0:
            edges = float(len(self.sandwich.exact.outer.xy))
            return (self.bound_evaluations + 8 * n_boxes) * edges
        per_layout = self.work / max(self.bound_evaluations, 1)
        return self.work + 8 * n_boxes * per_layout

    def boxes_within(self, max_work: float) -> int:
        """The most boxes a next round may have with :meth:`work_spent` within ``max_work``
        (0 if none): :meth:`work_spent` is linear in its boxes (box edges)."""
        per_box = self.work_spent(1) - self.work_spent(0)
        n = math.floor((max_work - self.work_spent(0)) / per_box) if per_box > 0 else 0
        n = max(n, 0)
        while n > 0 and self.work_spent(n) > max_work:  # rounding
            n -= 1
        return n

    def _inner_reach(self) -> float:
        return 0.0 if self.keep_inside else self.reach - 2 * self.tol

    def _hole_boxes(
        self, theta: NDArray[np.float64], d: NDArray[np.float64], grow: float
    ) -> HoleBoxes | None:
        """The holes' boxes of the lane-ends bound (``None`` where it does not apply)."""
        if not self.ends:
            return None
        grow = grow + 2 * self.tol
        return hole_boxes(self.hole_xy, self.hole_start, theta, d, self.origin, grow)

    def _tour_below(self, eps: float = 0.0) -> float | None:
        """Where the 1-tree bound is computed: layouts whose other bounds are below the best
        plan (the others are discarded anyway), in boxes of radius ``eps`` at most
        :data:`TOUR_EPS` spacings (:data:`TOUR_PLAIN_EPS` without holes); ``None`` without
        the lane-ends bounds."""
        if not (self.ends and self.tour) or eps > self.tour_eps:
            return None
        return self.best[0]

    def _walls(
        self, lv: Level, theta: NDArray[np.float64], d: NDArray[np.float64], eps: float = 0.0
    ) -> NDArray[np.float64] | None:
        """The walls inside ``lv``'s outer holes (and in its shells' pockets, with ``outside``)
        in the layouts' frames, where the 1-tree bound is computed."""
        if self._tour_below(eps) is None:
            return None
        return self.walls.frames(lv.outer, theta, d, self.origin)

    def k_range(self, eps: float) -> tuple[int, int]:
        far = self.radius + eps + self.reach
        return math.floor(-far / self.s) - 1, math.ceil(far / self.s) + 1

    def point_values(
        self,
        boxes: _Boxes,
        exact: bool = False,
        *,
        span_only: bool = False,
        multipliers: Multipliers | None = None,
        tour_keep: float | None = None,
    ) -> NDArray[np.float64]:
        """The bound at each box's centre with the region itself (a layout's own model); of
        the simplified region (:attr:`Sandwich.approximate`) unless ``exact``: the search only
        ranks and retires boxes by these, a plan's value is always exact. ``span_only``: the
        moves as the lines' span only (a second ranking, not recorded). ``multipliers``: the
        1-tree's starts (the boxes' own; not changed). ``tour_keep``: with real plans
        (``evaluate``), the 1-tree only at the layouts whose bound without it is below this (the
        branch and bound's: where the 1-tree could lower :attr:`model_min` or retire a box;
        elsewhere the value returned is the bound without it)."""
        if self.keep_inside:  # a relaxation of the plan even at one layout
            lv = self.sandwich.level(0.0, self.shrink)
        else:
            lv = self.sandwich.exact if exact else self.sandwich.approximate
        st = band_stats(
            lv.inner, lv.outer, boxes.theta, boxes.d, self.s, self.band, self.origin,
            self.k_range(0.0), self.n_holes, self.tol, inner_reach=self._inner_reach(),
        )  # fmt: skip
        self.bound_evaluations += len(boxes.theta)
        self.work += len(boxes.theta) * (len(lv.inner.xy) + len(lv.outer.xy)) / 2
        ends = None if span_only else self._hole_boxes(boxes.theta, boxes.d, 0.0)
        rank = None
        if self.keep_inside:  # the bound, and the value that ranks the layouts (inside_bound)
            decide = moves_decide() == "all" and self.moves_on_passes
            tight: list[NDArray[np.float64]] | None = [] if decide else None
            out, rank = self._inside(
                lv, st, 0.0, 0.0, boxes.theta, boxes.d, np.zeros(len(boxes.d)), ranking=True,
                tight=tight,
            )  # fmt: skip
            out = tight[0] if tight else out
        else:
            out = lower_bounds(
                st, lv, self.cost, self.s, boustrophedon=self.boustrophedon, ends=ends,
                runins=self.n_holes == 0,
            )  # fmt: skip
        if span_only:
            return out
        # the real plans are chosen by the model without the 1-tree, as before it (a routed
        # tour's cost is noisy between layouts: this ranking found the plans of 1158b53 again)
        self.ranks = out if rank is None else rank
        if self._tour_below() is not None:
            out = lower_bounds(
                st, lv, self.cost, self.s, boustrophedon=self.boustrophedon, ends=ends,
                runins=self.n_holes == 0, tour_below=self._tour_below(),
                walls=self._walls(lv, boxes.theta, boxes.d),
                tour_keep=None if tour_keep is None or self.evaluate is None else np.full(
                    len(boxes.theta), tour_keep
                ),
                multipliers=None if multipliers is None else Multipliers(
                    multipliers.values.copy(), multipliers.warm.copy(), multipliers.k0
                ),
                tour_steps=POINT_TREE_STEPS, tour_branch=self.branch,
            )  # fmt: skip
            if self.evaluate is None:  # the model is the plan
                self.ranks = out
        self.model_min = min(self.model_min, float(out.min(initial=math.inf)))
        self.points.append(np.stack([self.ranks, boxes.theta, boxes.d]))
        return out

    def box_bounds(
        self,
        boxes: _Boxes,
        keep_at: NDArray[np.float64] | None = None,
        tour_below: float | None = None,
        multipliers: Multipliers | None = None,
    ) -> NDArray[np.float64]:
        """A lower bound on the cost over each box: the sandwich at the radius that holds
        every rotation by ``delta`` about the origin and shift by ``eta`` across the lines.

        ``keep_at`` (per box): the 1-tree bound is computed only where the other bounds are
        below it (a box at or above it is taken out anyway); the boxes where it was skipped so
        but could still raise the bound (below the best plan) are marked in :attr:`skipped`.
        ``tour_below``: the 1-tree's stopping value instead of the best plan; ``multipliers``
        (per box): where its steps start, and where the best ones are kept. :attr:`tight`
        gets the bounds the certificate takes: with ``keep_inside`` higher (the moves on top
        of the passes, :mod:`~.inside_moves`) than those returned, by which the search decides
        (so it plans the same layouts), else the same."""
        eps = box_radius(boxes, self.radius)
        radius = level_radius(eps, self.top_eps)  # >= eps: a level of the sandwich
        out = np.empty(len(eps))
        self.tight = out
        self.skipped = np.zeros(len(eps), dtype=bool)
        for r in np.unique(radius):
            sel = radius == r
            lv = self.sandwich.level(float(r), self.shrink)
            reach_out = float(r) + self.sandwich.slack(float(r))
            # rigid hole cuts assume lanes spanning their bands: not with keep_inside
            rigid = None
            if not self.keep_inside:
                rigid = RigidBoxes(
                    self.hole_xy, self.hole_start, boxes.delta[sel], boxes.eta[sel],
                    self.split_rings,
                )  # fmt: skip
            st = band_stats(
                lv.inner, lv.outer, boxes.theta[sel], boxes.d[sel], self.s, self.band,
                self.origin, self.k_range(reach_out), self.n_holes, self.tol,
                inner_reach=self._inner_reach(), rigid=rigid, split=SPLIT_GAPS,
            )  # fmt: skip
            ends = self._hole_boxes(boxes.theta[sel], boxes.d[sel], reach_out)
            self.work += int(sel.sum()) * (len(lv.inner.xy) + len(lv.outer.xy)) / 2
            if self.keep_inside:
                cert: list[NDArray[np.float64]] | None = [] if self.moves_on_passes else None
                out[sel] = self._inside(
                    lv, st, float(r), reach_out, boxes.theta[sel], boxes.d[sel], boxes.delta[sel],
                    tight=cert,
                )  # fmt: skip
                if cert is not None:
                    if self.tight is out and moves_decide() == "certificate":
                        self.tight = out.copy()
                    self.tight[sel] = cert[0]
                continue
            below = self._tour_below(float(r))
            if below is not None and tour_below is not None:
                below = tour_below
            skipped = np.zeros(int(sel.sum()), dtype=bool)
            mult = None
            if multipliers is not None:
                mult = Multipliers(multipliers.values[sel], multipliers.warm[sel], multipliers.k0)
            # the 1-tree's steps stop just past the take-out value (STOP_TOUR_AT_KEEP): an
            # array per layout, which lower_bounds takes elementwise (its threshold and stop)
            stop: Any = below
            early = STOP_TOUR_AT_KEEP and below is not None and keep_at is not None
            if STOP_TOUR_AT_KEEP and below is not None and keep_at is not None:  # early, for mypy
                stop = np.minimum(keep_at[sel] + STOP_SHARE * (below - keep_at[sel]), below)
            out[sel] = lower_bounds(
                st, lv, self.cost, self.s, boustrophedon=self.boustrophedon, ends=ends,
                runins=self.n_holes == 0, tour_below=stop,
                walls=self._walls(lv, boxes.theta[sel], boxes.d[sel], float(r)),
                tour_keep=None if keep_at is None or early else keep_at[sel],
                tour_skipped=skipped, multipliers=mult, tour_branch=self.branch,
            )  # fmt: skip
            self.skipped[sel] = skipped
            if multipliers is not None and mult is not None:
                multipliers.values[sel], multipliers.warm[sel] = mult.values, mult.warm
        self.bound_evaluations += len(eps)
        return out

    def multipliers(self, n_boxes: int) -> Multipliers | None:
        """Cold multipliers for ``n_boxes`` boxes (:data:`WARM_TOUR`), over every line a box's
        sandwich may reach; ``None`` without the 1-tree or over more than twice
        :data:`~.one_tree.MAX_LANES` lines (the 1-tree's steps then start at 0)."""
        if not (WARM_TOUR and self.ends and self.tour):
            return None
        k_lo, k_hi = self.k_range(2 * self.top_eps + self.reach + self.s)
        if k_hi - k_lo + 1 > 2 * MAX_LANES:  # wide areas: layouts of few lanes are rare
            return None
        values = np.zeros((n_boxes, k_hi - k_lo + 1, 3, 2))
        return Multipliers(values, np.zeros(n_boxes, dtype=bool), k_lo)

    def deferred_min(self) -> float:
        """The lowest bound (without the 1-tree) of a box taken out before its 1-tree."""
        return min((float(b.min()) for _, b, _ in self.deferred), default=math.inf)

    def settle_deferred(self, lower: float) -> float:
        """The certificate's lower bound ``min(lower, bounds of the deferred boxes)``, each
        deferred box's bound with its 1-tree, computed only for the boxes whose bound without
        it is below ``lower`` (the others cannot lower the minimum), its steps stopping once
        the box's bound reaches ``lower``: the minimum a 1-tree at every box would give."""
        if not self.deferred:
            return lower
        boxes = _Boxes(*(np.concatenate([b[f] for b, _, _ in self.deferred]) for f in range(4)))
        base = np.concatenate([v for _, v, _ in self.deferred])
        mult = None
        if all(m is not None for _, _, m in self.deferred):
            parts = [m for _, _, m in self.deferred if m is not None]
            mult = Multipliers(
                np.concatenate([m.values for m in parts]),
                np.concatenate([m.warm for m in parts]),
                parts[0].k0,
            )
        self.deferred = []
        sel = base < lower
        if not sel.any():
            return lower
        work, evaluations = self.work, self.bound_evaluations  # not the search's work
        mult = take_multipliers(mult, sel)
        bounds = self.box_bounds(boxes.take(sel), tour_below=lower, multipliers=mult)
        self.work, self.bound_evaluations = work, evaluations
        return min(lower, float(bounds.min()))

    def settle_branched(self, lower: float, value: float, rtol: float) -> float:
        """The certificate's lower bound ``lower`` raised by the last pass over the boxes
        retired below the discard value of the best plan ``value``
        (:func:`~.last_pass.settle_branched`)."""
        return last_pass.settle_branched(self, lower, value, rtol)

    def _inside(self, lv: Any, st: Any, *args: Any, **kw: Any) -> NDArray[np.float64]:
        """The keep-inside bound (:func:`~.inside_bound.inside_box_bounds`)."""
        return inside_box_bounds(self, lv, st, *args, **kw)

    def counts(self) -> dict[str, Any]:
        """The plans made, the layouts ruled out, the brute-force sweep's plans and whether it
        planned every layout below the best plan (where it ran): a result's ``info``."""
        out: dict[str, Any] = {
            "plans": self.plans,
            "ruled_out": self.ruled_out,
            "screened": self.screened,
            "centred_plans": self.centred_plans,
        }
        if self.centred_complete is not None:
            out["centred_complete"] = self.centred_complete
        return out


def _initial(search: CoverSearch, n_angles: int, angle: float | None) -> _Boxes:
    return initial_boxes(search.s, search.radius, n_angles, angle, FIXED_OFFSETS)


def cover_optimum(
    region: Region | Polygon,
    spacing: float,
    cost: CoverCost,
    evaluate: Callable[[float, float], float] | None = None,
    *,
    reach: float | None = None,
    boustrophedon: bool | None = None,
    angle: float | None = None,
    keep_inside: bool = False,
    rtol: float = 1e-3,
    n_angles: int = 90,
    min_eps: float | None = None,
    max_work: float = MAX_WORK,
    max_seconds: float | None = None,
    progress: Callable[[float], None] | None = None,
    centred: bool = True,
    cutoff: float | None = None,
    screen: Callable[[float, float, float], float] | None = None,
    moves_on_passes: bool = True,
    outside: float | None = None,
    later: list[Callable[[], OptimizeResult]] | None = None,
) -> OptimizeResult:
    """The layout ``(angle, offset)`` whose plan has the least ``cost``, with a certificate.

    Branch and bound over boxes of layouts. For a box of angles ``theta +- delta`` and offsets
    ``d +- eta`` every layout's grid is the centre's grid after a rotation by at most ``delta``
    about the region's centre and a shift by at most ``eta``, so (moving the area instead of
    the grid) its plan is the centre grid's plan over an area between the region eroded and
    dilated by ``eps = delta * radius + eta`` (:class:`Sandwich`); :func:`lower_bounds` bounds
    the cost of every such plan from below. The plans at the centres of the most promising
    boxes are evaluated by ``evaluate(angle, offset) -> cost`` (the real planner: upper bounds);
    a box whose bound is within ``rtol`` of the best plan is discarded, the others are halved,
    until none is left or the radius falls below ``min_eps`` (default ``1e-6`` of the
    spacing), the boxes bounded times the area's edges exceed ``max_work`` or ``max_seconds``
    passed.

    Args:
        region: the area (plan units), convex or not, with holes.
        spacing: distance between lines; ``reach``: half-width of a lane's band (default
            ``spacing / 2``).
        cost: what is minimised (:class:`CoverCost`).
        evaluate: the cost of the plan of one layout; ``None``: the bound at the layout
            itself (then the certificate is about that model).
        angle: search only this angle (radians): the best offset at a fixed angle.
        keep_inside: the plans keep inside the area (:mod:`boustro.plan.inside`): their lanes
            stop at the boundary or half a spacing inside it, so the bound takes each line's
            chord through the inner set eroded by half a spacing more, with no boustrophedon
            moves and no rigid hole cuts.
        boustrophedon: whether plans fly one lane per line in boustrophedon order (the convex
            planner); default: the region is a convex polygon without holes.
        centred: whether the layouts of a 1-degree brute force of the angle are planned after
            the search where their bound is below its best plan (:func:`~.centred.try_centred`;
            a search over every angle with real plans, not keep-inside): its plan is then never
            longer than that brute force's. ``False`` where that guarantee is not needed (a
            decomposition's cells: a decomposed plan is kept only when it beats the one grid's).
        cutoff: stop as soon as no layout can cost less than this (the lowest bound of every
            box reached it): then ``info["stopped"]`` says so, ``info["cut_off"]`` is true, the
            plan is the best found so far and ``lower_bound`` is at least ``cutoff`` (a
            decomposition's cell whose candidate cannot beat the one grid any more).
        screen: ``screen(angle, offset, best)``, a lower bound of ``evaluate(angle, offset)``
            cheaper than it (a ``keep_inside`` plan's lanes and passes with a floor of its
            moves, :func:`boustro.plan.region_floor.screen_floor`; given the best plan's
            cost ``best``, it may return a cheaper floor already above it): a layout whose floor
            is above the best plan is not planned but counts as tried (``info["screened"]``),
            so the search finds the same plan.
        moves_on_passes: with ``keep_inside``, the certificate's floor counts the moves
            between lanes on top of the boundary passes (:mod:`~.inside_moves`; the search
            decides as without). ``False`` for a decomposition's cells, whose floor decides
            which candidates are planned (a screen: a cell planned alone counts passes along
            its cut edges that the whole plan never flies), so they decide as before; nor do
            they count margin 0's passes or the stretches near the lanes at the layouts
            (:data:`~.inside_bound.CUT_PASSES`, :data:`~.inside_bound.NEAR_AT_LAYOUTS`).
        outside: how far from the area any point of any plan ``evaluate`` returns may lie
            (its lanes, run-ins, connecting moves and passes; plan units), if known: the
            1-tree's moves then also go round the shell's pockets farther than that from it
            (:func:`~.walls.shell_walls`; docs/mission_time.md, "Walls outside the shell").
            ``None``: not known (a vehicle's turns, a decomposition's cells), no such walls.
        later: with ``centred=False`` (a decomposition's cells), a list: the plans made after
            the branch and bound (:func:`~.plans.polish`, :func:`~.plans.refine_offsets`) are
            left for later. The result returned is then the search's before them (its
            ``lower_bound`` that of the result, ``info["plans_later"]`` true) and a function
            that makes them and returns the result this call makes without ``later`` is
            appended to the list (:func:`_finished`); nothing is appended where they would not
            run (a search cut off, no plan). A decomposition's candidate whose cells' floor
            rules it out never needs them.

    Returns:
        an :class:`OptimizeResult` with ``fitness`` = the best plan's cost (minimised),
        ``method = "certified-cover"``, and ``info``: ``lower_bound`` (no layout's plan costs
        less), ``gap``, ``certified`` (``gap <= rtol * cost``), ``objective``, ``plans``,
        ``boxes``, ``rounds``, ``converged`` and, when not, ``stopped`` (why).
    """
    r = as_region(region)
    s = check_spacing(spacing, extent=r.diameter)
    reach = s / 2 if reach is None else float(reach)
    if not (0 < reach < math.inf):
        raise InvalidParameterError(f"reach must be > 0, got {reach}")
    if boustrophedon is None:
        boustrophedon = not r.holes and r.shell.is_convex
    search = CoverSearch(
        r, s, reach, cost, evaluate, boustrophedon, keep_inside, screen, outside=outside
    )
    search.moves_on_passes = moves_on_passes
    boustrophedon = search.boustrophedon
    if not centred:  # a decomposition's cell: the 1-tree without holes cost more than it gave
        search.tour = search.tour and search.n_holes > 0
    if min_eps is None:
        min_eps = (1e-6 if boustrophedon else RESOLVE_EPS) * s
    resolve = rtol if boustrophedon else max(rtol, RESOLVE_RTOL)
    t0 = time.perf_counter()
    if angle is None:
        try_edges(search)
        if evaluate is not None and not keep_inside:
            try_centred(search, CENTRED_SEEDS)
    else:
        angle = float(angle) % math.pi
        if not keep_inside:
            try_edges(search, [angle])
    boxes = _initial(search, n_angles, angle)
    search.top_eps = float(box_radius(boxes, search.radius).max())
    limits = Limits(rtol, resolve, min_eps, max_work, max_seconds, t0, cutoff)
    floor, rounds, stopped = branch_and_bound(search, boxes, limits, progress)
    cut_off = stopped == CUT_OFF
    found = math.isfinite(search.best[0]) and not cut_off
    improve = not boustrophedon and evaluate is not None and found
    if later is not None and improve and not centred:
        lower = search.settle_deferred(min(floor, search.best[0]))
        first = _result(search, lower, rounds, stopped, rtol, t0, plans_later=True)
        later.append(lambda: _finished(search, floor, lower, rounds, stopped, rtol, first.seconds))
        return first
    if improve:
        polish(search)
        refine_offsets(search)
    if centred and angle is None and evaluate is not None and not keep_inside and found:
        try_centred(search)
    value = search.best[0]
    if not math.isfinite(value):
        raise InvalidParameterError("no layout of this spacing has a lane over the area")
    lower = min(floor, value)
    if not cut_off and centred:  # not a decomposition's cells (their floors screen plans)
        # before the deferred boxes join the floor (settle_deferred empties their list): the
        # pass raises the other boxes' part of it only
        lower = search.settle_branched(lower, value, rtol)
    if not cut_off:  # cut off: the floor counts the deferred boxes' bounds (without 1-trees)
        lower = search.settle_deferred(lower)
    return _result(search, lower, rounds, stopped, rtol, t0)


def _finished(
    search: CoverSearch,
    floor: float,
    settled: float,
    rounds: int,
    stopped: str,
    rtol: float,
    seconds: float,
) -> OptimizeResult:
    """The plans a search with ``later`` left (:func:`cover_optimum`), then its result (its
    ``seconds`` those of the search, ``seconds``, and of the plans):
    ``settled`` is ``search.settle_deferred(min(floor, best plan before them))``, the lower
    bound :func:`cover_optimum` takes, ``search.settle_deferred(min(floor, best plan))``,
    wherever the best plan after them is not below ``floor`` (the same argument, and the
    deferred boxes' bounds do not depend on the plans). A plan below ``floor`` lowers it: then
    ``min(settled, plan)``, also a lower bound, though not always the value the search without
    ``later`` settles (``floor`` bounds the layouts of the boxes taken out with their bounds,
    not of the deferred boxes, whose layouts only ``settle_deferred`` bounds)."""
    t0 = time.perf_counter() - seconds
    before = min(floor, search.best[0])
    polish(search)
    refine_offsets(search)
    value = search.best[0]
    lower = settled if min(floor, value) == before else min(settled, value)
    return _result(search, lower, rounds, stopped, rtol, t0)


def _result(
    search: CoverSearch,
    lower: float,
    rounds: int,
    stopped: str,
    rtol: float,
    t0: float,
    plans_later: bool = False,
) -> OptimizeResult:
    """:func:`cover_optimum`'s result: the search's best plan, the lower bound ``lower``."""
    value, theta, d = search.best
    cut_off = stopped == CUT_OFF
    gap = max(0.0, value - lower)
    angle, offset = canonical(theta, d, search.s)
    return OptimizeResult(
        angle=angle,
        offset=offset,
        fitness=value,
        spacing=search.s,
        method="certified-cover",
        evaluations=search.bound_evaluations,
        seconds=time.perf_counter() - t0,
        info={
            "objective": search.cost.name,
            "lower_bound": lower,
            "gap": gap,
            "certified": gap <= rtol * abs(value) + 1e-12,
            "rtol": rtol,
            **search.counts(),
            "rounds": rounds,
            "cut_off": cut_off,
            "converged": not stopped,
            **({"stopped": stopped} if stopped else {}),
            **({"plans_later": True} if plans_later else {}),
        },
    )
