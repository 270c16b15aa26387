"""Inner routing domains of an area with a traced boundary: fewer router nodes, inside the area.

A shortest connecting move bends only at reflex vertices, and a boundary traced by GPS has
hundreds of them (noise): the visibility graph over all of them costs ``O(N^2)`` tests and its
shortest paths ``O(N^3)``. Above :data:`MAX_NODES` reflex vertices the router routes through
*inner domains* instead: the area eroded by ``eps`` (GEOS buffer, round joins) and simplified
(Douglas-Peucker, topology preserved) with tolerance ``eps / 2``. A simplification moves the
boundary by at most its tolerance, and the polygonal arcs of the buffer lie within
``eps (1 - cos(pi / 8))`` of the true erosion, so every domain lies inside the area with a
clearance of at least ``0.42 eps``: a route through a domain never leaves the area. ``eps``
starts at ``reach / 8`` (``reach``: the lanes' half-width, or 1/100 of the diameter without
one) and doubles (up to ``reach``) until at most :data:`MAX_NODES` reflex vertices remain.
Routes are then at most a few ``eps`` longer per bend than the shortest (the detour around
the clearance, shortened again by string pulling in the area itself).
shapely is imported on use.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidPolygonError
from ..geometry import Polygon
from ..geometry.polygon import _cross
from ..geometry.region import Region

__all__ = ["MAX_NODES", "inner_domains", "nearest_in", "reflex_count"]

#: Reflex vertices above which the router routes through inner domains (exact below).
MAX_NODES = 160
#: Segments per quarter circle of the erosion's round arcs.
_QUAD_SEGS = 2


def reflex_count(rings: list[NDArray[np.float64]]) -> int:
    """Vertices where the free space is reflex (rings with the area on their left)."""
    total = 0
    for ring in rings:
        turn = _cross(ring - np.roll(ring, 1, axis=0), np.roll(ring, -1, axis=0) - ring)
        total += int(np.count_nonzero(turn < 0))
    return total


def _as_regions(geom: Any) -> list[Region]:
    """The polygon parts of a shapely geometry as regions (parts that fail validation are
    dropped: a route cannot use them)."""
    out = []
    for part in getattr(geom, "geoms", [geom]):
        if part.is_empty or part.geom_type != "Polygon":
            continue
        try:
            shell = Polygon(np.asarray(part.exterior.coords)[:-1])
            holes = [Polygon(np.asarray(r.coords)[:-1]) for r in part.interiors]
        except InvalidPolygonError:
            continue
        out.append(Region._trusted(shell, holes))
    out.sort(key=lambda r: -r.area)
    return out


def inner_domains(region: Region, reach: float) -> list[Region]:
    """The inner domains of ``region`` (module docstring), largest first."""
    import shapely

    poly = shapely.Polygon(region.shell.vertices, [h.vertices for h in region.holes])
    if reach <= 0:  # no lane width to scale by: a hundredth of the diameter
        reach = 1e-2 * region.diameter
    eps = reach / 8
    last: list[Region] = []
    while True:
        inner = poly.buffer(-eps, quad_segs=_QUAD_SEGS).simplify(eps / 2, preserve_topology=True)
        domains = _as_regions(inner)
        if not domains:  # eroded away (a strip narrower than 2 eps): the last domains found
            return last
        count = sum(reflex_count(d.rings) for d in domains)
        if count <= MAX_NODES or eps >= reach:
            return domains
        last = domains
        eps = min(2 * eps, reach)


def nearest_in(
    domains: list[Region], points: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """For each point the nearest point of the domains (itself inside one) and that domain's
    index (``-1`` without domains)."""
    import shapely

    n = len(points)
    if not domains or n == 0:
        return points.copy(), np.full(n, -1, dtype=np.int64)
    polys = [shapely.Polygon(d.shell.vertices, [h.vertices for h in d.holes]) for d in domains]
    pts = shapely.points(points)
    dist = np.stack([shapely.distance(g, pts) for g in polys])  # (D, P)
    which = np.argmin(dist, axis=0)
    out = points.copy()
    for k, g in enumerate(polys):
        sel = np.flatnonzero((which == k) & (dist[k] > 0))
        if len(sel):
            lines = shapely.shortest_line(g, pts[sel])
            out[sel] = shapely.get_coordinates(lines)[0::2]
    return out, which.astype(np.int64)
