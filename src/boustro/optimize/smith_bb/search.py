"""The certified maximum of Eq. 1 over (angle, offset) at scale: a branch and bound over boxes
of layouts whose cost per box is ``O(n + lines)`` (``method="certified-bb"``).

For a box ``theta +- delta``, ``d +- eta`` every layout's lines are the box centre's lines over
a rigid image ``S`` of the polygon whose points moved by at most ``eps = delta R + eta``, so
``erosion(eps) ⊆ S ⊆ dilation(eps)`` (the cover search's :class:`Sandwich` and boxes). Each
line's chord lies between the inner and the outer set's chord and the counted lines between
theirs, which bounds Eq. 1 over the box (:mod:`.kernel`). Exact values at the box centres, each
polished over the offset within its piece (where Eq. 1 is concave), are the incumbents; a box
whose bound is within ``tol`` of the best is discarded, the others are halved. docs:
``docs/global_optimum.md``, "Certified at scale".
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..._torch import torch
from ...errors import InvalidParameterError, NoTransectError
from ...geometry import Polygon, halfplanes
from ...geometry.region import Region
from ...objectives import SmithFitness
from ...scoring import as_polygon
from ..cover.boxes import (
    Boxes,
    box_radius,
    initial_boxes,
    level_radius,
    split_boxes,
    split_parents,
)
from ..cover.sandwich import Sandwich
from ..cover.search import SIMPLIFY_EDGES, SIMPLIFY_SPACING
from ..exact import best_offset
from ..methods import register_method
from ..problem import _check_narrower, _progress_bar, evaluate_pairs
from ..result import OptimizeResult, canonical
from .kernel import box_bounds, eq1_at_angle, eq1_values

__all__ = ["DEFAULT_TOL", "MAX_WORK", "smith_bb", "solve"]

#: Default certified gap (absolute, on Eq. 1, which lies in ``[b/2, a + b]``).
DEFAULT_TOL = 1e-4
#: Work budget: boxes bounded times ``edges + BOX_OVERHEAD`` (a count, not a time, so that
#: results do not depend on the machine's load). On the project's machine a box costs about
#: ``0.022 us x (edges + 500)``, so the budget is about 2-3 s of CPU. Nearly circular areas, the
#: search's worst case, spend it before the default ``tol`` (regular 100- to 2000-gons stop at
#: gaps 2e-4 to 1e-3, reported); every other area measured converges far below it.
MAX_WORK = 1e8
#: A search allowed to extend its budget (``solve(extend=...)``, the region's default) doubles it
#: while the gap at the budget is at most this share of the gap at half of it (it shrank by a
#: tenth at least; a search whose bound stalls, e.g. a comb's lines along edges, stops).
SHRINK = 0.9
#: A box's cost that does not grow with the edges, in edge units (measured: regular 100- and
#: 2000-gons, 13 and 55 us a box).
BOX_OVERHEAD = 500
#: Boxes smaller than this (normalised frame) are not split (float64 cannot resolve them).
MIN_EPS = 1e-12
#: Box centres polished over the offset per round (the best new ones).
POLISH_PER_ROUND = 2
#: Zooms of a polish; each evaluates :data:`ZOOM_POINTS` offsets over two steps of the last.
POLISH_ZOOMS = 7
ZOOM_POINTS = 17
#: Angles of the first incumbents (:meth:`_Search.seed`), per first box angle.
SEED_ANGLES = 4
#: Boxes halved per round at least (those of the highest bounds), or this share of the pool.
BATCH = 256
BATCH_SHARE = 0.25
#: Layouts kept as candidates for the final exact scoring (the library's model).
CANDIDATES = 8
#: The exact per-angle closed form (``best_offset``, O(n^2)) is tried at the best angles of
#: polygons up to this many vertices.
CLOSED_FORM_VERTICES = 300


class _Search:
    """The state of one search, in the normalised frame of ``poly``."""

    def __init__(self, poly: Polygon, spacing: float, a: float, b: float) -> None:
        self.poly, self.frame = poly, poly.frame
        self.v = self.frame.to_normalised(poly.vertices)
        self.s, self.a, self.b = spacing / self.frame.scale, a, b
        self.xy = np.concatenate([self.v, np.roll(self.v, -1, axis=0)], axis=1)
        self.radius = float(np.hypot(self.v[:, 0], self.v[:, 1]).max())
        simplify = len(poly) > SIMPLIFY_EDGES
        # built in the polygon's units (no second validation of its vertices), read normalised
        self.sandwich = Sandwich(Region(poly), SIMPLIFY_SPACING * spacing if simplify else 0.0)
        self.levels: dict[float, tuple[NDArray[np.float64], NDArray[np.float64]]] = {}
        self.top_eps = 0.0
        self.best = -math.inf
        self.candidates: list[tuple[float, float, float]] = []
        self.polished: set[tuple[float, float]] = set()
        self.bounded = 0
        self.evaluations = 0

    def level(self, eps: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The inner and outer edges (normalised) of the sandwich of radius ``eps``."""
        if eps not in self.levels:
            lv = self.sandwich.level(eps * self.frame.scale)
            c = np.tile(self.frame.centre, 2)
            self.levels[eps] = tuple(  # type: ignore[assignment]
                (es.xy - c) / self.frame.scale for es in (lv.inner, lv.outer)
            )
        return self.levels[eps]

    def bounds(self, boxes: Boxes) -> NDArray[np.float64]:
        """An upper bound of Eq. 1 over each box (the sandwich of the smallest level radius
        that holds the box's ``eps``)."""
        radius = level_radius(box_radius(boxes, self.radius), self.top_eps)
        out = np.empty(len(radius))
        for r in np.unique(radius):
            sel = radius == r
            inner, outer = self.level(float(r))
            out[sel] = box_bounds(
                inner, outer, boxes.theta[sel], boxes.d[sel], self.s, self.a, self.b
            )
        self.bounded += len(radius)
        return out

    def values(self, theta: NDArray[np.float64], d: NDArray[np.float64]) -> NDArray[np.float64]:
        """Eq. 1 at the layouts (exact chords of the polygon)."""
        self.evaluations += len(theta)
        return eq1_values(self.xy, theta, d, self.s, self.a, self.b)

    def at_angle(self, theta: float, offsets: NDArray[np.float64]) -> NDArray[np.float64]:
        """Eq. 1 at one angle and many offsets (the polygon's two chains interpolated)."""
        self.evaluations += len(offsets)
        return eq1_at_angle(self.v, theta, offsets, self.s, self.a, self.b)

    def offer(self, value: float, theta: float, d: float) -> None:
        """A layout and its value: the incumbent, and a candidate for the final scoring."""
        self.best = max(self.best, value)
        if any(abs(t - theta) < 1e-15 and abs(e - d) < 1e-15 for _, t, e in self.candidates):
            return
        self.candidates.append((value, theta, d))
        self.candidates.sort(reverse=True)
        del self.candidates[CANDIDATES:]

    def pieces(self, theta: float, d: float, extremes: bool) -> list[tuple[float, float]]:
        """Pieces of the offset circle at ``theta`` (between consecutive offsets at which a line
        passes a vertex; Eq. 1 is concave in the offset on each): the one holding ``d`` and its
        neighbours, or with ``extremes`` those next to the offsets at which the extreme lines
        graze the extreme vertices (narrow pieces there hold peaks: both extreme lines just
        missing the polygon)."""
        h = self.v[:, 1] * math.cos(theta) - self.v[:, 0] * math.sin(theta)
        r = np.sort(np.mod(h, self.s))
        r = np.concatenate([r[-2:] - self.s, r, r[:2] + self.s])
        at = np.mod([h.max(), h.min()] if extremes else [d], self.s)
        js: set[int] = set()
        for j in np.searchsorted(r, at, side="right") - 1:
            js.update((int(j) - 1, int(j), int(j) + 1))
        shift = d - d % self.s
        return [(float(r[i]) + shift, float(r[i + 1]) + shift) for i in sorted(js)]

    def polish(self, theta: float, d: float, extremes: bool = False) -> None:
        """The best offset at ``theta`` within the :meth:`pieces` of ``d``: a scan and zooms
        (Eq. 1 is concave on a piece), and each piece's ends nudged inside (a line grazing a
        vertex)."""
        for lo, hi in self.pieces(theta, d, extremes):
            key = (round(theta, 12), round(lo / self.s, 9))
            if key not in self.polished:
                self.polished.add(key)
                self._polish_piece(theta, lo, hi)

    def _polish_piece(self, theta: float, lo: float, hi: float) -> None:
        width = hi - lo
        if not width > 0:
            return
        nudge = max(1e-9 * width, 1e-13)
        ends = np.array([lo + nudge, hi - nudge])
        offsets = lo + (np.arange(ZOOM_POINTS, dtype=np.float64) + 0.5) * (width / ZOOM_POINTS)
        step = width / ZOOM_POINTS
        best_v, best_d = -math.inf, 0.5 * (lo + hi)
        for _ in range(POLISH_ZOOMS):
            vals = self.at_angle(theta, offsets)
            k = int(np.argmax(vals))
            if vals[k] > best_v:
                best_v, best_d = float(vals[k]), float(offsets[k])
            near = best_d + np.linspace(-step, step, ZOOM_POINTS, dtype=np.float64)
            offsets = np.clip(near, ends[0], ends[1]).astype(np.float64)
            step *= 2.0 / (ZOOM_POINTS - 1)
        end_vals = self.at_angle(theta, ends)
        for value, off in ((best_v, best_d), *zip(end_vals.tolist(), ends.tolist(), strict=True)):
            if math.isfinite(value):
                self.offer(value, theta, off)

    def seed(self, n_angles: int) -> None:
        """First incumbents: at ``n_angles`` angles over ``[0, pi)``, the offsets at which the
        extreme lines just graze the polygon's extreme vertices (counted or not, where Eq. 1
        often peaks), then the best of them polished."""
        theta = np.arange(n_angles) * (math.pi / n_angles)
        h = np.outer(np.cos(theta), self.v[:, 1]) - np.outer(np.sin(theta), self.v[:, 0])
        nudge = 1e-9 * self.s
        ends = [h.max(axis=1) - nudge, h.max(axis=1) + nudge]
        ends += [h.min(axis=1) + nudge, h.min(axis=1) - nudge]
        d = np.mod(np.concatenate(ends), self.s)
        thetas = np.tile(theta, 4)
        self.polish_best(Boxes(thetas, thetas * 0, d, d * 0), self.values(thetas, d), False)

    def polish_best(self, boxes: Boxes, score: NDArray[np.float64], extremes: bool) -> None:
        """Polish the :data:`POLISH_PER_ROUND` boxes of the highest ``score`` whose bound
        (``score`` or not) could still beat the best layout."""
        for i in np.argsort(-score)[:POLISH_PER_ROUND]:
            if math.isfinite(score[i]):
                self.polish(float(boxes.theta[i]), float(boxes.d[i]), extremes)


