"""Walls inside the holes: segments that no connecting move of any plan of a box crosses
(docs/mission_time.md, "The tour's 1-tree").

Every area ``S`` of a box is the area moved rigidly, its points by at most ``eps``, so each of
its holes holds the original hole eroded by ``eps``, and the sandwich's outer set's holes (the
area dilated with mitred joins) lie inside those erosions. A segment inside such a hole ring
(closed) is inside every ``S``'s hole. A connecting move (routed around the holes), a lane (cut
at the holes), a run-in (cut where it would enter one), a vehicle's driven turn (replaced by a
routed move where it would enter one) and a pass around a hole never enter a hole, so they never
cross such a wall: crossing it at a point of the hole's interior enters the hole, and at a
point of its boundary too (a simple ring lies on the far side there).

The walls of a ring are the edges and the inner diagonals of the ring *inset* by
:data:`WALL_INSET` of the set's extent (shapely's mitred ``buffer(-inset)`` of the hole, each
segment checked to lie inside the hole itself), the :data:`WALLS_PER_RING` longest (listed in shells
of decreasing length, not all ``n^2`` pairs: :func:`_ring_walls`); the ring itself where the
inset leaves nothing. Inset, because a lane cut at a hole ends on its ring: a
move between the two lanes a hole splits (its chord through the hole) meets the ring's own
edges only at its ends, which is no proper crossing (:func:`~.one_tree._crosses` needs room), so
with the ring's own edges a triangular hole gave no detour at all (twelfth round: random area 0
of ``benchmarks/mission_time.py``, a move of 8.2 m straight and 18.7 m around the hole, bounded
8.2 m; docs/mission_time.md, "Walls inset into the holes"). An inset edge lies strictly inside
the hole, so such a chord crosses it properly, and the detour past its ends is the way around
the hole's corner, short of it by the inset only.

**Walls outside the shell** (:func:`shell_walls`, where the search is told ``outside``: how far
from the area any point of a plan lies; ``plan_cover`` passes it without a vehicle's turns,
headland passes or keep-inside). A lane lies within its reach of the area (it spans its band's
projection), a run-in within the reach plus the run-in, a straight connecting move within the
router's allowance (``max(reach, run-in)`` at points a sixteenth of it apart), a routed one
inside the area, or in the shell grown by that allowance where shorter, each of its segments
passing the straight move's test (:mod:`boustro.plan.route_grown`: so within the same
allowance, never in a hole), and a hole pass inside the area; a move the router found no way
for voids the certificate. Every
area ``S`` of a box lies in the outer set, so every plan of the box lies within ``outside`` of
the outer set. The pockets of the outer set's shells dilated by ``outside`` (shapely's mitred
dilation, which holds the round one: the parts of its convex hull outside it) lie farther than
``outside`` from them, so no lane, run-in, move or pass enters them, and a segment inside a
pocket is a wall as a hole's is (each is also checked, with shapely's exact distance, to lie
farther than ``outside`` from the shells).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .bands import EdgeSet

__all__ = ["WALLS_PER_RING", "WallCache", "hole_walls", "shell_walls", "walls_in_frames"]

#: The longest segments kept per hole ring.
WALLS_PER_RING = 6
#: How far inside its hole a ring's walls are, relative to the largest extent of the edge set:
#: far above what a proper crossing needs between two of its ends' ranges
#: (:data:`~.one_tree.CROSS_ROOM` of the segments' lengths, about ``3e-9`` of the extent), far
#: below any real detour (0.3 mm on a 300 m area).
WALL_INSET = 1e-6


def _ring_starts(es: EdgeSet) -> NDArray[np.intp]:
    """Indices of the first edge of each ring of ``es`` (rings are consecutive edges)."""
    xy = es.xy
    if not len(xy):
        return np.zeros(0, dtype=np.intp)
    brk = np.any(xy[1:, :2] != xy[:-1, 2:], axis=1) | (es.hole[1:] != es.hole[:-1])
    return np.concatenate([[0], np.nonzero(brk)[0] + 1]).astype(np.intp)


def _inset_rings(poly: Any, inset: float) -> list[NDArray[np.float64]]:
    """The rings of ``poly`` inset by ``inset`` (mitred; one per part), or its own ring where
    nothing is left (a hole thinner than twice the inset)."""
    small = poly.buffer(-inset, join_style="mitre") if inset > 0 else poly
    parts = [g for g in getattr(small, "geoms", [small]) if not g.is_empty and g.area > 0]
    if not parts:
        parts = [poly]
    return [np.asarray(g.exterior.coords)[:-1] for g in parts]


def _projections(ring: NDArray[np.float64]) -> list[tuple[NDArray[np.intp], NDArray[np.float64]]]:
    """Per direction of :data:`_DIRECTIONS` (angles ``k pi / K``): the vertices' order along it
    and their sorted projections."""
    out = []
    for k in range(_DIRECTIONS):
        angle = k * math.pi / _DIRECTIONS
        p = ring[:, 0] * math.cos(angle) + ring[:, 1] * math.sin(angle)
        order = np.argsort(p, kind="stable")
        out.append((order, p[order]))
    return out


def _starts(proj: list[tuple[NDArray[np.intp], NDArray[np.float64]]], least: float) -> list:
    """Per direction, each sorted vertex's first partner at least ``least cos(pi / (2 K))``
    further along it: a pair ``|v| >= least`` apart lies within ``pi / (2 K)`` of one of the
    ``K`` directions, so its projections on it differ by at least that (less a billionth: the
    rounding's room)."""
    gap = least * math.cos(math.pi / (2 * _DIRECTIONS)) * (1 - 1e-9)
    return [np.searchsorted(ps, ps + gap, side="left") for _, ps in proj]


def _pairs(
    proj: list[tuple[NDArray[np.intp], NDArray[np.float64]]], starts: list
) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """``(i, j)``, ``i < j``, once each: the pairs :func:`_starts` lists (each vertex with the
    suffix of its direction's order from its start), every pair at least ``least`` apart among
    them."""
    m = len(proj[0][0])
    keys = []
    for (order, _), start in zip(proj, starts, strict=True):
        count = m - start
        lo = np.repeat(np.arange(m), count)
        hi = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count) + start[lo]
        a, b = order[lo], order[hi]
        keys.append(np.minimum(a, b) * m + np.maximum(a, b))
    key = np.unique(np.concatenate(keys))
    return key // m, key % m


