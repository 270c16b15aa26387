"""Plans for concave areas and areas with holes: cells, per-cell optima, one connected path.

Layer 5 of the core (numpy and torch; shapely is never imported here). Two ways to plan a
:class:`~boustro.regions.Region`:

* **single angle** (``decompose=False``): one transect grid over the whole area, optimised with
  the exact per-segment fitness (:mod:`boustro.regions`); every line is cut at the boundary and
  at the holes into lane segments.
* **decomposed** (default): a boustrophedon cellular decomposition (Choset) at a sweep direction
  (:func:`decompose`), each cell with its own optimised angle and offset, then all cells'
  lanes in one path.

Trapezoids and cells
--------------------
Lines through every vertex, parallel to the sweep direction, cut the area into slabs, and each
slab into trapezoids bounded by one entry and one exit edge (:func:`trapezoids`); they tile the
area exactly. A trapezoid joins the one above it in the same cell when each is the other's only
neighbour across the slab line (no critical point between them); the cells are then merged
pairwise where one lies on top of the other across a critical line (the union is still monotone:
every line parallel to the sweep meets it in one segment), longest shared boundary first. Cells
are monotone polygons, interior-disjoint, and their union is the area.

Coverage guarantee
------------------
As for convex polygons (:mod:`boustro.plan`), lane ``k`` of a cell is responsible for the band
``|n . p - c_k| <= reach`` and its segments span the projection onto its line of band ∩ cell
(from the trapezoids, in closed form), so they may reach beyond the cell and the area by at most
``reach`` across the lanes. A lane never enters a hole: the parts of its line inside a hole are
cut out. A point of the area whose projection onto its lane falls in a hole lies within
``reach`` of that hole's boundary, so one pass around each hole that cuts a lane (driven on the
hole's boundary, its sensor seeing ``reach`` to each side and sweeping the corners as it turns
on the spot) completes the coverage. ``coverage(plan)`` checks it exactly with shapely.

Path
----
Lane segments on consecutive lines that overlap one-to-one form *chains* driven back and forth;
chains and hole passes are ordered greedily from the start, then improved by 2-opt with the
best entry corner of every chain chosen by dynamic programming, with the lengths of the real
connecting moves (:class:`~boustro.routing.Router`: straight where allowed, else the shortest
path inside the area around the holes).
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import InvalidParameterError, InvalidPolygonError, NoTransectError, as_number
from .fitness import SmithFitness
from .geometry import Polygon
from .models import check_spacing
from .objectives import objective_sign
from .optimize import OptimizeResult, grid_search
from .plan import KINDS, Plan, PlanCell, PlanStats
from .regions import Region, as_region, evaluate_region_grid, points_in_ring, segment_moments
from .routing import Router

__all__ = [
    "Decomposition",
    "Lanes",
    "Trapezoids",
    "choose_sweep",
    "decompose",
    "optimize_region",
    "plan_region",
    "region_lanes",
    "trapezoids",
]

Layout = Literal["guaranteed", "chords"]

#: Relative tolerance (to the area's diameter) for coincident slab lines and overlaps.
_TOL = 1e-9


def _frame(angle: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    u = np.array([math.cos(angle), math.sin(angle)])
    return u, np.array([-u[1], u[0]])


# -- trapezoids -------------------------------------------------------------------------------
class Trapezoids(NamedTuple):
    """The slab decomposition of a region at one angle (plan units, relative to ``origin``).

    Trapezoid ``i`` spans positions ``c`` in ``[a[i], b[i]]`` across the lines of direction
    ``angle``; along them it spans ``[entry edge, exit edge]``, whose along-coordinates at
    ``a`` and ``b`` are ``te_a, te_b`` and ``tx_a, tx_b``. Ordered by slab, then along ``u``.
    """

    angle: float
    origin: NDArray[np.float64]
    a: NDArray[np.float64]
    b: NDArray[np.float64]
    te_a: NDArray[np.float64]
    te_b: NDArray[np.float64]
    tx_a: NDArray[np.float64]
    tx_b: NDArray[np.float64]
    slab: NDArray[np.int64]

    def point(self, c: ArrayLike, t: ArrayLike) -> NDArray[np.float64]:
        """Plan coordinates of ``(c, t)`` pairs."""
        u, n = _frame(self.angle)
        c, t = np.asarray(c, float), np.asarray(t, float)
        return self.origin + c[..., None] * n + t[..., None] * u

    def polygons(self) -> NDArray[np.float64]:
        """``(Q, 4, 2)`` every trapezoid's corners."""
        return np.stack(
            [
                self.point(self.a, self.te_a),
                self.point(self.a, self.tx_a),
                self.point(self.b, self.tx_b),
                self.point(self.b, self.te_b),
            ],
            axis=1,
        )


def _crossings(
    edges: NDArray[np.float64], u: NDArray[np.float64], n: NDArray[np.float64], c: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.int64]]:
    """Sorted crossings of lines ``n . p = c`` with ``edges (E, 2, 2)``: ``(t, edge, count)``
    with ``t, edge`` ``(K, E)`` (padded with inf / -1) and ``count (K,)``."""
    c = np.asarray(c, dtype=np.float64).reshape(-1)
    c1, c2 = edges[:, 0] @ n, edges[:, 1] @ n
    t1, t2 = edges[:, 0] @ u, edges[:, 1] @ u
    cross = (c1[None] <= c[:, None]) != (c2[None] <= c[:, None])
    dc = c2 - c1
    slope = (t2 - t1) / np.where(dc == 0, 1.0, dc)
    t = np.where(cross, t1[None] + (c[:, None] - c1[None]) * slope[None], np.inf)
    order = np.argsort(t, axis=1, kind="stable")
    t = np.take_along_axis(t, order, axis=1)
    count = cross.sum(axis=1)
    edge = np.where(np.isfinite(t), order, -1)
    return t, edge, count


