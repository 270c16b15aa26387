"""The learned planner's network: a polygon's edge set and spacing to ``k`` layouts."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple, cast

import torch
from torch import nn

from ..geometry import HalfPlanes
from ..models import chords_at
from .batch import PlanBatch
from .config import PlannerConfig

__all__ = ["LearnedPlanner", "PlannerConfig", "Prediction", "hypotheses"]

_TWO_PI = 2.0 * math.pi


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
    hp = HalfPlanes(batch.normals[:, None], batch.offsets[:, None], 0.0)
    return chords_at(hp, theta, c).lengths


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
    """Polygon (edge set) + spacing -> ``k`` hypotheses ``(theta, offset)``; the
    architecture is described in ``docs/learned.md``.

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


def hypotheses(planner: LearnedPlanner, batch: PlanBatch) -> tuple[torch.Tensor, torch.Tensor]:
    """The network's ``k`` hypotheses ``(theta, offset)`` ``(P, k)`` in the batch's dtype."""
    with torch.no_grad():
        pred = planner(batch)
    return pred.theta.to(batch.spacing.dtype), pred.offset.to(batch.spacing.dtype)
