"""Validated simple polygons (:class:`Polygon`) and the paper's normalised frame (:class:`Frame`).

Vertices are ``(x, y)`` in user units, stored counter-clockwise; angles are radians,
counter-clockwise from ``+x``. The normalised frame centres a polygon on its vertex mean and
scales its diameter to 1.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidPolygonError, NonConvexPolygonError
from .validity import ring_problem

__all__ = [
    "COORDINATE_LIMIT",
    "MIN_RELATIVE_EXTENT",
    "RELATIVE_TOLERANCE",
    "Frame",
    "Polygon",
    "as_polygon",
    "edge_halfplanes",
    "rotation_matrix",
]

#: Relative tolerance (to the polygon's diameter) under which two vertices are the same point,
#: three vertices are collinear, or an area is zero.
RELATIVE_TOLERANCE = 1e-12

#: Largest coordinate magnitude accepted (squares of coordinates, as in areas, stay finite).
COORDINATE_LIMIT = 1e100
#: Smallest extent of a polygon relative to its largest coordinate: below it the vertices have
#: fewer than ~4 significant digits in float64.
MIN_RELATIVE_EXTENT = 1e-12

#: Rows of the pairwise distances computed at once by the diameter (memory ~ 24 * n * block).
_DIAMETER_BLOCK = 256
#: Above this many vertices the diameter is sought among the convex hull's vertices only.
_DIAMETER_HULL_FROM = 1024


def rotation_matrix(angle: float) -> NDArray[np.float64]:
    """The 2x2 matrix that rotates points counter-clockwise by ``angle`` radians."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s], [s, c]])


class Frame(NamedTuple):
    """An affine map between user coordinates and the normalised frame.

    ``normalised = (user - centre) / scale``; ``scale`` is the polygon's diameter in user units.
    """

    centre: NDArray[np.float64]
    scale: float

    def to_normalised(self, points: ArrayLike) -> NDArray[np.float64]:
        """Map user points ``(..., 2)`` to the normalised frame."""
        return (np.asarray(points, dtype=np.float64) - self.centre) / self.scale

    def to_user(self, points: ArrayLike) -> NDArray[np.float64]:
        """Map normalised points ``(..., 2)`` back to user coordinates."""
        return np.asarray(points, dtype=np.float64) * self.scale + self.centre


