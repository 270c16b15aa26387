"""The certified maximum of Eq. 1 over the SEGMENTS of a concave region or one with holes
(:func:`smith_bb_region`): :mod:`.search`'s branch and bound over boxes of (angle, offset),
the same boxes, sandwiches, incumbents and polish, with the region's per-box bound
(:mod:`.region_kernel`; above ``SIMPLIFY_EDGES`` edges the lines' intervals come from strips of
the real boundary, :mod:`.region_strips`, instead of the simplified sandwich). The fitness
is that of ``docs/concave.md``: Eq. 1 over every segment of every line (population std), in
the shell's normalised frame, as ``region-grid`` scores it.
docs: ``docs/global_optimum.md``, "Concave areas and holes".
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...errors import NoTransectError
from ...geometry import Polygon
from ...geometry.region import Region, as_region
from ...models import check_spacing
from ...objectives import SmithFitness
from ..cover.boxes import Boxes, box_radius, initial_boxes, level_radius
from ..cover.sandwich import Sandwich
from ..cover.search import SIMPLIFY_EDGES, SIMPLIFY_SPACING
from ..region_grid import evaluate_region_grid
from ..result import OptimizeResult
from .region_chains import near_margin
from .region_kernel import region_bounds, region_nodes, region_values, ring_starts
from .search import DEFAULT_TOL, SEED_ANGLES, _check, _check_angles, _Search, _weights, solve

__all__ = [
    "REGION_EXTEND",
    "REGION_EXTEND_POOLED",
    "REGION_MAX_WORK",
    "ROBUST_ANGLE",
    "ROBUST_OFFSET",
    "robust_values",
    "smith_bb_region",
]

#: Segments at most this long (share of the normalised frame) are not counted, as
#: :func:`~boustro.models.region.segment_moments` is called by ``region-grid``.
TINY = 1e-12


#: The perturbations of a candidate layout at which :func:`_final` also scores it: its angle by
#: this many radians and its offset by this share of the spacing (the normalised frame, radius
#: about 1). Far above float rounding (1e-16) and far below any real feature of an area (a
#: vertex 1e-9 of the area's size from a line): a value that exists only at one layout, a line
#: exactly through a vertex that rounding counts on one side, is not a layout one can fly.
ROBUST_ANGLE = 1e-9
ROBUST_OFFSET = 1e-9


#: Boxes of the best centre values whose quarters' centres are scored each round (strips).
DIVE_PER_ROUND = 4


class _RegionSearch(_Search):
    """A :class:`_Search` over a region: its vertices (shell and holes) for the polish's
    pieces, its segments for the values, the region bound for the boxes."""

    def __init__(self, region: Region, spacing: float, a: float, b: float) -> None:
        self.region, self.poly, self.frame = region, region.shell, region.frame
        self.v = self.frame.to_normalised(region.vertices)
        self.s, self.a, self.b = spacing / self.frame.scale, a, b
        rings = [self.frame.to_normalised(r) for r in region.rings]
        self.real = ring_starts(rings)
        self.xy = self.real[0]
        self.radius = float(np.hypot(self.v[:, 0], self.v[:, 1]).max())
        self.tiny = TINY * max(self.radius, 1e-300)
        self.margin = near_margin(rings, self.tiny)
        simplify = len(self.xy) > SIMPLIFY_EDGES
        self.sandwich = Sandwich(region, SIMPLIFY_SPACING * spacing if simplify else 0.0)
        self.levels: dict[float, tuple[NDArray[np.float64], NDArray[np.float64]]] = {}
        self.top_eps = 0.0
        self.best = -math.inf
        self.candidates: list[tuple[float, float, float]] = []
        self.polished: set[tuple[float, float]] = set()
        self.bounded = 0
        self.evaluations = 0
        self.tol = -math.inf  # the search's (set by smith_bb_region): a box bounded at most
        # best + tol is discarded, its bound need not be the tightest
        # the boxes' bounds from strips of the real boundary where the sandwich is simplified
        # (False: the sandwich's; small areas keep it: their searches and plans unchanged)
        self.strips = simplify

    def bounds(self, boxes: Boxes) -> NDArray[np.float64]:
        """Each box's bound from strips of the real boundary (:mod:`.region_strips`: within
        the sandwich of its radius, so no sandwich is built; areas of more than
        ``SIMPLIFY_EDGES`` edges), else from the sandwich of the smallest level radius that
        holds the box's ``eps``."""
        eps = box_radius(boxes, self.radius)
        if self.strips:
            self.bounded += len(eps)
            return region_bounds(
                self.real[0][:0], self.real[0][:0], self.real, boxes.theta, boxes.delta,
                boxes.d, eps * (1 + 1e-9) + 1e-12, self.s, self.a, self.b, self.tiny,
                boxes.eta * (1 + 1e-9) + 1e-12, self.margin, self.best + self.tol,
                radius=self.radius * (1 + 1e-12))  # fmt: skip
        radius = level_radius(eps, self.top_eps)
        out = np.empty(len(radius))
        for r in np.unique(radius):
            sel = radius == r
            inner, outer = self.level(float(r))
            out[sel] = region_bounds(
                inner, outer, self.real, boxes.theta[sel], boxes.delta[sel], boxes.d[sel],
                eps[sel] * (1 + 1e-9) + 1e-12, self.s, self.a, self.b, self.tiny,
                boxes.eta[sel] * (1 + 1e-9) + 1e-12, self.margin, self.best + self.tol)  # fmt: skip
        self.bounded += len(radius)
        return out

    def values(self, theta: NDArray[np.float64], d: NDArray[np.float64]) -> NDArray[np.float64]:
        self.evaluations += len(theta)
        return region_values(self.xy, theta, d, self.s, self.a, self.b, self.tiny)

    def at_angle(self, theta: float, offsets: NDArray[np.float64]) -> NDArray[np.float64]:
        return self.values(np.full(len(offsets), theta), np.asarray(offsets, dtype=np.float64))

    def polish_best(self, boxes: Boxes, score: NDArray[np.float64], extremes: bool) -> None:
        """As :meth:`_Search.polish_best`; with the strips, the centres of the four quarters of
        the :data:`DIVE_PER_ROUND` boxes of the best ``score`` are also scored (the best offered)
        and the best two polished: the strips' order splits the boxes of good centres later than
        the sandwich's did, and a peak narrower than its box was reached only after the default
        budget (issue 21's field: 48.125 deg, a quarter of the best centre's box, 1474 boxes in,
        not 7666; docs/global_optimum.md, section 10, "The incumbent"). Values only: the boxes
        and their bounds are unchanged."""
        super().polish_best(boxes, score, extremes)
        if not self.strips or extremes:
            return
        top = np.argsort(-score)[:DIVE_PER_ROUND]
        top = top[np.isfinite(score[top]) & (boxes.delta[top] > 0)]
        if not len(top):
            return
        sides = np.array([-0.5, 0.5])
        dt, dd = np.repeat(sides, 2), np.tile(sides, 2)
        theta = (boxes.theta[top, None] + dt * boxes.delta[top, None]).ravel()
        d = (boxes.d[top, None] + dd * boxes.eta[top, None]).ravel()
        quarters = Boxes(
            theta, np.repeat(boxes.delta[top] / 2, 4), d, np.repeat(boxes.eta[top] / 2, 4)
        )
        values = self.values(theta, d)
        k = int(np.argmax(values))
        if math.isfinite(values[k]):
            self.offer(float(values[k]), float(theta[k]), float(d[k]))
        super().polish_best(quarters, values, False)

    def offer(self, value: float, theta: float, d: float) -> None:
        """As :meth:`_Search.offer`, but a layout that would raise the incumbent is first
        scored robustly (the least value at it and its eight neighbours, :func:`robust_values`'s
        steps): an incumbent that float rounding grants one layout (a line exactly through a
        vertex) would prune the boxes holding the real optimum."""
        if value > self.best:
            steps = np.array([-1.0, 0.0, 1.0])
            near = self.values(
                theta + np.repeat(steps, 3) * ROBUST_ANGLE,
                d + np.tile(steps, 3) * (ROBUST_OFFSET * self.s),
            )
            value = float(np.min(np.where(np.isnan(near), -np.inf, near)))
            if not math.isfinite(value):
                return
        super().offer(value, theta, d)