def _weights(a: float, b: float, fitness: Any) -> tuple[float, float]:
    if fitness is not None:
        if type(fitness) is not SmithFitness:
            raise InvalidParameterError(
                "the certified-bb optimiser maximises Eq. 1 (a SmithFitness), got "
                f"{type(fitness).__name__}"
            )
        if getattr(fitness, "statistics", "weighted") != "weighted":
            raise InvalidParameterError(
                "the certified-bb optimiser maximises Eq. 1 with weighted statistics, got "
                f"statistics={fitness.statistics!r} (use the grid or another method)"
            )
        return float(fitness.a), float(fitness.b)
    SmithFitness(a=a, b=b)  # validates a, b >= 0 and finite
    return float(a), float(b)


def _check(name: str, value: Any, low: float) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be a number, got {value!r}") from None
    if not (x >= low and math.isfinite(x)):
        raise InvalidParameterError(f"{name} must be a finite number >= {low:g}, got {value!r}")
    return x


def _check_angles(n_angles: Any) -> int:
    """``n_angles`` as an int, or :class:`InvalidParameterError` (not a whole number >= 1)."""
    ok = isinstance(n_angles, (int, float, np.integer, np.floating)) and not isinstance(
        n_angles, bool
    )
    if not ok or not math.isfinite(n_angles) or int(n_angles) != n_angles or n_angles < 1:
        raise InvalidParameterError(f"n_angles must be an integer >= 1, got {n_angles!r}")
    return int(n_angles)


