"""Whether straight segments stay in a router's area, many at once.

A segment is visible when it properly crosses no ring edge and its midpoint lies in the closed
area; a segment that touches a ring vertex in its middle is decided piece by piece between the
breakpoints (:meth:`~boustro.plan.routing.Router.inside`, for all such segments at once:
:func:`~boustro.plan.straight_moves.inside_moves`). Up to
:data:`~boustro.plan.visibility_kernel.DENSE_EDGES` edges every pair is tested by a
compiled kernel; above, only the edges whose bounding box meets the segment's (the grid of
:mod:`~boustro.plan.edge_grid`; before it an STRtree, :func:`visible_tree`), with the same
arithmetic.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..geometry.polygon import _cross
from .edge_index import CHUNK
from .straight_moves import inside_moves
from .visibility_kernel import DENSE_EDGES, segment_crossings

__all__ = ["decide", "visible_many", "visible_tree"]


def visible_many(router: Any, a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Whether each segment ``a[i] -> b[i]`` stays in ``router``'s closed area, ``(M,)`` (a
    :class:`~boustro.plan.routing.Router`)."""
    m = len(a)
    if m == 0:
        return np.zeros(0, dtype=bool)
    if m > CHUNK:  # bounded memory: the candidate pairs in slices
        return np.concatenate(
            [visible_many(router, a[k : k + CHUNK], b[k : k + CHUNK]) for k in range(0, m, CHUNK)]
        )
    e1, e2 = router._e1, router._e2
    tol = router.tol
    if len(e1) <= DENSE_EDGES:  # compiled, every pair: the same tests as below
        hit, touched = segment_crossings(a, b, e1, e2, tol)
        return decide(router, a, b, ~hit, touched)
    hit, touched = router._index.grid.crossings(a, b, tol)  # the STRtree's candidates
    return decide(router, a, b, ~hit, touched)


def visible_tree(router: Any, a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.bool_]:
    """:func:`visible_many` above the dense edges by the STRtree's candidate pairs in
    numpy (before :mod:`~boustro.plan.edge_grid`; the reference of its tests)."""
    m = len(a)
    e1, e2 = router._e1, router._e2
    tol = router.tol
    mi, ei = router._index.box_pairs(np.minimum(a, b) - tol, np.maximum(a, b) + tol)
    pa, pb = a[mi], b[mi]
    q1, q2 = e1[ei], e2[ei]
    r = pb - pa
    s = q2 - q1
    rl = np.linalg.norm(r, axis=1)
    sl = np.linalg.norm(s, axis=1)

    def side(x: NDArray[np.float64], scale: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.where(np.abs(x) <= tol * scale, 0.0, np.sign(x))

    o1 = side(_cross(r, q1 - pa), rl)
    o2 = side(_cross(r, q2 - pa), rl)
    o3 = side(_cross(s, pa - q1), sl)
    o4 = side(_cross(s, pb - q1), sl)
    proper = ((o1 * o2) < 0) & ((o3 * o4) < 0)
    # A vertex touched in the middle of a segment: check every piece between such vertices.
    on = (
        (o1 == 0)
        & (np.einsum("ij,ij->i", q1 - pa, r) > tol * rl)
        & (np.einsum("ij,ij->i", q1 - pb, -r) > tol * rl)
    )
    ok = np.bincount(mi[proper], minlength=m) == 0
    touched = np.bincount(mi[on], minlength=m) > 0
    return decide(router, a, b, ok, touched)


def decide(
    router: Any,
    a: NDArray[np.float64],
    b: NDArray[np.float64],
    ok: NDArray[np.bool_],
    touched: NDArray[np.bool_],
) -> NDArray[np.bool_]:
    """Visibility of segments that cross no edge (``ok``): by the midpoint's class, or piece
    by piece where they touch a vertex."""
    m = len(a)
    simple = ok & ~touched
    res = np.zeros(m, dtype=bool)
    if simple.any():
        res[simple] = router.classify(((a + b) / 2)[simple]) == 0
    hard = np.flatnonzero(ok & touched)
    if len(hard):  # Router.inside of each, all at once (the same arithmetic)
        res[hard] = inside_moves(router, a[hard], b[hard])
    return res
