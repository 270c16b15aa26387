"""Segments against a region's edges through a uniform grid of the edges, compiled by numba.

Above :data:`~boustro.plan.visibility_kernel.DENSE_EDGES` edges the router's segment test
(:func:`~boustro.plan.route_visibility.visible_many`) asked a GEOS STRtree for the edges whose
bounding box meets each segment's, then ran the orientation tests on those pairs in numpy: on
a traced field the query (building a box a segment, the tree walk, sorting the pairs) cost as
much as the tests. Here the edges are registered in the cells of a grid over their bounding
boxes (about one cell an edge), and a compiled loop visits, for each segment, the edges of the
cells its box (grown by ``tol``) covers, each edge once, and keeps exactly the edges whose
closed box meets the segment's (the STRtree's candidates: a box that meets another shares a
cell with it, the cell index being monotone in the coordinate); the tests on them are
:func:`~boustro.plan.visibility_kernel.segment_crossings`' (the same floating-point operations
in the same order as the numpy tests), so the answers are identical. Memory ``O(E + cells)``.
Points near the edges (:meth:`EdgeGrid.near`, the class of a point) are found the same way,
with :func:`~boustro.plan.visibility_kernel.points_near`'s arithmetic. numba is imported on
use; without it the plain Python loops run.
"""

from __future__ import annotations

import math
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._jit import compiled
from .visibility_kernel import _contact, _near_edge, jit_into

__all__ = ["EdgeGrid"]


def _cell(x, x0, inv, n):
    """The grid index of coordinate ``x`` (clipped to ``0 .. n - 1``, NaN to 0; monotone in
    ``x``)."""
    k = (x - x0) * inv
    if not k >= 0.0:
        return 0
    if k >= n - 1:
        return n - 1
    return math.floor(k)


def _grid_crossings(a, b, e1, e2, tol, x0, y0, inv, nx, ny, start, items, seen, proper, touched):
    for i in range(a.shape[0]):
        pax, pay, pbx, pby = a[i, 0], a[i, 1], b[i, 0], b[i, 1]
        lox, hix = min(pax, pbx) - tol, max(pax, pbx) + tol
        loy, hiy = min(pay, pby) - tol, max(pay, pby) + tol
        rx, ry = pbx - pax, pby - pay
        rs = tol * math.sqrt(rx * rx + ry * ry)
        for cx in range(_cell(lox, x0, inv, nx), _cell(hix, x0, inv, nx) + 1):
            for cy in range(_cell(loy, y0, inv, ny), _cell(hiy, y0, inv, ny) + 1):
                c = cx * ny + cy
                for k in range(start[c], start[c + 1]):
                    e = items[k]
                    if seen[e] == i:
                        continue
                    seen[e] = i
                    hit = _contact(pax, pay, pbx, pby, lox, hix, loy, hiy, rx, ry, rs,
                                   e1[e, 0], e1[e, 1], e2[e, 0], e2[e, 1], tol)  # fmt: skip
                    if hit & 1:
                        proper[i] = True
                    if hit & 2:
                        touched[i] = True


def _grid_near(p, e1, e2, n_edges, r, tiny, x0, y0, inv, nx, ny, start, items, seen, out):
    for i in range(p.shape[0]):
        px, py = p[i, 0], p[i, 1]
        for cx in range(_cell(px - 2 * r, x0, inv, nx), _cell(px + 2 * r, x0, inv, nx) + 1):
            for cy in range(_cell(py - 2 * r, y0, inv, ny), _cell(py + 2 * r, y0, inv, ny) + 1):
                c = cx * ny + cy
                for k in range(start[c], start[c + 1]):
                    e = items[k]
                    if e >= n_edges or seen[e] == i:
                        continue
                    seen[e] = i
                    if _near_edge(px, py, e1[e, 0], e1[e, 1], e2[e, 0], e2[e, 1], r, tiny):
                        out[i] = True