def trapezoids(
    region: Region | Polygon | ArrayLike, angle: float, origin: ArrayLike | None = None
) -> Trapezoids:
    """The slab decomposition of ``region`` by lines of direction ``angle`` through its vertices."""
    r = as_region(region)
    angle = _check_float("sweep angle", angle)
    o = r.centre if origin is None else np.asarray(origin, dtype=np.float64)
    u, n = _frame(angle)
    e = r.edges - o
    c1, c2 = e[:, 0] @ n, e[:, 1] @ n
    t1, t2 = e[:, 0] @ u, e[:, 1] @ u
    events = np.unique(c1)
    tol = _TOL * r.diameter
    keep = np.concatenate([[True], np.diff(events) > tol])
    events = events[keep]
    a, b = events[:-1], events[1:]
    mid = (a + b) / 2
    _, edge, count = _crossings(e, u, n, mid)
    pairs = count // 2
    m = int(pairs.max()) if len(pairs) else 0
    slot = np.arange(m)
    valid = slot[None] < pairs[:, None]
    entry = edge[:, 0 : 2 * m : 2][valid]
    exit_ = edge[:, 1 : 2 * m : 2][valid]
    slab = np.repeat(np.arange(len(mid)), pairs)
    dc = c2 - c1
    slope = (t2 - t1) / np.where(dc == 0, 1.0, dc)

    def t_at(j: NDArray[np.int64], c: NDArray[np.float64]) -> NDArray[np.float64]:
        return t1[j] + (c - c1[j]) * slope[j]

    aa, bb = a[slab], b[slab]
    return Trapezoids(
        float(angle),
        o,
        aa,
        bb,
        t_at(entry, aa),
        t_at(entry, bb),
        t_at(exit_, aa),
        t_at(exit_, bb),
        slab.astype(np.int64),
    )


# -- cells ------------------------------------------------------------------------------------
class _UnionFind:
    def __init__(self, n: int) -> None:
        self.parent = list(range(n))

    def find(self, i: int) -> int:
        while self.parent[i] != i:
            self.parent[i] = self.parent[self.parent[i]]
            i = self.parent[i]
        return i

    def union(self, i: int, j: int) -> int:
        ri, rj = self.find(i), self.find(j)
        self.parent[rj] = ri
        return ri


def _interval_minus(
    a: list[tuple[float, float]], b: list[tuple[float, float]], tol: float
) -> list[tuple[float, float]]:
    out = []
    for lo, hi in a:
        pieces = [(lo, hi)]
        for g0, g1 in b:
            nxt = []
            for x0, x1 in pieces:
                if g1 <= x0 or g0 >= x1:
                    nxt.append((x0, x1))
                    continue
                if g0 > x0:
                    nxt.append((x0, g0))
                if g1 < x1:
                    nxt.append((g1, x1))
            pieces = nxt
        out += [(x0, x1) for x0, x1 in pieces if x1 - x0 > tol]
    return out


def _straighten(ring: NDArray[np.float64], tol: float) -> NDArray[np.float64]:
    """Drop the vertices where a traced ring goes straight on (many: every slab line crossing
    an edge makes one), all at once: those within ``tol`` of the line through their
    neighbours, between them. Tiny steps along an edge would otherwise leave nearly collinear
    vertices that :class:`~boustro.geometry.Polygon` may take for a self-intersection."""
    while len(ring) > 3:
        prev = ring - np.roll(ring, 1, axis=0)
        nxt = np.roll(ring, -1, axis=0) - ring
        chord = np.linalg.norm(prev + nxt, axis=1)
        cross = prev[:, 0] * nxt[:, 1] - prev[:, 1] * nxt[:, 0]
        straight = (np.abs(cross) <= tol * chord) & (np.einsum("ij,ij->i", prev, nxt) >= 0)
        straight |= np.linalg.norm(prev, axis=1) <= tol
        if not straight.any() or straight.all():
            break
        ring = ring[~straight]  # a run of straight vertices lies on one line: drop them all
    return ring


def _ring_area(ring: NDArray[np.float64]) -> float:
    x, y = ring[:, 0], ring[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def trace_region(tr: Trapezoids, members: ArrayLike, diameter: float) -> Region:
    """The union of trapezoids ``members`` as a :class:`~boustro.regions.Region` (its outer
    boundary and any holes it surrounds), by tracing the boundary of the union.

    Raises:
        InvalidPolygonError: the union is not a valid region (e.g. it touches itself at a point).
    """
    idx = np.asarray(members, dtype=np.int64)
    tol = _TOL * diameter
    segs: list[tuple[float, float, float, float]] = []  # (c0, t0, c1, t1), union on the left
    for i in idx:
        segs.append((tr.a[i], tr.te_a[i], tr.b[i], tr.te_b[i]))
        segs.append((tr.b[i], tr.tx_b[i], tr.a[i], tr.tx_a[i]))
    by_b: dict[float, list[tuple[float, float]]] = {}
    by_a: dict[float, list[tuple[float, float]]] = {}
    for i in idx:
        by_b.setdefault(float(tr.b[i]), []).append((float(tr.te_b[i]), float(tr.tx_b[i])))
        by_a.setdefault(float(tr.a[i]), []).append((float(tr.te_a[i]), float(tr.tx_a[i])))
    for line in set(by_a) | set(by_b):
        left, right = by_b.get(line, []), by_a.get(line, [])
        segs += [(line, lo, line, hi) for lo, hi in _interval_minus(left, right, tol)]
        segs += [(line, hi, line, lo) for lo, hi in _interval_minus(right, left, tol)]
    seg = np.array(segs, dtype=np.float64).reshape(-1, 4)
    seg = seg[np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1]) > tol]
    ends = np.concatenate([seg[:, :2], seg[:, 2:]])
    # Cluster end points that differ by rounding only: snap to a grid, then join grid cells
    # that are neighbours (a cluster straddling a grid line).
    snap = 0.1 * tol  # below the gap between distinct slab lines (> tol)
    key = np.floor(ends / snap).astype(np.int64)
    _, label = np.unique(key, axis=0, return_inverse=True)
    label = label.ravel()
    cells: dict[tuple[int, int], int] = {}
    for (kx, ky), raw in zip(map(tuple, key), label, strict=True):
        cells.setdefault((int(kx), int(ky)), int(raw))
    uf = _UnionFind(int(label.max()) + 1 if len(label) else 0)
    first = np.zeros(len(uf.parent), dtype=np.int64)
    first[label[::-1]] = np.arange(len(label))[::-1]
    for (kx, ky), lab in cells.items():
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                other = cells.get((kx + dx, ky + dy))
                if other is not None and other != lab:
                    a, b = ends[first[lab]], ends[first[other]]
                    if np.max(np.abs(a - b)) <= snap:
                        uf.union(int(lab), int(other))
    label = np.array([uf.find(int(x)) for x in label])
    m = len(seg)
    start, stop = label[:m], label[m:]
    outgoing: dict[int, list[int]] = {}
    for k in range(m):
        outgoing.setdefault(int(start[k]), []).append(k)
    used = np.zeros(m, dtype=bool)
    rings = []
    for k0 in range(m):
        if used[k0]:
            continue
        ring, k = [], k0
        while not used[k]:
            used[k] = True
            ring.append(seg[k, :2])
            nxt = [j for j in outgoing.get(int(stop[k]), []) if not used[j]]
            if not nxt:
                break
            k = nxt[0]
        cs, ts = np.array([p[0] for p in ring]), np.array([p[1] for p in ring])
        arr = _straighten(tr.point(cs, ts), tol)
        if len(arr) >= 3 and abs(_ring_area(arr)) > tol * diameter:
            rings.append(arr)
    if not rings:
        raise InvalidPolygonError("the cells' union has no area")
    rings.sort(key=lambda x: -abs(_ring_area(x)))
    shell = Polygon(rings[0])
    holes = [Polygon(h) for h in rings[1:]]
    if all(points_in_ring(h.vertices[:1], shell.vertices)[0] for h in holes):
        return Region._trusted(shell, holes)  # rings of a tiling: disjoint by construction
    return Region(shell, holes)


