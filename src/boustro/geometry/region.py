"""Survey regions: a simple polygon (the shell, any shape) minus disjoint holes (:class:`Region`).

Rings are validated :class:`~boustro.geometry.Polygon` s; edges are stored with the region on
their left (shell counter-clockwise, holes clockwise). The normalised frame is the shell's.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError, InvalidPolygonError
from .polygon import Frame, Polygon, _cross
from .random import random_convex_polygon
from .validity import holes_problem

__all__ = [
    "TOUCH_TOLERANCE",
    "Region",
    "as_region",
    "points_in_ring",
    "random_region",
    "segment_distances",
]

#: Relative tolerance (to the shell's diameter) under which a hole is said to touch the shell
#: or another hole.
TOUCH_TOLERANCE = 1e-9


def _point_segment_distance(
    p: NDArray[np.float64], a: NDArray[np.float64], b: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Distance of points ``p`` to segments ``a -> b`` (all broadcasting, ``(..., 2)``)."""
    ab = b - a
    den = np.maximum(np.einsum("...i,...i->...", ab, ab), np.finfo(np.float64).tiny)
    t = np.clip(np.einsum("...i,...i->...", p - a, ab) / den, 0.0, 1.0)
    return np.linalg.norm(p - (a + t[..., None] * ab), axis=-1)


