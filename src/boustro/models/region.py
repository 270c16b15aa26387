"""Exact transect segments of regions with holes, and their fitness over many layouts.

A transect line meets a region in several *segments*, found exactly by pairing the line's ring
crossings even-odd; every segment counts as its own transect (Eq. 1 over segments). The soft
counterpart is :mod:`boustro.models.region_soft`. See ``docs/concave.md``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._torch import torch
from .._validate import check_spacing
from ..errors import InvalidParameterError
from ..geometry import Polygon
from ..geometry.region import Region, as_region
from .base import TransectLengths, transect_positions

__all__ = [
    "RegionEdges",
    "RegionExactModel",
    "RegionSegments",
    "region_edges",
    "region_segments",
    "segment_moments",
]


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
    dtype: torch.dtype | None = None,
    device: torch.device | str | None = None,
) -> RegionEdges:
    """The tensor edges of a region, in its normalised frame by default."""
    r = as_region(region)
    e = r.edges
    if normalise:
        e = r.frame.to_normalised(e)
    radius = float(np.max(np.linalg.norm(e[:, 0], axis=1)))
    dtype = torch.float64 if dtype is None else dtype
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

    Example:
        >>> from boustro.geometry import Region
        >>> r = Region([(0, 0), (4, 0), (4, 4), (0, 4)], holes=[[(1, 1), (3, 1), (3, 3), (1, 3)]])
        >>> seg = region_segments(region_edges(r, normalise=False), 0.0, 0.5, 1.0)
        >>> seg.lengths[seg.n_segments > 0].tolist()  # the hole cuts the middle lines in two
        [[4.0, 0.0], [1.0, 1.0], [1.0, 1.0], [4.0, 0.0]]
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