@dataclass(frozen=True)
class Decomposition:
    """Cells of a boustrophedon decomposition.

    Attributes:
        sweep: the sweep direction (radians): lines of this direction cut the area into
            trapezoids; cells not merged for being small are monotone along them.
        cells: the cells as regions (plan units), interior-disjoint, union = the area.
        trapezoids: the slab decomposition they are made of.
        membership: ``(Q,)`` the cell of each trapezoid.
        widths: ``(C,)`` each cell's extent across the sweep lines.
        shared: ``(C, C)`` length of the boundary each pair of cells shares.
    """

    sweep: float
    cells: tuple[Region, ...]
    trapezoids: Trapezoids
    membership: NDArray[np.int64]
    widths: NDArray[np.float64]
    shared: NDArray[np.float64]

    def union(self, cells: Sequence[int], diameter: float) -> Region:
        """The union of some cells as one region."""
        members = np.flatnonzero(np.isin(self.membership, np.asarray(cells)))
        return trace_region(self.trapezoids, members, diameter)


def _links(tr: Trapezoids, tol: float) -> list[tuple[float, int, int, bool]]:
    """Trapezoids touching across slab lines: ``(overlap, lower, upper, one-to-one)``."""
    out = []
    by_slab: dict[int, NDArray[np.int64]] = {}
    for s in np.unique(tr.slab):
        by_slab[int(s)] = np.flatnonzero(tr.slab == s)
    for s, lower in by_slab.items():
        upper = by_slab.get(s + 1)
        if upper is None or tr.b[lower[0]] != tr.a[upper[0]]:
            continue
        lo = np.maximum(tr.te_b[lower][:, None], tr.te_a[upper][None])
        hi = np.minimum(tr.tx_b[lower][:, None], tr.tx_a[upper][None])
        overlap = hi - lo
        touching = overlap > tol
        for i, j in zip(*np.nonzero(touching), strict=True):
            single = bool(touching[i].sum() == 1 and touching[:, j].sum() == 1)
            out.append((float(overlap[i, j]), int(lower[i]), int(upper[j]), single))
    return out


def decompose(
    region: Region | Polygon | ArrayLike,
    sweep: float,
    *,
    merge: bool = True,
    min_width: float = 0.0,
    polygons: bool = True,
) -> Decomposition:
    """Boustrophedon cellular decomposition of ``region`` at sweep direction ``sweep`` (radians).

    Args:
        region: the area (plan units).
        sweep: direction of the sweep lines (the lanes along which every cell is monotone).
        merge: merge cells stacked across a critical line (module docstring); ``False`` gives
            Choset's cells, split at every critical point.
        min_width: then merge every cell narrower than this across the sweep lines (typically
            a few spacings: the cells that wiggles of the boundary cut off) into the neighbour
            it shares the longest boundary with; such merged cells need not be monotone.
        polygons: build the cells' regions (``False``: only membership and widths, faster).
    """
    r = as_region(region)
    tr = trapezoids(r, sweep)
    q = len(tr.a)
    tol = _TOL * r.diameter
    uf = _UnionFind(q)
    links = _links(tr, tol)
    stacked = []
    for overlap, i, j, single in links:
        if single:
            uf.union(i, j)
        else:
            stacked.append((overlap, i, j))
    lo_c: dict[int, float] = {}
    hi_c: dict[int, float] = {}
    top: dict[int, int] = {}
    bottom: dict[int, int] = {}
    for i in range(q):
        rt, sl = uf.find(i), int(tr.slab[i])
        top[rt] = max(top.get(rt, sl), sl)
        bottom[rt] = min(bottom.get(rt, sl), sl)
        lo_c[rt] = min(lo_c.get(rt, math.inf), float(tr.a[i]))
        hi_c[rt] = max(hi_c.get(rt, -math.inf), float(tr.b[i]))

    def join(ri: int, rj: int) -> None:
        new = uf.union(ri, rj)
        top[new], bottom[new] = max(top[ri], top[rj]), min(bottom[ri], bottom[rj])
        lo_c[new], hi_c[new] = min(lo_c[ri], lo_c[rj]), max(hi_c[ri], hi_c[rj])

    if merge:
        for _, i, j in sorted(stacked, reverse=True):
            ri, rj = uf.find(i), uf.find(j)
            if ri != rj and top[ri] == tr.slab[i] and bottom[rj] == tr.slab[j]:
                join(ri, rj)
    if min_width > 0:
        while True:
            shared: dict[tuple[int, int], float] = {}
            for overlap, i, j, _ in links:
                ri, rj = uf.find(i), uf.find(j)
                if ri != rj:
                    key = (min(ri, rj), max(ri, rj))
                    shared[key] = shared.get(key, 0.0) + overlap
            roots = {uf.find(i) for i in range(q)}
            narrow = sorted(
                (hi_c[rt] - lo_c[rt], rt) for rt in roots if hi_c[rt] - lo_c[rt] < min_width
            )
            done = False
            for _, rt in narrow:
                best = max(
                    ((length, key) for key, length in shared.items() if rt in key),
                    default=None,
                )
                if best is not None:
                    join(*best[1])
                    done = True
                    break
            if not done:
                break
    labels = np.array([uf.find(i) for i in range(q)], dtype=np.int64)
    _, membership = np.unique(labels, return_inverse=True)
    n_cells = int(membership.max()) + 1 if q else 0
    # Order the cells by their lowest slab, then along the sweep lines.
    first = [np.flatnonzero(membership == k)[0] for k in range(n_cells)]
    rank = np.lexsort(([tr.te_a[i] for i in first], [tr.slab[i] for i in first]))
    remap = np.empty_like(rank)
    remap[rank] = np.arange(n_cells)
    membership = remap[membership]
    lo = np.full(n_cells, np.inf)
    hi = np.full(n_cells, -np.inf)
    np.minimum.at(lo, membership, tr.a)
    np.maximum.at(hi, membership, tr.b)
    shared_m = np.zeros((n_cells, n_cells))
    for overlap, i, j, _ in links:
        ci, cj = membership[i], membership[j]
        if ci != cj:
            shared_m[ci, cj] += overlap
            shared_m[cj, ci] += overlap
    cells: tuple[Region, ...] = ()
    if polygons:
        cells = tuple(
            trace_region(tr, np.flatnonzero(membership == k), r.diameter) for k in range(n_cells)
        )
    return Decomposition(float(sweep), cells, tr, membership, hi - lo, shared_m)


