"""The differentiable region model: the region's indicator blurred across the transects.

The soft indicator at smoothing length ``h`` blurs the region by a logistic kernel across the
transects; its line integrals have a closed form over trapezoids (slabs between vertex
positions), so every (line, trapezoid) pair is a soft segment with a weight and a length that
tend to the exact segments as ``h -> 0``. See ``docs/concave.md``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

from .._torch import functional as F
from .._torch import torch
from .._validate import check_positive, check_spacing
from ..errors import InvalidParameterError
from .base import TransectLengths, transect_positions
from .region import RegionEdges, _as_tensors, _project, _segments_at

__all__ = ["RegionSoftModel", "soft_indicator", "soft_region_lengths"]


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
    return check_positive("smoothing", smoothing)


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