#: Directions of the projections (:func:`_starts`).
_DIRECTIONS = 8
#: The pairs listed by the first shell of :func:`_ring_walls`, and the growth of each next one.
_FIRST_SHELL, _GROWTH = 256, 4


def _shell_pairs(
    ring: NDArray[np.float64], proj: list, above: float, total: int
) -> tuple[float, NDArray[np.intp], NDArray[np.intp]]:
    """``(least, i, j)``: a length below ``above`` whose pairs :func:`_starts` lists number
    about ``total`` (bisected), and those pairs; ``least = 0`` and every pair where about as
    many as every pair would be listed."""
    m = len(ring)
    if total >= m * (m - 1) // 2:
        i, j = np.triu_indices(m, 1)
        return 0.0, i, j
    lo, hi = 0.0, min(above, float(np.hypot(*np.ptp(ring, axis=0))))
    for _ in range(40):  # the largest length listing at least `total` pairs
        mid = 0.5 * (lo + hi)
        if sum(m * m - int(st.sum()) for st in _starts(proj, mid)) >= total:
            lo = mid
        else:
            hi = mid
    if lo <= 0:
        i, j = np.triu_indices(m, 1)
        return 0.0, i, j
    i, j = _pairs(proj, _starts(proj, lo))
    return lo, i, j