#: Grid of the quick optimisations that compare sweep directions (:func:`choose_sweep`).
SWEEP_SEARCH = {"n_angles": 36, "n_offsets": 6, "refine": 1}


def _estimate(
    cells: Sequence[Region], optima: Sequence[OptimizeResult], spacing: float
) -> tuple[float, float]:
    """``(turns, lane length)`` estimated from each cell's line segments at its optimum: one
    turn per segment, plus one per cell to reach it, minus one."""
    turns, length = -1.0, 0.0
    for cell, opt in zip(cells, optima, strict=True):
        frame = cell.frame
        n, s1, _ = segment_moments(
            frame.to_normalised(cell.edges),
            [opt.angle],
            [opt.offset / frame.scale],
            spacing / frame.scale,
            tiny=1e-12,
        )
        turns += float(n[0]) + 1.0
        length += float(s1[0]) * frame.scale
    return turns, length


def _cells_for_sweep(
    region: Region,
    spacing: float,
    sweep: float,
    *,
    min_width: float,
    merge_angle: float,
    options: dict[str, Any],
) -> tuple[list[Region], list[OptimizeResult]]:
    dec = decompose(region, sweep, min_width=min_width)
    _, cells, optima = _merge_by_angle(dec, region.diameter, spacing, merge_angle, **options)
    return cells, optima


def choose_sweep(
    region: Region | Polygon | ArrayLike,
    spacing: float,
    *,
    candidates: Sequence[float] | None = None,
    n_candidates: int = 6,
    min_width: float | None = None,
    merge_angle: float = math.radians(15.0),
    fitness: Any = None,
) -> tuple[float, tuple[float, float]]:
    """The sweep direction whose decomposition promises the fewest turns.

    For each candidate the area is decomposed (:func:`decompose`), every cell optimised on a
    coarse grid (:data:`SWEEP_SEARCH`), neighbours with similar angles merged, and the plan's
    turns and lane length estimated from the cells' line segments at their optima. Candidates
    (radians): ``n_candidates`` directions over 180 degrees and those of the 2 longest edges.

    Returns:
        ``(sweep, (estimated turns, estimated lane length))`` of the best candidate.
    """
    r = as_region(region)
    s = check_spacing(spacing, extent=r.diameter)
    min_width = 2 * s if min_width is None else float(min_width)
    if candidates is None:
        e = r.edges
        d = e[:, 1] - e[:, 0]
        longest = np.argsort(-np.linalg.norm(d, axis=1))[:2]
        edge_angles = np.arctan2(d[longest, 1], d[longest, 0]) % math.pi
        candidates = list(np.arange(n_candidates) * math.pi / n_candidates) + list(edge_angles)
    options = dict(SWEEP_SEARCH, fitness=fitness)
    best: tuple[tuple[float, float], float] | None = None
    for angle in candidates:
        try:
            cells, optima = _cells_for_sweep(
                r, s, float(angle), min_width=min_width, merge_angle=merge_angle, options=options
            )
        except InvalidPolygonError:  # a cell that rounding made invalid: skip this sweep
            continue
        key = _estimate(cells, optima, s)
        if best is None or key < best[0]:
            best = (key, float(angle) % math.pi)
    if best is None:
        return 0.0, (math.inf, math.inf)
    return best[1], best[0]


# -- optimising a region ----------------------------------------------------------------------
def optimize_region(
    region: Region | Polygon | ArrayLike,
    spacing: float,
    *,
    n_angles: int = 90,
    n_offsets: int = 16,
    refine: int = 2,
    fitness: Any = None,
) -> OptimizeResult:
    """Grid search of angle and offset for any region with the exact per-segment fitness.

    A convex polygon goes to :func:`boustro.optimize.grid_search` (closed-form chords); any
    other region is scored by :func:`boustro.regions.evaluate_region_grid` on an
    ``n_angles x n_offsets`` grid, then ``refine`` times on a 9 x 9 grid zoomed (by 4) around
    the best point. A region narrower than the spacing in every direction gets the single lane
    through its vertex mean along its diameter.

    Returns:
        :class:`~boustro.optimize.OptimizeResult` in the region's units (offset from the shell's
        vertex mean), method ``"region-grid"`` (or ``"grid"`` for a convex polygon).
    """
    t0 = time.perf_counter()
    r = as_region(region)
    s = check_spacing(spacing, extent=r.diameter)
    fitness = SmithFitness() if fitness is None else fitness
    sign = objective_sign(fitness)
    if s >= r.diameter:
        v = r.shell.vertices
        dif = v[:, None] - v[None]
        i, j = np.unravel_index(int(np.argmax(np.einsum("ijk,ijk->ij", dif, dif))), dif.shape[:2])
        angle = math.atan2(*(v[j] - v[i])[::-1]) % math.pi
        return OptimizeResult(angle, 0.0, math.nan, s, "single-lane", 0, time.perf_counter() - t0)
    if r.is_convex:
        try:
            return grid_search(r.shell, s, n_angles=n_angles, n_offsets=n_offsets, fitness=fitness)
        except NoTransectError:
            pass
    frame = r.frame
    edges = frame.to_normalised(r.edges)
    s_n = s / frame.scale
    angles = np.arange(n_angles) * (math.pi / n_angles)
    offsets = np.arange(n_offsets) * (s_n / n_offsets)
    values = evaluate_region_grid(edges, angles, offsets, s_n, fitness=fitness)
    evaluations = values.size
    i, j = np.unravel_index(int(np.argmax(sign * values)), values.shape)
    best = (float(values[i, j]), float(angles[i]), float(offsets[j]))
    da, do = math.pi / n_angles, s_n / n_offsets
    for _ in range(int(refine)):
        a = best[1] + np.linspace(-da, da, 9)
        o = best[2] + np.linspace(-do, do, 9)
        vals = evaluate_region_grid(edges, a, o, s_n, fitness=fitness)
        evaluations += vals.size
        i, j = np.unravel_index(int(np.argmax(sign * vals)), vals.shape)
        if sign * vals[i, j] > sign * best[0]:
            best = (float(vals[i, j]), float(a[i]), float(o[j]))
        da, do = da / 4, do / 4
    if not math.isfinite(best[0]):
        raise NoTransectError(f"no transect crosses the area at spacing {s:g}")
    angle, offset = best[1], best[2]
    turns = math.floor(angle / math.pi)
    angle -= turns * math.pi
    if turns % 2:
        offset = -offset
    offset = math.fmod(offset, s_n) % s_n
    return OptimizeResult(
        angle=angle,
        offset=offset * frame.scale,
        fitness=best[0],
        spacing=s,
        method="region-grid",
        evaluations=int(evaluations),
        seconds=time.perf_counter() - t0,
        info={"n_angles": n_angles, "n_offsets": n_offsets, "refine": int(refine)},
    )