def segment_distances(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """Distances ``(n, m)`` between segments ``a (n, 2, 2)`` and ``b (m, 2, 2)``; 0 where they
    cross."""
    a1, a2 = a[:, None, 0], a[:, None, 1]
    b1, b2 = b[None, :, 0], b[None, :, 1]
    d = np.minimum(
        np.minimum(_point_segment_distance(a1, b1, b2), _point_segment_distance(a2, b1, b2)),
        np.minimum(_point_segment_distance(b1, a1, a2), _point_segment_distance(b2, a1, a2)),
    )
    o1, o2 = _cross(a2 - a1, b1 - a1), _cross(a2 - a1, b2 - a1)
    o3, o4 = _cross(b2 - b1, a1 - b1), _cross(b2 - b1, a2 - b1)
    crossing = (o1 * o2 < 0) & (o3 * o4 < 0)
    return np.where(crossing, 0.0, d)


def points_in_ring(points: ArrayLike, ring: ArrayLike) -> NDArray[np.bool_]:
    """Even-odd (crossing number) test of points ``(P, 2)`` against a closed ring ``(N, 2)``.

    Points exactly on the ring may come out either way; callers that care test the distance.
    """
    p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    v = np.asarray(ring, dtype=np.float64)
    w = np.roll(v, -1, axis=0)
    y = p[:, None, 1]
    straddle = (v[None, :, 1] <= y) != (w[None, :, 1] <= y)
    dy = w[:, 1] - v[:, 1]
    safe = np.where(dy == 0, 1.0, dy)
    x_cross = v[None, :, 0] + (y - v[None, :, 1]) * (w[None, :, 0] - v[None, :, 0]) / safe
    hits = straddle & (p[:, None, 0] < x_cross)
    return (np.count_nonzero(hits, axis=1) % 2) == 1


def _ring_segments(ring: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.stack([ring, np.roll(ring, -1, axis=0)], axis=1)


# -- regions ----------------------------------------------------------------------------------
class Region:
    """A validated simple polygon with holes: the shell minus the holes' interiors.

    Args:
        shell: the outer boundary, anything :class:`~boustro.geometry.Polygon` accepts (any
            orientation; validated: simple, non-degenerate). Concave shells are fine.
        holes: zero or more inner boundaries, each validated the same way. Every hole must lie
            strictly inside the shell, and the holes must be disjoint: no hole may touch or cross
            the shell's boundary or another hole, or lie inside another hole (distances under
            :data:`TOUCH_TOLERANCE` times the shell's diameter count as touching).

    Raises:
        InvalidPolygonError: a ring is invalid, or the holes break the rules above; the message
            names the ring and a point where the problem is.

    Example:
        >>> r = Region([(0, 0), (4, 0), (4, 4), (0, 4)], holes=[[(1, 1), (2, 1), (2, 2), (1, 2)]])
        >>> r.area, r.n_holes
        (15.0, 1)
    """

    __slots__ = ("_edges", "_holes", "_shell")

    def __init__(
        self, shell: Polygon | ArrayLike, holes: Sequence[Polygon | ArrayLike] = ()
    ) -> None:
        self._shell = _as_polygon(shell, "the shell")
        if isinstance(holes, np.ndarray) and holes.ndim == 2:
            raise InvalidPolygonError(
                "holes must be a sequence of rings (each an (N, 2) array), got one (N, 2) array"
            )
        self._holes = tuple(_as_polygon(h, f"hole {i}") for i, h in enumerate(holes, start=1))
        _check_holes(self._shell, self._holes)
        rings = [self._shell.vertices] + [h.vertices[::-1] for h in self._holes]
        edges = np.concatenate([_ring_segments(r) for r in rings])
        edges.setflags(write=False)
        self._edges = edges

    @classmethod
    def _trusted(cls, shell: Polygon, holes: Sequence[Polygon]) -> Region:
        """A region whose holes are known to be valid (built by boustro itself, e.g. a traced
        union of cells): the hole checks are skipped."""
        self = object.__new__(cls)
        self._shell = shell
        self._holes = tuple(holes)
        rings = [shell.vertices] + [h.vertices[::-1] for h in self._holes]
        edges = np.concatenate([_ring_segments(r) for r in rings])
        edges.setflags(write=False)
        self._edges = edges
        return self

    # -- basic properties -------------------------------------------------------------------
    @property
    def shell(self) -> Polygon:
        """The outer boundary (counter-clockwise)."""
        return self._shell

    @property
    def holes(self) -> tuple[Polygon, ...]:
        """The holes, each a counter-clockwise :class:`~boustro.geometry.Polygon`."""
        return self._holes

    @property
    def n_holes(self) -> int:
        return len(self._holes)

    @property
    def rings(self) -> list[NDArray[np.float64]]:
        """Every ring with the region on its left: the shell CCW, then each hole clockwise."""
        return [self._shell.vertices] + [h.vertices[::-1] for h in self._holes]

    @property
    def edges(self) -> NDArray[np.float64]:
        """``(E, 2, 2)`` all ring edges ``[p1, p2]``, oriented with the region on their left."""
        return self._edges

    @property
    def vertices(self) -> NDArray[np.float64]:
        """``(E, 2)`` every vertex (shell first, then the holes): the edges' start points."""
        return self._edges[:, 0]

    @property
    def area(self) -> float:
        """Shell area minus the holes' areas."""
        return self._shell.area - sum(h.area for h in self._holes)

    @property
    def is_convex(self) -> bool:
        """True for a convex shell without holes (the paper's setting)."""
        return self._shell.is_convex and not self._holes

    @property
    def centre(self) -> NDArray[np.float64]:
        """The shell's vertex mean: the origin of the normalised frame."""
        return self._shell.centre

    @property
    def diameter(self) -> float:
        """The shell's diameter: the unit length of the normalised frame."""
        return self._shell.diameter

    @property
    def frame(self) -> Frame:
        return self._shell.frame

    def __repr__(self) -> str:
        return (
            f"Region(shell={self._shell.vertices.tolist()!r}, "
            f"holes={[h.vertices.tolist() for h in self._holes]!r})"
        )

    # -- transformations --------------------------------------------------------------------
    def map(self, fn) -> Region:
        """The region with every ring's vertices mapped by ``fn`` (validated again)."""
        return Region(fn(self._shell.vertices), [fn(h.vertices) for h in self._holes])

    def normalised(self) -> Region:
        """This region in the shell's normalised frame."""
        return self.map(self.frame.to_normalised)

    def contains(self, points: ArrayLike) -> NDArray[np.bool_]:
        """Whether points ``(P, 2)`` lie in the region (even-odd over all rings; points on the
        boundary may come out either way)."""
        inside = points_in_ring(points, self._shell.vertices)
        for h in self._holes:
            inside &= ~points_in_ring(points, h.vertices)
        return inside

    def boundary_distance(self, points: ArrayLike) -> NDArray[np.float64]:
        """Distance ``(P,)`` of points to the nearest ring edge."""
        p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        e = self._edges
        return _point_segment_distance(p[:, None, :], e[None, :, 0], e[None, :, 1]).min(axis=1)


def _as_polygon(ring: Polygon | ArrayLike, what: str) -> Polygon:
    if isinstance(ring, Polygon):
        return ring
    try:
        return Polygon(ring)
    except InvalidPolygonError as exc:
        raise InvalidPolygonError(f"{what}: {exc}") from None


def _check_holes(shell: Polygon, holes: tuple[Polygon, ...]) -> None:
    """Refuse holes that touch the shell or each other, or lie outside the shell or inside
    another hole (GEOS distance predicates: memory ``O(n)``)."""
    tol = TOUCH_TOLERANCE * shell.diameter
    problem = holes_problem(shell.vertices, [h.vertices for h in holes], tol)
    if problem is not None:
        raise InvalidPolygonError(problem)


def as_region(area: Region | Polygon | ArrayLike) -> Region:
    """A :class:`Region` from a region, a polygon (no holes), or ``(N, 2)`` shell vertices."""
    if isinstance(area, Region):
        return area
    return Region(area)


# -- random regions (tests, benchmarks) -------------------------------------------------------
def random_region(
    rng: np.random.Generator,
    n_vertices: int = 12,
    n_holes: int = 1,
    *,
    hole_vertices: tuple[int, int] = (3, 8),
    hole_size: tuple[float, float] = (0.08, 0.22),
    roughness: float = 0.45,
    jitter: float = 0.05,
) -> Region:
    """A random concave region with holes, centred near the origin, radius about 1.

    The shell is star-shaped about the origin (sorted random angles), so it is simple; its
    radius is ``1 - roughness * g`` with ``g`` in ``[0, 1]`` a random smooth profile (a few
    random low-frequency waves: lobes and bays, as real fields have) plus ``jitter``, so for
    ``roughness > 0`` it is usually concave. Each
    hole is a random convex polygon (Valtr) of diameter drawn from ``hole_size``, placed at a
    random point at least half its size away from the shell and from the other holes (redrawn
    until it fits; a ValueError after many failures).
    """
    if int(n_vertices) != n_vertices or n_vertices < 3:
        raise InvalidParameterError(f"n_vertices must be an integer >= 3, got {n_vertices!r}")
    n = int(n_vertices)
    while True:
        gaps = rng.uniform(0.3, 1.0, n)
        angles = np.cumsum(gaps) / gaps.sum() * 2 * math.pi + rng.uniform(0, 2 * math.pi)
        freq = rng.integers(1, 6, 4)
        amp = rng.uniform(0.2, 1.0, 4)
        phase = rng.uniform(0, 2 * math.pi, 4)
        wave = (amp[:, None] * np.cos(freq[:, None] * angles[None] + phase[:, None])).sum(0)
        wave = (wave - wave.min()) / max(float(np.ptp(wave)), 1e-12)
        radii = 1.0 - roughness * (wave + jitter * rng.uniform(-1, 1, n)) / (1 + jitter)
        shell = np.stack([radii * np.cos(angles), radii * np.sin(angles)], axis=1)
        try:
            shell_poly = Polygon(shell)
        except InvalidPolygonError:
            continue
        if len(shell_poly) == n:
            break
    holes: list[Polygon] = []
    shell_edges = _ring_segments(shell_poly.vertices)
    for _ in range(int(n_holes)):
        for _attempt in range(2000):
            size = rng.uniform(*hole_size)
            hole = random_convex_polygon(
                rng, int(rng.integers(hole_vertices[0], hole_vertices[1] + 1))
            )
            centre = rng.uniform(-1, 1, 2)
            ring = hole.vertices * size + centre
            if not points_in_ring(ring, shell_poly.vertices).all():
                continue
            edges = _ring_segments(ring)
            if segment_distances(edges, shell_edges).min() < size / 2:
                continue
            if any(
                segment_distances(edges, _ring_segments(h.vertices)).min() < size / 2
                or points_in_ring(ring[:1], h.vertices)[0]
                or points_in_ring(h.vertices[:1], ring)[0]
                for h in holes
            ):
                continue
            holes.append(Polygon(ring))
            break
        else:
            raise InvalidParameterError(
                f"could not place {n_holes} holes in the shell; ask for fewer or smaller ones"
            )
    return Region(shell_poly, holes)
