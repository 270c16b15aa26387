"""The sigmoid integral of Eq. 4-6 as one autograd Function: every point or only the band."""

from __future__ import annotations

from typing import Any, NamedTuple

from .._torch import Function, autograd_function, once_differentiable, torch
from .paper_band import _Band, _band, _band_integrand, _group_points, integrand

__all__ = ["SigmoidIntegral"]

#: Elements of the ``(items, points, edges)`` tensor per step of the fused kernel.
_TARGET = 1 << 18


class _Items(NamedTuple):
    """One row per line of the inputs of :class:`_SigmoidIntegral`: ``(M, E)`` and ``(M,)``."""

    lhs: torch.Tensor
    slope: torch.Tensor
    temp: torch.Tensor
    grid: torch.Tensor
    dx: torch.Tensor


def _items(
    lhs: torch.Tensor,
    slope: torch.Tensor,
    temp: torch.Tensor,
    grid: torch.Tensor,
    dx: torch.Tensor,
) -> _Items:
    """The lines of the blocks ``lhs: (N, K, E)``, one row each (``N * K`` rows)."""
    n, k, e = lhs.shape
    gi = grid.repeat_interleave(k)
    return _Items(
        lhs.reshape(n * k, e),
        slope.repeat_interleave(k, dim=0),
        temp.repeat_interleave(k, dim=0),
        gi,
        dx[gi],
    )


def _trapezoid_weights(t: torch.Tensor, dx: torch.Tensor) -> torch.Tensor:
    """``(grids, P)`` trapezoid weights of the points ``t: (grids, P)`` with steps ``dx``."""
    w = dx[:, None].expand(t.shape).clone()
    w[:, 0] = w[:, -1] = dx / 2
    return w


class _Grids(NamedTuple):
    """The points ``t: (grids, P)``, their steps ``dx: (grids,)``, the grid of each block."""

    t: torch.Tensor
    dx: torch.Tensor
    grid: torch.Tensor


def _as_grids(
    t: torch.Tensor, dx: torch.Tensor | float, grid: torch.Tensor | None, n: int
) -> _Grids:
    """One shared grid ``t: (P,)`` with a float step, or ``(grids, P)`` with ``grid: (N,)``."""
    if t.ndim == 1:
        t = t[None]
    dx = torch.as_tensor(dx, dtype=t.dtype, device=t.device).reshape(-1)
    if grid is None:
        grid = torch.zeros(n, dtype=torch.int64, device=t.device)
    return _Grids(t, dx, grid)


def _plan(lhs: torch.Tensor, slope: torch.Tensor, temp: torch.Tensor, g: _Grids) -> _Band:
    """The band (:func:`_band`) of the blocks ``lhs: (N, K, E)``."""
    it = _items(lhs, slope, temp, g.grid, g.dx)
    return _band(it.lhs, it.slope, g.t, it.grid, lhs.shape[1], _TARGET)


