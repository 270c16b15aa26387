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
segment checked to lie inside the hole itself), the :data:`WALLS_PER_RING` longest; the ring
itself where the inset leaves nothing. Inset, because a lane cut at a hole ends on its ring: a
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
router's allowance (``max(reach, run-in)`` at points a sixteenth of it apart), a routed one and
a hole pass inside the area; a move the router found no way for voids the certificate. Every
area ``S`` of a box lies in the outer set, so every plan of the box lies within ``outside`` of
the outer set. The pockets of the outer set's shells dilated by ``outside`` (shapely's mitred
dilation, which holds the round one: the parts of its convex hull outside it) lie farther than
``outside`` from them, so no lane, run-in, move or pass enters them, and a segment inside a
pocket is a wall as a hole's is (each is also checked, with shapely's exact distance, to lie
farther than ``outside`` from the shells).
"""

from __future__ import annotations

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


def _ring_walls(poly: Any, inset: float, per_ring: int, far: Any = None) -> list[Any]:
    """The ``per_ring`` longest segments between the vertices of ``poly``'s ring inset by
    ``inset`` that lie inside ``poly`` (and, with ``far = (geometry, distance)``, farther than
    ``distance`` from ``geometry``, measured exactly)."""
    from shapely import LineString, covered_by, prepare

    prepare(poly)
    kept: list[Any] = []
    for ring in _inset_rings(poly, inset):
        i, j = np.triu_indices(len(ring), 1)
        seg = np.concatenate([ring[i], ring[j]], axis=1)
        length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
        found = 0
        for k in np.argsort(-length):
            line = LineString([seg[k, :2], seg[k, 2:]])
            if not covered_by(line, poly):  # inside the hole (the pocket)
                continue
            if far is not None and not line.distance(far[0]) > far[1]:
                continue
            kept.append(seg[k])
            found += 1
            if found >= per_ring:
                break
    return kept


def hole_walls(
    es: EdgeSet, per_ring: int = WALLS_PER_RING, inset: float = WALL_INSET
) -> NDArray[np.float64]:
    """``(W, 4)`` walls ``x1, y1, x2, y2`` inside the hole rings of ``es`` (module docstring):
    per hole, the ``per_ring`` longest segments between the vertices of its ring inset by
    ``inset`` of the set's extent that lie inside the hole."""
    from shapely import Polygon

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
        out.extend(_ring_walls(poly, inset * extent, per_ring))
    return np.asarray(out, dtype=np.float64).reshape(-1, 4)


def shell_walls(
    es: EdgeSet, outside: float, per_ring: int = WALLS_PER_RING, inset: float = WALL_INSET
) -> NDArray[np.float64]:
    """``(W, 4)`` walls in the shell's pockets (module docstring, "Walls outside the shell"):
    the parts of the convex hull of ``es``'s outer rings dilated by ``outside`` outside that
    dilation (shapely's mitred one, which holds the round one), per part the ``per_ring`` longest
    segments between the vertices of its ring inset by ``inset`` of the set's extent that lie
    inside it and, measured exactly, farther than ``outside`` from every outer ring."""
    from shapely import Polygon, unary_union

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
        out.extend(_ring_walls(Polygon(part.exterior), inset * extent, per_ring, (body, outside)))
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
