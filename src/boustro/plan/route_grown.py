"""The grown routing domain: where a connecting move may go when a plan may leave its area.

Without keep-inside a plan leaves its area anyway: its lanes run up to their reach past the
boundary, and a straight connecting move is flown wherever it stays within the router's reach
of the shell (:meth:`~boustro.plan.routing.Router.path`). A move that is not straight was
routed inside the area, bending at the area's own reflex vertices, even where a path within the
reach cuts the corner (docs/mission_time.md, "Connecting moves in the grown domain": a move
passing a reflex vertex of the shell 5.3 m out, with a 5 m reach, flew 46.9 m through the
vertex where 37 m stay within the reach).

The *grown domain* is the shell dilated by the reach (GEOS buffer, round joins of
:data:`QUAD_SEGS` segments a quarter circle, by ``reach (1 - 1e-6)``), with the area's holes
and any pocket the dilation closes (points farther than the reach from the shell) as holes. A
round join's vertices lie on its circle and its chords inside it, so every point of the
grown domain lies within the reach of the shell; the holes are the area's own, so a path in
it enters none. The router routes a move that is not straight in the grown domain (a
visibility graph of its reflex vertices, :class:`~boustro.plan.routing.Router` with no reach),
checks every segment of the result with its own straight test (within the reach at points a
sixteenth of it apart, no hole), and keeps it if it is shorter than the move inside the area:
so a plan's moves lie where its straight moves may already lie (the premise of the search's
walls outside the shell, :mod:`boustro.optimize.cover.walls`), and no move is longer than
before. With keep-inside the reach is 0 and there is no grown domain. A tour's distances
(:meth:`~boustro.plan.routing.Router.distances`) are the moves flown: the shorter of the move
inside the area and the grown domain's (the grown router's own distances), the latter only
between ends the router would route there (:meth:`~boustro.plan.routing.Router._grown_ends`),
so that the exact order is the shortest flown. shapely is imported on use.
"""

from __future__ import annotations

from typing import Any

from ..geometry.region import Region
from .route_domain import MAX_NODES, _as_regions, reflex_count

__all__ = ["QUAD_SEGS", "grown_region"]

#: Segments per quarter circle of the dilation's round joins.
QUAD_SEGS = 4
#: The dilation's distance relative to the reach (below 1: the rounding's room).
_SHRINK = 1 - 1e-6


def grown_region(region: Region, reach: float) -> Region | None:
    """The grown domain of ``region`` (module docstring); ``None`` without a reach, where
    the dilation is not one valid region, or where it has more than
    :data:`~boustro.plan.route_domain.MAX_NODES` reflex vertices (a traced boundary)."""
    if not reach > 0:
        return None
    import shapely

    shell = shapely.Polygon(region.shell.vertices).buffer(reach * _SHRINK, quad_segs=QUAD_SEGS)
    holes = [shapely.Polygon(h.vertices) for h in region.holes]
    grown: Any = shell.difference(shapely.unary_union(holes)) if holes else shell
    parts = _as_regions(grown)
    if len(parts) != 1 or len(parts[0].holes) < len(region.holes):
        return None
    if reflex_count(parts[0].rings) > MAX_NODES:
        return None
    return parts[0]