def _angle_gap(a: float, b: float) -> float:
    d = abs(a - b) % math.pi
    return min(d, math.pi - d)


def _merge_by_angle(
    dec: Decomposition,
    diameter: float,
    spacing: float,
    merge_angle: float,
    **options: Any,
) -> tuple[list[list[int]], list[Region], list[OptimizeResult]]:
    """Optimise every cell; then repeatedly merge the two neighbouring cells (longest shared
    boundary first) whose angles differ by less than ``merge_angle`` and optimise the union."""
    groups = [[k] for k in range(len(dec.cells))]
    regions = list(dec.cells)
    optima = [optimize_region(c, spacing, **options) for c in regions]
    refused: set[tuple[tuple[int, ...], tuple[int, ...]]] = set()
    while len(groups) > 1:
        best = None
        for i in range(len(groups)):
            for j in range(i + 1, len(groups)):
                shared = float(dec.shared[np.ix_(groups[i], groups[j])].sum())
                if shared <= 0 or (tuple(groups[i]), tuple(groups[j])) in refused:
                    continue
                if _angle_gap(optima[i].angle, optima[j].angle) >= merge_angle:
                    continue
                if best is None or shared > best[0]:
                    best = (shared, i, j)
        if best is None:
            break
        _, i, j = best
        try:
            union = dec.union(groups[i] + groups[j], diameter)
        except InvalidPolygonError:
            refused.add((tuple(groups[i]), tuple(groups[j])))
            continue
        groups[i] = groups[i] + groups[j]
        regions[i] = union
        optima[i] = optimize_region(union, spacing, **options)
        del groups[j], regions[j], optima[j]
    return groups, regions, optima


# -- lanes ------------------------------------------------------------------------------------
class Lanes(NamedTuple):
    """Lane segments of one transect grid (plan units).

    Segment ``i`` lies on line ``k[i]`` (position ``c[i]`` from ``origin`` along the left normal
    of ``angle``) and spans ``t0[i] <= t <= t1[i]`` along it; sorted by line, then along it.
    ``cut`` lists the holes that cut any lane (their parts of the lines were removed).
    """

    angle: float
    origin: NDArray[np.float64]
    k: NDArray[np.int64]
    c: NDArray[np.float64]
    t0: NDArray[np.float64]
    t1: NDArray[np.float64]
    cut: frozenset[int]

    def points(self, t: ArrayLike) -> NDArray[np.float64]:
        u, n = _frame(self.angle)
        t = np.asarray(t, float)
        return self.origin + self.c[:, None] * n + t[..., None] * u

    @property
    def segments(self) -> NDArray[np.float64]:
        """``(T, 2, 2)`` the segments from ``t0`` to ``t1``."""
        return np.stack([self.points(self.t0), self.points(self.t1)], axis=1)


def _merge_intervals(
    key: NDArray[np.int64], lo: NDArray[np.float64], hi: NDArray[np.float64], tol: float
) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]:
    order = np.lexsort((lo, key))
    key, lo, hi = key[order], lo[order], hi[order]
    out_k: list[int] = []
    out_lo: list[float] = []
    out_hi: list[float] = []
    for kk, a, b in zip(key, lo, hi, strict=True):
        if out_k and out_k[-1] == kk and a <= out_hi[-1] + tol:
            out_hi[-1] = max(out_hi[-1], b)
        else:
            out_k.append(int(kk))
            out_lo.append(float(a))
            out_hi.append(float(b))
    return np.array(out_k, dtype=np.int64), np.array(out_lo), np.array(out_hi)


def _intervals_on_lines(
    edges: NDArray[np.float64],
    u: NDArray[np.float64],
    n: NDArray[np.float64],
    c: NDArray[np.float64],
) -> list[list[tuple[float, float]]]:
    t, _, count = _crossings(edges, u, n, c)
    out = []
    for row, cnt in zip(t, count, strict=True):
        out.append([(float(row[i]), float(row[i + 1])) for i in range(0, int(cnt) - 1, 2)])
    return out


def _subtract(
    pieces: list[tuple[float, float]], cuts: list[tuple[float, float]], tol: float
) -> tuple[list[tuple[float, float]], bool]:
    out, changed = pieces, False
    for g0, g1 in cuts:
        nxt = []
        for a, b in out:
            if g1 <= a or g0 >= b:
                nxt.append((a, b))
                continue
            changed = True
            if g0 - a > tol:
                nxt.append((a, g0))
            if b - g1 > tol:
                nxt.append((g1, b))
        out = nxt
    return out, changed


