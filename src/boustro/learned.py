"""A learned planner: a small network trained through the differentiable fitness (layer 4).

The paper's case for a differentiable representation is that gradients can flow "into other
differentiable systems, like neural networks". This module does exactly that: a small network
maps a convex polygon and a spacing to ``k`` candidate layouts ``(angle, offset)``, and it is
trained WITHOUT labels by maximising the fitness of its own predictions through the smooth
closed-form model (:func:`boustro.smooth.smooth_lengths`), on random convex polygons.

Pieces:

* :class:`PlanObjective` / :func:`as_plan_objective`: user-defined differentiable objectives, any
  torch function of the soft lengths AND the plan parameters ``(theta, offset, spacing)``; used by
  training (:func:`train_planner`) and by the batched gradient refinement (:func:`refine`).
* :class:`PlanBatch` / :func:`make_batch`: many polygons with their own spacings as padded
  tensors; :func:`batch_objective` scores ``(P, k)`` layouts of them in one batched call per
  size class, exactly or smoothly.
* :class:`LearnedPlanner`: the network (rotation-equivariant by construction, see below),
  :func:`load_planner` loads the weights shipped in ``boustro/data``.
* :func:`learned` (one polygon, an :class:`~boustro.optimize.OptimizeResult`),
  :func:`learned_batch` (many polygons at once), :func:`warm_start` (starts for the other
  optimisers), :func:`train_planner` (the training loop behind ``boustro train``).

Network (all in the normalised frame: polygon centred on its vertex mean, diameter 1):

* elements are the polygon's edges, a set: each edge gets rotation-INVARIANT features (length,
  distance from the centre, turning angles at its ends, its neighbours' lengths, the spacing);
  one round of message passing over all pairs of edges adds their relative directions (as
  ``cos``/``sin`` of the angle between them and of its double); masked mean and max pooling
  give a polygon embedding (DeepSets). Nothing depends on the vertex order or start.
* angle head: per edge ``j`` and hypothesis ``m`` a complex weight ``c_jm`` (invariant), and
  ``z_m = sum_j c_jm exp(2i phi_j)`` with ``phi_j`` the edge's direction; ``theta_m = arg(z_m)/2``.
  The angle is predicted as the unit vector of the doubled angle, so it respects the pi period,
  and rotating the polygon by ``a`` rotates every prediction by ``a`` exactly (equivariance).
* offset head: for each hypothesis the vertices are projected on the transects' normal,
  ``h_i = n(theta_m) . v_i``; a DeepSets over the vertices gives each a complex weight ``w_i``
  from shift-invariant features (distances to the extreme projections, in spacings and relative
  to the width, the along-transect coordinate, the width's fraction of a spacing), and the
  offset's phase is ``arg(sum_i w_i exp(2 pi i h_i / s))``: the offset is predicted as the unit
  vector of the phase ``2 pi d / s``, so it respects the period, and the transect grid is
  placed relative to the polygon's own vertices.

Training: loss = minus a soft winner-takes-all of the ``k`` hypotheses' fitness (each polygon's
best hypothesis gets most of the weight, so the hypotheses specialise on different basins), through
the smooth closed form with a smoothing length annealed from a large fraction of the spacing (a
smooth, nearly convex surface) to a small one. At inference the ``k`` hypotheses are scored with
the EXACT model and the best is the answer; :func:`refine` improves them further, in one batch
over all polygons (an exact offset sweep at the best hypotheses' angles, the "event" layouts with
transects through two vertices, optional gradient ascent through the smooth model, an exact
coarse-to-fine zoom). See ``docs/learned.md`` for the design, training and benchmark.
"""

from __future__ import annotations

import copy
import io
import json
import math
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, NamedTuple, cast

import numpy as np
import torch
from numpy.typing import ArrayLike, NDArray
from torch import nn

from ._files import atomic_write
from .errors import InvalidParameterError, NoTransectError
from .geometry import PAD_OFFSET, HalfPlanes, Polygon, random_convex_polygon
from .models import TransectLengths, _prepare, check_spacing, transect_positions
from .objectives import (
    LengthObjective,
    PlanObjective,
    PreferredAngle,
    as_plan_objective,
    objective_sign,
)
from .optimize import OptimizeResult, canonical
from .scoring import as_polygon
from .smooth import smooth_lengths

__all__ = [
    "DEFAULT_WEIGHTS",
    "BatchResult",
    "LearnedPlanner",
    "LengthObjective",
    "PlanBatch",
    "PlanObjective",
    "PlannerConfig",
    "Prediction",
    "PreferredAngle",
    "RefineOptions",
    "TrainConfig",
    "TrainResult",
    "as_plan_objective",
    "batch_objective",
    "learned",
    "learned_batch",
    "load_planner",
    "make_batch",
    "random_batch",
    "refine",
    "save_planner",
    "train_planner",
    "warm_start",
]

#: The weights shipped with the package (``torch.save(state_dict)``) and their hyperparameters.
DEFAULT_WEIGHTS = Path(__file__).parent / "data" / "learned_planner.pt"

_TWO_PI = 2.0 * math.pi


# =============================================================================================
# Batches of polygons with their own spacings
# =============================================================================================


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


def _from_normalised(
    vertices: Sequence[NDArray[np.float64]],
    spacing: ArrayLike,
    scale: ArrayLike,
    centre: ArrayLike,
    dtype: torch.dtype,
) -> PlanBatch:
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
    dtype: torch.dtype = torch.float64,
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
    return _from_normalised(verts, s / scale, scale, centre, dtype)


def random_batch(
    rng: np.random.Generator,
    count: int,
    *,
    min_vertices: int = 3,
    max_vertices: int = 9,
    min_spacing: float = 0.01,
    max_spacing: float = 1.0 / 3.0,
    dtype: torch.dtype = torch.float64,
) -> PlanBatch:
    """``count`` random convex polygons (Valtr, ``min..max`` vertices, normalised frame) with
    spacings uniform in ``(min_spacing, max_spacing)`` of the diameter: the benchmarks'
    distribution."""
    polys = [
        random_convex_polygon(rng, int(rng.integers(min_vertices, max_vertices + 1)))
        for _ in range(count)
    ]
    s = rng.uniform(min_spacing, max_spacing, count)
    return _from_normalised(
        [p.vertices for p in polys], s, np.ones(count), np.zeros((count, 2)), dtype
    )


def _size_classes(batch: PlanBatch) -> list[torch.Tensor]:
    """Indices grouped by ``ceil(log2(radius / spacing))``: each group's grid of candidate
    transects is at most twice as long as any member needs."""
    ratio = (batch.radius / batch.spacing).detach().to(torch.float64)
    key = torch.ceil(torch.log2(ratio.clamp(min=1.0)))
    return [torch.nonzero(key == k)[:, 0] for k in torch.unique(key)]