#: Work budget of a region's search (as :data:`~boustro.optimize.smith_bb.search.MAX_WORK`),
#: a tenth of the convex one's: a region's box costs more, and where the bound still stalls
#: (more than 8 lines along edges at once, a comb; docs/global_optimum.md, section 10, "The
#: chain bound") more work does not close the gap. Measured (2026-11-27, load 7): the L, the U
#: (10 m, 1 m) and the pond L converge within it (0.1-0.5 s), the 40 m square ring at 7 m ends at
#: a gap of 1.05e-4 (converges with 2e7: by default since the extension, :data:`REGION_EXTEND`);
#: random concave areas with holes in 0.05-0.2 s.
REGION_MAX_WORK = 1e7
#: The default budget doubles, up to this many times :data:`REGION_MAX_WORK`, while the gap
#: shrinks fast (:data:`~boustro.optimize.smith_bb.search.SHRINK`; an explicit ``max_work`` is
#: a hard limit).
REGION_EXTEND = 8.0
#: As :data:`REGION_EXTEND` for an area whose boxes keep the pooled split bound (more lines
#: than :data:`~boustro.optimize.smith_bb.region_splits.NODE_LINES`): such a box costs about
#: 0.35-0.45 of a branched one (issue 21's field at 3 m: 160 against 460 us) but needs more
#: splitting, so its budget may double once more and spends about the CPU the branched boxes
#: did (docs/global_optimum.md, section 10, "Finer spacing").
REGION_EXTEND_POOLED = 16.0


