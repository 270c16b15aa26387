"""Tracing the boundary of a union of trapezoids: its segments, nodes and rings, vectorised.

:func:`boustro.plan.cells.trace_region` turns a set of trapezoids of one slab decomposition
into the rings of their union. Its three steps, each ``O(m log m)`` in numpy for ``m``
boundary segments (the Python loops they replace were ``O(m)`` Python steps with a dict per
slab line, 65 ms per call on a 2000-vertex field, the largest cost of choosing a sweep):

* :func:`_segments`: the trapezoids' entry and exit edges (two per trapezoid, in the order of
  the members) and, on every slab line, the parts of the left trapezoids' intervals not covered
  by the right ones and vice versa (sorted interval differences, :func:`_minus`);
* :func:`_node_labels`: end points that differ by rounding only share a node (a grid of
  ``snap`` with neighbouring cells joined when their first points are within ``snap``: the
  same closure the loop computed);
* :func:`_cycles`: when every node has one segment in and one out, the rings are the cycles of
  the successor permutation, each started at its lowest segment (as the loop started them);
  otherwise (a union touching itself at a point) ``None``, and the caller takes the loops
  (:func:`_segments_loops`, :func:`_walk_loops`), which decide such nodes in segment order.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

__all__: list[str] = []


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


class _Members(NamedTuple):
    """The members' trapezoids: slab ends ``a, b``, entry ``te_*`` and exit ``tx_*`` at them."""

    a: NDArray[np.float64]
    b: NDArray[np.float64]
    te_a: NDArray[np.float64]
    te_b: NDArray[np.float64]
    tx_a: NDArray[np.float64]
    tx_b: NDArray[np.float64]


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


def _trapezoid_segments(m: _Members) -> NDArray[np.float64]:
    """``(2 Q, 4)``: each member's entry edge ``(a, te_a) -> (b, te_b)``, then its exit edge
    ``(b, tx_b) -> (a, tx_a)`` (the union on the left of each)."""
    seg = np.empty((2 * len(m.a), 4))
    seg[0::2] = np.stack([m.a, m.te_a, m.b, m.te_b], axis=1)
    seg[1::2] = np.stack([m.b, m.tx_b, m.a, m.tx_a], axis=1)
    return seg


def _segments_loops(m: _Members, tol: float) -> NDArray[np.float64]:
    """The boundary segments as the Python loops built them (the slab lines in set order)."""
    segs = [tuple(s) for s in _trapezoid_segments(m).tolist()]
    by_b: dict[float, list[tuple[float, float]]] = {}
    by_a: dict[float, list[tuple[float, float]]] = {}
    for i in range(len(m.a)):
        by_b.setdefault(float(m.b[i]), []).append((float(m.te_b[i]), float(m.tx_b[i])))
        by_a.setdefault(float(m.a[i]), []).append((float(m.te_a[i]), float(m.tx_a[i])))
    for line in set(by_a) | set(by_b):
        left, right = by_b.get(line, []), by_a.get(line, [])
        segs += [(line, lo, line, hi) for lo, hi in _interval_minus(left, right, tol)]
        segs += [(line, hi, line, lo) for lo, hi in _interval_minus(right, left, tol)]
    seg = np.array(segs, dtype=np.float64).reshape(-1, 4)
    return seg[np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1]) > tol]


def _minus(
    line_a: NDArray[np.float64],
    lo_a: NDArray[np.float64],
    hi_a: NDArray[np.float64],
    line_b: NDArray[np.float64],
    lo_b: NDArray[np.float64],
    hi_b: NDArray[np.float64],
    tol: float,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """``(line, lo, hi)``: on every line, each interval of ``a`` minus the union of the
    intervals of ``b`` on that line, the pieces longer than ``tol`` (ascending within an
    interval; the end points are the intervals' own numbers, as :func:`_interval_minus`'s).

    Exact: lines and positions are replaced by their ranks, so ``(line, position)`` pairs
    compare as integers; ``b`` is merged into disjoint intervals by a running maximum, and the
    merged intervals that overlap an interval of ``a`` are a run found by ``searchsorted``."""
    lines = np.unique(np.concatenate([line_a, line_b]))
    ts = np.unique(np.concatenate([lo_a, hi_a, lo_b, hi_b]))
    width = len(ts) + 1

    def key(line: NDArray[np.float64], t: NDArray[np.float64]) -> NDArray[np.int64]:
        return np.searchsorted(lines, line) * width + np.searchsorted(ts, t)

    order = np.lexsort((lo_b, line_b))
    klo, khi = key(line_b[order], lo_b[order]), key(line_b[order], hi_b[order])
    reach = np.maximum.accumulate(khi) if len(khi) else khi
    new = np.ones(len(klo), dtype=bool)
    new[1:] = klo[1:] > reach[:-1]  # a new line, or a gap after everything before it
    first = np.flatnonzero(new)
    last = np.append(first[1:] - 1, len(klo) - 1) if len(first) else first
    m_klo, m_khi = klo[first], reach[last]
    m_lo, m_hi = lo_b[order][first], ts[m_khi % width]
    j0 = np.searchsorted(m_khi, key(line_a, lo_a), side="right")
    j1 = np.searchsorted(m_klo, key(line_a, hi_a), side="left")
    cnt = np.maximum(j1 - j0, 0)
    # interval i gives cnt + 1 candidate pieces: [lo, m_lo[j0]], [m_hi[j], m_lo[j + 1]] ...,
    # [m_hi[j1 - 1], hi]
    n_piece = cnt + 1
    owner = np.repeat(np.arange(len(lo_a)), n_piece)
    rank = np.arange(int(n_piece.sum())) - np.repeat(np.cumsum(n_piece) - n_piece, n_piece)
    j = j0[owner] + rank  # the merged interval ending the piece (if rank < cnt)
    is_first, is_last = rank == 0, rank == cnt[owner]
    jj = np.minimum(j, max(len(m_lo) - 1, 0))
    jp = np.maximum(j - 1, 0)
    start = np.where(is_first, lo_a[owner], m_hi[jp] if len(m_hi) else 0.0)
    stop = np.where(is_last, hi_a[owner], m_lo[jj] if len(m_lo) else 0.0)
    keep = (stop > start) & (stop - start > tol)
    return line_a[owner][keep], start[keep], stop[keep]


def _segments(m: _Members, tol: float) -> NDArray[np.float64]:
    """The boundary segments: the trapezoids' edges as :func:`_segments_loops` (same indices),
    then the pieces of the slab lines (in another order)."""
    seg = _trapezoid_segments(m)
    left = (m.b, m.te_b, m.tx_b)  # the trapezoids ending at a line
    right = (m.a, m.te_a, m.tx_a)  # those starting there
    up_line, up_lo, up_hi = _minus(*left, *right, tol)
    down_line, down_lo, down_hi = _minus(*right, *left, tol)
    vertical = np.concatenate(
        [
            np.stack([up_line, up_lo, up_line, up_hi], axis=1),
            np.stack([down_line, down_hi, down_line, down_lo], axis=1),
        ]
    )
    seg = np.concatenate([seg, vertical])
    return seg[np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1]) > tol]


