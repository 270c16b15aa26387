"""Batches of convex polygons with their own spacings, scored in one batched model call."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._torch import torch
from ..errors import InvalidParameterError, NoTransectError
from ..geometry import PAD_OFFSET, HalfPlanes, Polygon, random_convex_polygon
from ..models import ExactModel, TransectLengths, check_spacing
from ..models.smooth import smooth_lengths
from ..objectives import as_plan_objective
from ..scoring import as_polygon

__all__ = [
    "PlanBatch",
    "batch_lengths",
    "batch_objective",
    "from_normalised",
    "make_batch",
    "random_batch",
]


class PlanBatch(NamedTuple):
    """``P`` convex polygons in their normalised frames, padded to ``N`` vertices, and spacings.

    Attributes:
        vertices: ``(P, N, 2)`` CCW vertices (diameter 1, centred on the vertex mean); padding
            repeats the first vertex.
        mask: ``(P, N)`` True for real vertices (and for the edge starting there).
        normals: ``(P, N, 2)`` unit inward normals of the edges ``v_j -> v_j+1``; padding 0.
        offsets: ``(P, N)`` half-plane offsets (the edge's distance from the centre); padding
            :data:`~boustro.geometry.PAD_OFFSET` (always true).
        spacing: ``(P,)`` spacings, normalised frame.
        radius: ``(P,)`` largest vertex distance from the centre.
        scale: ``(P,)`` user length of one normalised unit (the diameter), to map results back.
        centre: ``(P, 2)`` vertex mean in user units.
    """

    vertices: torch.Tensor
    mask: torch.Tensor
    normals: torch.Tensor
    offsets: torch.Tensor
    spacing: torch.Tensor
    radius: torch.Tensor
    scale: torch.Tensor
    centre: torch.Tensor

    @property
    def size(self) -> int:
        """The number of polygons ``P``."""
        return int(self.vertices.shape[0])

    def to(self, dtype: torch.dtype) -> PlanBatch:
        """The same batch with floating tensors in ``dtype``."""
        return PlanBatch(*(t if t.dtype == torch.bool else t.to(dtype) for t in self))

    def select(self, index: torch.Tensor) -> PlanBatch:
        """The sub-batch ``index`` (a 1-D index or boolean tensor)."""
        return PlanBatch(*(t[index] for t in self))


def from_normalised(
    vertices: Sequence[NDArray[np.float64]],
    spacing: ArrayLike,
    scale: ArrayLike,
    centre: ArrayLike,
    dtype: torch.dtype | None,
) -> PlanBatch:
    """A :class:`PlanBatch` of CCW vertices already in their normalised frames (float64 tensors
    unless ``dtype``)."""
    dtype = torch.float64 if dtype is None else dtype
    n_max = max(len(v) for v in vertices)
    verts = np.empty((len(vertices), n_max, 2))
    mask = np.zeros((len(vertices), n_max), dtype=bool)
    for k, vk in enumerate(vertices):
        verts[k, : len(vk)] = vk
        verts[k, len(vk) :] = vk[0]
        mask[k, : len(vk)] = True
    v = torch.as_tensor(verts, dtype=torch.float64)
    m = torch.as_tensor(mask)
    count = m.sum(dim=1)
    nxt = (torch.arange(n_max)[None, :] + 1) % count[:, None]
    p2 = torch.gather(v, 1, nxt[..., None].expand(-1, -1, 2))
    normal = torch.stack([v[..., 1] - p2[..., 1], p2[..., 0] - v[..., 0]], dim=-1)
    offset = v[..., 0] * p2[..., 1] - p2[..., 0] * v[..., 1]
    norm = torch.linalg.norm(normal, dim=-1)
    safe = torch.where(m, norm, torch.ones_like(norm))
    normal = torch.where(m[..., None], normal / safe[..., None], 0.0)
    offset = torch.where(m, offset / safe, PAD_OFFSET)
    radius = torch.linalg.norm(v, dim=-1).amax(dim=1)
    f = lambda x: torch.as_tensor(np.asarray(x, dtype=np.float64)).to(dtype)  # noqa: E731
    return PlanBatch(
        v.to(dtype),
        m,
        normal.to(dtype),
        offset.to(dtype),
        f(spacing),
        radius.to(dtype),
        f(scale),
        f(centre).reshape(-1, 2),
    )


def make_batch(
    polygons: Sequence[Polygon | ArrayLike],
    spacings: ArrayLike,
    *,
    dtype: torch.dtype | None = None,
) -> PlanBatch:
    """A :class:`PlanBatch` of convex polygons (user units) and spacings (user units).

    Args:
        polygons: ``P`` convex polygons (any :class:`~boustro.geometry.Polygon` or vertices).
        spacings: one spacing for all, or ``(P,)``, in each polygon's units, each smaller than
            its polygon's diameter.

    Raises:
        NonConvexPolygonError: a polygon is concave.
        NoTransectError: a spacing is not smaller than its polygon's diameter.
    """
    polys = [as_polygon(p).require_convex("the learned planner") for p in polygons]
    if not polys:
        raise InvalidParameterError("expected at least one polygon, got none")
    s = np.broadcast_to(np.asarray(spacings, dtype=np.float64), (len(polys),))
    for k, (p, sk) in enumerate(zip(polys, s, strict=True)):
        check_spacing(sk)
        if sk >= p.diameter:
            raise NoTransectError(
                f"spacing {sk:g} of polygon {k} is not smaller than its diameter {p.diameter:g}"
            )
    frames = [p.frame for p in polys]
    verts = [f.to_normalised(p.vertices) for p, f in zip(polys, frames, strict=True)]
    scale = np.array([f.scale for f in frames])
    centre = np.array([f.centre for f in frames])
    return from_normalised(verts, s / scale, scale, centre, dtype)


def random_batch(
    rng: np.random.Generator,
    count: int,
    *,
    min_vertices: int = 3,
    max_vertices: int = 9,
    min_spacing: float = 0.01,
    max_spacing: float = 1.0 / 3.0,
    dtype: torch.dtype | None = None,
) -> PlanBatch:
    """``count`` random convex polygons (Valtr, ``min..max`` vertices, normalised frame) with
    spacings uniform in ``(min_spacing, max_spacing)`` of the diameter: the benchmarks'
    distribution."""
    polys = [
        random_convex_polygon(rng, int(rng.integers(min_vertices, max_vertices + 1)))
        for _ in range(count)
    ]
    s = rng.uniform(min_spacing, max_spacing, count)
    return from_normalised(
        [p.vertices for p in polys], s, np.ones(count), np.zeros((count, 2)), dtype
    )


def _size_classes(batch: PlanBatch) -> list[torch.Tensor]:
    """Indices grouped by ``ceil(log2(radius / spacing))``: each group's grid of candidate
    transects is at most twice as long as any member needs."""
    ratio = (batch.radius / batch.spacing).detach().to(torch.float64)
    key = torch.ceil(torch.log2(ratio.clamp(min=1.0)))
    return [torch.nonzero(key == k)[:, 0] for k in torch.unique(key)]


def batch_lengths(
    batch: PlanBatch,
    index: torch.Tensor,
    theta: torch.Tensor,
    offset: torch.Tensor,
    smoothing: float | None,
) -> TransectLengths:
    """Transect lengths of the polygons ``index`` at layouts ``theta, offset`` ``(len(index), k)``.

    Every polygon is scaled by ``1 / spacing`` so that the group shares spacing 1 (the models
    take one spacing per call), and lengths come back in the normalised frame.

    Args:
        smoothing: ``None`` for the exact chords (:class:`~boustro.models.ExactModel`), else the
            smooth closed form with smoothing length ``smoothing * spacing`` (a fraction of each
            polygon's spacing).

    Returns:
        :class:`~boustro.models.TransectLengths` ``(len(index), k, K)``, normalised frame.
    """
    s = batch.spacing[index]
    radius = float((batch.radius[index] / s).max())
    hp = HalfPlanes(
        batch.normals[index][:, None], (batch.offsets[index] / s[:, None])[:, None], radius
    )
    d = offset / s[:, None]
    if smoothing is None:
        tl = ExactModel(fused=True)(hp, theta, d, 1.0)
    else:
        tl = smooth_lengths(hp, theta, d, 1.0, smoothing=smoothing)
    return TransectLengths(
        tl.lengths * s[:, None, None], tl.weights, tl.positions * s[:, None, None]
    )


def batch_objective(
    batch: PlanBatch,
    theta: torch.Tensor,
    offset: torch.Tensor,
    *,
    smoothing: float | None = None,
    objective: Any = None,
    mask_empty: bool = True,
) -> torch.Tensor:
    """Objective values ``(P, k)`` of the layouts ``theta, offset`` ``(P, k)`` (normalised).

    One batched model call per size class (:func:`batch_lengths`). With ``smoothing=None``
    (exact) and ``mask_empty``, layouts where no transect crosses get ``-inf`` (never chosen;
    ``mask_empty=False`` keeps the objective's own value there); with smoothing the result is
    differentiable in ``theta``, ``offset`` (and anything they depend on). The objective is
    maximised (see :func:`as_plan_objective`).
    """
    obj = as_plan_objective(objective)
    out = torch.empty(theta.shape, dtype=theta.dtype, device=theta.device)
    parts = []
    for index in _size_classes(batch):
        tl = batch_lengths(batch, index, theta[index], offset[index], smoothing)
        value = obj(tl, theta[index], offset[index], batch.spacing[index, None])
        if smoothing is None and mask_empty:
            ok = (tl.weights.sum(dim=-1) > 0) & ~torch.isnan(value)
            value = torch.where(ok, value, -math.inf)
        parts.append((index, value))
    if not any(v.requires_grad for _, v in parts):
        for index, value in parts:
            out[index] = value
        return out
    order = torch.cat([i for i, _ in parts])
    values = torch.cat([v for _, v in parts])
    return values[torch.argsort(order)]