def robust_values(
    xy: NDArray[np.float64], theta: ArrayLike, d: ArrayLike, s: float, a: float, b: float
) -> NDArray[np.float64]:
    """Per layout, the least exact value (``region-grid``'s evaluator over the segments
    ``xy``, normalised frame) at it and at its eight neighbours ``+-``:data:`ROBUST_ANGLE`,
    ``+-``:data:`ROBUST_OFFSET` ``* s`` (NaN or no segment at any of them: ``-inf``)."""
    th = np.asarray(theta, dtype=np.float64).reshape(-1)
    dd = np.asarray(d, dtype=np.float64).reshape(-1)
    steps = np.array([-1.0, 0.0, 1.0])
    dt = np.repeat(steps, 3) * ROBUST_ANGLE
    do = np.tile(steps, 3) * (ROBUST_OFFSET * s)
    values = evaluate_region_grid(
        xy.reshape(-1, 2, 2),
        (th[:, None] + dt[None, :]).reshape(-1),
        (dd[:, None] + do[None, :]).reshape(-1),
        s,
        fitness=SmithFitness(a=a, b=b),
        pairs=True,
    ).reshape(len(th), 9)
    values = np.where(np.isnan(values), -np.inf, values)
    return np.asarray(values.min(axis=1), dtype=np.float64)


def _final(search: _RegionSearch) -> tuple[float, float, float]:
    """``(fitness, theta, d)``: the candidate of the best robust value (:func:`robust_values`,
    the exact evaluator at the layout and its neighbours), and that value: a fitness that float
    rounding grants a single layout (a line through a vertex) is not reported."""
    cands = list(search.candidates)
    if not cands:
        return -math.inf, 0.0, 0.0
    values = robust_values(
        search.xy, [c[1] for c in cands], [c[2] for c in cands], search.s, search.a, search.b
    )
    k = int(np.argmax(values))
    return float(values[k]), cands[k][1], cands[k][2]


def _checked(region: Region | Polygon | ArrayLike, spacing: float) -> tuple[Region, float]:
    r = as_region(region)
    spacing = check_spacing(spacing, extent=r.diameter)
    if spacing >= r.diameter:
        raise NoTransectError(
            f"spacing {spacing:g} is not smaller than the area's diameter {r.diameter:g}: at "
            "most one transect can cross it"
        )
    return r, spacing


def smith_bb_region(
    region: Region | Polygon | ArrayLike,
    spacing: float,
    *,
    fitness: SmithFitness | None = None,
    a: float = 0.5,
    b: float = 0.5,
    tol: float = DEFAULT_TOL,
    n_angles: int = 90,
    max_work: float | None = None,
    progress: bool | None = False,
    incumbents: Sequence[tuple[float, float]] = (),
) -> OptimizeResult:
    """The maximum of Eq. 1 over the segments of a region (shell and holes, concave or not)
    over every angle and offset, with a certified upper bound.

    Args as :func:`~boustro.optimize.smith_bb.smith_bb` (the budget's default
    :data:`REGION_MAX_WORK`, doubled while the gap shrinks by a tenth per doubling, up to
    :data:`REGION_EXTEND` times, :data:`REGION_EXTEND_POOLED` where the boxes keep the pooled
    split bound; an explicit ``max_work`` is a hard limit); ``region`` in user
    units; ``incumbents``: layouts ``(angle, offset)`` (radians; user units from the shell's
    vertex mean, as returned, e.g. by ``region-grid``) scored and polished before the first
    boxes: a good first incumbent prunes more boxes (the result is as certified without them).

    Returns:
        :class:`OptimizeResult` with ``method="certified-bb"``, the offset from the shell's
        vertex mean, ``fitness`` the exact per-segment value of the returned layout (as
        :func:`~boustro.optimize.region_grid.evaluate_region_grid` scores it), ``upper_bound``
        >= that fitness at every layout, and ``info`` as :func:`smith_bb`'s (``converged``
        False with ``stopped`` when the budget was spent: the bound still holds).

    >>> area = Region([(0, 0), (5, 1), (4, 5), (2, 3), (-1, 4)], holes=[[(1, 1), (1, 2), (2, 1.5)]])
    >>> r = smith_bb_region(area, 0.4)
    >>> r.info["converged"], r.gap <= 1e-4
    (True, True)
    """
    t0 = time.perf_counter()
    r, spacing = _checked(region, spacing)
    a, b = _weights(a, b, fitness)
    tol = _check("tol", tol, 1e-9)
    hard = max_work is not None
    if max_work is None:
        max_work = REGION_MAX_WORK * max(1.0, DEFAULT_TOL / tol)
    max_work = _check("max_work", max_work, 0.0)
    n_angles = _check_angles(n_angles)
    search = _RegionSearch(r, spacing, a, b)
    search.tol = tol
    pooled = region_nodes(search.real[0], search.s) == 0
    extend = 1.0 if hard else (REGION_EXTEND_POOLED if pooled else REGION_EXTEND)
    boxes = initial_boxes(search.s, search.radius, n_angles)
    for angle, offset in incumbents:
        theta, d = float(angle), float(offset) / search.frame.scale
        value = float(search.values(np.array([theta]), np.array([d]))[0])
        if math.isfinite(value):
            search.offer(value, theta, d)
        search.polish(theta, d)
    search.seed(SEED_ANGLES * n_angles)
    return solve(search, boxes, spacing, tol, max_work, progress, t0, "area", _final, extend,
                 region=True)  # fmt: skip