@cache
def _compiled() -> Any:
    return compiled(
        globals(), ("_grid_crossings", "_grid_near"), ("_cell",), [lambda: jit_into(globals())]
    )


class EdgeGrid:
    """The edges ``e1[k] -> e2[k]`` registered in the cells of a uniform grid (module
    docstring)."""

    def __init__(self, e1: NDArray[np.float64], e2: NDArray[np.float64]) -> None:
        self.e1 = np.ascontiguousarray(e1, dtype=np.float64)
        self.e2 = np.ascontiguousarray(e2, dtype=np.float64)
        lo, hi = np.minimum(self.e1, self.e2), np.maximum(self.e1, self.e2)
        self.x0, self.y0 = float(lo[:, 0].min()), float(lo[:, 1].min())
        w = max(float(hi[:, 0].max()) - self.x0, float(hi[:, 1].max()) - self.y0, 1e-300)
        n = max(1, min(1024, math.ceil(math.sqrt(len(self.e1)))))  # about an edge a cell
        while True:  # long edges cover many cells: a coarser grid past 32 cells an edge
            self.inv = n / w
            origin = np.array([self.x0, self.y0])
            first = np.floor((lo - origin) * self.inv).clip(0, n - 1).astype(np.int64)
            last = np.floor((hi - origin) * self.inv).clip(0, n - 1).astype(np.int64)
            wide, high = last[:, 0] - first[:, 0] + 1, last[:, 1] - first[:, 1] + 1
            count = wide * high
            if n == 1 or int(count.sum()) <= 32 * len(self.e1):
                break
            n //= 2
        self.nx = self.ny = n
        owner = np.repeat(np.arange(len(self.e1)), count)  # each edge's cells, edge by edge
        k = np.arange(len(owner)) - np.repeat(np.cumsum(count) - count, count)
        cell = (first[owner, 0] + k // high[owner]) * n + first[owner, 1] + k % high[owner]
        order = np.argsort(cell, kind="stable")  # by cell, then edge
        self.items = owner[order].astype(np.int64)
        counts = np.bincount(cell, minlength=n * n)
        self.start = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)

    def crossings(
        self, a: NDArray[np.float64], b: NDArray[np.float64], tol: float
    ) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
        """``(proper, touched)`` of the segments ``a[i] -> b[i]`` as
        :func:`~boustro.plan.visibility_kernel.segment_crossings`, ``(M,)`` each."""
        m = len(a)
        proper = np.zeros(m, dtype=np.bool_)
        touched = np.zeros(m, dtype=np.bool_)
        seen = np.full(len(self.e1), -1, dtype=np.int64)
        _compiled()[0](
            np.ascontiguousarray(a, dtype=np.float64),
            np.ascontiguousarray(b, dtype=np.float64),
            self.e1,
            self.e2,
            float(tol),
            self.x0,
            self.y0,
            self.inv,
            self.nx,
            self.ny,
            self.start,
            self.items,
            seen,
            proper,
            touched,
        )
        return proper, touched

    def near(self, p: NDArray[np.float64], r: float, n_edges: int) -> NDArray[np.bool_]:
        """``(P,)``: whether each point lies within ``r`` of one of the first ``n_edges`` edges,
        as :func:`~boustro.plan.visibility_kernel.points_near` (the same arithmetic; the grid
        only skips edges whose box, grown by ``2 r``, misses the point)."""
        out = np.zeros(len(p), dtype=np.bool_)
        seen = np.full(len(self.e1), -1, dtype=np.int64)
        _compiled()[1](
            np.ascontiguousarray(p, dtype=np.float64),
            self.e1,
            self.e2,
            int(n_edges),
            float(r),
            float(np.finfo(np.float64).tiny),
            self.x0,
            self.y0,
            self.inv,
            self.nx,
            self.ny,
            self.start,
            self.items,
            seen,
            out,
        )
        return out