def region_lanes(
    cover: Region | Polygon | ArrayLike,
    spacing: float,
    angle: float,
    offset: float = 0.0,
    *,
    reach: float | None = None,
    holes: Sequence[Polygon] = (),
    layout: Layout = "guaranteed",
    origin: ArrayLike | None = None,
) -> Lanes:
    """Lane segments covering ``cover`` at one transect grid, never entering ``holes``.

    Args:
        cover: the region (or cell) the lanes must cover, plan units.
        spacing, angle, offset: the grid; ``offset`` from ``origin`` (default: the cover's
            vertex mean), as everywhere in boustro.
        reach: half-width of each lane's band (default ``spacing / 2``).
        holes: obstacles no lane may enter (the area's holes; those of ``cover`` itself are
            avoided anyway).
        layout: ``"guaranteed"`` (each lane spans the projection of band ∩ cover, module
            docstring) or ``"chords"`` (the lines' exact segments inside the cover).
    """
    r = as_region(cover)
    s = check_spacing(spacing, extent=r.diameter)
    reach = s / 2 if reach is None else float(reach)
    o = r.centre if origin is None else np.asarray(origin, dtype=np.float64)
    u, n = _frame(angle)
    tol = _TOL * r.diameter
    vc = (r.vertices - o) @ n
    k_min = math.floor((vc.min() - reach - offset) / s) - 1
    k_max = math.ceil((vc.max() + reach - offset) / s) + 1
    ks = np.arange(k_min, k_max + 1)
    cs = offset + ks * s
    if layout == "guaranteed":
        tr = trapezoids(r, angle, o)
        lo_k = np.floor((tr.a - reach - offset) / s).astype(np.int64) + 1
        hi_k = np.ceil((tr.b + reach - offset) / s).astype(np.int64) - 1
        counts = np.maximum(hi_k - lo_k + 1, 0)
        which = np.repeat(np.arange(len(tr.a)), counts)
        first = np.repeat(np.cumsum(counts) - counts, counts)
        k = lo_k[which] + (np.arange(len(which)) - first)
        c = offset + k * s
        alpha = np.maximum(tr.a[which], c - reach)
        beta = np.minimum(tr.b[which], c + reach)
        ok = beta - alpha > tol
        which, k, alpha, beta = which[ok], k[ok], alpha[ok], beta[ok]
        width = np.where(tr.b - tr.a > 0, tr.b - tr.a, 1.0)[which]
        fa, fb = (alpha - tr.a[which]) / width, (beta - tr.a[which]) / width
        te = lambda f: tr.te_a[which] + (tr.te_b[which] - tr.te_a[which]) * f  # noqa: E731
        tx = lambda f: tr.tx_a[which] + (tr.tx_b[which] - tr.tx_a[which]) * f  # noqa: E731
        lo = np.minimum(te(fa), te(fb))
        hi = np.maximum(tx(fa), tx(fb))
        key, lo, hi = _merge_intervals(k, lo, hi, tol)
    elif layout == "chords":
        rows = _intervals_on_lines(r.edges - o, u, n, cs)
        key_l, lo_l, hi_l = [], [], []
        for kk, row in zip(ks, rows, strict=True):
            for a, b in row:
                if b - a > tol:
                    key_l.append(int(kk))
                    lo_l.append(a)
                    hi_l.append(b)
        key, lo, hi = np.array(key_l, dtype=np.int64), np.array(lo_l), np.array(hi_l)
    else:
        raise InvalidParameterError(f"layout must be 'guaranteed' or 'chords', got {layout!r}")
    # Cut out the parts of each line inside a hole, where the lines at c - eps and c + eps are
    # inside it too (a line along a hole's edge, or through its extreme vertex, is not cut).
    cut: set[int] = set()
    lines = np.unique(key)
    per_line: dict[int, list[tuple[float, float]]] = {int(kk): [] for kk in lines}
    for kk, a, b in zip(key, lo, hi, strict=True):
        per_line[int(kk)].append((float(a), float(b)))
    eps = 1e-7 * max(s, tol)
    for h_index, hole in enumerate(holes):
        he = np.stack([hole.vertices, np.roll(hole.vertices, -1, axis=0)], axis=1) - o
        hc = he[:, :, :] @ n
        lines_hit = [kk for kk in per_line if hc.min() < offset + kk * s < hc.max()]
        if not lines_hit:
            continue
        cpos = offset + np.array(lines_hit, dtype=np.float64) * s
        at = _intervals_on_lines(he, u, n, cpos)
        below = _intervals_on_lines(he, u, n, cpos - eps)
        above = _intervals_on_lines(he, u, n, cpos + eps)
        for kk, g_at, g_lo, g_hi in zip(lines_hit, at, below, above, strict=True):
            gaps = [
                (x0, x1)
                for x0, x1 in g_at
                if any(min(x1, b1) > max(x0, b0) for b0, b1 in g_lo)
                and any(min(x1, b1) > max(x0, b0) for b0, b1 in g_hi)
            ]
            if gaps:
                per_line[kk], changed = _subtract(per_line[kk], gaps, tol)
                if changed:
                    cut.add(h_index)
    out_k, out_lo, out_hi = [], [], []
    for kk in sorted(per_line):
        for a, b in sorted(per_line[kk]):
            out_k.append(kk)
            out_lo.append(a)
            out_hi.append(b)
    k_arr = np.array(out_k, dtype=np.int64)
    return Lanes(
        float(angle),
        o,
        k_arr,
        np.asarray(offset + k_arr * s, dtype=np.float64),
        np.array(out_lo, dtype=np.float64),
        np.array(out_hi, dtype=np.float64),
        frozenset(cut),
    )


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


#: Orders the 2-opt improvement of a tour evaluates at most (about 0.25 s for 60 passes on the
#: project's machine): a count, not a time, so that plans do not depend on the machine's load.
ORDER_BUDGET = 4000


def _order(
    passes: list[_Pass],
    start: NDArray[np.float64],
    router: Router,
    budget: int = ORDER_BUDGET,
    *,
    force_start: bool = True,
) -> tuple[list[int], list[int]]:
    """Order and driving option of every pass. With ``force_start`` the first is the pass and
    option whose entry (a lane end) is nearest ``start``; without, ``start`` only seeds the
    greedy order and the tour begins where it is shortest. The rest greedy, then 2-opt (at most
    ``budget`` orders evaluated) with the options chosen by dynamic programming."""
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

    def cost(order: list[int]) -> tuple[float, list[int]]:
        first = order[0]
        acc = dist[0, entry_idx[first]] + internal[first]
        if force_start:
            acc = acc + forced
        back = []
        for prev, cur in itertools.pairwise(order):
            trans = dist[np.ix_(exit_idx[prev], entry_idx[cur])] + acc[:, None]
            arg = np.argmin(trans, axis=0)
            back.append(arg)
            acc = trans[arg, np.arange(trans.shape[1])] + internal[cur]
        choice = [int(np.argmin(acc))]
        for arg in reversed(back):
            choice.append(int(arg[choice[-1]]))
        return float(acc.min()), choice[::-1]

    # Greedy nearest pass from the first pass's exit.
    remaining = set(range(len(passes))) - {first_pass}
    order: list[int] = [first_pass]
    here = exit_idx[first_pass][first_option : first_option + 1]
    while remaining:
        best = (math.inf, -1, -1)
        for candidate in remaining:
            d = dist[np.ix_(here, entry_idx[candidate])].min(axis=0)
            j = int(np.argmin(d))
            if d[j] < best[0]:
                best = (float(d[j]), candidate, j)
        order.append(best[1])
        remaining.discard(best[1])
        here = exit_idx[best[1]][best[2] : best[2] + 1]
    best_cost, choice = cost(order)
    # 2-opt within a budget of evaluated orders, not of seconds, so that the same input gives
    # the same plan on a busy machine and an idle one
    left = budget
    improved = len(order) > 2
    while improved and left > 0:
        improved = False
        for i in range(int(force_start), len(order) - 1):  # a forced first pass stays first
            for j in range(i + 1, len(order)):
                cand = order[:i] + order[i : j + 1][::-1] + order[j + 1 :]
                c, ch = cost(cand)
                left -= 1
                if c < best_cost - 1e-9:
                    order, best_cost, choice = cand, c, ch
                    improved = True
                if left <= 0:
                    break
            if left <= 0:
                break
    return order, choice