def _exact_lengths(
    hp: HalfPlanes, theta: torch.Tensor, offset: torch.Tensor, spacing: float
) -> TransectLengths:
    """:class:`~boustro.models.ExactModel` in fewer passes over the ``(*, K, E)`` tensor.

    The same chords (:func:`~boustro.models.exact_chords`), with each edge's bound written as
    ``slope * c + intercept`` and the edges of the other role given slope 0 and intercept
    ``-+inf``, so that each max and min is one fused multiply-add and one reduction.
    Lengths agree with ``ExactModel`` to rounding (1e-13 relative); weights are the same rule
    (length above ``1e-12`` of the radius).
    """
    theta, offset, across, along, b = _prepare(hp, theta, offset)
    c = transect_positions(offset, spacing, hp.radius)  # (*, K)
    parallel = along == 0
    inv = 1.0 / torch.where(parallel, torch.ones_like(along), along)
    slope, intercept = -across * inv, -b * inv  # edge j bounds t by slope_j c + intercept_j
    inf = torch.as_tensor(math.inf, dtype=c.dtype, device=c.device)
    is_lower, is_upper = along > 0, along < 0
    cc = c[..., :, None]
    lower = torch.addcmul(
        torch.where(is_lower, intercept, -inf)[..., None, :],
        torch.where(is_lower, slope, 0.0)[..., None, :],
        cc,
    ).amax(dim=-1)
    upper = torch.addcmul(
        torch.where(is_upper, intercept, inf)[..., None, :],
        torch.where(is_upper, slope, 0.0)[..., None, :],
        cc,
    ).amin(dim=-1)
    length = (upper - lower).clamp(min=0.0)
    if bool(parallel.any()):  # an edge parallel to the transects empties the chords beyond it
        lhs = across[..., None, :] * cc + b[..., None, :]
        length = torch.where((parallel[..., None, :] & (lhs < 0)).any(dim=-1), 0.0, length)
    tiny = 1e-12 * max(hp.radius, 1e-300)
    return TransectLengths(
        length, (length > tiny).to(length.dtype), torch.broadcast_to(c, length.shape)
    )


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
        smoothing: ``None`` for the exact chords (:class:`~boustro.models.ExactModel`'s, in
            fewer passes: :func:`_exact_lengths`), else the
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
        tl = _exact_lengths(hp, theta, d, 1.0)
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


# =============================================================================================
# The network
# =============================================================================================


@dataclass(frozen=True)
class PlannerConfig:
    """Hyperparameters of :class:`LearnedPlanner` (saved next to the weights as JSON)."""

    hidden: int = 64
    hypotheses: int = 16
    rounds: int = 1
    profile: bool = True  # chord-length profile near both extremes as offset-head features


def _mlp(sizes: Sequence[int]) -> nn.Sequential:
    layers: list[nn.Module] = []
    for i in range(len(sizes) - 1):
        layers.append(nn.Linear(sizes[i], sizes[i + 1]))
        if i < len(sizes) - 2:
            layers.append(nn.SiLU())
    return nn.Sequential(*layers)


def _split_mlp(mlp: nn.Sequential, parts: Sequence[torch.Tensor]) -> torch.Tensor:
    """``mlp(cat(parts, -1))`` for parts that broadcast against each other, without
    materialising the broadcast: the first layer is applied part by part (a per-polygon
    context is projected once, not once per vertex and hypothesis)."""
    first = cast(nn.Linear, mlp[0])
    projected = []
    start = 0
    for part in parts:
        stop = start + part.shape[-1]
        projected.append(part @ first.weight[:, start:stop].T)
        start = stop
    projected.sort(key=lambda t: t.numel())  # add the small ones first, the big one once
    x = first.bias + projected[0]
    for t in projected[1:]:
        x = x + t
    rest = cast(nn.Sequential, mlp[1:])
    return cast(torch.Tensor, rest(x))


