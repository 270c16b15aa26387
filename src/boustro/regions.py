"""Areas with concave boundaries and holes: validation, exact transect segments, a soft model.

The paper's model needs a convex polygon. A survey *region* here is a simple polygon (the
*shell*, any shape) minus zero or more *holes* (obstacles: ponds, buildings). A transect line
meets it in several *segments*; this module computes them exactly, scores them, and offers a
differentiable counterpart whose gradients reach the angle and the offset for any region.

Conventions are those of :mod:`boustro.models`: ``theta`` is the transect direction,
``u = (cos, sin)``, ``n = (-sin, cos)`` its left normal, transect ``k`` is the line
``n . p = d + k s`` with positions from :func:`boustro.models.transect_positions`, and ``t = u . p``
is the along-transect coordinate. The normalised frame is the SHELL's (vertex mean of the shell,
diameter of the shell), so a region without holes has the frame of its polygon.

Exact segments
--------------
Every ring edge is oriented with the region on its left (shell counter-clockwise, holes
clockwise). Edge ``p1 -> p2`` with across-coordinates ``c1 = n . p1``, ``c2 = n . p2`` is crossed
by the line at ``c`` iff ``(c1 <= c) != (c2 <= c)`` (half-open, so a line through a vertex counts
it once or twice, consistently, and every ring gives an even number of crossings); the crossing is
at ``t = t1 + (c - c1) (t2 - t1) / (c2 - c1)``. Sorted along the line, crossings pair up
(even-odd) into the segments ``[t_0, t_1], [t_2, t_3], ...``. Edges parallel to the transects are
never crossed (their neighbours' vertices are). Exact to rounding, O(E log E) per line.

Fitness per segment
-------------------
A vehicle drives every segment as its own transect (it turns at each end), so boustro scores a
layout of a region with Eq. 1 over the SEGMENTS: ``f = a mean(L) + b (1 - std(L))`` over the
lengths of all segments of all lines (normalised frame, population std). A line cut in two by a
hole counts as two transects, which lowers the mean and usually raises the std: the fitness
prefers layouts whose lines are cut less. For a convex polygon every line has one segment and
this is exactly the paper's fitness. :class:`RegionExactModel` returns the segment lengths as
:class:`~boustro.models.TransectLengths` with ``K = lines x segment slots`` entries (empty slots
length 0, weight 0), so every fitness of :mod:`boustro.fitness` applies unchanged;
``per="line"`` scores the total length inside per line instead.

The differentiable model
------------------------
The soft indicator of the region at smoothing length ``h`` is the region's indicator blurred
ACROSS the transects by a logistic kernel ``k_h(s) = sigmoid'(s / h) / h``::

    I_h(p) = integral 1_R(p - s n) k_h(s) ds        (~1 inside, ~0 outside and in holes)

Its integral along transect ``c`` is the exact total length inside, ``L(c)``, convolved with
``k_h``, and that convolution has a closed form: cut the region into *trapezoids* by lines
through every vertex parallel to the transects (slabs between consecutive vertex positions; in
each slab the segments are bounded by a fixed entry and exit edge, so the chord length is linear
in ``c``). A trapezoid with ``c`` in ``[a, b]`` and chord length ``l(c)`` linear contributes

* weight ``w = F(c - a) - F(c - b)`` with ``F(x) = sigmoid(x / h)`` (the kernel mass of
  ``[a, b]`` seen from ``c``), and
* length ``L = l(c*)`` at the kernel-weighted mean position ``c* = c - (G(c - a) - G(c - b)) / w``
  with ``G(x) = x sigmoid(x / h) - h softplus(x / h)`` (the kernel's partial first moment),

so that ``w L = integral_a^b l(c') k_h(c - c') dc'`` exactly. Each (line, trapezoid) pair is a
*soft segment*: with ``h -> 0`` the trapezoid holding a segment of line ``c`` gets weight 1, every
other weight 0, and the soft lengths and weights become the exact segments (tested). Summed over
a line, ``sum w L`` is the closed-form line integral of ``I_h`` (tested by quadrature), and
``sum w`` is the segment count convolved with ``k_h``. The fitness over soft segments is Eq. 1
with these weights (``statistics="weighted"``): the mean is exact for the blurred lengths, the
variance omits each trapezoid's own variation within the kernel's width (``O(h)``). Which edges
bound each trapezoid is decided without gradient (it is constant between vertex events); the
positions ``a, b`` and the chord lengths carry the gradient to ``theta`` and ``offset``.

Why not a product of sigmoids over a convex decomposition: the line integral of a product of
sigmoids has no closed form, while the kernel blur keeps the closed form of
:mod:`boustro.smooth`'s idea (O(1) per trapezoid and line, no sampling), stays non-negative (a
blurred indicator), and keeps the segment structure that the per-segment fitness needs.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal, NamedTuple

import numpy as np
import torch
import torch.nn.functional as F
from numpy.typing import ArrayLike, NDArray

from .errors import InvalidParameterError, InvalidPolygonError, as_number
from .fitness import SmithFitness
from .geometry import Frame, Polygon, random_convex_polygon
from .models import TransectLengths, check_spacing, transect_positions
from .objectives import objective_sign

__all__ = [
    "TOUCH_TOLERANCE",
    "Region",
    "RegionEdges",
    "RegionExactModel",
    "RegionSegments",
    "RegionSoftModel",
    "as_region",
    "evaluate_region_grid",
    "points_in_ring",
    "random_region",
    "region_edges",
    "region_segments",
    "segment_distances",
    "segment_moments",
    "soft_indicator",
    "soft_region_lengths",
]

#: Relative tolerance (to the shell's diameter) under which a hole is said to touch the shell
#: or another hole.
TOUCH_TOLERANCE = 1e-9


# -- small vectorised geometry ----------------------------------------------------------------
def _cross(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


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
        self._holes = tuple(_as_polygon(h, f"hole {i}") for i, h in enumerate(holes))
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
    tol = TOUCH_TOLERANCE * shell.diameter
    shell_edges = _ring_segments(shell.vertices)
    hole_edges = [_ring_segments(h.vertices) for h in holes]
    for i, (hole, edges) in enumerate(zip(holes, hole_edges, strict=True)):
        d = segment_distances(edges, shell_edges)
        if d.min() <= tol:
            j = int(np.argmin(d.min(axis=1)))
            raise InvalidPolygonError(
                f"hole {i} touches or crosses the shell's boundary near "
                f"{edges[j, 0].tolist()} (holes must lie strictly inside the shell)"
            )
        if not points_in_ring(hole.vertices[:1], shell.vertices)[0]:
            raise InvalidPolygonError(
                f"hole {i} lies outside the shell (its vertex {hole.vertices[0].tolist()} is not "
                "inside the shell)"
            )
    for i in range(len(holes)):
        for j in range(i + 1, len(holes)):
            d = segment_distances(hole_edges[i], hole_edges[j])
            if d.min() <= tol:
                k = int(np.argmin(d.min(axis=1)))
                raise InvalidPolygonError(
                    f"holes {i} and {j} touch or overlap near {hole_edges[i][k, 0].tolist()} "
                    "(holes must be disjoint)"
                )
            if points_in_ring(holes[j].vertices[:1], holes[i].vertices)[0]:
                raise InvalidPolygonError(f"hole {j} lies inside hole {i} (holes must be disjoint)")
            if points_in_ring(holes[i].vertices[:1], holes[j].vertices)[0]:
                raise InvalidPolygonError(f"hole {i} lies inside hole {j} (holes must be disjoint)")


def as_region(area: Region | Polygon | ArrayLike) -> Region:
    """A :class:`Region` from a region, a polygon (no holes), or ``(N, 2)`` shell vertices."""
    if isinstance(area, Region):
        return area
    return Region(area)


# -- tensors of edges -------------------------------------------------------------------------
class RegionEdges(NamedTuple):
    """A region's ring edges as tensors, the region's counterpart of
    :class:`~boustro.geometry.HalfPlanes` for the transect models.

    Attributes:
        starts, ends: ``(E, 2)`` edge end points, region on the left of ``start -> end``.
        radius: a bound on the distance of every vertex from the origin.
    """

    starts: torch.Tensor
    ends: torch.Tensor
    radius: float

    @property
    def normals(self) -> torch.Tensor:
        """``(E, 2)`` unit inward (left) normals; present so that code sizing batches by
        ``normals.shape[-2]`` (the number of edges) works with regions too."""
        d = self.ends - self.starts
        left = torch.stack([-d[..., 1], d[..., 0]], dim=-1)
        return left / left.norm(dim=-1, keepdim=True).clamp_min(torch.finfo(d.dtype).tiny)


def region_edges(
    region: Region | Polygon | ArrayLike,
    *,
    normalise: bool = True,
    dtype: torch.dtype = torch.float64,
    device: torch.device | str | None = None,
) -> RegionEdges:
    """The tensor edges of a region, in its normalised frame by default."""
    r = as_region(region)
    e = r.edges
    if normalise:
        e = r.frame.to_normalised(e)
    radius = float(np.max(np.linalg.norm(e[:, 0], axis=1)))
    return RegionEdges(
        torch.as_tensor(np.ascontiguousarray(e[:, 0]), dtype=dtype, device=device),
        torch.as_tensor(np.ascontiguousarray(e[:, 1]), dtype=dtype, device=device),
        radius,
    )


def _project(
    edges: RegionEdges, theta: torch.Tensor
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]:
    """``(c1, c2, t1, t2)``, each ``(*, E)``: edge ends across (``n .``) and along (``u .``)."""
    cos, sin = torch.cos(theta)[..., None], torch.sin(theta)[..., None]
    sx, sy = edges.starts[..., 0], edges.starts[..., 1]
    ex, ey = edges.ends[..., 0], edges.ends[..., 1]
    return -sx * sin + sy * cos, -ex * sin + ey * cos, sx * cos + sy * sin, ex * cos + ey * sin


def _as_tensors(
    edges: RegionEdges, theta: torch.Tensor | float, offset: torch.Tensor | float
) -> tuple[torch.Tensor, torch.Tensor]:
    dtype, device = edges.starts.dtype, edges.starts.device
    a = torch.as_tensor(theta, dtype=dtype, device=device)
    d = torch.as_tensor(offset, dtype=dtype, device=device)
    a, d = torch.broadcast_tensors(a, d)
    return a, d


# -- exact segments ---------------------------------------------------------------------------
class RegionSegments(NamedTuple):
    """Exact segments of a transect grid in a region.

    Attributes:
        positions: ``(*, K)`` line positions ``d + k s``.
        lower, upper: ``(*, K, M)`` along-coordinates of each segment's ends (0 in empty slots).
        lengths: ``(*, K, M)`` segment lengths (0 in empty slots); ``M`` is the largest number of
            segments on any line of the batch.
        n_segments: ``(*, K)`` number of segments on each line (a line through a vertex where
            the region only touches it may have a zero-length one).
    """

    positions: torch.Tensor
    lower: torch.Tensor
    upper: torch.Tensor
    lengths: torch.Tensor
    n_segments: torch.Tensor


def _segments_at(
    edges: RegionEdges, theta: torch.Tensor, c: torch.Tensor
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]:
    """Sorted crossings of the lines at positions ``c (*, K)`` (angle ``theta (*)``).

    Returns ``(lower, upper, count, entry, exit)``: ``(*, K, M)`` segment ends, ``(*, K)``
    segment counts, and the index of the edge at each end (``(*, K, M)``, only meaningful where
    ``slot < count``).
    """
    c1, c2, t1, t2 = _project(edges, theta)
    cc = c[..., :, None]
    c1k, c2k = c1[..., None, :], c2[..., None, :]
    cross = (c1k <= cc) != (c2k <= cc)  # (*, K, E)
    dc = c2 - c1
    slope = (t2 - t1) / torch.where(dc == 0, torch.ones_like(dc), dc)
    t = t1[..., None, :] + (cc - c1k) * slope[..., None, :]
    inf = torch.as_tensor(math.inf, dtype=t.dtype, device=t.device)
    ts, order = torch.sort(torch.where(cross, t, inf), dim=-1)
    n_cross = cross.sum(dim=-1)
    m = int(n_cross.max()) // 2 if n_cross.numel() else 0
    lower, upper = ts[..., 0 : 2 * m : 2], ts[..., 1 : 2 * m : 2]
    count = torch.div(n_cross, 2, rounding_mode="floor")
    valid = torch.arange(m, device=t.device) < count[..., None]
    zero = torch.zeros((), dtype=t.dtype, device=t.device)
    lower = torch.where(valid, lower, zero)
    upper = torch.where(valid, upper, zero)
    return lower, upper, count, order[..., 0 : 2 * m : 2], order[..., 1 : 2 * m : 2]


def region_segments(
    edges: RegionEdges,
    theta: torch.Tensor | float,
    offset: torch.Tensor | float,
    spacing: float,
) -> RegionSegments:
    """Exact segments of every transect of the grid ``(theta, offset, spacing)`` in a region.

    Batched over the broadcast shape ``(*)`` of ``theta`` and ``offset``; differentiable almost
    everywhere in both (not where a line passes a vertex), gradients finite everywhere.

    Args:
        edges: :func:`region_edges` (normalised frame by default).
        theta: transect direction(s), radians.
        offset: grid offset(s), same frame as the edges.
        spacing: transect spacing, same frame, > 0.
    """
    spacing = check_spacing(spacing)
    theta, offset = _as_tensors(edges, theta, offset)
    c = transect_positions(offset, spacing, edges.radius)
    lower, upper, count, _, _ = _segments_at(edges, theta, c)
    return RegionSegments(c, lower, upper, upper - lower, count)


Per = Literal["segment", "line"]


@dataclass(frozen=True)
class RegionExactModel:
    """Exact transect lengths of a region, for any fitness (module docstring).

    ``per="segment"`` (default): one entry per segment, ``K = lines x M`` entries, weights 1 for
    segments of positive length. ``per="line"``: one entry per line, the total length inside.
    Called like the convex models, with :class:`RegionEdges` in place of half-planes.
    """

    per: Per = "segment"
    name: str = "region-exact"

    def __post_init__(self) -> None:
        if self.per not in ("segment", "line"):
            raise InvalidParameterError(f"per must be 'segment' or 'line', got {self.per!r}")

    def __call__(
        self,
        edges: RegionEdges,
        theta: torch.Tensor | float,
        offset: torch.Tensor | float,
        spacing: float,
    ) -> TransectLengths:
        seg = region_segments(edges, theta, offset, spacing)
        tiny = 1e-12 * max(edges.radius, 1e-300)
        if self.per == "line":
            lengths = seg.lengths.sum(dim=-1)
            positions = seg.positions
        else:
            lengths = seg.lengths.flatten(-2)
            positions = seg.positions[..., None].expand_as(seg.lengths).flatten(-2)
        return TransectLengths(lengths, (lengths > tiny).to(lengths.dtype), positions)


# -- fast exact moments (numpy) ---------------------------------------------------------------
def segment_moments(
    edges: NDArray[np.float64],
    angles: ArrayLike,
    offsets: ArrayLike,
    spacing: float,
    *,
    tiny: float = 0.0,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Count, sum and sum of squares of the segment lengths of many layouts, in O(crossings).

    The sparse counterpart of :func:`region_segments` for scoring: each edge is crossed by the
    lines ``k`` with ``lo <= d + k s < hi`` (``lo, hi`` its across-extent), so the crossings are
    generated directly, sorted per (layout, line) and paired, with no ``K x E`` table.

    Args:
        edges: ``(E, 2, 2)`` ring edges (any frame; e.g. :attr:`Region.edges`, normalised).
        angles, offsets: ``(P,)`` layouts (the same frame as ``edges``).
        spacing: transect spacing, > 0.
        tiny: segments of length ``<= tiny`` are ignored (a line touching a vertex).

    Returns:
        ``(count, sum, sum of squares)``, each ``(P,)``.
    """
    s = check_spacing(spacing)
    a = np.asarray(angles, dtype=np.float64).reshape(-1)
    d = np.asarray(offsets, dtype=np.float64).reshape(-1)
    n_pairs = len(a)
    cos, sin = np.cos(a)[:, None], np.sin(a)[:, None]
    p1, p2 = edges[:, 0], edges[:, 1]
    c1 = -p1[:, 0] * sin + p1[:, 1] * cos  # (P, E)
    c2 = -p2[:, 0] * sin + p2[:, 1] * cos
    t1 = p1[:, 0] * cos + p1[:, 1] * sin
    t2 = p2[:, 0] * cos + p2[:, 1] * sin
    lo, hi = np.minimum(c1, c2), np.maximum(c1, c2)
    k_lo = np.ceil((lo - d[:, None]) / s)
    k_hi = np.ceil((hi - d[:, None]) / s)
    # Floating ceil can miss the half-open rule by one line at an exact vertex; fix it against
    # the rule itself so every ring keeps an even number of crossings on every line.
    dd = d[:, None]
    k_lo -= (dd + (k_lo - 1) * s >= lo).astype(np.float64)
    k_lo += (dd + k_lo * s < lo).astype(np.float64)
    k_hi -= (dd + (k_hi - 1) * s >= hi).astype(np.float64)
    k_hi += (dd + k_hi * s < hi).astype(np.float64)
    counts = np.maximum(k_hi - k_lo, 0).astype(np.int64).ravel()
    total = int(counts.sum())
    zeros = np.zeros(n_pairs)
    if total == 0:
        return zeros, zeros.copy(), zeros.copy()
    flat = np.repeat(np.arange(counts.size), counts)
    first = np.repeat(np.cumsum(counts) - counts, counts)
    k = k_lo.ravel()[flat] + (np.arange(total) - first)
    pair = flat // edges.shape[0]
    c = d[pair] + k * s
    c1f, c2f, t1f, t2f = c1.ravel()[flat], c2.ravel()[flat], t1.ravel()[flat], t2.ravel()[flat]
    t = t1f + (c - c1f) * (t2f - t1f) / (c2f - c1f)
    order = np.lexsort((t, k, pair))
    t, pair = t[order], pair[order]
    length = t[1::2] - t[0::2]
    pair = pair[0::2]
    keep = length > tiny
    length, pair = length[keep], pair[keep]
    count = np.asarray(np.bincount(pair, minlength=n_pairs), dtype=np.float64)
    s1 = np.asarray(np.bincount(pair, weights=length, minlength=n_pairs), dtype=np.float64)
    s2 = np.asarray(np.bincount(pair, weights=length * length, minlength=n_pairs), dtype=np.float64)
    return count, s1, s2


