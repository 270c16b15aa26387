"""Inner and outer sets around a region: every rigid motion of it by at most ``eps`` lies
between them (shapely buffers, made conservative for their polygonal arcs).

Simplified sandwiches (a region with many vertices: a traced field). With a ``tolerance``
``h > 0`` the level of radius ``eps`` is built at radius ``eps + t`` (``t = eps / 8``)
and then simplified (GEOS, Douglas-Peucker, topology preserved) with tolerance ``0.99 t``.
A simplification replaces chains of the boundary by chords; where each removed vertex lies
within ``d`` of its chord, every point the simplification adds or removes lies within ``d`` of
the set's boundary (a point enclosed between a chain and its chord meets the chain on the ray
leaving the chord). GEOS does not always keep ``d`` below its tolerance (it can drop a ring's
start vertex without re-checking it: 1.2 x the tolerance measured), so :func:`_simplify`
measures ``d`` from the vertices it kept and halves the tolerance until ``d <= 0.99 t``
(unsimplified after four tries). Then the simplified erosion lies in
``erosion(eps + t) + t ⊆ erosion(eps)``, and the simplified dilation contains every point at
least ``t`` inside ``dilation(eps + t)``, i.e. ``dilation(eps)``. Both are still a sandwich at
radius ``eps``, with far fewer edges (the bound is that of a radius up to ``eps + t``: a
little weaker, never invalid).
"""

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
#: Share of the slack ``t`` used as the simplification tolerance (the rest: rounding margin).
SIMPLIFY_SHARE = 0.99
#: The erosion radius is divided by the cosine of half a segment's angle, so that the
#: polygonal arcs (vertices on the circle, chords inside) stay outside the true circle.
ARC_FACTOR = 1.0 / math.cos(math.pi / (4 * QUAD_SEGS))


class Level(NamedTuple):
    """The sandwich at one radius: inner and outer edge sets, and per original hole the
    perimeter of the convex hull of what remains of it in the outer set (0 if nothing) and
    of the hole itself."""

    eps: float
    inner: EdgeSet
    outer: EdgeSet
    hole_perimeter: NDArray[np.float64]
    hull_perimeter: NDArray[np.float64]


def _rings(geom: Any) -> list[tuple[NDArray[np.float64], bool]]:
    """``(ring, is_hole)`` of every polygon part of a shapely geometry (closing point dropped)."""
    out: list[tuple[NDArray[np.float64], bool]] = []
    for part in getattr(geom, "geoms", [geom]):
        if part.is_empty or part.geom_type != "Polygon":
            continue
        out.append((np.asarray(part.exterior.coords, dtype=np.float64)[:-1], False))
        out.extend((np.asarray(r.coords, dtype=np.float64)[:-1], True) for r in part.interiors)
    return out


def _simplify(geom: Any, limit: float, tries: int = 4) -> Any:
    """``geom`` simplified (GEOS, topology preserved) so that every removed vertex lies within
    ``limit`` of the chord that replaced it, measured (module docstring); ``geom`` itself if
    four halvings of the tolerance do not get there."""
    rings = _rings(geom)
    where = {(x, y): (i, k) for i, (ring, _) in enumerate(rings) for k, (x, y) in enumerate(ring)}
    tol = limit
    for _ in range(tries):
        simple = geom.simplify(tol, preserve_topology=True)
        if _deviation(rings, _rings(simple), where) <= limit:
            return simple
        tol /= 2
    return geom


def _deviation(
    rings: list[tuple[NDArray[np.float64], bool]],
    simple: list[tuple[NDArray[np.float64], bool]],
    where: dict[tuple[float, float], tuple[int, int]],
) -> float:
    """The largest distance of a vertex of ``rings`` removed in ``simple`` from its chord
    (infinite where a simplified ring is not a subsequence of one ring, in order)."""
    if len(simple) != len(rings):
        return math.inf
    worst = 0.0
    for ring, _ in simple:
        hits = [where.get((x, y), (-1, -1)) for x, y in ring]
        if len({h[0] for h in hits}) != 1 or hits[0][0] < 0:
            return math.inf
        orig = rings[hits[0][0]][0]
        idx = np.array([h[1] for h in hits])
        n = len(orig)
        if np.mod(np.diff(idx, append=idx[0]), n).sum() != n:
            idx = idx[::-1]  # GEOS kept the ring but reversed it
            if np.mod(np.diff(idx, append=idx[0]), n).sum() != n:
                return math.inf
        worst = max(worst, _chain_distance(orig, idx))
    return worst