def _masked_pool(h: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
    """Masked mean and max over dim -2: ``(*, n, H)`` -> ``(*, 2H)``."""
    m = mask[..., None].to(h.dtype)
    mean = (h * m).sum(dim=-2) / m.sum(dim=-2).clamp(min=1.0)
    big = torch.as_tensor(torch.finfo(h.dtype).max, dtype=h.dtype, device=h.device)
    mx = torch.where(mask[..., None], h, -big).amax(dim=-2)
    return torch.cat([mean, mx], dim=-1)


_EDGE_FEATURES = 10
_VERTEX_FEATURES = 11
_HYPOTHESIS_FEATURES = 6
#: Where the chord-length profile is sampled, in spacings inside each extreme of the polygon.
_PROFILE = (0.125, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0)


def _chords_at(batch: PlanBatch, theta: torch.Tensor, c: torch.Tensor) -> torch.Tensor:
    """Exact chord lengths ``(P, k, M)`` of the lines ``n(theta) . p = c`` (``c`` ``(P, k, M)``)."""
    cos, sin = torch.cos(theta)[..., None, None], torch.sin(theta)[..., None, None]
    nx, ny = batch.normals[:, None, None, :, 0], batch.normals[:, None, None, :, 1]
    across, along = -nx * sin + ny * cos, nx * cos + ny * sin  # (P, k, 1, E)
    lhs = across * c[..., None] + batch.offsets[:, None, None, :]
    safe = torch.where(along == 0, torch.ones_like(along), along)
    bound = -lhs / safe
    inf = torch.as_tensor(math.inf, dtype=c.dtype, device=c.device)
    lower = torch.where(along > 0, bound, -inf).amax(dim=-1)
    upper = torch.where(along < 0, bound, inf).amin(dim=-1)
    blocked = ((along == 0) & (lhs < 0)).any(dim=-1)
    return torch.where(blocked, 0.0, (upper - lower).clamp(min=0.0))


class Prediction(NamedTuple):
    """The network's ``k`` hypotheses ``(P, k)`` per polygon, normalised frame.

    ``theta`` in ``(-pi/2, pi/2]``; ``offset`` in ``(-spacing/2, spacing/2]``; ``angle_vector``
    and ``offset_vector`` ``(P, k, 2)`` are the raw (unnormalised) doubled-angle and phase vectors.
    """

    theta: torch.Tensor
    offset: torch.Tensor
    angle_vector: torch.Tensor
    offset_vector: torch.Tensor


class LearnedPlanner(nn.Module):
    """Polygon (edge set) + spacing -> ``k`` hypotheses ``(theta, offset)``; see the module
    docstring for the architecture.

    ``forward(batch) -> Prediction``. The input is invariant to the vertex order and start,
    and the angle is rotation-equivariant by construction: rotating every polygon by ``a``
    adds ``a`` to every predicted angle (mod pi) and leaves the offsets unchanged.
    """

    def __init__(self, config: PlannerConfig | None = None) -> None:
        super().__init__()
        self.config = config = config or PlannerConfig()
        h, k = config.hidden, config.hypotheses
        self.edge_in = _mlp([_EDGE_FEATURES, h, h])
        self.msg_self = nn.ModuleList(nn.Linear(h, h) for _ in range(config.rounds))
        self.msg_other = nn.ModuleList(nn.Linear(h, h) for _ in range(config.rounds))
        self.msg_rel = nn.ModuleList(nn.Linear(4, h) for _ in range(config.rounds))
        self.msg_out = nn.ModuleList(_mlp([h, h]) for _ in range(config.rounds))
        self.update = nn.ModuleList(_mlp([2 * h, h, h]) for _ in range(config.rounds))
        self.angle_head = _mlp([3 * h, h, 2 * k])
        n_hyp = _HYPOTHESIS_FEATURES + (2 * len(_PROFILE) if config.profile else 0)
        self.vertex_in = _mlp([_VERTEX_FEATURES + n_hyp + 2 * h, h, h])
        self.offset_head = _mlp([3 * h, h, 2])

    # -- features -----------------------------------------------------------------------------
    @staticmethod
    def _edges(batch: PlanBatch) -> tuple[torch.Tensor, torch.Tensor]:
        """Invariant edge features ``(P, N, F)`` and edge directions ``phi`` ``(P, N)``."""
        v, mask, s = batch.vertices, batch.mask, batch.spacing
        count = mask.sum(dim=1)
        n = v.shape[1]
        j = torch.arange(n, device=v.device)[None, :]
        nxt = (j + 1) % count[:, None]
        prv = (j - 1) % count[:, None]
        e = torch.gather(v, 1, nxt[..., None].expand(-1, -1, 2)) - v
        length = torch.linalg.norm(e, dim=-1)
        phi = torch.atan2(e[..., 1], e[..., 0])
        turn_in = torch.remainder(phi - torch.gather(phi, 1, prv), _TWO_PI)
        turn_out = torch.gather(turn_in, 1, nxt)
        ls = torch.log(s)[:, None].expand_as(length)
        feats = torch.stack(
            [
                length,
                torch.where(mask, batch.offsets, 0.0),
                turn_in / math.pi,
                turn_out / math.pi,
                torch.gather(length, 1, prv),
                torch.gather(length, 1, nxt),
                torch.log(length.clamp(min=1e-6) / s[:, None]) / 4.0,
                (s * 4.0)[:, None].expand_as(length),
                ls / 4.0,
                (count.to(v.dtype)[:, None] / 9.0).expand_as(length),
            ],
            dim=-1,
        )
        return torch.where(mask[..., None], feats, 0.0), phi

    def _vertices(
        self, batch: PlanBatch, theta: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """Shift-invariant vertex features ``(P, k, N, F)``, per-hypothesis features
        ``(P, k, G)`` and the projections ``h`` ``(P, k, N)``."""
        v, mask, s = batch.vertices, batch.mask, batch.spacing[:, None, None]
        c, sn = torch.cos(theta)[..., None], torch.sin(theta)[..., None]
        x, y = v[:, None, :, 0], v[:, None, :, 1]
        h = -sn * x + c * y  # across the transects: (P, k, N)
        t = c * x + sn * y  # along them
        m = mask[:, None, :]
        big = torch.as_tensor(1e9, dtype=v.dtype, device=v.device)
        lo = torch.where(m, h, big).amin(dim=-1, keepdim=True)
        hi = torch.where(m, h, -big).amax(dim=-1, keepdim=True)
        width = (hi - lo).clamp(min=1e-9)
        a, b = (h - lo), (hi - h)
        feats = torch.stack(
            [
                a / width,
                b / width,
                t,
                torch.log1p(a / s) / 3.0,
                torch.log1p(b / s) / 3.0,
                torch.cos(_TWO_PI * a / s),
                torch.sin(_TWO_PI * a / s),
                torch.cos(_TWO_PI * b / s),
                torch.sin(_TWO_PI * b / s),
                (a < 1e-9 * width).to(v.dtype),
                (b < 1e-9 * width).to(v.dtype),
            ],
            dim=-1,
        )
        w = (width / s)[..., 0]
        hyp = torch.stack(
            [
                torch.log(w) / 4.0,
                torch.cos(_TWO_PI * w),
                torch.sin(_TWO_PI * w),
                width[..., 0],
                torch.cos(2 * (theta - theta[:, :1])),
                torch.sin(2 * (theta - theta[:, :1])),
            ],
            dim=-1,
        )
        if self.config.profile:
            u = torch.as_tensor(_PROFILE, dtype=v.dtype, device=v.device)
            pos = torch.cat([lo + u * s, hi - u * s], dim=-1)  # (P, k, 2M)
            prof = _chords_at(batch, theta, pos)
            top = _chords_at(batch, theta, 0.5 * (lo + hi)).clamp(min=1e-9)
            hyp = torch.cat([hyp, prof / top], dim=-1)
        return feats, hyp, h

    # -- forward ------------------------------------------------------------------------------
    def forward(self, batch: PlanBatch) -> Prediction:
        dtype = next(self.parameters()).dtype
        batch = batch.to(dtype)
        mask = batch.mask
        feats, phi = self._edges(batch)
        h = self.edge_in(feats)
        rel = phi[:, None, :] - phi[:, :, None]  # (P, N, N): direction of m relative to j
        rel_f = torch.stack(
            [torch.cos(rel), torch.sin(rel), torch.cos(2 * rel), torch.sin(2 * rel)], dim=-1
        )
        pair_mask = mask[:, None, :] & mask[:, :, None]
        pair_mask = pair_mask & ~torch.eye(mask.shape[1], dtype=torch.bool, device=h.device)
        for r in range(self.config.rounds):
            msg = self.msg_self[r](h)[:, :, None] + self.msg_other[r](h)[:, None, :]
            msg = self.msg_out[r](torch.nn.functional.silu(msg + self.msg_rel[r](rel_f)))
            pm = pair_mask[..., None].to(h.dtype)
            agg = (msg * pm).sum(dim=2) / pm.sum(dim=2).clamp(min=1.0)
            h = h + self.update[r](torch.cat([h, agg], dim=-1))
        pooled = _masked_pool(h, mask)  # (P, 2H)
        k = self.config.hypotheses
        coef = _split_mlp(self.angle_head, [h, pooled[:, None]])
        coef = torch.where(mask[..., None], coef, 0.0).reshape(*coef.shape[:2], k, 2)
        c2, s2 = torch.cos(2 * phi)[..., None], torch.sin(2 * phi)[..., None]
        re = (coef[..., 0] * c2 - coef[..., 1] * s2).sum(dim=1)  # (P, k)
        im = (coef[..., 0] * s2 + coef[..., 1] * c2).sum(dim=1)
        eps = torch.as_tensor(1e-12, dtype=dtype, device=re.device)
        theta = 0.5 * torch.atan2(im, torch.where((re == 0) & (im == 0), eps, re))

        vf, hyp, proj = self._vertices(batch, theta.detach())
        g = _split_mlp(self.vertex_in, [vf, hyp[:, :, None], pooled[:, None, None]])
        vmask = mask[:, None, :].expand(-1, k, -1)
        gp = _masked_pool(g, vmask)
        w = _split_mlp(self.offset_head, [g, gp[:, :, None]])  # (P, k, N, 2)
        w = torch.where(vmask[..., None], w, 0.0)
        s = batch.spacing[:, None, None]
        ca, sa = torch.cos(_TWO_PI * proj / s), torch.sin(_TWO_PI * proj / s)
        ore = (w[..., 0] * ca - w[..., 1] * sa).sum(dim=-1)
        oim = (w[..., 0] * sa + w[..., 1] * ca).sum(dim=-1)
        phase = torch.atan2(oim, torch.where((ore == 0) & (oim == 0), eps, ore))
        offset = phase / _TWO_PI * batch.spacing[:, None]
        return Prediction(theta, offset, torch.stack([re, im], -1), torch.stack([ore, oim], -1))


def check_weights_path(path: str | Path) -> Path:
    """``path`` as a :class:`Path`, refused if it ends in ``.json``: the settings of the planner
    are written beside the weights under that suffix (:func:`save_planner`)."""
    path = Path(path)
    if path.suffix.lower() == ".json":
        raise InvalidParameterError(
            f"weights file {path} must not end in .json: the settings are written beside it "
            "with that suffix"
        )
    return path


def save_planner(
    model: LearnedPlanner, path: str | Path, *, metadata: dict[str, Any] | None = None
) -> tuple[Path, Path]:
    """Save ``state_dict`` (float32) to ``path`` and hyperparameters (+ metadata) to ``.json``.

    Both files are written atomically (a temporary file, then a rename), the settings last;
    missing folders are created.

    Raises:
        InvalidParameterError: ``path`` ends in ``.json`` (the settings' name), or a weight or a
            metadata number is not finite (a diverged training).
    """
    path = check_weights_path(path)
    state = {k: v.detach().to(torch.float32).clone() for k, v in model.state_dict().items()}
    if not all(bool(torch.isfinite(v).all()) for v in state.values()):
        raise InvalidParameterError("the planner's weights are not all finite; nothing saved")
    meta = {"config": asdict(model.config), **(metadata or {})}
    try:
        text = json.dumps(meta, indent=2, sort_keys=True, allow_nan=False) + "\n"
    except ValueError:
        raise InvalidParameterError(
            "the planner's metadata has a number that is not finite; nothing saved"
        ) from None
    buffer = io.BytesIO()
    torch.save(state, buffer)
    path.parent.mkdir(parents=True, exist_ok=True)
    json_path = path.with_suffix(".json")
    atomic_write(path, buffer.getvalue())
    atomic_write(json_path, text)
    return path, json_path


_CACHE: dict[tuple[tuple[str, int, int], ...], LearnedPlanner] = {}


def load_planner(path: str | Path | None = None) -> LearnedPlanner:
    """Load a planner saved by :func:`save_planner` (default: the weights shipped in the
    package), with ``torch.load(..., weights_only=True)``; in eval mode, cached by path."""
    path = Path(DEFAULT_WEIGHTS if path is None else path)
    json_path = path.with_suffix(".json")
    try:  # the cache knows a file by its name and its version on disk
        stats = [(f, f.stat()) for f in (path, json_path)]
        key = tuple((str(f.resolve()), st.st_mtime_ns, st.st_size) for f, st in stats)
    except FileNotFoundError as exc:
        missing = "its settings file " if exc.filename == str(json_path) else ""
        raise InvalidParameterError(
            f"no learned planner at {path} ({missing}{exc.filename} is missing): train one with "
            "'boustro train', which writes both files"
        ) from None
    if key in _CACHE:
        return _CACHE[key]
    try:
        meta = json.loads(json_path.read_text())
        state = torch.load(path, map_location="cpu", weights_only=True)
        model = LearnedPlanner(PlannerConfig(**meta["config"]))
        model.load_state_dict(state)
    except Exception as exc:  # any malformed or foreign file: one clear error
        raise InvalidParameterError(
            f"{path} (with {json_path.name}) is not a planner saved by boustro: "
            f"{type(exc).__name__}: {exc}"[:300]
        ) from None
    model.eval()
    _CACHE[key] = model
    return model


# =============================================================================================
# Inference and refinement
# =============================================================================================


def _hypotheses(planner: LearnedPlanner, batch: PlanBatch) -> tuple[torch.Tensor, torch.Tensor]:
    with torch.no_grad():
        pred = planner(batch)
    return pred.theta.to(batch.spacing.dtype), pred.offset.to(batch.spacing.dtype)


def _offset_sweep(
    batch: PlanBatch, theta: torch.Tensor, offset: torch.Tensor, n: int, objective: Any
) -> tuple[torch.Tensor, torch.Tensor]:
    """At each candidate's angle, the best of ``n`` offsets over a whole spacing (exact)."""
    p, k = theta.shape
    u = torch.arange(n, dtype=theta.dtype, device=theta.device) / n
    o = offset[..., None] + u * batch.spacing[:, None, None]
    th = theta[..., None].expand(-1, -1, n)
    values = batch_objective(batch, th.reshape(p, -1), o.reshape(p, -1), objective=objective)
    values = values.reshape(p, k, n)
    best = values.argmax(dim=-1, keepdim=True)
    return values.gather(-1, best)[..., 0], o.gather(-1, best)[..., 0]


def _zoom(
    batch: PlanBatch,
    theta: torch.Tensor,
    offset: torch.Tensor,
    half_angle: float,
    half_offset: float,
    points: int,
    levels: int,
    objective: Any,
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Coarse-to-fine exact search around every candidate ``(P, c)``: ``points^2`` a level,
    the window shrinking to one cell of the level before; ``half_offset`` in spacings."""
    p, c = theta.shape
    u = torch.linspace(-1.0, 1.0, points, dtype=theta.dtype, device=theta.device)
    s = batch.spacing[:, None, None, None]
    best = batch_objective(batch, theta, offset, objective=objective)
    for _ in range(levels):
        a = theta[..., None, None] + half_angle * u[:, None]
        o = offset[..., None, None] + half_offset * s * u
        a, o = torch.broadcast_tensors(a, o)
        a, o = a.reshape(p, c, -1), o.reshape(p, c, -1)
        values = batch_objective(
            batch, a.reshape(p, -1), o.reshape(p, -1), objective=objective
        ).reshape(p, c, -1)
        top, where = values.max(dim=-1)
        better = top > best
        theta = torch.where(better, a.gather(-1, where[..., None])[..., 0], theta)
        offset = torch.where(better, o.gather(-1, where[..., None])[..., 0], offset)
        best = torch.maximum(top, best)
        half_angle *= 2.0 / (points - 1)
        half_offset *= 2.0 / (points - 1)
    return best, theta, offset


@dataclass(frozen=True)
class RefineOptions:
    """Settings of :func:`refine` (defaults tuned on random polygons, see docs/learned.md).

    Costs per polygon, in exact evaluations: ``k`` (the hypotheses), ``sweep_top * sweep``,
    ``2 N (N - 1)`` with ``events`` (``N`` vertices),
    ``top * steps / check_every`` plus ``steps`` smooth forward and backward passes of ``top``
    layouts, ``zoom_top * zoom_points^2 * zoom_levels``, and 6 for the final nudge.
    """

    sweep: int = 16  # offsets tried over one spacing at each swept hypothesis's angle
    sweep_top: int = 4  # hypotheses swept, best first by the exact model (0: all)
    events: bool = True  # add the layouts with transects through two vertices (m <= 1 apart)
    top: int = 2  # candidates kept for the gradient and zoom stages
    steps: int = 0  # gradient steps (see :meth:`gradient`)
    check_every: int = 2  # exact scoring of the gradient iterates every this many steps
    lr_angle: float = 0.01
    lr_offset: float = 0.05  # fraction of the spacing per Adam step
    smoothing: float = 0.05  # fraction of the spacing
    zoom_top: int = 1
    zoom_points: int = 5
    zoom_levels: int = 3
    zoom_angle: float = 0.02  # radians, first window half-width
    zoom_offset: float = 0.08  # spacings

    @classmethod
    def gradient(cls) -> RefineOptions:
        """A wider, slower preset with 20 Adam steps through the smooth closed form: every
        hypothesis swept, 4 candidates descended, the best 2 zoomed (7 x 7 points a level)."""
        return cls(sweep_top=0, top=4, steps=20, zoom_top=2, zoom_points=7)


def _event_layouts(batch: PlanBatch) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Layouts ``(P, C)`` where one transect passes through vertex ``i`` and a transect
    ``m in {-1, 0, 1}`` spacings away through vertex ``j``, for every pair of vertices, and a
    mask of the real ones (``n(theta) . (v_i - v_j) = m s``: the events of
    :func:`boustro.global_opt.event_angles` with ``|m| <= 1``).

    Eq. 1's optimum often sits exactly there: at a spacing comparable to the polygon's width
    the best layout is one or two long transects, pressed against the angle where a
    neighbouring transect would enter the polygon (or, ``m = 0``, one transect along a
    diagonal). Such optima are needles in the (angle, offset) plane that sampling rarely hits.

    Exactly on an event a transect may graze an extreme vertex and count or not by rounding,
    so the offset is nudged by ``NUDGE`` spacings to the side where it does not: down when the
    lower transect of an ``m = 1`` pair grazes the lowest vertex, up when the upper one grazes
    the highest. ``m = 0`` layouts come on both sides: along an extreme edge, the transect just
    inside and the grid with that transect just outside are different layouts.
    """
    n = batch.vertices.shape[1]
    i, j = torch.triu_indices(n, n, offset=1)
    vi, vj = batch.vertices[:, i], batch.vertices[:, j]
    delta = vi - vj
    dist = torch.linalg.norm(delta, dim=-1)
    real = batch.mask[:, i] & batch.mask[:, j] & (dist > 0)
    dist = torch.where(real, dist, torch.ones_like(dist))
    alpha = torch.atan2(-delta[..., 0], delta[..., 1])  # n(theta) . delta = dist cos(theta - a)
    # m = -1 gives the same grids as m = 1 turned by pi (the offset's sign flips with the turn)
    ratio = batch.spacing[:, None] / dist
    ok = real & (ratio <= 1)
    acos = torch.acos(ratio.clamp(max=1.0))
    theta = torch.cat([alpha + math.pi / 2, alpha + acos, alpha - acos], dim=1)
    mask = torch.cat([real, ok, ok], dim=1)
    vi, vj = vi.repeat(1, 3, 1), vj.repeat(1, 3, 1)
    sin, cos = torch.sin(theta), torch.cos(theta)
    h_i = -sin * vi[..., 0] + cos * vi[..., 1]
    h_j = -sin * vj[..., 0] + cos * vj[..., 1]
    h = (
        -sin[..., None] * batch.vertices[:, None, :, 0]
        + cos[..., None] * batch.vertices[:, None, :, 1]
    )
    lo, hi = h.amin(dim=-1), h.amax(dim=-1)  # padding repeats vertex 0: no effect
    tol = 1e-9 * batch.radius[:, None]
    pair = torch.arange(theta.shape[1], device=theta.device) < i.numel()  # the m = 0 block
    down = torch.where(pair, h_i >= hi - tol, h_j <= lo + tol)
    step = NUDGE * batch.spacing[:, None]
    offset = h_i + torch.where(down, -step, step)
    # m = 0 along an extreme edge: just outside is a layout of its own (the transect leaves)
    c = i.numel()
    return (
        torch.cat([theta, theta[:, :c]], dim=1),
        torch.cat([offset, h_i[:, :c] + torch.where(down[:, :c], step, -step)], dim=1),
        torch.cat([mask, mask[:, :c]], dim=1),
    )


def _keep(k: torch.Tensor, *tensors: torch.Tensor) -> list[torch.Tensor]:
    return [t.gather(1, k) for t in tensors]


def refine(
    batch: PlanBatch,
    theta: torch.Tensor,
    offset: torch.Tensor,
    *,
    objective: Any = None,
    options: RefineOptions | None = None,
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Improve candidate layouts ``(P, k)`` of a batch of polygons, all in one batch.

    1. the candidates are scored exactly; at the angles of the best ``sweep_top`` of them
       (``0``: all) ``sweep`` offsets over one spacing are tried (exact), each keeping its best;
    2. with ``events``, the layouts with transects through two vertices, at most one spacing
       apart (:func:`_event_layouts`), join the candidates; the best ``top`` go on;
    3. gradient ascent (Adam) of the objective through the smooth closed form (smoothing a
       fraction of each spacing), ``steps`` steps (0 by default, see
       :meth:`RefineOptions.gradient`), the iterates scored exactly;
    4. exact coarse-to-fine zoom around each polygon's best ``zoom_top`` candidates.

    Args:
        batch: the polygons, :func:`make_batch` (float64 for exact answers).
        theta, offset: ``(P, k)`` starting layouts, normalised frame.
        objective: anything :func:`as_plan_objective` accepts (default Eq. 1), maximised.
        options: :class:`RefineOptions` (default: the fast preset of the benchmark).

    Returns ``(value, theta, offset)`` ``(P,)``: each polygon's best layout by the EXACT
    objective over all stages (never worse than the best input candidate).
    """
    o = options or RefineOptions()
    obj = as_plan_objective(objective)
    best_t, best_o = theta.detach(), offset.detach()
    best_v = batch_objective(batch, best_t, best_o, objective=obj)
    if o.sweep > 1:
        if 0 < o.sweep_top < best_t.shape[1]:
            k = torch.argsort(best_v, dim=1, descending=True)[:, : o.sweep_top]
            best_v, best_t, best_o = _keep(k, best_v, best_t, best_o)
        v, off = _offset_sweep(batch, best_t, best_o, o.sweep, obj)
        better = v > best_v
        best_v = torch.where(better, v, best_v)
        best_o = torch.where(better, off, best_o)
    if o.events:
        pt, po, real = _event_layouts(batch)
        # 2 N (N - 1) layouts a polygon: scored in chunks so that memory stays bounded for
        # polygons of many vertices (each layout costs about K x E elements)
        n_pairs, n_edges = batch.normals.shape[0], batch.normals.shape[-2]
        k_est = int(2.0 / float(batch.spacing.min()) + 4.0)
        chunk = max(1, _EVENT_CHUNK_ELEMENTS // max(1, n_pairs * n_edges * k_est))
        pv = torch.cat(
            [
                batch_objective(batch, pt[:, i : i + chunk], po[:, i : i + chunk], objective=obj)
                for i in range(0, pt.shape[1], chunk)
            ],
            dim=1,
        )
        pv = torch.where(real, pv, -math.inf)
        best_v, best_t, best_o = (
            torch.cat(x, dim=1) for x in ((best_v, pv), (best_t, pt), (best_o, po))
        )
    if 0 < o.top < best_t.shape[1]:
        k = torch.argsort(best_v, dim=1, descending=True)[:, : o.top]
        best_v, best_t, best_o = _keep(k, best_v, best_t, best_o)
    if o.steps > 0:
        th = best_t.clone().requires_grad_(True)
        # the offset in units of the spacing, so that one learning rate fits every polygon
        u = (best_o / batch.spacing[:, None]).clone().requires_grad_(True)
        opt = torch.optim.Adam(
            [{"params": [th], "lr": o.lr_angle}, {"params": [u], "lr": o.lr_offset}]
        )
        every = max(1, o.check_every)
        for step in range(o.steps):
            opt.zero_grad(set_to_none=True)
            value = batch_objective(
                batch, th, u * batch.spacing[:, None], smoothing=o.smoothing, objective=obj
            )
            (-value.sum()).backward()
            for param in (th, u):
                if param.grad is not None:
                    torch.nan_to_num_(param.grad, nan=0.0, posinf=0.0, neginf=0.0)
            opt.step()
            if (step + 1) % every and step + 1 < o.steps:
                continue
            with torch.no_grad():
                cur_t, cur_o = th.detach().clone(), u.detach() * batch.spacing[:, None]
                v = batch_objective(batch, cur_t, cur_o, objective=obj)
                better = v > best_v
                best_v = torch.where(better, v, best_v)
                best_t = torch.where(better, cur_t, best_t)
                best_o = torch.where(better, cur_o, best_o)
    if o.zoom_levels > 0 and o.zoom_top > 0:
        k = torch.argsort(best_v, dim=1, descending=True)[:, : min(o.zoom_top, best_t.shape[1])]
        zt, zo = _keep(k, best_t, best_o)
        zv, zt, zo = _zoom(
            batch, zt, zo, o.zoom_angle, o.zoom_offset, o.zoom_points, o.zoom_levels, obj
        )
        best_v = torch.cat([best_v, zv], dim=1)
        best_t = torch.cat([best_t, zt], dim=1)
        best_o = torch.cat([best_o, zo], dim=1)
    k = best_v.argmax(dim=1, keepdim=True)
    return best_v.gather(1, k)[:, 0], best_t.gather(1, k)[:, 0], best_o.gather(1, k)[:, 0]


#: Elements (layouts x transects x edges) of one chunk of event layouts in :func:`refine`.
_EVENT_CHUNK_ELEMENTS = 1 << 23

#: Offset nudge (in spacings) of the event layouts: far above rounding (1e-16), far below any
#: difference that matters (the fitness moves by about this much).
NUDGE = 1e-7


_refine = refine  # the functions below have a parameter named refine


def _as_planner(planner: LearnedPlanner | str | Path | None) -> LearnedPlanner:
    if isinstance(planner, LearnedPlanner):
        return planner
    return load_planner(planner)


class BatchResult(NamedTuple):
    """Answers of :func:`learned_batch`, ``(P,)`` arrays in each polygon's units.

    ``angle`` radians in ``[0, pi)``, ``offset`` in ``[0, spacing)``, ``fitness`` the exact
    objective (maximised; for an objective with ``maximise = False`` its negation).
    """

    angle: NDArray[np.float64]
    offset: NDArray[np.float64]
    fitness: NDArray[np.float64]
    spacing: NDArray[np.float64]
    seconds: float


def _canonical_arrays(
    theta: torch.Tensor, offset: torch.Tensor, spacing: torch.Tensor
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Angles into ``[0, pi)`` (flipping the offset's sign on odd half-turns), offsets into
    ``[0, spacing)``; same units as given."""
    turns = torch.floor(theta / math.pi)
    angle = theta - turns * math.pi
    sign = torch.where(torch.remainder(turns, 2) == 1, -1.0, 1.0).to(offset.dtype)
    off = torch.remainder(sign * offset, spacing)
    angle = torch.where(angle >= math.pi, angle - math.pi, angle).clamp(min=0.0)
    off = torch.where(off >= spacing, off - spacing, off).clamp(min=0.0)
    return angle.numpy().astype(np.float64), off.numpy().astype(np.float64)


def learned_batch(
    polygons: Sequence[Polygon | ArrayLike] | PlanBatch,
    spacings: ArrayLike | None = None,
    *,
    refine: bool | RefineOptions = False,
    fitness: Any = None,
    planner: LearnedPlanner | str | Path | None = None,
    chunk: int = 256,
) -> BatchResult:
    """The learned planner on many polygons at once: the network's ``k`` hypotheses scored
    exactly, optionally refined (:func:`refine`), the best per polygon.

    Args:
        polygons: convex polygons (user units), or a :class:`PlanBatch` (then ``spacings`` is
            ignored and results are in the batch's user units).
        spacings: one spacing for all or ``(P,)``, user units.
        refine: ``True`` (default :class:`RefineOptions`) or options; ``False``: network only.
        fitness: objective, anything :func:`as_plan_objective` accepts (default Eq. 1).
        planner: a :class:`LearnedPlanner`, a path to saved weights, or ``None`` (shipped).
        chunk: polygons per batched call.
    """
    t0 = time.perf_counter()
    net = _as_planner(planner)
    if isinstance(polygons, PlanBatch):
        batch = polygons.to(torch.float64)
    else:
        if spacings is None:
            raise InvalidParameterError("spacings are required with a list of polygons")
        batch = make_batch(polygons, spacings)
    options = RefineOptions() if refine is True else (refine or None)
    angles, offsets, values = [], [], []
    for start in range(0, batch.size, chunk):
        sub = batch.select(torch.arange(start, min(start + chunk, batch.size)))
        theta, offset = _hypotheses(net, sub)
        if options is None:
            v = batch_objective(sub, theta, offset, objective=fitness)
            k = v.argmax(dim=1, keepdim=True)
            v, theta, offset = (
                v.gather(1, k)[:, 0],
                theta.gather(1, k)[:, 0],
                offset.gather(1, k)[:, 0],
            )
        else:
            v, theta, offset = _refine(sub, theta, offset, objective=fitness, options=options)
        a, o = _canonical_arrays(theta, offset * sub.scale, sub.spacing * sub.scale)
        angles.append(a)
        offsets.append(o)
        values.append(v.numpy())
    return BatchResult(
        np.concatenate(angles),
        np.concatenate(offsets),
        np.concatenate(values),
        (batch.spacing * batch.scale).numpy(),
        time.perf_counter() - t0,
    )


def learned(
    polygon: Polygon | ArrayLike,
    spacing: float,
    *,
    refine: bool | RefineOptions = False,
    fitness: Any = None,
    planner: LearnedPlanner | str | Path | None = None,
    progress: bool | None = None,
) -> OptimizeResult:
    """``method="learned"``: the learned planner's layout for one convex polygon.

    The network predicts ``k`` hypotheses (angle, offset) in one forward pass; they are scored
    with the exact model and the best is returned. With ``refine=True`` they are refined first
    (:func:`refine`: exact offset sweep, event layouts, optional gradient ascent through the
    smooth closed form, exact zoom), which is never worse.

    Args:
        polygon: convex polygon, user units.
        spacing: transect spacing, user units, smaller than the polygon's diameter.
        refine: ``False`` (network only), ``True`` or :class:`RefineOptions`.
        fitness: the objective (default Eq. 1); a length objective like
            :class:`~boustro.fitness.SmithFitness` or a :class:`PlanObjective`. The network was
            trained for Eq. 1; with another objective its hypotheses are only starts.
        planner: a :class:`LearnedPlanner`, a path to weights, or ``None`` (the shipped ones).
        progress: accepted for the optimisers' common interface and ignored (milliseconds).

    Returns:
        :class:`~boustro.optimize.OptimizeResult` (``method="learned"``), fitness exact; a
        minimised objective's own value (not negated). ``info`` holds ``hypotheses`` (the
        network's candidates, radians and user units) and ``refined``.
    """
    t0 = time.perf_counter()
    poly = as_polygon(polygon).require_convex("the learned planner")
    spacing = check_spacing(spacing, extent=poly.diameter)
    if spacing >= poly.diameter:
        raise NoTransectError(
            f"spacing {spacing:g} is not smaller than the polygon's diameter {poly.diameter:g}: "
            "there is no boustrophedon layout to optimise"
        )
    net = _as_planner(planner)
    batch = make_batch([poly], spacing)
    theta, offset = _hypotheses(net, batch)
    options = RefineOptions() if refine is True else (refine or None)
    obj = as_plan_objective(fitness)
    values = batch_objective(batch, theta, offset, objective=obj)
    k = int(values[0].argmax())
    if options is None:
        v, t, o = values[0, k], theta[0, k], offset[0, k]
        evaluations = theta.shape[1]
    else:
        vv, tt, oo = _refine(batch, theta, offset, objective=obj, options=options)
        v, t, o = vv[0], tt[0], oo[0]
        evaluations = _refine_evaluations(theta.shape[1], len(poly), options)
    if not math.isfinite(float(v)):
        raise NoTransectError(
            f"no transect crosses the polygon at spacing {spacing:g} at any layout the learned "
            "planner found"
        )
    angle, off = canonical(float(t), float(o) * poly.diameter, spacing)
    sign = objective_sign(fitness)
    hyp_angles, hyp_offsets = _canonical_arrays(
        theta[0], offset[0] * poly.diameter, torch.tensor(spacing, dtype=theta.dtype)
    )
    return OptimizeResult(
        angle=angle,
        offset=off,
        fitness=sign * float(v),
        spacing=spacing,
        method="learned",
        evaluations=evaluations,
        seconds=time.perf_counter() - t0,
        info={
            "refined": options is not None,
            "hypotheses": np.stack([hyp_angles, hyp_offsets], axis=1),
            "hypothesis_fitness": sign * values[0].numpy(),
        },
    )


def _refine_evaluations(k: int, n_vertices: int, o: RefineOptions) -> int:
    """Exact evaluations plus gradient evaluations (one each) of :func:`refine`, per polygon."""
    swept = min(o.sweep_top, k) if o.sweep_top > 0 else k
    count = k + (swept * o.sweep if o.sweep > 1 else 0)
    events = 2 * n_vertices * (n_vertices - 1) if o.events else 0
    m = min(o.top, k + events) if o.top > 0 else k + events
    count += events + m * (o.steps + -(-o.steps // max(1, o.check_every)))
    if o.zoom_levels:
        count += min(o.zoom_top, m) * o.zoom_points**2 * o.zoom_levels
    return count + 6


def warm_start(
    polygon: Polygon | ArrayLike,
    spacing: float,
    *,
    planner: LearnedPlanner | str | Path | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The network's ``k`` hypotheses as starts for the other optimisers: ``(angles, offsets)``,
    radians in ``[0, pi)`` and user units in ``[0, spacing)``, best first by the exact model.

    Example::

        gradient_descent(poly, s, init=warm_start(poly, s), steps=40)
    """
    poly = as_polygon(polygon).require_convex("the learned planner")
    spacing = check_spacing(spacing, extent=poly.diameter)
    batch = make_batch([poly], spacing)
    theta, offset = _hypotheses(_as_planner(planner), batch)
    order = torch.argsort(batch_objective(batch, theta, offset)[0], descending=True)
    return _canonical_arrays(
        theta[0, order], offset[0, order] * poly.diameter, torch.tensor(spacing, dtype=theta.dtype)
    )


# =============================================================================================
# Training
# =============================================================================================


@dataclass(frozen=True)
class TrainConfig:
    """Settings of :func:`train_planner` (the defaults made the shipped weights)."""

    epochs: int = 30
    steps_per_epoch: int = 40
    batch_size: int = 128
    pool: int = 6000  # random polygons generated once; spacings are redrawn every batch
    validation: int = 256
    lr: float = 3e-3
    weight_decay: float = 1e-5
    smoothing_start: float = 0.2  # fractions of the spacing, annealed geometrically
    smoothing_end: float = 0.02
    wta_temperature: float = 0.01  # soft winner-takes-all over the hypotheses (fitness units)
    wta_floor: float = 0.05  # weight of the plain mean of the hypotheses in the loss
    min_spacing: float = 0.01
    max_spacing: float = 1.0 / 3.0
    seed: int = 0
    threads: int | None = 1  # the shipped weights were trained on 1 thread


@dataclass
class TrainResult:
    """What :func:`train_planner` returns: the trained network and its curves.

    ``history`` holds per step ``loss``, ``train_fitness`` (the soft winner-takes-all fitness
    of the batch, through the smooth model) and ``smoothing``, and per epoch ``val_fitness`` (mean
    exact fitness of the best hypothesis on held-out polygons), ``val_mean_fitness`` (mean over
    all hypotheses) and ``epoch_seconds``; ``initial_val_fitness`` is before any step.
    """

    planner: LearnedPlanner
    config: TrainConfig
    history: dict[str, list[float]] = field(default_factory=dict)
    seconds: float = 0.0

    def metadata(self) -> dict[str, Any]:
        h = self.history
        return {
            "train": asdict(self.config),
            "seconds": round(self.seconds, 1),
            "val_fitness": h["val_fitness"][-1] if h.get("val_fitness") else None,
            "initial_val_fitness": h.get("initial_val_fitness", [None])[0],
            "val_fitness_per_epoch": [round(x, 6) for x in h.get("val_fitness", [])],
            "torch": torch.__version__,
        }


def _validate(net: LearnedPlanner, batch: PlanBatch, objective: Any) -> tuple[float, float]:
    net.eval()
    theta, offset = _hypotheses(net, batch)
    values = batch_objective(batch, theta, offset, objective=objective, mask_empty=False)
    net.train()
    return float(values.max(dim=1).values.mean()), float(values.mean())


def train_planner(
    config: TrainConfig | None = None,
    *,
    planner: LearnedPlanner | None = None,
    planner_config: PlannerConfig | None = None,
    objective: Any = None,
    progress: bool | None = None,
    callback: Callable[[int, dict[str, list[float]]], None] | None = None,
) -> TrainResult:
    """Train a :class:`LearnedPlanner` without labels: maximise the smooth fitness of its
    hypotheses on random convex polygons.

    Loss per polygon: ``-(sum_m w_m f_m + wta_floor * mean_m f_m)``, ``f_m`` the objective of
    hypothesis ``m`` through the smooth closed form (smoothing annealed from
    ``smoothing_start`` to ``smoothing_end`` spacings) and ``w = softmax(f / wta_temperature)``
    (detached): a soft winner-takes-all. float32, Adam, cosine learning-rate decay, gradient
    clipping. Validation: exact fitness of the best hypothesis on ``validation`` held-out
    polygons (a separate seed), every epoch.

    Args:
        config: :class:`TrainConfig`.
        planner: a network to continue training from (copied: it is left unchanged; default:
            a new one, seeded).
        planner_config: its hyperparameters when new.
        objective: the training objective (default Eq. 1), see :func:`as_plan_objective`.
        progress: tqdm bar on stderr: True, False, or None (if stderr is a TTY).
        callback: called as ``callback(epoch, history)`` after every epoch.
    """
    cfg = config or TrainConfig()
    obj = as_plan_objective(objective)
    t0 = time.perf_counter()
    old_threads = torch.get_num_threads()
    if cfg.threads:
        torch.set_num_threads(cfg.threads)
    try:
        torch.manual_seed(cfg.seed)
        rng = np.random.default_rng(cfg.seed)
        # a copy: the planner passed in (perhaps the shipped, cached one) stays as it was
        net = copy.deepcopy(planner) if planner is not None else LearnedPlanner(planner_config)
        net.to(torch.float32).train()
        pool_polys = [random_convex_polygon(rng, int(rng.integers(3, 10))) for _ in range(cfg.pool)]
        pool = _from_normalised(
            [p.vertices for p in pool_polys],
            np.full(cfg.pool, 0.1),
            np.ones(cfg.pool),
            np.zeros((cfg.pool, 2)),
            torch.float32,
        )
        val = random_batch(
            np.random.default_rng(cfg.seed + 10_000_019),
            cfg.validation,
            min_spacing=cfg.min_spacing,
            max_spacing=cfg.max_spacing,
        )
        total = cfg.epochs * cfg.steps_per_epoch
        opt = torch.optim.AdamW(net.parameters(), lr=cfg.lr, weight_decay=cfg.weight_decay)
        sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, T_max=max(total, 1))
        keys = ("loss", "train_fitness", "smoothing", "val_fitness", "val_mean_fitness")
        history: dict[str, list[float]] = {key: [] for key in (*keys, "epoch_seconds")}
        best0, _ = _validate(net, val, obj)
        history["initial_val_fitness"] = [best0]
        bar = None
        show = sys.stderr.isatty() if progress is None else bool(progress)
        if show:
            from tqdm.auto import tqdm

            bar = tqdm(total=total, desc="train", file=sys.stderr, unit="step")
        step = 0
        try:
            for epoch in range(cfg.epochs):
                for _ in range(cfg.steps_per_epoch):
                    frac = step / max(total - 1, 1)
                    sigma = cfg.smoothing_start * (cfg.smoothing_end / cfg.smoothing_start) ** frac
                    idx = torch.as_tensor(rng.integers(0, cfg.pool, cfg.batch_size))
                    spacing = rng.uniform(cfg.min_spacing, cfg.max_spacing, cfg.batch_size)
                    batch = pool.select(idx)._replace(
                        spacing=torch.as_tensor(spacing, dtype=torch.float32)
                    )
                    pred = net(batch)
                    f = batch_objective(
                        batch, pred.theta, pred.offset, smoothing=sigma, objective=obj
                    )
                    w = torch.softmax(f.detach() / cfg.wta_temperature, dim=1)
                    wta = (w * f).sum(dim=1)
                    loss = -(wta + cfg.wta_floor * f.mean(dim=1)).mean()
                    opt.zero_grad(set_to_none=True)
                    loss.backward()
                    for p in net.parameters():
                        if p.grad is not None:
                            torch.nan_to_num_(p.grad, nan=0.0, posinf=0.0, neginf=0.0)
                    nn.utils.clip_grad_norm_(net.parameters(), 1.0)
                    opt.step()
                    sched.step()
                    history["loss"].append(float(loss.detach()))
                    history["train_fitness"].append(float(wta.detach().mean()))
                    history["smoothing"].append(sigma)
                    step += 1
                    if bar is not None:
                        bar.update(1)
                        if step % 10 == 0:
                            bar.set_postfix(loss=f"{float(loss.detach()):.4f}", refresh=False)
                best, mean = _validate(net, val, obj)
                history["val_fitness"].append(best)
                history["val_mean_fitness"].append(mean)
                history["epoch_seconds"].append(time.perf_counter() - t0)
                if bar is not None:
                    bar.set_postfix(loss=f"{float(loss.detach()):.4f}", val=f"{best:.4f}")
                if callback is not None:
                    callback(epoch, history)
        finally:
            if bar is not None:
                bar.close()
        net.eval()
        return TrainResult(net, cfg, history, time.perf_counter() - t0)
    finally:
        torch.set_num_threads(old_threads)
