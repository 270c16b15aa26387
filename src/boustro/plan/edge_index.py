"""The edges of a region in a GEOS STRtree: which edges a segment or a point may touch, and
which points lie in the area, without a dense ``(points x edges)`` test.

The tree only proposes candidates (bounding boxes that meet); every decision is then taken by
the same floating-point arithmetic as the dense tests it replaces, on the candidate pairs, so
the answers are identical and the work is ``O((P + candidates) log E)`` instead of ``P E``.
shapely is imported on use (``import boustro`` does not load it).
"""

from __future__ import annotations

from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..geometry.region import Region, _point_segment_distance
from .edge_grid import EdgeGrid
from .visibility_kernel import DENSE_EDGES, points_near

__all__ = ["CHUNK", "EdgeIndex"]

#: Segments (or points) queried at once: bounds the memory of the candidate pairs.
CHUNK = 1 << 14


class EdgeIndex:
    """A region's ring edges in an STRtree, and its rings as prepared GEOS polygons.

    Args:
        region: the area; its edges are ``region.edges`` (the area on their left).
        tol: distances up to ``tol`` count as touching (the caller's tolerance).
    """

    def __init__(self, region: Region, tol: float) -> None:
        import shapely

        e = region.edges
        self.e1, self.e2 = np.ascontiguousarray(e[:, 0]), np.ascontiguousarray(e[:, 1])
        self.tol = float(tol)
        lo, hi = np.minimum(self.e1, self.e2), np.maximum(self.e1, self.e2)
        self.tree = shapely.STRtree(shapely.box(lo[:, 0], lo[:, 1], hi[:, 0], hi[:, 1]))
        self.shell: Any = shapely.Polygon(region.shell.vertices)
        self.holes: list[Any] = [shapely.Polygon(h.vertices) for h in region.holes]
        shapely.prepare(self.shell)
        shapely.prepare(self.holes)
        # the holes' bounding boxes (H, 4): a hole is asked only about the points in its box
        self.hole_boxes = np.array(
            [[*h.vertices.min(axis=0), *h.vertices.max(axis=0)] for h in region.holes]
        ).reshape(-1, 4)

    @cached_property
    def grid(self) -> EdgeGrid:
        """The edges in a uniform grid (:mod:`~boustro.plan.edge_grid`), built on first use."""
        return EdgeGrid(self.e1, self.e2)

    def box_pairs(
        self, lo: NDArray[np.float64], hi: NDArray[np.float64]
    ) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        """``(i, e)``: every box ``lo[i] .. hi[i]`` and edge ``e`` whose bounding boxes meet
        (closed boxes; sorted by ``i``)."""
        import shapely

        if len(lo) == 0:
            return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
        parts_i, parts_e = [], []
        for k in range(0, len(lo), CHUNK):
            a, b = lo[k : k + CHUNK], hi[k : k + CHUNK]
            boxes = shapely.box(a[:, 0], a[:, 1], b[:, 0], b[:, 1])
            i, e = self.tree.query(boxes)
            parts_i.append(i.astype(np.int64) + k)
            parts_e.append(e.astype(np.int64))
        i, e = np.concatenate(parts_i), np.concatenate(parts_e)
        order = np.lexsort((e, i))
        return i[order], e[order]

    def near(self, p: NDArray[np.float64]) -> NDArray[np.bool_]:
        """``(P,)``: whether each point is within ``tol`` of an edge."""
        if len(self.e1) <= DENSE_EDGES:  # compiled, every pair: the same decisions
            return points_near(p, self.e1, self.e2, self.tol)
        return self.grid.near(p, self.tol, len(self.e1))  # compiled, the grid's candidates

    def within(self, p: NDArray[np.float64], r: float, n_edges: int) -> NDArray[np.bool_]:
        """``(P,)``: whether each point is within ``r`` of one of the first ``n_edges`` edges
        (the shell's)."""
        if len(self.e1) <= DENSE_EDGES:
            return points_near(p, self.e1[:n_edges], self.e2[:n_edges], r)
        return self.grid.near(p, r, n_edges)

    def near_tree(
        self, p: NDArray[np.float64], r: float, n_edges: int, pad: float
    ) -> NDArray[np.bool_]:
        """:meth:`within` by the STRtree's candidates (boxes grown by ``pad``) in numpy: what
        :meth:`near` (``pad = 2 tol``) and :meth:`within` (``pad = r (1 + 1e-6) + tol``) did
        before the grid (:mod:`~boustro.plan.edge_grid`), the reference of its tests."""
        i, e = self.box_pairs(p - pad, p + pad)
        keep = e < n_edges
        i, e = i[keep], e[keep]
        out = np.zeros(len(p), dtype=bool)
        if len(i):
            d = _point_segment_distance(p[i], self.e1[e], self.e2[e])
            out[i[d <= r]] = True
        return out

    def classify(self, p: NDArray[np.float64]) -> NDArray[np.int64]:
        """``(P,)``: 0 in the closed area (or within ``tol`` of its boundary), 1 strictly
        inside a hole, 2 strictly outside the shell."""
        import shapely

        out = np.zeros(len(p), dtype=np.int64)
        if len(p) == 0:
            return out
        far = ~self.near(p)
        x, y = p[:, 0], p[:, 1]
        out[far & ~shapely.contains_xy(self.shell, x, y)] = 2
        if not self.holes:
            return out
        b = self.hole_boxes
        boxed = (
            far[:, None]
            & (x[:, None] >= b[None, :, 0])
            & (y[:, None] >= b[None, :, 1])
            & (x[:, None] <= b[None, :, 2])
            & (y[:, None] <= b[None, :, 3])
        )  # (P, H): a point outside a hole's box is not in it
        for k in np.flatnonzero(boxed.any(axis=0)):
            sel = np.flatnonzero(boxed[:, k])
            out[sel[shapely.contains_xy(self.holes[k], x[sel], y[sel])]] = 1
        return out