def _evaluate(search: _Search, boxes: Boxes) -> NDArray[np.float64]:
    """The boxes' bounds; their centres' values offered, the best centres and the most
    promising boxes polished (a peak can be narrower than a box)."""
    bounds = search.bounds(boxes)
    values = search.values(boxes.theta, boxes.d)
    k = int(np.argmax(values))
    if math.isfinite(values[k]):
        search.offer(float(values[k]), float(boxes.theta[k]), float(boxes.d[k]))
    search.polish_best(boxes, values, extremes=False)
    search.polish_best(boxes, np.where(bounds > search.best, bounds, -np.inf), extremes=True)
    return bounds


def _run(
    search: _Search, boxes: Boxes, tol: float, max_work: float, bar: Any, extend: float = 1.0
) -> tuple[float, int, str]:
    """Best first, in batches: halve the boxes of the highest bounds (:data:`BATCH`, or a
    :data:`BATCH_SHARE` of the pool if more), discard those within ``tol`` of the best layout,
    until no box is left or a limit is reached: ``(the largest bound of a box taken out,
    rounds, why it stopped early or "")``. With ``extend > 1`` the budget doubles, up to
    ``extend`` times ``max_work``, while the gap shrinks: each time the work reaches the
    budget, if the gap is at most :data:`SHRINK` times the gap at half of it."""
    closed, rounds, stopped, shown = -math.inf, 0, "", 0
    edges = len(search.xy) + BOX_OVERHEAD
    limit, half_gap = max_work, math.inf
    bounds = _evaluate(search, boxes)
    while True:
        keep = bounds > search.best + tol
        if (~keep).any():
            closed = max(closed, float(bounds[~keep].max()))
        boxes, bounds = boxes.take(keep), bounds[keep]
        if bar is not None and math.isfinite(search.best):
            top = max(closed, float(bounds.max()) if len(bounds) else -math.inf)
            done = int(100 * min(1.0, tol / max(top - search.best, tol)))
            bar.update(max(0, done - shown))
            shown = max(shown, done)
        if not len(bounds):
            break
        fine = box_radius(boxes, search.radius) <= MIN_EPS
        if fine.any():
            closed = max(closed, float(bounds[fine].max()))
            stopped = "the boxes reached the smallest radius float64 resolves"
            boxes, bounds = boxes.take(~fine), bounds[~fine]
            if not len(bounds):
                break
        work = (search.bounded + 4 * BATCH) * edges
        if work > 0.5 * limit and half_gap == math.inf:
            half_gap = max(closed, float(bounds.max())) - search.best
        if work > limit:
            gap = max(closed, float(bounds.max())) - search.best
            shrank = math.isfinite(gap) and gap <= SHRINK * half_gap  # no layout yet: stop
            if 2 * limit <= extend * max_work * (1 + 1e-12) and shrank:
                limit, half_gap = 2 * limit, gap  # the gap at half of the doubled budget
            else:
                closed = max(closed, float(bounds.max()))
                stopped = f"the work budget ({limit:.0e} box edges) was spent"
                break
        rounds += 1
        size = max(BATCH, int(BATCH_SHARE * len(bounds)))
        order = np.argsort(-bounds)
        chosen, rest = order[:size], order[size:]
        parents = boxes.take(chosen)
        children = split_boxes(parents, search.radius)
        # a parent's bound holds on each child (its subset): the least of the two is a bound
        up = bounds[chosen][split_parents(parents, search.radius)]
        child_bounds = np.minimum(_evaluate(search, children), up)
        boxes = Boxes(*(np.concatenate(p) for p in zip(boxes.take(rest), children, strict=True)))
        bounds = np.concatenate([bounds[rest], child_bounds])
    return closed, rounds, stopped


