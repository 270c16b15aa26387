"""Inner and outer sets around a region: every rigid motion of it by at most ``eps`` lies
between them (shapely buffers, made conservative for their polygonal arcs)."""

from __future__ import annotations

import math
from functools import cached_property
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from ...geometry.region import Region
from .bands import EdgeSet, edge_set

__all__ = ["Level", "Sandwich"]

#: Segments per quarter circle of the erosion's round arcs.
QUAD_SEGS = 8
#: The erosion radius is divided by the cosine of half a segment's angle, so that the
#: polygonal arcs (vertices on the circle, chords inside) stay outside the true circle.
ARC_FACTOR = 1.0 / math.cos(math.pi / (4 * QUAD_SEGS))


class Level(NamedTuple):
    """The sandwich at one radius: inner and outer edge sets, and per original hole the
    perimeter of the convex hull of what remains of it in the outer set (0 if nothing)."""

    eps: float
    inner: EdgeSet
    outer: EdgeSet
    hole_perimeter: NDArray[np.float64]


def _rings(geom: Any) -> list[tuple[NDArray[np.float64], bool]]:
    """``(ring, is_hole)`` of every polygon part of a shapely geometry (closing point dropped)."""
    out: list[tuple[NDArray[np.float64], bool]] = []
    for part in getattr(geom, "geoms", [geom]):
        if part.is_empty or part.geom_type != "Polygon":
            continue
        out.append((np.asarray(part.exterior.coords, dtype=np.float64)[:-1], False))
        out.extend((np.asarray(r.coords, dtype=np.float64)[:-1], True) for r in part.interiors)
    return out


class Sandwich:
    """The region and its inner (eroded) and outer (dilated) sets at radii ``eps``.

    A map that moves every point by at most ``eps`` sends the region into a set ``S`` with
    ``erosion(eps) ⊆ S ⊆ dilation(eps)``: a point ``p`` of the erosion has its preimage within
    ``eps`` of it, inside the region. The dilation uses mitred joins (they contain the round
    ones); the erosion's radius is enlarged by :data:`ARC_FACTOR` plus ``1e-9`` of the diameter
    so that its polygonal arcs lie inside the true erosion.
    """

    def __init__(self, region: Region) -> None:
        import shapely

        self.region = region
        self.holes = [np.asarray(h.vertices, dtype=np.float64) for h in region.holes]
        self.polygon = shapely.Polygon(region.shell.vertices, self.holes)
        self.hole_polygons = [shapely.Polygon(h) for h in self.holes]
        shapely.prepare(self.hole_polygons)
        self._levels: dict[tuple[float, float], Level] = {}

    @cached_property
    def exact(self) -> Level:
        """The region itself (inner = outer)."""
        rings = [self.region.shell.vertices, *self.holes]
        es = edge_set(rings, [-1, *range(len(self.holes))])
        return Level(0.0, es, es, self._perimeters([(h, i) for i, h in enumerate(self.holes)]))

    def level(self, eps: float, shrink: float = 0.0) -> Level:
        """The sandwich at radius ``eps >= 0`` (cached), its inner set eroded by ``shrink``
        more (a plan whose lanes may stop that far inside the area)."""
        key = (eps, shrink)
        if key not in self._levels:
            self._levels[key] = self._build(eps, shrink)
        return self._levels[key]

    def _build(self, eps: float, shrink: float = 0.0) -> Level:
        import shapely

        pad = 1e-9 * self.region.diameter
        outer = self.polygon.buffer(eps + pad, join_style="mitre", mitre_limit=5.0)
        inner = self.polygon.buffer(-((eps + shrink) * ARC_FACTOR + pad), quad_segs=QUAD_SEGS)
        in_rings = _rings(inner)
        inner_set = edge_set([r for r, _ in in_rings], [0 if h else -1 for _, h in in_rings])
        out_rings = _rings(outer)
        ids, kept = [], []
        for ring, is_hole in out_rings:
            hid = -1
            if is_hole:
                point = shapely.Polygon(ring).representative_point()
                hid = next((i for i, hp in enumerate(self.hole_polygons) if hp.contains(point)), -1)
                kept.append((ring, hid))
            ids.append(hid)
        outer_set = edge_set([r for r, _ in out_rings], ids)
        return Level(eps, inner_set, outer_set, self._perimeters(kept))

    def _perimeters(self, rings: list[tuple[NDArray[np.float64], int]]) -> NDArray[np.float64]:
        import shapely

        out = np.zeros(len(self.holes))
        for i in range(len(self.holes)):
            pts = [r for r, h in rings if h == i]
            if pts:
                out[i] = shapely.MultiPoint(np.concatenate(pts)).convex_hull.length
        return out