# -- plans ------------------------------------------------------------------------------------
def _check_float(name: str, value: Any, low: float | None = None) -> float:
    v = as_number(name, value)
    if not math.isfinite(v) or (low is not None and v < low):
        bound = "" if low is None else f" >= {low:g}"
        raise InvalidParameterError(f"{name} must be a finite number{bound}, got {value!r}")
    return v


def _extension_end(
    router: Router, p: NDArray[np.float64], q: NDArray[np.float64]
) -> NDArray[np.float64]:
    """``q``, or the point where ``p -> q`` first enters a hole (run-ins never enter holes)."""
    br, cls = router._pieces(p, q)
    bad = np.flatnonzero(cls == 1)
    if len(bad) == 0:
        return q
    return p + br[bad[0]] * (q - p)


def plan_region(
    region: Region | Polygon | ArrayLike,
    spacing: float,
    *,
    decompose_area: bool | Literal["auto"] = "auto",
    sweep: float | None = None,
    angle: float | None = None,
    offset: float | None = None,
    fitness: Any = None,
    n_angles: int = 90,
    n_offsets: int = 16,
    layout: Layout = "guaranteed",
    start: ArrayLike | None = None,
    turnaround: float = 0.0,
    reach: float | None = None,
    nadir_gap: float = 0.0,
    hole_passes: bool = True,
    ground_scale: float = 1.0,
    speed: float | None = None,
    turn_time: float = 0.0,
    area: float | None = None,
    min_width: float | None = None,
    merge_angle: float = math.radians(15.0),
) -> Plan:
    """Plan a concave area or an area with holes: lanes, hole passes, one connected path.

    Args:
        region: the area (plan units): a :class:`~boustro.regions.Region`, or a polygon.
        spacing: distance between lanes, > 0.
        decompose_area: ``"auto"`` (default): decompose into cells, each with its own
            optimised angle and offset, when that promises fewer turns (or, on a tie, less
            lane length) than one grid over the whole area (:func:`choose_sweep`'s estimate);
            ``True``: always decompose; ``False``: one grid over the whole area.
        sweep: sweep direction of the decomposition (radians); default: the best of
            :func:`choose_sweep`'s candidates.
        angle, offset: with ``decompose_area=False``, plan this grid instead of optimising
            (offset from the shell's vertex mean).
        fitness: the objective of the per-cell (or whole-area) optimisation (default Eq. 1 over
            segments).
        n_angles, n_offsets: grid of :func:`optimize_region`.
        layout: ``"guaranteed"`` (default; with hole passes, every point of the area is within
            ``reach`` of a lane across it or of a hole pass) or ``"chords"``.
        start: the path begins at the entry nearest this point of a chain of lanes (a chain
            starts at its first or last lane's ends); default: where the tour is shortest.
        turnaround: run-in / run-out beyond each lane end (shortened where it would enter a
            hole), plan units.
        reach: half-width of each lane's band (default ``spacing / 2``).
        nadir_gap: blind strip under the vehicle (not supported with hole passes).
        hole_passes: drive around every hole that cuts a lane (guaranteed layout only).
        ground_scale, speed, turn_time, area: as in :func:`boustro.plan.build_plan`.
        min_width: cells narrower than this across the sweep are merged into a neighbour
            (default two spacings), see :func:`decompose`.
        merge_angle: neighbouring cells whose optimised angles differ by less than this
            (radians, default 15 degrees) are merged and optimised again as one cell.

    Returns:
        a :class:`~boustro.plan.Plan` with ``region``, ``cells``, per-transect angles and
        roles; its ``polygon`` is the shell.

    Raises:
        InvalidParameterError: bad parameters. NoTransectError: nothing to plan.
    """
    r = as_region(region)
    s = check_spacing(spacing, extent=r.diameter)
    reach = s / 2 if reach is None else _check_float("reach", reach)
    if reach < s / 2 * (1 - 1e-12):
        raise InvalidParameterError(
            f"reach must be >= spacing / 2 = {s / 2:g} for the bands to tile the area, "
            f"got {reach:g}"
        )
    turnaround = _check_float("turnaround", turnaround, 0.0)
    nadir_gap = _check_float("nadir_gap", nadir_gap, 0.0)
    turn_time = _check_float("turn_time", turn_time, 0.0)
    ground_scale = _check_float("ground_scale", ground_scale)
    if ground_scale <= 0:
        raise InvalidParameterError(f"ground_scale must be > 0, got {ground_scale!r}")
    if speed is not None and _check_float("speed", speed) <= 0:
        raise InvalidParameterError(f"speed must be > 0, got {speed!r}")
    if layout not in ("guaranteed", "chords"):
        raise InvalidParameterError(f"layout must be 'guaranteed' or 'chords', got {layout!r}")
    if nadir_gap > 0 and r.n_holes and hole_passes and layout == "guaranteed":
        raise InvalidParameterError(
            "a nadir gap is not supported with holes: the passes around holes would not cover "
            "their own blind strip"
        )
    tol = _TOL * r.diameter
    notes: list[str] = []

    # Cells and their grids.
    if decompose_area not in (True, False, "auto"):
        raise InvalidParameterError(
            f"decompose_area must be True, False or 'auto', got {decompose_area!r}"
        )
    min_width = 2 * s if min_width is None else _check_float("min_width", min_width, 0.0)
    options = {"n_angles": n_angles, "n_offsets": n_offsets, "fitness": fitness}
    cell_regions: list[Region] = [r]
    optima: list[OptimizeResult | None] = [None]
    if angle is None:
        optima = [optimize_region(r, s, **options)]
    if decompose_area and not r.is_convex and angle is None:
        if sweep is None:
            sweep_angle, estimate = choose_sweep(
                r, s, min_width=min_width, merge_angle=merge_angle, fitness=fitness
            )
        else:
            sweep_angle, estimate = _check_float("sweep", sweep), (-math.inf, -math.inf)
        single = _estimate([r], optima, s)  # type: ignore[arg-type]
        if decompose_area is True or estimate < single:
            try:
                cell_regions, cells_opt = _cells_for_sweep(
                    r, s, sweep_angle, min_width=min_width, merge_angle=merge_angle, options=options
                )
            except InvalidPolygonError as exc:
                notes.append(f"the decomposition failed ({exc}); the area is planned as one cell")
                cell_regions, cells_opt = [r], optima  # type: ignore[assignment]
            if len(cell_regions) > 1 and (
                decompose_area is True or _estimate(cell_regions, cells_opt, s) < single
            ):
                optima = list(cells_opt)
            else:  # one cell after all: the whole area, as planned without decomposition
                cell_regions = [r]
    cells: list[PlanCell] = []
    lanes_by_cell: list[Lanes] = []
    for cell, opt in zip(cell_regions, optima, strict=True):
        if opt is None:
            cell_angle = _check_float("angle", angle)
            cell_offset = 0.0 if offset is None else _check_float("offset", offset)
            value = math.nan
        else:
            cell_angle, cell_offset, value = opt.angle, opt.offset, opt.fitness
        lanes = region_lanes(
            cell, s, cell_angle, cell_offset, reach=reach, holes=r.holes, layout=layout
        )
        lanes_by_cell.append(lanes)
        cells.append(PlanCell(cell, cell_angle, cell_offset, value, len(lanes.k), opt))
    if sum(len(lanes.k) for lanes in lanes_by_cell) == 0:
        raise NoTransectError(f"no lane crosses the area at spacing {s:g}")

    passes: list[_Pass] = []
    for ci, lanes in enumerate(lanes_by_cell):
        for chain in _chains(lanes, tol):
            passes.append(_chain_pass(lanes, chain, ci))
    cut = set().union(*(lanes.cut for lanes in lanes_by_cell))
    if layout == "guaranteed" and hole_passes:
        for hi in sorted(cut):
            passes.append(_hole_pass(r.holes[hi]))
    elif cut and layout == "guaranteed":
        notes.append(
            f"{len(cut)} hole(s) cut lanes and hole passes are off: the area along their edges "
            "is not fully covered"
        )

    router = Router(r, reach=max(reach, turnaround))
    force_start = start is not None
    if start is None:
        start_pt = r.shell.vertices[0]
    else:
        start_pt = np.asarray(start, dtype=np.float64).reshape(-1)
        if start_pt.shape != (2,) or not np.all(np.isfinite(start_pt)):
            raise InvalidParameterError(f"start must be a finite (x, y) pair, got {start!r}")
    order, choice = _order(passes, start_pt, router, force_start=force_start)

    # Waypoints.
    points: list[NDArray[np.float64]] = []
    kinds: list[str] = []
    lane_of: list[int] = []
    transects: list[NDArray[np.float64]] = []
    angles_t: list[float] = []
    roles: list[str] = []
    cells_t: list[int] = []
    positions: list[float] = []
    outside = 0.0
    hole_length = 0.0
    blocked: list[tuple[NDArray[np.float64], NDArray[np.float64]]] = []

    def move_to(target: NDArray[np.float64], next_transect: int) -> None:
        nonlocal outside
        if not points:
            return
        route = router.path(points[-1], target)
        outside += route.outside
        if not route.found:
            blocked.append((points[-1], target))
        for p in route.points[1:-1]:
            points.append(p)
            kinds.append("via")
            lane_of.append(next_transect)

    for pi, oi in zip(order, choice, strict=True):
        p = passes[pi]
        _, _, pts, _ = p.options[oi]
        if p.kind == "chain":
            u, n = _frame(p.angle)
            origin = lanes_by_cell[p.cell].origin
            for j in range(0, len(pts), 2):
                a, b = pts[j], pts[j + 1]
                ti = len(transects)
                d = b - a
                length = float(np.linalg.norm(d))
                direction = d / length if length > 0 else (u if j % 4 == 0 else -u)
                run_in = _extension_end(router, a, a - turnaround * direction) if turnaround else a
                move_to(run_in, ti)
                if turnaround:
                    points.append(run_in)
                    kinds.append("run_in")
                    lane_of.append(ti)
                points += [a, b]
                kinds += ["start", "end"]
                lane_of += [ti, ti]
                if turnaround:
                    points.append(_extension_end(router, b, b + turnaround * direction))
                    kinds.append("run_out")
                    lane_of.append(ti)
                transects.append(np.stack([a, b]))
                angles_t.append(p.angle)
                roles.append("lane")
                cells_t.append(p.cell)
                positions.append(float((a - origin) @ n))
        else:
            ti = len(transects)
            move_to(pts[0], ti)
            for j in range(len(pts) - 1):
                a, b = pts[j], pts[j + 1]
                transects.append(np.stack([a, b]))
                d = b - a
                angles_t.append(math.atan2(d[1], d[0]))
                roles.append("hole")
                cells_t.append(-1)
                positions.append(math.nan)
                hole_length += float(np.linalg.norm(d))
            points.append(pts[0])
            kinds.append("start")
            lane_of.append(ti)
            for j in range(1, len(pts) - 1):
                points.append(pts[j])
                kinds.append("loop")
                lane_of.append(ti + j)
            points.append(pts[-1])
            kinds.append("end")
            lane_of.append(ti + len(pts) - 2)
    assert set(kinds) <= set(KINDS)
    waypoints = np.asarray(points)
    tr = np.asarray(transects)
    lane_role = np.array(roles) == "lane"
    transect_length = float(np.linalg.norm(tr[:, 1] - tr[:, 0], axis=1)[lane_role].sum())
    path_length = float(np.linalg.norm(np.diff(waypoints, axis=0), axis=1).sum())
    n_lanes = int(lane_role.sum())
    n_turns = n_lanes + sum(1 for p in passes if p.kind == "hole") - 1  # passes - 1
    for a, b in blocked:
        notes.append(
            f"no connecting move inside the area from {a.round(3).tolist()} to "
            f"{b.round(3).tolist()}: the straight line is used"
        )
    duration = None if speed is None else path_length / ground_scale / speed + n_turns * turn_time
    stats = PlanStats(
        n_transects=n_lanes,
        n_turns=n_turns,
        transect_length=transect_length / ground_scale,
        path_length=path_length / ground_scale,
        area=r.area / ground_scale**2 if area is None else float(area),
        speed=speed,
        turn_time=turn_time,
        duration=duration,
        n_cells=len(cells),
        hole_pass_length=hole_length / ground_scale,
        outside_length=outside / ground_scale,
    )
    main = max(range(len(cells)), key=lambda i: cells[i].polygon.area)
    return Plan(
        polygon=r.shell,
        spacing=s,
        angle=cells[main].angle,
        offset=cells[main].offset,
        layout=layout,
        reach=float(reach),
        nadir_gap=nadir_gap,
        turnaround=turnaround,
        positions=np.asarray(positions),
        transects=tr,
        waypoints=waypoints,
        kinds=tuple(kinds),
        lane=np.asarray(lane_of, dtype=np.int64),
        ground_scale=ground_scale,
        stats=stats,
        region=r,
        cells=tuple(cells),
        transect_angles=np.asarray(angles_t),
        roles=tuple(roles),
        transect_cells=np.asarray(cells_t, dtype=np.int64),
        notes=tuple(notes),
    )