def _chain_distance(orig: NDArray[np.float64], kept: NDArray[np.int64]) -> float:
    """Largest distance of a vertex of the closed ring ``orig`` from the chord between the kept
    vertices (``kept``: cyclic, in the ring's order) around it."""
    n = len(orig)
    rolled = np.roll(orig, -int(kept[0]), axis=0)
    k = np.sort(np.mod(kept - kept[0], n))
    run = np.searchsorted(k, np.arange(n), side="right") - 1
    a = rolled[k[run]]
    b = rolled[k[(run + 1) % len(k)]]
    ab = b - a
    ap = rolled - a
    den = np.einsum("ij,ij->i", ab, ab)
    u = np.clip(np.einsum("ij,ij->i", ap, ab) / np.where(den > 0, den, 1.0), 0.0, 1.0)
    return float(np.hypot(*(ap - u[:, None] * ab).T).max(initial=0.0))


class Sandwich:
    """The region and its inner (eroded) and outer (dilated) sets at radii ``eps``.

    A map that moves every point by at most ``eps`` sends the region into a set ``S`` with
    ``erosion(eps) ⊆ S ⊆ dilation(eps)``: a point ``p`` of the erosion has its preimage within
    ``eps`` of it, inside the region. The dilation uses mitred joins (they contain the round
    ones); the erosion's radius is enlarged by :data:`ARC_FACTOR` plus ``1e-9`` of the diameter
    so that its polygonal arcs lie inside the true erosion.
    """

    def __init__(self, region: Region, tolerance: float = 0.0) -> None:
        import shapely

        self.region = region
        self.tolerance = float(tolerance)
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
        return Level(0.0, es, es, self.hull_perimeter, self.hull_perimeter)

    @cached_property
    def hull_perimeter(self) -> NDArray[np.float64]:
        """Per hole, the perimeter of its convex hull."""
        return self._perimeters([(h, i) for i, h in enumerate(self.holes)])

    def slack(self, eps: float) -> float:
        """How much farther than ``eps`` the level of radius ``eps`` reaches (0 unsimplified)."""
        return eps / 8 if self.tolerance > 0 else 0.0

    @cached_property
    def approximate(self) -> Level:
        """The region simplified with the tolerance (the region itself without one): a model
        of the region with fewer edges, not a bound."""
        if self.tolerance <= 0:
            return self.exact
        geom = self.polygon.simplify(self.tolerance, preserve_topology=True)
        return self._level(0.0, geom, geom)

    def level(self, eps: float, shrink: float = 0.0) -> Level:
        """The sandwich at radius ``eps >= 0`` (cached), its inner set eroded by ``shrink``
        more (a plan whose lanes may stop that far inside the area: ``keep_inside``)."""
        key = (eps, shrink)
        if key not in self._levels:
            self._levels[key] = self._build(eps, shrink)
        return self._levels[key]

    def _build(self, eps: float, shrink: float = 0.0) -> Level:
        pad = 1e-9 * self.region.diameter
        t = self.slack(eps)
        if t > 0:  # simplified (module docstring); round dilation: fewer spikes than mitres
            r = eps + t
            outer = self.polygon.buffer(r * ARC_FACTOR + pad, quad_segs=QUAD_SEGS)
            inner = self.polygon.buffer(-((r + shrink) * ARC_FACTOR + pad), quad_segs=QUAD_SEGS)
            holes = self._dilated_holes((r + shrink) * ARC_FACTOR + pad)
            outer, inner, holes = (_simplify(g, SIMPLIFY_SHARE * t) for g in (outer, inner, holes))
        else:
            outer = self.polygon.buffer(eps + pad, join_style="mitre", mitre_limit=5.0)
            inner = self.polygon.buffer(-((eps + shrink) * ARC_FACTOR + pad), quad_segs=QUAD_SEGS)
            holes = self._dilated_holes((eps + shrink) * ARC_FACTOR + pad)
        return self._level(eps, inner, outer, holes)

    def _dilated_holes(self, radius: float) -> Any:
        """The union of the holes dilated by ``radius`` (round joins, polygonal arcs outside
        the true circle as the erosion's): the inner set's holes, also where the erosion
        merged them with the outside or with each other. Every hole of a sandwiched area lies
        in it (a hole moves by at most ``eps``), so a line loses at most its chords there,
        while the inner set's own rings lose a merged hole (its band projection may then cover
        the hole's chord: a lane length above the plan's, issue 16)."""
        import shapely

        parts = [h.buffer(radius, quad_segs=QUAD_SEGS) for h in self.hole_polygons]
        return shapely.union_all(parts)

    def _level(self, eps: float, inner: Any, outer: Any, holes: Any = None) -> Level:
        import shapely

        in_rings = _rings(inner)
        chords = None if holes is None else [r for r, _ in _rings(holes)]
        inner_set = edge_set(
            [r for r, _ in in_rings], [0 if h else -1 for _, h in in_rings], chords
        )
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
        return Level(eps, inner_set, outer_set, self._perimeters(kept), self.hull_perimeter)

    def _perimeters(self, rings: list[tuple[NDArray[np.float64], int]]) -> NDArray[np.float64]:
        import shapely

        out = np.zeros(len(self.holes))
        for i in range(len(self.holes)):
            pts = [r for r, h in rings if h == i]
            if pts:
                out[i] = shapely.MultiPoint(np.concatenate(pts)).convex_hull.length
        return out
