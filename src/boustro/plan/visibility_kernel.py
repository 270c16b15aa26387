"""Which segments cross a region's edges, and which points lie near them, compiled by numba on
first use.

For every segment ``a[i] -> b[i]`` and every edge whose bounding box meets the segment's
(grown by ``tol``; closed boxes, as the STRtree candidates of
:meth:`boustro.plan.edge_index.EdgeIndex.box_pairs`), the orientation tests of
:meth:`boustro.plan.routing.Router._visible_many` with the same floating-point operations in
the same order: whether the segment properly crosses an edge, and whether it touches an edge's
first vertex strictly between its ends; and whether points lie within a distance of an edge,
by :func:`boustro.geometry.region._point_segment_distance`'s arithmetic. Dense (every pair's
boxes compared), for areas of a few dozen edges (:data:`DENSE_EDGES`), where a grid of the
edges saves nothing. numba is imported on use; without it the plain Python loops run.
"""

from __future__ import annotations

import math
from collections.abc import MutableMapping
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._jit import compiled, jit_globals

__all__ = ["DENSE_EDGES", "HELPERS", "jit_into", "points_near", "segment_crossings"]

#: Areas with at most this many edges test every segment and point against every edge (above:
#: the grid of :mod:`~boustro.plan.edge_grid`, the same answers). 512 until the twelfth round;
#: measured on the time objective's 2000-vertex field with 10 holes, whose inner domains and
#: cells have up to 480 edges: segments (5170 calls, 2.55 million) 1.44 s against every edge,
#: 0.79 s through the grids (their building included); points (12 170 calls, 1.48 million)
#: 0.27 s against 0.11 s.
DENSE_EDGES = 64
#: The per-pair tests, shared with :mod:`~boustro.plan.edge_grid`'s kernels.
HELPERS = ("_side", "_contact", "_near_edge")


def _side(x, scale):
    """``0`` where ``|x| <= scale`` (on the line), else the sign of ``x``."""
    if abs(x) <= scale:
        return 0.0
    return 1.0 if x > 0 else -1.0


def _contact(pax, pay, pbx, pby, lox, hix, loy, hiy, rx, ry, rs, q1x, q1y, q2x, q2y, tol):
    """The segment ``p_a -> p_b`` (its box ``lo/hi`` grown by ``tol``, ``r = p_b - p_a``,
    ``rs = tol |r|``) against the edge ``q1 -> q2``: bit 1 a proper crossing, bit 2 the edge's
    first vertex touched strictly between the segment's ends (0 where the boxes miss)."""
    if min(q1x, q2x) > hix or max(q1x, q2x) < lox:
        return 0
    if min(q1y, q2y) > hiy or max(q1y, q2y) < loy:
        return 0
    sx, sy = q2x - q1x, q2y - q1y
    ss = tol * math.sqrt(sx * sx + sy * sy)
    o1 = _side(rx * (q1y - pay) - ry * (q1x - pax), rs)
    o2 = _side(rx * (q2y - pay) - ry * (q2x - pax), rs)
    o3 = _side(sx * (pay - q1y) - sy * (pax - q1x), ss)
    o4 = _side(sx * (pby - q1y) - sy * (pbx - q1x), ss)
    out = 0
    if o1 * o2 < 0 and o3 * o4 < 0:
        out |= 1
    if (
        o1 == 0
        and (q1x - pax) * rx + (q1y - pay) * ry > rs
        and (q1x - pbx) * -rx + (q1y - pby) * -ry > rs
    ):
        out |= 2
    return out


def _near_edge(px, py, ax, ay, bx, by, r, tiny):
    """Whether the point ``p`` lies within ``r`` of the edge ``a -> b`` (boxes grown by ``2 r``
    first: a point within ``r`` of the edge is inside them, rounding and all)."""
    abx, aby = bx - ax, by - ay
    if min(ax, ax + abx) > px + 2 * r or max(ax, ax + abx) < px - 2 * r:
        return False
    if min(ay, ay + aby) > py + 2 * r or max(ay, ay + aby) < py - 2 * r:
        return False
    den = max(abx * abx + aby * aby, tiny)
    t = min(max(((px - ax) * abx + (py - ay) * aby) / den, 0.0), 1.0)
    dx, dy = px - (ax + t * abx), py - (ay + t * aby)
    return math.sqrt(dx * dx + dy * dy) <= r


def _crossings(a, b, e1, e2, tol, proper, touched):
    for i in range(a.shape[0]):
        pax, pay, pbx, pby = a[i, 0], a[i, 1], b[i, 0], b[i, 1]
        lox, hix = min(pax, pbx) - tol, max(pax, pbx) + tol
        loy, hiy = min(pay, pby) - tol, max(pay, pby) + tol
        rx, ry = pbx - pax, pby - pay
        rs = tol * math.sqrt(rx * rx + ry * ry)
        for e in range(e1.shape[0]):
            hit = _contact(pax, pay, pbx, pby, lox, hix, loy, hiy, rx, ry, rs,
                           e1[e, 0], e1[e, 1], e2[e, 0], e2[e, 1], tol)  # fmt: skip
            if hit & 1:
                proper[i] = True
            if hit & 2:
                touched[i] = True


def _near(p, e1, e2, n_edges, r, tiny, out):
    for i in range(p.shape[0]):
        px, py = p[i, 0], p[i, 1]
        for e in range(n_edges):
            if _near_edge(px, py, e1[e, 0], e1[e, 1], e2[e, 0], e2[e, 1], r, tiny):
                out[i] = True
                break


@cache
def _compiled() -> Any:
    return compiled(globals(), ("_crossings", "_near"), HELPERS)


def jit_into(namespace: MutableMapping[str, Any]) -> None:
    """Swap :data:`HELPERS` for their compiled versions here (they call each other by name) and
    in ``namespace``, the globals of a kernel module that imported some of them
    (:mod:`~boustro.plan.edge_grid`)."""
    jit_globals(globals(), HELPERS)
    namespace.update({name: globals()[name] for name in HELPERS if name in namespace})


def segment_crossings(
    a: NDArray[np.float64],
    b: NDArray[np.float64],
    e1: NDArray[np.float64],
    e2: NDArray[np.float64],
    tol: float,
) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    """``(proper, touched)`` of the segments ``a[i] -> b[i]`` against the edges ``e1 -> e2``
    (module docstring), ``(M,)`` each."""
    m = len(a)
    proper = np.zeros(m, dtype=np.bool_)
    touched = np.zeros(m, dtype=np.bool_)
    _compiled()[0](
        np.ascontiguousarray(a, dtype=np.float64),
        np.ascontiguousarray(b, dtype=np.float64),
        np.ascontiguousarray(e1, dtype=np.float64),
        np.ascontiguousarray(e2, dtype=np.float64),
        float(tol),
        proper,
        touched,
    )
    return proper, touched


def points_near(
    p: NDArray[np.float64], e1: NDArray[np.float64], e2: NDArray[np.float64], r: float
) -> NDArray[np.bool_]:
    """``(P,)``: whether each point lies within ``r`` of an edge ``e1[k] -> e2[k]``."""
    out = np.zeros(len(p), dtype=np.bool_)
    _compiled()[1](
        np.ascontiguousarray(p, dtype=np.float64),
        np.ascontiguousarray(e1, dtype=np.float64),
        np.ascontiguousarray(e2, dtype=np.float64),
        len(e1),
        float(r),
        float(np.finfo(np.float64).tiny),
        out,
    )
    return out