def _node_labels(ends: NDArray[np.float64], snap: float) -> NDArray[np.int64]:
    """A node label per end point: points in one grid cell of ``snap`` share it, and
    neighbouring cells whose first points are within ``snap`` (max norm) are joined."""
    key = np.floor(ends / snap)
    code = key[:, 0] + 1j * key[:, 1]  # complex numbers sort lexicographically
    cells, label = np.unique(code, return_inverse=True)
    label = label.ravel()
    first = np.zeros(len(cells), dtype=np.int64)
    first[label[::-1]] = np.arange(len(label))[::-1]
    pairs = []
    for off in (1 - 1j, 1 + 0j, 1 + 1j, 1j):
        pos = np.searchsorted(cells, cells + off)
        hit = np.flatnonzero(pos < len(cells))
        hit = hit[cells[pos[hit]] == cells[hit] + off]
        near = np.max(np.abs(ends[first[hit]] - ends[first[pos[hit]]]), axis=1) <= snap
        pairs += list(zip(hit[near].tolist(), pos[hit][near].tolist(), strict=True))
    if not pairs:
        return label.astype(np.int64)
    uf = _UnionFind(len(cells))
    for i, j in pairs:
        uf.union(i, j)
    root = np.arange(len(cells))
    touched = np.unique(np.array(pairs).ravel())
    root[touched] = [uf.find(int(i)) for i in touched]
    return root[label].astype(np.int64)


def _cycles(start: NDArray[np.int64], stop: NDArray[np.int64]) -> list[list[int]] | None:
    """The rings as lists of segment indices, each from its lowest index, in the order of
    those; ``None`` when some node has more or fewer than one segment in or out."""
    m = len(start)
    n = int(max(start.max(), stop.max())) + 1 if m else 0
    out_deg = np.bincount(start, minlength=n)
    in_deg = np.bincount(stop, minlength=n)
    if np.any(out_deg != in_deg) or np.any(out_deg > 1):
        return None
    pos = np.empty(n, dtype=np.int64)
    pos[start] = np.arange(m)
    nxt = pos[stop].tolist()
    used = bytearray(m)
    rings = []
    for k0 in range(m):
        if used[k0]:
            continue
        ring, k = [], k0
        while not used[k]:
            used[k] = 1
            ring.append(k)
            k = nxt[k]
        rings.append(ring)
    return rings


def _walk_loops(start: NDArray[np.int64], stop: NDArray[np.int64]) -> list[list[int]]:
    """The rings as the loop traced them: from each unused segment, the first unused segment
    leaving its end (segment order decides at a node with several)."""
    m = len(start)
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
            ring.append(k)
            nxt = [j for j in outgoing.get(int(stop[k]), []) if not used[j]]
            if not nxt:
                break
            k = nxt[0]
        rings.append(ring)
    return rings


def _ring_indices(
    m: _Members, tol: float, loops: bool = False
) -> tuple[NDArray[np.float64], list[list[int]]]:
    """``(segments, rings)``: the boundary segments and each ring's segments in order
    (``loops``: always as the loops traced them, for tests)."""
    snap = 0.1 * tol  # below the gap between distinct slab lines (> tol)
    seg = _segments(m, tol)
    n = len(seg)
    label = _node_labels(np.concatenate([seg[:, :2], seg[:, 2:]]), snap)
    rings = None if loops else _cycles(label[:n], label[n:])
    if rings is None:  # a node with several segments: the loops' order decides
        seg = _segments_loops(m, tol)
        n = len(seg)
        label = _node_labels(np.concatenate([seg[:, :2], seg[:, 2:]]), snap)
        rings = _walk_loops(label[:n], label[n:])
    return seg, rings