def _final(search: _Search) -> tuple[float, float, float]:
    """``(fitness, theta, d)``: the candidates scored by the library's exact model (which also
    counts a line lying along an edge), with the closed-form best offset at the best angles of
    a small polygon; the best wins."""
    cands = list(search.candidates)
    if not cands:  # no layout with a transect was seen
        return -math.inf, 0.0, 0.0
    fit = SmithFitness(a=search.a, b=search.b)
    if len(search.v) <= CLOSED_FORM_VERTICES:
        for theta in {c[1] for c in cands[:2]}:
            d, _ = best_offset(search.v, search.s, theta, fitness=fit)
            cands.append((-math.inf, theta, d))
    values = evaluate_pairs(
        halfplanes(search.poly),  # the library's own normalised frame (its Eq. 1, exactly)
        torch.tensor([c[1] for c in cands], dtype=torch.float64),
        torch.tensor([c[2] for c in cands], dtype=torch.float64),
        search.s,
        fitness=fit,
    )
    k = int(torch.argmax(values))
    return float(values[k]), cands[k][1], cands[k][2]


@register_method("certified-bb")
def smith_bb(
    polygon: Polygon | ArrayLike,
    spacing: float,
    *,
    fitness: SmithFitness | None = None,
    a: float = 0.5,
    b: float = 0.5,
    tol: float = DEFAULT_TOL,
    n_angles: int = 90,
    max_work: float | None = None,
    progress: bool | None = False,
) -> OptimizeResult:
    """The maximum of Eq. 1 over every angle and offset with a certified upper bound, at a
    cost per box of ``O(n + lines)`` (no event enumeration): for polygons with many vertices.

    Args:
        polygon: convex polygon, user units.
        spacing: transect spacing, user units, > 0.
        fitness: a :class:`~boustro.objectives.SmithFitness` (default ``a = b = 0.5``).
        a, b: weights of Eq. 1 when ``fitness`` is not given.
        tol: the gap to certify (absolute, on Eq. 1); at least ``1e-9``.
        n_angles: angles of the first boxes over ``[0, pi)``.
        max_work: budget of boxes bounded times ``edges +`` :data:`BOX_OVERHEAD` (default
            :data:`MAX_WORK`, times ``DEFAULT_TOL / tol`` for a tighter ``tol``: the boxes grow
            like ``1 / tol``); when spent the bound is still valid,
            the gap may exceed ``tol`` (``info["converged"]`` False).
        progress: a bar on stderr (``None``: when stderr is a terminal).

    Returns:
        :class:`OptimizeResult` with ``method="certified-bb"``, ``fitness`` the exact value of
        the returned layout, ``upper_bound`` >= Eq. 1 at every layout, and ``info``: ``gap``,
        ``converged`` (``gap <= tol``), ``tol``, ``boxes`` (bounded), ``rounds``, ``stopped``.

    >>> r = smith_bb([(0, 0), (2, 0), (2, 1), (0, 1)], 0.25, tol=1e-4)
    >>> round(r.fitness, 4), r.gap <= 1e-4
    (0.9505, True)
    """
    t0 = time.perf_counter()
    poly = as_polygon(polygon).require_convex("the certified-bb optimiser")
    spacing = _check_narrower(poly, spacing)
    a, b = _weights(a, b, fitness)
    tol = _check("tol", tol, 1e-9)
    if max_work is None:
        max_work = MAX_WORK * max(1.0, DEFAULT_TOL / tol)
    max_work = _check("max_work", max_work, 0.0)
    n_angles = _check_angles(n_angles)
    search = _Search(poly, spacing, a, b)
    boxes = initial_boxes(search.s, search.radius, int(n_angles))
    search.seed(SEED_ANGLES * int(n_angles))
    return solve(search, boxes, spacing, tol, max_work, progress, t0, "polygon", _final)