#: Upper bound on the crossings generated by one call of :func:`segment_moments` inside
#: :func:`evaluate_region_grid` (layouts are processed in chunks under it).
_CHUNK_CROSSINGS = 2_000_000


def evaluate_region_grid(
    edges: RegionEdges | NDArray[np.float64],
    angles: ArrayLike,
    offsets: ArrayLike,
    spacing: float,
    *,
    fitness: object | None = None,
    model: RegionExactModel | None = None,
    pairs: bool = False,
) -> NDArray[np.float64]:
    """Exact per-segment fitness of every (angle, offset), ``(A, O)`` (or ``(N,)`` with
    ``pairs=True``); layouts with no segment get the worst value (``-inf`` if maximised).

    Eq. 1 (:class:`~boustro.fitness.SmithFitness`, weighted statistics, the default) runs on
    :func:`segment_moments` (sparse, fast); any other objective on :class:`RegionExactModel`.
    """
    fitness = SmithFitness() if fitness is None else fitness
    model = RegionExactModel() if model is None else model
    sign = objective_sign(fitness)
    if isinstance(edges, RegionEdges):
        e = torch.stack([edges.starts, edges.ends], dim=-2).detach().cpu().numpy()
        radius = edges.radius
    else:
        e = np.asarray(edges, dtype=np.float64)
        radius = float(np.max(np.linalg.norm(e[:, 0], axis=1)))
    a = np.asarray(angles, dtype=np.float64).reshape(-1)
    o = np.asarray(offsets, dtype=np.float64).reshape(-1)
    if pairs:
        if a.shape != o.shape:
            raise InvalidParameterError(f"pairs need equal lengths, got {a.shape} and {o.shape}")
        aa, oo = a, o
    else:
        aa, oo = np.repeat(a, len(o)), np.tile(o, len(a))
    tiny = 1e-12 * max(radius, 1e-300)
    fast = (
        isinstance(fitness, SmithFitness)
        and fitness.statistics == "weighted"
        and model.per == "segment"
    )
    out = np.empty(len(aa))
    per_layout = max(1, int(2 * len(e) * (2 * radius / spacing + 2) / 4))
    chunk = max(1, _CHUNK_CROSSINGS // per_layout)
    for i in range(0, len(aa), chunk):
        sl = slice(i, i + chunk)
        if fast:
            n, s1, s2 = segment_moments(e, aa[sl], oo[sl], spacing, tiny=tiny)
            den = np.where(n > 0, n, 1.0)
            mean = s1 / den
            var = np.maximum(s2 / den - mean**2, 0.0)
            value = fitness.a * mean + fitness.b * (1 - np.sqrt(var))  # type: ignore[attr-defined]
        else:
            te = RegionEdges(torch.as_tensor(e[:, 0]), torch.as_tensor(e[:, 1]), radius)
            with torch.no_grad():
                tl = model(te, torch.as_tensor(aa[sl]), torch.as_tensor(oo[sl]), spacing)
                value = fitness(tl).numpy()  # type: ignore[operator]
                n = tl.weights.sum(dim=-1).numpy()
        out[sl] = np.where((n > 0) & ~np.isnan(value), value, -math.inf * sign)
    return out if pairs else out.reshape(len(a), len(o))


# -- the differentiable model ------------------------------------------------------------------
def _g(x: torch.Tensor, h: torch.Tensor | float) -> torch.Tensor:
    """``G(x) = integral_{-inf}^x y k_h(y) dy = x sigmoid(x/h) - h softplus(x/h)``, even in x,
    computed at ``-|x|`` so that nothing cancels."""
    z = -x.abs()
    return z * torch.sigmoid(z / h) - h * F.softplus(z / h)


class _Trapezoids(NamedTuple):
    a: torch.Tensor  # (B, S) slab bottoms
    b: torch.Tensor  # (B, S) slab tops
    la: torch.Tensor  # (B, S, P) chord length at a
    lb: torch.Tensor  # (B, S, P) chord length at b
    valid: torch.Tensor  # (B, S, P)


def _trapezoids(edges: RegionEdges, theta: torch.Tensor) -> _Trapezoids:
    """Slab decomposition at angles ``theta (B,)``: slabs between consecutive vertex positions,
    each cut into trapezoids by its segments (which edges bound them is found without grad)."""
    c1, c2, t1, t2 = _project(edges, theta)  # (B, E)
    events, _ = torch.sort(c1, dim=-1)  # every vertex starts exactly one edge
    a, b = events[..., :-1], events[..., 1:]  # (B, S)
    with torch.no_grad():
        mid = (a + b) / 2
        _, _, count, entry, exit_ = _segments_at(
            RegionEdges(edges.starts.detach(), edges.ends.detach(), edges.radius),
            theta.detach(),
            mid,
        )
        valid = torch.arange(entry.shape[-1], device=entry.device) < count[..., None]
        valid &= (b - a > 0)[..., None]
    dc = c2 - c1
    slope = (t2 - t1) / torch.where(dc == 0, torch.ones_like(dc), dc)  # (B, E)

    def t_at(edge: torch.Tensor, c: torch.Tensor) -> torch.Tensor:
        """Along-coordinate of edge ``edge (B, S, P)`` at positions ``c (B, S)``."""
        flat = edge.flatten(-2)
        g = lambda x: torch.gather(x, -1, flat).view(edge.shape)  # noqa: E731
        return g(t1) + (c[..., None] - g(c1)) * g(slope)

    la = (t_at(exit_, a) - t_at(entry, a)).clamp_min(0.0)
    lb = (t_at(exit_, b) - t_at(entry, b)).clamp_min(0.0)
    zero = torch.zeros((), dtype=la.dtype, device=la.device)
    return _Trapezoids(a, b, torch.where(valid, la, zero), torch.where(valid, lb, zero), valid)


def _check_smoothing(smoothing: float) -> float:
    h = as_number("smoothing", smoothing)
    if not (math.isfinite(h) and h > 0):
        raise InvalidParameterError(f"smoothing must be finite and > 0, got {smoothing!r}")
    return h


def soft_region_lengths(
    edges: RegionEdges,
    theta: torch.Tensor | float,
    offset: torch.Tensor | float,
    spacing: float,
    *,
    smoothing: float = 1e-3,
) -> TransectLengths:
    """Soft segments of a region's transect grid in closed form (module docstring).

    Args:
        edges: :func:`region_edges` of ONE region (``(E, 2)`` tensors).
        theta, offset: ``(*B)`` broadcasting; gradients flow to both.
        spacing: transect spacing, same frame as the edges.
        smoothing: the kernel's length ``h`` (> 0, same frame); ``h = 1 / T`` matches the
            temperature of the paper's sigmoids.

    Returns:
        :class:`~boustro.models.TransectLengths` ``(*B, K * S * P)``: one soft segment per
        (line, slab, segment slot), ``S = E - 1`` slabs and ``P`` slots; ``sum(w L)`` over a
        line is the line integral of :func:`soft_indicator`.
    """
    spacing = check_spacing(spacing)
    h = _check_smoothing(smoothing)
    theta, offset = _as_tensors(edges, theta, offset)
    shape = theta.shape
    theta, offset = theta.reshape(-1), offset.reshape(-1)
    tr = _trapezoids(edges, theta)
    c = transect_positions(offset, spacing, edges.radius + 32.0 * h)  # (B, K)
    cc = c[:, :, None]  # (B, K, 1)
    a, b = tr.a[:, None, :], tr.b[:, None, :]  # (B, 1, S)
    xa, xb = cc - a, cc - b
    w = torch.sigmoid(xa / h) - torch.sigmoid(xb / h)  # (B, K, S)
    dg = _g(xa, h) - _g(xb, h)
    tiny = torch.finfo(w.dtype).tiny ** 0.5
    ok = w > tiny
    c_star = cc - dg / torch.where(ok, w, torch.ones_like(w))
    nearest = torch.where(cc < a, a, b).expand_as(c_star)
    c_star = torch.where(ok, torch.minimum(torch.maximum(c_star, a), b), nearest)
    width = b - a
    frac = (c_star - a) / torch.where(width > 0, width, torch.ones_like(width))  # (B, K, S)
    la, lb = tr.la[:, None], tr.lb[:, None]  # (B, 1, S, P)
    length = la + (lb - la) * frac[..., None]  # (B, K, S, P)
    weight = w[..., None] * tr.valid[:, None].to(w.dtype)
    length = length * tr.valid[:, None].to(w.dtype)
    k = c.shape[-1]
    positions = c[:, :, None, None].expand_as(length)
    return TransectLengths(
        length.reshape(*shape, k * length.shape[-2] * length.shape[-1]),
        weight.expand_as(length).reshape(*shape, -1),
        positions.reshape(*shape, -1),
    )


@dataclass(frozen=True)
class RegionSoftModel:
    """The differentiable region model with its smoothing length; see
    :func:`soft_region_lengths`. ``h = 1 / T`` (:meth:`from_temperature`)."""

    smoothing: float = 1e-3
    name: str = "region-soft"

    def __post_init__(self) -> None:
        _check_smoothing(self.smoothing)

    @classmethod
    def from_temperature(cls, temperature: float) -> RegionSoftModel:
        t = float(temperature)
        if not (math.isfinite(t) and t > 0):
            raise InvalidParameterError(f"temperature must be finite and > 0, got {temperature!r}")
        return cls(smoothing=1.0 / t)

    @property
    def temperature(self) -> float:
        return 1.0 / self.smoothing

    def __call__(
        self,
        edges: RegionEdges,
        theta: torch.Tensor | float,
        offset: torch.Tensor | float,
        spacing: float,
    ) -> TransectLengths:
        return soft_region_lengths(edges, theta, offset, spacing, smoothing=self.smoothing)


def soft_indicator(
    edges: RegionEdges,
    points: torch.Tensor,
    theta: torch.Tensor | float,
    *,
    smoothing: float = 1e-3,
) -> torch.Tensor:
    """The soft indicator ``I_h(p)`` of the region blurred across transects of direction
    ``theta`` (module docstring): ~1 inside, ~0 outside and in holes, a transition ``~h`` wide.

    Closed form: the line through ``p`` along ``n`` meets the region in segments
    ``[c_lo, c_hi]`` (positions along ``n``), and ``I_h(p) = sum sigmoid((n.p - c_lo) / h) -
    sigmoid((n.p - c_hi) / h)``.

    Args:
        edges: :func:`region_edges` of one region.
        points: ``(*P, 2)`` points in the edges' frame.
        theta: transect direction (a scalar).
        smoothing: ``h`` > 0.

    Returns:
        ``(*P)`` values in ``[0, 1]``.
    """
    h = _check_smoothing(smoothing)
    dtype, device = edges.starts.dtype, edges.starts.device
    pts = torch.as_tensor(points, dtype=dtype, device=device)
    theta = torch.as_tensor(theta, dtype=dtype, device=device)
    if theta.ndim:
        raise InvalidParameterError("soft_indicator takes one angle (a scalar theta)")
    shape = pts.shape[:-1]
    p = pts.reshape(-1, 2)
    u = torch.stack([torch.cos(theta), torch.sin(theta)])
    n = torch.stack([-torch.sin(theta), torch.cos(theta)])
    # Lines along n through each point: direction theta + pi/2, left normal -u, position -u.p.
    perp = theta + math.pi / 2
    lower, upper, count, _, _ = _segments_at(edges, perp, (-(p @ u))[None, :])
    lower, upper = lower[0], upper[0]  # (P, M): along n, i.e. positions n . q
    valid = torch.arange(lower.shape[-1], device=device) < count[0][:, None]
    cp = (p @ n)[:, None]
    value = torch.sigmoid((cp - lower) / h) - torch.sigmoid((cp - upper) / h)
    value = torch.where(valid, value, torch.zeros_like(value)).sum(dim=-1)
    return value.reshape(shape)


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