def _ring_walls(
    ring: NDArray[np.float64], poly: Any, per_ring: int, far: Any = None
) -> list[NDArray[np.float64]]:
    """The ``per_ring`` longest segments between vertices of ``ring`` covered by ``poly`` (and,
    with ``far = (geometry, distance)``, farther than ``distance`` from ``geometry``, measured
    exactly) (longest first; equal lengths in the order of ``np.triu_indices``). The pairs are taken
    in shells of decreasing length (:func:`_shell_pairs`, each sorted and tested in order),
    about :data:`_FIRST_SHELL` pairs first and :data:`_GROWTH` times more each time: the same
    walls as sorting every pair, without listing the ``n^2`` pairs of a traced hole."""
    from shapely import covered_by, distance, linestrings

    m, want = len(ring), max(per_ring, 1)  # at least one, as the sort of every pair kept
    proj = _projections(ring)
    kept: list[NDArray[np.float64]] = []
    above, total = math.inf, _FIRST_SHELL
    while True:
        least, i, j = _shell_pairs(ring, proj, above, total)
        seg = np.concatenate([ring[i], ring[j]], axis=1)
        length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
        shell = (length >= least) & (length < above)
        index = (i * m - i * (i + 1) // 2 + j - i - 1)[shell]  # the pair's place in triu order
        seg = seg[shell][np.lexsort((index, -length[shell]))]
        at, batch = 0, want
        while at < len(seg) and len(kept) < want:  # tested in order, in growing batches
            part = seg[at : at + batch]
            lines = linestrings(part.reshape(-1, 2, 2))
            ok = covered_by(lines, poly)
            if far is not None:
                ok &= distance(lines, far[0]) > far[1]
            kept.extend(part[ok])
            at, batch = at + batch, 2 * batch
        if len(kept) >= want or least <= 0:
            return kept[:want]
        above, total = least, total * _GROWTH


def hole_walls(
    es: EdgeSet, per_ring: int = WALLS_PER_RING, inset: float = WALL_INSET
) -> NDArray[np.float64]:
    """``(W, 4)`` walls ``x1, y1, x2, y2`` inside the hole rings of ``es`` (module docstring):
    per hole, the ``per_ring`` longest segments between the vertices of its ring inset by
    ``inset`` of the set's extent that lie inside the hole (:func:`_ring_walls`)."""
    from shapely import Polygon, prepare

    starts = _ring_starts(es)
    ends = np.append(starts[1:], len(es.xy))
    extent = float(np.ptp(es.xy[:, :2], axis=0).max()) if len(es.xy) else 0.0
    out: list[NDArray[np.float64]] = []
    for a, b in zip(starts, ends, strict=True):
        if es.hole[a] < 0 or b - a < 3:
            continue
        poly: Any = Polygon(es.xy[a:b, :2])
        if not poly.is_valid or poly.area <= 0:
            continue
        prepare(poly)
        for ring in _inset_rings(poly, inset * extent):
            out.extend(_ring_walls(ring, poly, per_ring))
    return np.asarray(out, dtype=np.float64).reshape(-1, 4)


def shell_walls(
    es: EdgeSet, outside: float, per_ring: int = WALLS_PER_RING, inset: float = WALL_INSET
) -> NDArray[np.float64]:
    """``(W, 4)`` walls in the shell's pockets (module docstring, "Walls outside the shell"):
    the parts of the convex hull of ``es``'s outer rings dilated by ``outside`` outside that
    dilation (shapely's mitred one, which holds the round one), per part the ``per_ring`` longest
    segments between the vertices of its ring inset by ``inset`` of the set's extent that lie
    inside it and, measured exactly, farther than ``outside`` from every outer ring."""
    from shapely import Polygon, prepare, unary_union

    if not len(es.xy) or not outside > 0:
        return np.zeros((0, 4))
    starts = _ring_starts(es)
    ends = np.append(starts[1:], len(es.xy))
    shells = [
        Polygon(es.xy[a:b, :2])
        for a, b in zip(starts, ends, strict=True)
        if es.hole[a] < 0 and b - a >= 3
    ]
    shells = [p if p.is_valid else p.buffer(0) for p in shells]
    if not shells:
        return np.zeros((0, 4))
    body: Any = unary_union(shells)
    extent = float(np.ptp(es.xy[:, :2], axis=0).max())
    grown = body.buffer(outside, join_style="mitre")  # holds the round dilation
    pockets: Any = grown.convex_hull.difference(grown)
    out: list[NDArray[np.float64]] = []
    for part in getattr(pockets, "geoms", [pockets]):
        if part.is_empty or part.geom_type != "Polygon" or part.area <= 0:
            continue
        poly = Polygon(part.exterior)
        prepare(poly)
        for ring in _inset_rings(poly, inset * extent):
            out.extend(_ring_walls(ring, poly, per_ring, (body, outside)))
    return np.asarray(out, dtype=np.float64).reshape(-1, 4)


def walls_in_frames(
    walls: NDArray[np.float64],
    theta: NDArray[np.float64],
    d: NDArray[np.float64],
    origin: NDArray[np.float64],
) -> NDArray[np.float64]:
    """``(L, W, 4)`` the walls in each layout's frame: ``u`` along the lines, ``v`` across
    (lines at ``v = k * spacing``, as :func:`~.bands.band_stats`), rows ``u1, v1, u2, v2``."""
    cs, sn = np.cos(theta)[:, None], np.sin(theta)[:, None]
    out = np.empty((len(theta), len(walls), 4))
    for e in range(2):
        x = walls[None, :, 2 * e] - origin[0]
        y = walls[None, :, 2 * e + 1] - origin[1]
        out[:, :, 2 * e] = cs * x + sn * y
        out[:, :, 2 * e + 1] = -sn * x + cs * y - d[:, None]
    return out


class WallCache:
    """The walls of each sandwich level (:func:`hole_walls` of its outer set, and with
    ``outside`` its :func:`shell_walls`), computed once per level of a search: the levels are
    cached, so their arrays (the keys, by identity, kept alive here) live as long as the
    search."""

    def __init__(self, outside: float | None = None) -> None:
        self._walls: dict[int, tuple[NDArray[np.float64], NDArray[np.float64]]] = {}
        self.outside = outside  # walls in the shell's pockets too (shell_walls), if given

    def frames(
        self,
        outer: EdgeSet,
        theta: NDArray[np.float64],
        d: NDArray[np.float64],
        origin: NDArray[np.float64],
    ) -> NDArray[np.float64]:
        """:func:`walls_in_frames` of the walls of the level whose outer set is ``outer``."""
        key = id(outer.xy)
        if key not in self._walls:
            walls = hole_walls(outer)
            if self.outside is not None:
                walls = np.concatenate([walls, shell_walls(outer, self.outside)])
            self._walls[key] = (outer.xy, walls)
        return walls_in_frames(self._walls[key][1], theta, d, origin)