def solve(
    search: Any,
    boxes: Boxes,
    spacing: float,
    tol: float,
    max_work: float,
    progress: bool | None,
    t0: float,
    what: str,
    final: Any,
    extend: float = 1.0,
    **info: Any,
) -> OptimizeResult:
    """Run a seeded search (:class:`_Search` or the region's) over its first ``boxes`` to
    ``tol`` or ``max_work`` and return its certified result; ``final(search)`` gives the
    returned ``(value, theta, d)``, ``what`` names the area in the error of no transect,
    ``info`` is added to the result's; ``extend``: as :func:`_run`'s."""
    search.top_eps = float(box_radius(boxes, search.radius).max())
    bar = _progress_bar(100, progress, "certified-bb", unit="%")
    try:
        with np.errstate(all="ignore"):
            closed, rounds, stopped = _run(search, boxes, tol, max_work, bar, extend)
    finally:
        if bar is not None:
            bar.close()
    value, theta, d = final(search)
    if not math.isfinite(value):
        raise NoTransectError(f"no transect crosses the {what} at spacing {spacing:g}")
    upper = max(closed, search.best, value)
    gap = upper - value
    angle, offset = canonical(theta, d * search.frame.scale, spacing)
    return OptimizeResult(
        angle=angle,
        offset=offset,
        fitness=value,
        spacing=spacing,
        method="certified-bb",
        evaluations=search.evaluations,
        seconds=time.perf_counter() - t0,
        upper_bound=upper,
        info={
            "gap": gap,
            "converged": gap <= tol * (1 + 1e-9),
            "tol": tol,
            "a": search.a,
            "b": search.b,
            "boxes": search.bounded,
            "rounds": rounds,
            **info,
            **({"stopped": stopped} if stopped else {}),
        },
    )