@autograd_function
class _SigmoidIntegral(Function):
    """Eq. 4-6 fused: lengths ``(N, K)`` from ``tv = lhs[n, k, j] + slope[n, j] * t[p]``.

    Each block ``n`` of ``K`` lines shares its slopes, its temperature ``temp[n]`` and its
    points: ``t: (P,)`` with the step ``dx`` for all, or ``t: (grids, P)``, ``dx: (grids,)``
    and ``grid: (N,)`` the grid of each block. ``band``: ``True`` plans the band evaluation
    below, ``False`` evaluates every point, or a plan (:func:`_plan`).

    The ``(N, K, P, E)`` tensor of the paper's model dominates its cost and memory. This saves
    only the small inputs and recomputes in the backward pass with the analytic derivative: with
    ``s_j = sigmoid(tv_j)``, ``P = prod_j s_j`` (Eq. 4), ``q = sigmoid(T (P - 0.5))`` (Eq. 5),
    ``L = trapezoid(q)`` (Eq. 6), ``dL / dtv_j = w_p T q (1 - q) P (1 - s_j)``. That derivative
    has no division (the autograd of ``prod`` divides by ``s_j`` and gives NaN where a sigmoid
    underflows to 0), so it is as stable as the log-space product: in float64 ``P`` underflows
    only below 1e-308, where ``q`` and its gradient are saturated anyway. Same values as the
    log-space form to rounding (tests compare the two).

    Band evaluation (``band=True``), exact to rounding: with ``tau`` from :func:`band_tau`
    (41 in float64, 21 in float32), where every ``tv_j >= tau`` each sigmoid rounds to 1, so
    ``P == 1`` and ``q == sigmoid(T / 2)`` exactly, and ``1 - s_j == 0`` so the derivative is
    exactly 0; where some ``tv_j <= -tau``, ``P <= exp(-tau)`` so ``P - 0.5 == -0.5`` and
    ``q == sigmoid(-T / 2)`` exactly. Both sets are index ranges of ``p`` (intersections of
    half-lines in ``t``), summed in closed form; only the band between them (for transects
    crossing the polygon, ``~2 * 2 tau / |slope|`` points around the two crossings) is evaluated,
    gathered and padded in groups of items of similar width; blocks whose band covers most of
    their points (near-parallel edges, low ``T``) take every point. Values equal the full
    evaluation up to the order of summation. The only dropped derivative terms are those of
    points with some ``tv_j <= -tau``: at most ``w_p T q (1 - q) exp(-tau) <= 4e-19 T w_p``
    each in float64 (``2e-10 T w_p`` in float32), so the gradient of a length differs from the
    full evaluation's by at most ``4e-19 T`` times the transect's span ``sum_p w_p``.
    """

    @staticmethod
    def forward(
        ctx: Any,
        lhs: torch.Tensor,
        slope: torch.Tensor,
        t: torch.Tensor,
        temp: torch.Tensor,
        dx: torch.Tensor | float,
        band: bool | _Band = True,
        grid: torch.Tensor | None = None,
    ) -> torch.Tensor:
        g = _as_grids(t, dx, grid, len(lhs))
        ctx.save_for_backward(lhs, slope, temp, *g)
        chosen = _plan(lhs, slope, temp, g) if band is True and lhs.numel() else band
        plan: _Band | None = chosen if isinstance(chosen, _Band) else None
        ctx.plan = plan
        if plan is None:
            return _full_lengths(lhs, slope, temp, g, slice(None))
        n, k, _ = lhs.shape
        it = _items(lhs, slope, temp, g.grid, g.dx)
        w = _trapezoid_weights(g.t, g.dx)
        n_points = g.t.shape[-1]

        def span(lo: torch.Tensor, hi: torch.Tensor) -> torch.Tensor:  # sum of w over [lo, hi)
            some = hi > lo
            ends = (some & (lo == 0)).to(lhs.dtype) + (some & (hi == n_points)).to(lhs.dtype)
            return it.dx * (hi - lo).to(lhs.dtype) - (it.dx / 2) * ends

        one, zero = torch.ones_like(it.temp), torch.zeros_like(it.temp)
        q_in = torch.sigmoid(it.temp * (one - 0.5))  # P == 1 exactly
        q_out = torch.sigmoid(it.temp * (zero - 0.5))  # P - 0.5 == -0.5 exactly
        outside = span(torch.zeros_like(plan.lo), plan.lo)
        outside = outside + span(plan.hi, torch.full_like(plan.hi, n_points))
        out = q_in * span(plan.c, plan.d) + q_out * outside
        for grp in plan.groups:
            lhs_g, slope_g, tp, wp = _group_points(grp, it.lhs, it.slope, g.t, w, it.grid)
            q = _band_integrand(lhs_g, slope_g, tp, it.temp[grp.item])[0]
            out.index_add_(0, grp.item, (q * wp).sum(dim=-1))
        out = out.view(n, k)
        rows = plan.full_rows
        if len(rows):
            out[rows] = _full_lengths(lhs, slope, temp, g, rows)
        return out

    @staticmethod
    @once_differentiable
    def backward(ctx: Any, grad: torch.Tensor) -> tuple[torch.Tensor | None, ...]:
        lhs, slope, temp, *grids = ctx.saved_tensors
        g = _Grids(*grids)
        w = _trapezoid_weights(g.t, g.dx)
        plan: _Band | None = ctx.plan
        none = (None,) * 5
        if plan is None:
            return (*_full_grads(lhs, slope, temp, g, w, grad, slice(None)), *none)
        n, k, e = lhs.shape
        it = _items(lhs, slope, temp, g.grid, g.dx)
        grad_i = grad.reshape(-1)
        g_lhs_i, g_slope_i = torch.zeros_like(it.lhs), torch.zeros_like(it.lhs)
        for grp in plan.groups:
            lhs_g, slope_g, tp, wp = _group_points(grp, it.lhs, it.slope, g.t, w, it.grid)
            tmp = it.temp[grp.item]
            q, p, sig = _band_integrand(lhs_g, slope_g, tp, tmp)
            g_p = grad_i[grp.item, None] * wp * tmp[:, None] * q * (1 - q) * p
            g_tv = g_p[..., None] * (1 - sig)  # (G, width, A)
            at = (grp.item[:, None] * e + grp.edges).view(-1)
            g_lhs_i.view(-1).index_add_(0, at, g_tv.sum(dim=1).view(-1))
            g_slope_i.view(-1).index_add_(0, at, torch.einsum("gqa,gq->ga", g_tv, tp).reshape(-1))
        g_lhs, g_slope = g_lhs_i.view(n, k, e), g_slope_i.view(n, k, e).sum(dim=1)
        rows = plan.full_rows
        if len(rows):
            g_lhs[rows], g_slope[rows] = _full_grads(lhs, slope, temp, g, w, grad, rows)
        return (g_lhs, g_slope, *none)