def _as_vertex_array(vertices: ArrayLike) -> NDArray[np.float64]:
    try:
        arr = np.asarray(vertices, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidPolygonError(
            f"expected a sequence of (x, y) number pairs, got non-numeric data: {exc}"
        ) from None
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise InvalidPolygonError(
            f"expected an array of (x, y) pairs with shape (N, 2), got shape {arr.shape}"
        )
    if not np.all(np.isfinite(arr)):
        raise InvalidPolygonError("vertex coordinates must be finite numbers (got NaN or inf)")
    return arr


def _cross(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _twice_signed_area(v: NDArray[np.float64]) -> float:
    """Twice the signed area of the ring ``v`` (shoelace), positive counter-clockwise; summed
    about ``v[0]``: at absolute coordinates a small ring far from the origin cancels to nothing
    (a 1 cm^2 hole at UTM coordinates: 0.0 instead of 2e-4 m^2, refused as zero area)."""
    w = v - v[0]
    return float(np.sum(_cross(w, np.roll(w, -1, axis=0))))


def _drop_duplicates(v: NDArray[np.float64], tol: float) -> NDArray[np.float64]:
    """Remove consecutive (cyclically) coincident vertices, including a closing vertex."""
    steps = np.linalg.norm(np.diff(v, axis=0), axis=1)
    if np.all(steps > tol) and np.linalg.norm(v[-1] - v[0]) > tol:
        return v  # nothing to drop (the usual case), without a loop over the vertices
    keep = [0]
    for i in range(1, len(v)):
        if np.linalg.norm(v[i] - v[keep[-1]]) > tol:
            keep.append(i)
    out = v[keep]
    while len(out) > 1 and np.linalg.norm(out[-1] - out[0]) <= tol:
        out = out[:-1]
    return out


def _drop_collinear(v: NDArray[np.float64], tol: float) -> NDArray[np.float64]:
    """Remove vertices where the boundary goes straight on; refuse spikes (turning back)."""
    changed = True
    while changed and len(v) >= 3:
        changed = False
        prev_edge = v - np.roll(v, 1, axis=0)
        next_edge = np.roll(v, -1, axis=0) - v
        cross = _cross(prev_edge, next_edge)
        scale = np.linalg.norm(prev_edge, axis=1) * np.linalg.norm(next_edge, axis=1)
        flat = np.abs(cross) <= tol * scale
        if np.any(flat):
            i = int(np.argmax(flat))
            if float(np.dot(prev_edge[i], next_edge[i])) < 0:
                raise InvalidPolygonError(
                    f"the boundary turns back on itself at vertex {v[i].tolist()} "
                    "(a zero-width spike): the polygon is not simple"
                )
            v = np.delete(v, i, axis=0)
            changed = True
    return v


def _far_candidates(v: NDArray[np.float64]) -> NDArray[np.float64]:
    """The vertices that can be an end of the farthest pair: ``|p - c| + max |q - c|`` (a bound
    of the farthest distance from ``p``, ``c`` the vertex mean) at least a known pair's
    distance, with a margin of 1e-9 for rounding. Both ends of the farthest pair pass, so the
    maximum over the candidates' pairs is the same number; an elongated ring keeps its two ends
    only (a 1000-vertex ellipse: a few vertices), a circle keeps all."""
    d = v - v.mean(axis=0)
    r = np.sqrt(np.einsum("ij,ij->i", d, d))
    far = v - v[int(np.argmax(r))]
    known = float(np.max(np.einsum("ij,ij->i", far, far)))  # a pair's squared distance
    return v[(r + r.max()) ** 2 * (1.0 + 1e-9) >= known]


def _diameter(v: NDArray[np.float64]) -> float:
    """Largest vertex-to-vertex distance, in blocks of rows (memory ``O(n)``, not ``O(n^2)``).

    The farthest pair is a pair of convex-hull vertices, so a large ring is reduced to its hull
    first (GEOS), and then to the vertices that can end it (:func:`_far_candidates`); the value
    is the same maximum of the same squared distances."""
    if len(v) > _DIAMETER_HULL_FROM:
        import shapely

        hull = shapely.get_coordinates(shapely.convex_hull(shapely.multipoints(v)))
        v = np.unique(hull, axis=0)
    if len(v) > _DIAMETER_BLOCK:
        v = _far_candidates(v)
    best = 0.0
    for start in range(0, len(v), _DIAMETER_BLOCK):
        diffs = v[start : start + _DIAMETER_BLOCK, None, :] - v[None, :, :]
        best = max(best, float(np.max(np.einsum("ijk,ijk->ij", diffs, diffs))))
    return float(np.sqrt(best))


class Polygon:
    """A validated simple polygon with counter-clockwise vertices.

    Built from vertices in any order of traversal: a closing vertex is accepted, consecutive
    duplicates and collinear vertices are removed, clockwise input is re-oriented. Fewer than 3
    distinct vertices, non-finite coordinates, zero area and self-intersection raise
    :class:`~boustro.errors.InvalidPolygonError`.

    Args:
        vertices: ``(N, 2)`` array-like of ``(x, y)`` in user units.

    Example:
        >>> p = Polygon([(0, 0), (0, 1), (2, 1), (2, 0)])  # clockwise in, CCW stored
        >>> p.area, p.is_convex
        (2.0, True)
    """

    __slots__ = ("_diameter", "_is_convex", "_normalised", "_vertices")

    def __init__(self, vertices: ArrayLike) -> None:
        v = _as_vertex_array(vertices)
        if len(v) < 3:
            raise InvalidPolygonError(f"a polygon needs at least 3 vertices, got {len(v)}")
        extent = float(np.max(np.ptp(v, axis=0)))
        size = float(np.max(np.abs(v)))
        if size > COORDINATE_LIMIT:
            raise InvalidPolygonError(
                f"coordinates up to {size:.3g}: boustro supports coordinates within "
                f"+-{COORDINATE_LIMIT:g}"
            )
        if extent < size * MIN_RELATIVE_EXTENT:
            raise InvalidPolygonError(
                f"the polygon is {extent:.3g} across at coordinates of {size:.3g}: too small for "
                f"float64 to resolve (at least {MIN_RELATIVE_EXTENT:g} of the coordinates' size); "
                "subtract a reference point from the coordinates"
            )
        tol = RELATIVE_TOLERANCE * max(extent, np.finfo(np.float64).tiny)
        v = _drop_duplicates(v, tol)
        distinct = len(np.unique(v, axis=0))
        if distinct < 3:
            raise InvalidPolygonError(
                f"a polygon needs at least 3 distinct vertices, got {distinct}"
            )
        far = v[np.argmax(np.linalg.norm(v - v[0], axis=1))] - v[0]
        if np.max(np.abs(_cross(v - v[0], far))) <= RELATIVE_TOLERANCE * extent**2:
            raise InvalidPolygonError("the polygon has zero area (all vertices are collinear)")
        v = _drop_collinear(v, RELATIVE_TOLERANCE)
        if len(v) < 3:
            raise InvalidPolygonError("the polygon has zero area (all vertices are collinear)")
        problem = ring_problem(v, RELATIVE_TOLERANCE * extent)
        if problem is not None:
            raise InvalidPolygonError(problem)
        area2 = _twice_signed_area(v)
        if abs(area2) <= RELATIVE_TOLERANCE * extent**2:
            raise InvalidPolygonError("the polygon has zero area")
        if area2 < 0:
            v = v[::-1].copy()
        v.setflags(write=False)
        self._vertices = v
        turns = _cross(v - np.roll(v, 1, axis=0), np.roll(v, -1, axis=0) - v)
        self._is_convex = bool(np.all(turns > 0))
        self._diameter = _diameter(v)

    # -- basic properties -------------------------------------------------------------------
    @property
    def vertices(self) -> NDArray[np.float64]:
        """``(N, 2)`` read-only array of CCW vertices, no closing vertex."""
        return self._vertices

    def __len__(self) -> int:
        return len(self._vertices)

    def __repr__(self) -> str:
        return f"Polygon({self._vertices.tolist()!r})"

    @property
    def area(self) -> float:
        """Area in user units squared (positive)."""
        return 0.5 * _twice_signed_area(self._vertices)

    @property
    def is_convex(self) -> bool:
        """True when every interior angle is below 180 degrees."""
        return self._is_convex

    @property
    def centre(self) -> NDArray[np.float64]:
        """Mean of the vertices: the origin of the normalised frame (not the area centroid)."""
        return self._vertices.mean(axis=0)

    @property
    def diameter(self) -> float:
        """Largest vertex-to-vertex distance: the unit length of the normalised frame."""
        return self._diameter

    @property
    def frame(self) -> Frame:
        """The map between user coordinates and the paper's normalised frame."""
        return Frame(self.centre, self._diameter)

    def require_convex(self, what: str = "this operation") -> Polygon:
        """Return ``self`` if convex, else raise :class:`NonConvexPolygonError` naming ``what``."""
        if not self._is_convex:
            raise NonConvexPolygonError(
                f"{what} needs a convex polygon, but this one is concave "
                f"({len(self)} vertices, area {self.area:.6g}, "
                f"{self.area / self.convex_hull_area():.4f} of its convex hull)"
            )
        return self

    def convex_hull_area(self) -> float:
        """Area of the convex hull (Andrew's monotone chain)."""
        pts = sorted(map(tuple, self._vertices))

        def half(points: Iterable[tuple[float, float]]) -> list[tuple[float, float]]:
            out: list[tuple[float, float]] = []
            for p in points:
                while (
                    len(out) >= 2
                    and (
                        (out[-1][0] - out[-2][0]) * (p[1] - out[-2][1])
                        - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0])
                    )
                    <= 0
                ):
                    out.pop()
                out.append(p)
            return out

        hull = np.array(half(pts)[:-1] + half(reversed(pts))[:-1])
        return 0.5 * float(np.sum(_cross(hull, np.roll(hull, -1, axis=0))))

    # -- transformations --------------------------------------------------------------------
    def normalised(self) -> Polygon:
        """This polygon in the normalised frame (centred on the vertex mean, diameter 1).

        Made (and validated) once per polygon: a polygon is immutable, and the optimisers and
        the lane layout of one plan each ask for it."""
        try:
            return self._normalised
        except AttributeError:
            self._normalised: Polygon = Polygon(self.frame.to_normalised(self._vertices))
            return self._normalised

    def rotated(self, angle: float, origin: ArrayLike | None = None) -> Polygon:
        """Rotate counter-clockwise by ``angle`` radians about ``origin`` (default: the centre)."""
        o = self.centre if origin is None else np.asarray(origin, dtype=np.float64)
        return Polygon((self._vertices - o) @ rotation_matrix(angle).T + o)

    def translated(self, dx: float, dy: float) -> Polygon:
        return Polygon(self._vertices + np.array([dx, dy]))

    def scaled(self, factor: float, origin: ArrayLike | None = None) -> Polygon:
        o = self.centre if origin is None else np.asarray(origin, dtype=np.float64)
        return Polygon((self._vertices - o) * factor + o)

    # -- half-planes ------------------------------------------------------------------------
    def halfplanes(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Unit inward normals ``(E, 2)`` and offsets ``(E,)``: inside iff ``n . p + b >= 0``.

        For a convex polygon the intersection of these half-planes IS the polygon; for a concave
        one it is not (use the polygon's edges directly).
        """
        return edge_halfplanes(self._vertices)

    @property
    def radius(self) -> float:
        """Largest distance of a vertex from the centre (<= diameter, >= diameter / 2)."""
        return float(np.max(np.linalg.norm(self._vertices - self.centre, axis=1)))


def edge_halfplanes(vertices: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """:meth:`Polygon.halfplanes` of CCW ``vertices`` ``(N, 2)`` taken as they are (no
    validation): unit inward normals ``(N, 2)`` and offsets ``(N,)`` of the edges."""
    p1 = np.asarray(vertices, dtype=np.float64)
    p2 = np.roll(p1, -1, axis=0)
    normal = np.stack([p1[:, 1] - p2[:, 1], p2[:, 0] - p1[:, 0]], axis=1)
    offset = p1[:, 0] * p2[:, 1] - p2[:, 0] * p1[:, 1]
    norm = np.linalg.norm(normal, axis=1)
    return normal / norm[:, None], offset / norm


def as_polygon(polygon: Polygon | ArrayLike) -> Polygon:
    """Accept a :class:`Polygon` or anything :class:`Polygon` accepts.

    Example:
        >>> as_polygon([(0, 0), (1, 0), (0, 1)]).area
        0.5
    """
    return polygon if isinstance(polygon, Polygon) else Polygon(polygon)
