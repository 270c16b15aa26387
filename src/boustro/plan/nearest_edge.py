"""The nearest point of a region's boundary to points outside it (:meth:`Router.anchor
<boustro.plan.routing.Router.anchor>`), over every edge or over an STRtree's candidates.

Both give the same point, bit for bit: the candidates are the edges whose bounding boxes lie
within ``d1`` of the point, ``d1`` the distance to the edge of the nearest box (at least the
nearest distance), so they hold the nearest edge and all its ties; each distance is computed
with the same arithmetic, and ties go to the first edge, as over every edge. shapely is
imported on use.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .edge_index import EdgeIndex

__all__ = ["DENSE_ANCHOR", "edge_feet", "index_feet", "nearest_feet", "pair_feet"]

#: Edges up to which :meth:`Router.anchor` measures every edge (above: an STRtree first).
DENSE_ANCHOR = 256


def edge_feet(
    q: NDArray[np.float64], e1: NDArray[np.float64], e2: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(foot (P, E, 2), distance (P, E))``: the nearest point of each edge to each point."""
    ab = e2 - e1
    den = np.maximum(np.einsum("ij,ij->i", ab, ab), np.finfo(np.float64).tiny)
    t = np.clip(np.einsum("pij,ij->pi", q[:, None] - e1[None], ab) / den, 0, 1)
    foot = e1[None] + t[..., None] * ab[None]
    return foot, np.linalg.norm(foot - q[:, None], axis=-1)


def pair_feet(
    q: NDArray[np.float64], e1: NDArray[np.float64], e2: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """:func:`edge_feet` of the pairs point ``q[i]``, edge ``i`` (the same arithmetic):
    ``(M, 2)``, ``(M,)``."""
    ab = e2 - e1
    den = np.maximum(np.einsum("ij,ij->i", ab, ab), np.finfo(np.float64).tiny)
    t = np.clip(np.einsum("ij,ij->i", q - e1, ab) / den, 0, 1)
    foot = e1 + t[:, None] * ab
    return foot, np.linalg.norm(foot - q, axis=-1)


def nearest_feet(
    q: NDArray[np.float64], e1: NDArray[np.float64], e2: NDArray[np.float64]
) -> NDArray[np.float64]:
    """``(P, 2)``: each point's nearest point of the edges (ties: the first edge)."""
    foot, dist = edge_feet(q, e1, e2)
    k = np.argmin(dist, axis=1)
    return foot[np.arange(len(q)), k]


def index_feet(index: EdgeIndex, q: NDArray[np.float64]) -> NDArray[np.float64]:
    """:func:`nearest_feet` of the points ``q`` over the index's edges, computed on the
    candidates of its STRtree (module docstring)."""
    import shapely

    e1, e2 = index.e1, index.e2
    qi, qe = index.tree.query_nearest(shapely.points(q))
    d1 = np.full(len(q), np.inf)
    np.minimum.at(d1, qi, pair_feet(q[qi], e1[qe], e2[qe])[1])
    pad = (d1 * (1 + 1e-9) + index.tol)[:, None]
    i, e = index.box_pairs(q - pad, q + pad)
    foot, dist = pair_feet(q[i], e1[e], e2[e])
    pick = np.lexsort((e, dist, i))  # by point, nearest first, ties: the first edge
    first = np.ones(len(pick), dtype=bool)
    first[1:] = i[pick][1:] != i[pick][:-1]
    out = np.full_like(q, np.nan)  # a point without a candidate (NaN): NaN, as every edge
    out[i[pick][first]] = foot[pick][first]
    return out