def _chunks(n_rows: int, per_row: int, target: int = _TARGET) -> list[slice]:
    """Slices of ``n_rows`` rows whose ``(c, K, P, E)`` tensor holds about ``target`` elements."""
    step = max(1, target // max(1, per_row))
    return [slice(i, i + step) for i in range(0, n_rows, step)]


def _sigmoid_integrand(
    lhs: torch.Tensor, slope: torch.Tensor, temp: torch.Tensor, g: _Grids, rows: torch.Tensor
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]:
    """``(P_sigma, P, sigmoid(tv), t)`` of Eq. 5 and 4 at every point of the blocks ``rows``:
    ``(c, K, P)``, ``(c, K, P)``, ``(c, K, P, E)`` and their points ``(c, P)``."""
    tr = g.t[g.grid[rows]]
    tv = lhs[rows, :, None, :] + (slope[rows, None, :] * tr[..., None])[:, None]
    return (*integrand(tv, temp[rows, None, None]), tr)


def _full_lengths(
    lhs: torch.Tensor,
    slope: torch.Tensor,
    temp: torch.Tensor,
    g: _Grids,
    rows: torch.Tensor | slice,
) -> torch.Tensor:
    """Eq. 4-6 at every point of the blocks ``rows``, in chunks of blocks: ``(c, K)``."""
    idx = torch.arange(len(lhs), device=lhs.device)[rows]
    per_row = lhs.shape[-2] * lhs.shape[-1] * g.t.shape[-1]
    out = []
    for r in _chunks(len(idx), per_row):
        q = _sigmoid_integrand(lhs, slope, temp, g, idx[r])[0]
        if len(g.dx) == 1:  # one step: torch's trapezoid (the same arithmetic)
            out.append(torch.trapezoid(q, dx=float(g.dx[0]), dim=-1))
        else:
            dx = g.dx[g.grid[idx[r]], None]
            out.append((q.sum(dim=-1) - (q[..., 0] + q[..., -1]) * 0.5) * dx)
    return torch.cat(out) if out else lhs.new_zeros((0, lhs.shape[-2]))


def _full_grads(
    lhs: torch.Tensor,
    slope: torch.Tensor,
    temp: torch.Tensor,
    g: _Grids,
    w: torch.Tensor,
    grad: torch.Tensor,
    rows: torch.Tensor | slice,
) -> tuple[torch.Tensor, torch.Tensor]:
    """Gradients of :func:`_full_lengths` with respect to ``lhs`` and ``slope`` (of ``rows``)."""
    idx = torch.arange(len(lhs), device=lhs.device)[rows]
    g_lhs, g_slope = torch.zeros_like(lhs[idx]), torch.zeros_like(slope[idx])
    per_row = lhs.shape[-2] * lhs.shape[-1] * g.t.shape[-1]
    for r in _chunks(len(idx), per_row):
        q, p, sig, tr = _sigmoid_integrand(lhs, slope, temp, g, idx[r])
        wr = w[g.grid[idx[r]], None, :]
        g_p = grad[idx[r], :, None] * wr * temp[idx[r], None, None] * q * (1 - q) * p
        g_tv = g_p[..., None] * (1 - sig)  # (c, K, P, E)
        g_lhs[r] = g_tv.sum(dim=2)
        if len(g.dx) == 1:
            g_slope[r] = torch.einsum("ckpe,p->ce", g_tv, g.t[0])
        else:
            g_slope[r] = torch.einsum("ckpe,cp->ce", g_tv, tr)
    return g_lhs, g_slope


#: The public name of the Function (its former private name stays).
SigmoidIntegral = _SigmoidIntegral
