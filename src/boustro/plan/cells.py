"""Boustrophedon cellular decomposition: trapezoids, cells, :func:`decompose`."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validate import as_number
from ..errors import InvalidParameterError, InvalidPolygonError
from ..geometry import Polygon
from ..geometry.region import Region, as_region, points_in_ring
from .cell_merge import _merge_narrow
from .cell_trace import _Members, _ring_indices, _UnionFind

__all__ = [
    "Decomposition",
    "Trapezoids",
    "decompose",
    "slab_decomposition",
    "trace_region",
    "trapezoids",
]


#: Relative tolerance (to the area's diameter) for coincident slab lines and overlaps.
_TOL = 1e-9


def _frame(angle: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    u = np.array([math.cos(angle), math.sin(angle)])
    return u, np.array([-u[1], u[0]])


def _check_float(name: str, value: Any, low: float | None = None) -> float:
    v = as_number(name, value)
    if not math.isfinite(v) or (low is not None and v < low):
        bound = "" if low is None else f" >= {low:g}"
        raise InvalidParameterError(f"{name} must be a finite number{bound}, got {value!r}")
    return v


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


def _crossing_pairs(
    edges: NDArray[np.float64], u: NDArray[np.float64], n: NDArray[np.float64], c: ArrayLike
) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.int64]]:
    """Every crossing of lines ``n . p = c`` with ``edges (E, 2, 2)`` as ``(line, t, edge)``,
    sorted by line, then ``t``, then edge: a sweep (each edge spans a run of the sorted lines),
    ``O((E + K) log K + crossings)``, never the dense ``(K, E)`` test."""
    c = np.asarray(c, dtype=np.float64).reshape(-1)
    c1, c2 = edges[:, 0] @ n, edges[:, 1] @ n
    t1, t2 = edges[:, 0] @ u, edges[:, 1] @ u
    order = np.argsort(c, kind="stable")
    cs = c[order]
    # line c crosses edge i iff (c1 <= c) != (c2 <= c), i.e. min(c1, c2) <= c < max(c1, c2)
    first = np.searchsorted(cs, np.minimum(c1, c2), side="left")
    last = np.searchsorted(cs, np.maximum(c1, c2), side="left")
    counts = np.maximum(last - first, 0)
    edge = np.repeat(np.arange(len(c1)), counts)
    start = np.repeat(np.cumsum(counts) - counts, counts)
    line = order[np.repeat(first, counts) + (np.arange(len(edge)) - start)]
    dc = c2 - c1
    slope = (t2 - t1) / np.where(dc == 0, 1.0, dc)
    t = t1[edge] + (c[line] - c1[edge]) * slope[edge]
    by = np.lexsort((edge, t, line))
    return line[by].astype(np.int64), t[by], edge[by].astype(np.int64)


def _crossings(
    edges: NDArray[np.float64], u: NDArray[np.float64], n: NDArray[np.float64], c: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.int64]]:
    """Sorted crossings of lines ``n . p = c`` with ``edges (E, 2, 2)``: ``(t, edge, count)``
    with ``t, edge`` ``(K, W)`` (``W`` the most crossings of a line; padded with inf / -1)
    and ``count (K,)``."""
    k = np.asarray(c, dtype=np.float64).reshape(-1).shape[0]
    line, t_pairs, e_pairs = _crossing_pairs(edges, u, n, c)
    count = np.bincount(line, minlength=k).astype(np.int64)
    width = int(count.max()) if k else 0
    slot = np.arange(len(line)) - np.repeat(np.cumsum(count) - count, count)
    t = np.full((k, width), np.inf)
    edge = np.full((k, width), -1, dtype=np.int64)
    t[line, slot] = t_pairs
    edge[line, slot] = e_pairs
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

    t_lo, t_hi = np.minimum(t1, t2), np.maximum(t1, t2)

    def t_at(j: NDArray[np.int64], c: NDArray[np.float64]) -> NDArray[np.float64]:
        # within the edge: a slab whose end merged a vertex event within tol would otherwise
        # extend an edge almost along the lines far past its end (a lane across a 5 mm slit)
        return np.clip(t1[j] + (c - c1[j]) * slope[j], t_lo[j], t_hi[j])

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
    m = _Members(tr.a[idx], tr.b[idx], tr.te_a[idx], tr.te_b[idx], tr.tx_a[idx], tr.tx_b[idx])
    seg, ring_indices = _ring_indices(m, tol)
    rings = []
    for ring in ring_indices:
        cs, ts = seg[ring, 0], seg[ring, 1]
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
    """Trapezoids touching across slab lines: ``(overlap, lower, upper, one-to-one)``, ordered
    by the lower trapezoid, then the upper one.

    A sweep: the trapezoids of a slab are ordered along the lines, so the upper trapezoids
    that may overlap a lower one are a run of the next slab, found by ``searchsorted`` on
    ``(slab, t)`` keys (complex numbers sort lexicographically; the run is widened by two each
    side against rounding), then tested with the dense code's arithmetic. ``O(Q log Q +
    candidates)`` instead of a ``(lower, upper)`` matrix per slab in a Python loop."""
    q = len(tr.a)
    if q == 0:
        return []
    slab = tr.slab
    n_slab = int(slab.max()) + 1
    bounds = np.searchsorted(slab, np.arange(n_slab + 2))  # trapezoids of slab s: [b[s], b[s+1])
    up_lo, up_hi = bounds[np.minimum(slab + 1, n_slab)], bounds[np.minimum(slab + 2, n_slab + 1)]
    key_te, key_tx = slab + 1j * tr.te_a, slab + 1j * tr.tx_a
    j0 = np.searchsorted(key_tx, (slab + 1) + 1j * tr.te_b, side="right") - 2
    j1 = np.searchsorted(key_te, (slab + 1) + 1j * tr.tx_b, side="left") + 2
    j0, j1 = np.maximum(j0, up_lo), np.minimum(j1, up_hi)
    cnt = np.maximum(j1 - j0, 0)
    lower = np.repeat(np.arange(q), cnt)
    upper = j0[lower] + np.arange(len(lower)) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    lo = np.maximum(tr.te_b[lower], tr.te_a[upper])
    hi = np.minimum(tr.tx_b[lower], tr.tx_a[upper])
    overlap = hi - lo
    touching = overlap > tol
    lower, upper, overlap = lower[touching], upper[touching], overlap[touching]
    single = (np.bincount(lower, minlength=q)[lower] == 1) & (
        np.bincount(upper, minlength=q)[upper] == 1
    )
    return list(zip(overlap.tolist(), lower.tolist(), upper.tolist(), single.tolist(), strict=True))


def _membership(tr: Trapezoids, roots: list[int]) -> NDArray[np.int64]:
    """The cell of every trapezoid, cells ordered by their lowest slab, then along the lines."""
    labels = np.array(roots, dtype=np.int64)
    _, membership = np.unique(labels, return_inverse=True)
    n_cells = int(membership.max()) + 1 if len(roots) else 0
    first = [np.flatnonzero(membership == k)[0] for k in range(n_cells)]
    rank = np.lexsort(([tr.te_a[i] for i in first], [tr.slab[i] for i in first]))
    remap = np.empty_like(rank)
    remap[rank] = np.arange(n_cells)
    return remap[membership]


def _shared_lengths(
    links: list[tuple[float, int, int, bool]], membership: NDArray[np.int64], n_cells: int
) -> NDArray[np.float64]:
    """``(C, C)`` length of the boundary each pair of cells shares."""
    shared_m = np.zeros((n_cells, n_cells))
    for overlap, i, j, _ in links:
        ci, cj = membership[i], membership[j]
        if ci != cj:
            shared_m[ci, cj] += overlap
            shared_m[cj, ci] += overlap
    return shared_m


def _extents(
    tr: Trapezoids, roots: list[int]
) -> tuple[dict[int, int], dict[int, int], dict[int, float], dict[int, float]]:
    """Per root: its top and bottom slab and its extent ``[lo, hi]`` across the lines."""
    r = np.asarray(roots, dtype=np.int64)
    u, inv = np.unique(r, return_inverse=True)
    inv = inv.ravel()
    top = np.full(len(u), np.iinfo(np.int64).min)
    bottom = np.full(len(u), np.iinfo(np.int64).max)
    lo, hi = np.full(len(u), np.inf), np.full(len(u), -np.inf)
    np.maximum.at(top, inv, tr.slab)
    np.minimum.at(bottom, inv, tr.slab)
    np.minimum.at(lo, inv, tr.a)
    np.maximum.at(hi, inv, tr.b)
    keys = u.tolist()
    return (
        dict(zip(keys, top.tolist(), strict=True)),
        dict(zip(keys, bottom.tolist(), strict=True)),
        dict(zip(keys, lo.tolist(), strict=True)),
        dict(zip(keys, hi.tolist(), strict=True)),
    )


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

    Example:
        >>> u_shape = [(0, 0), (9, 0), (9, 9), (6, 9), (6, 3), (3, 3), (3, 9), (0, 9)]
        >>> [round(cell.area, 3) for cell in decompose(u_shape, 0.0).cells]
        [45.0, 18.0]
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
    top, bottom, lo_c, hi_c = _extents(tr, [uf.find(i) for i in range(q)])

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
        _merge_narrow(links, uf, q, lambda rt: hi_c[rt] - lo_c[rt], join, min_width)
    membership = _membership(tr, [uf.find(i) for i in range(q)])
    n_cells = int(membership.max()) + 1 if q else 0
    lo = np.full(n_cells, np.inf)
    hi = np.full(n_cells, -np.inf)
    np.minimum.at(lo, membership, tr.a)
    np.maximum.at(hi, membership, tr.b)
    shared_m = _shared_lengths(links, membership, n_cells)
    cells: tuple[Region, ...] = ()
    if polygons:
        cells = tuple(
            trace_region(tr, np.flatnonzero(membership == k), r.diameter) for k in range(n_cells)
        )
    return Decomposition(float(sweep), cells, tr, membership, hi - lo, shared_m)


def slab_decomposition(region: Region | Polygon | ArrayLike, sweep: float) -> Decomposition:
    """Every trapezoid of the slab decomposition (:func:`trapezoids`) its own cell: the
    finest decomposition at ``sweep``, cut at every vertex (an L-shape: its two arms)."""
    r = as_region(region)
    tr = trapezoids(r, sweep)
    q = len(tr.a)
    links = _links(tr, _TOL * r.diameter)
    membership = np.arange(q, dtype=np.int64)
    cells = tuple(trace_region(tr, [k], r.diameter) for k in range(q))
    shared_m = _shared_lengths(links, membership, q)
    return Decomposition(float(sweep), cells, tr, membership, tr.b - tr.a, shared_m)


#: Grid of the quick optimisations that compare sweep directions (:func:`choose_sweep`).
