"""The paper's integral by a matrix product over the subsets of the edges (low temperatures)."""

from __future__ import annotations

from .._torch import torch

__all__ = ["subsets_blocks", "subsets_lengths"]

#: ``|exponent|`` bounds of the subset expansion: the point factors stay in
#: ``[exp(-300), exp(300)]``, the line factors are capped at ``exp(400)``, so no product or sum
#: of 2^9 of them overflows and none is 0 x inf.
_GAMMA_EXP = 300.0
_ALPHA_EXP = 400.0

#: Elements (points x edges) of one step (4 MB of float64): small enough that the allocator
#: reuses its blocks.
_CHUNK_ELEMENTS = 1 << 19


def subsets_blocks(slope: torch.Tensor, span: torch.Tensor) -> float:
    """The largest number of point blocks of a line (``slope: (S, E)``, ``span: (S,)``)."""
    reach = float((slope.detach().abs().sum(dim=-1) * span).max()) if len(span) else 0.0
    return max(1.0, reach / (2 * _GAMMA_EXP))


def _subset_bits(n_edges: int, dtype: torch.dtype) -> tuple[torch.Tensor, ...]:
    bits = ((torch.arange(1 << n_edges)[:, None] >> torch.arange(n_edges)) & 1).to(dtype)
    e_lo = n_edges // 2
    return bits, bits[: 1 << e_lo, :e_lo], bits[:: 1 << e_lo, e_lo:]


def subsets_lengths(
    lhs: torch.Tensor,
    slope: torch.Tensor,
    start: torch.Tensor,
    t: torch.Tensor,
    w: torch.Tensor,
    grid: torch.Tensor,
    temp: torch.Tensor,
) -> torch.Tensor:
    """Eq. 3-6 of lines ``lhs: (M, E)`` by a matrix product (forward only): ``(M,)``.

    The lines of polygon ``s`` are the rows ``start[s]:start[s + 1]`` (``start: (S + 1,)``);
    they share its ``slope[s]: (E,)``, temperature ``temp[s]`` and points ``t[grid[s]]`` with
    trapezoid weights ``w[grid[s]]`` (``t, w: (grids, P)``).

    ``1 / P = prod_j (1 + exp(-z_j)) = sum_S alpha_S gamma_S``: on a line
    ``z_j(t) = lhs_j + slope_j t``; around a centre ``t_m``,
    ``exp(-z_j(t)) = exp(-z_j(t_m)) exp(-slope_j (t - t_m))``, so the product over the edges
    expands into a sum over the ``2^E`` subsets ``S`` of the edges of (a factor of the line,
    ``alpha``) x (a factor of the point, ``gamma``): one ``(K, 2^E) @ (2^E, points)`` matrix
    product per polygon instead of ``K x points x E`` sigmoids. All terms are positive (no
    cancellation); the points are cut into blocks short enough that ``gamma`` stays within
    ``exp(+-300)``. A line factor above ``exp(400)`` is capped there: the point is then outside
    by so much that ``P < exp(-100)``, and Eq. 5 gives the same value to the last bit.
    """
    n_edges, n_points = lhs.shape[-1], t.shape[-1]
    bits, bits_lo, bits_hi = _subset_bits(n_edges, lhs.dtype)
    e_lo = n_edges // 2
    out = torch.zeros(len(lhs), dtype=lhs.dtype, device=lhs.device)
    bounds = start.tolist()
    for s in range(len(bounds) - 1):
        r0, r1 = bounds[s], bounds[s + 1]
        if r0 == r1:
            continue
        tal, ts, ws = slope[s], t[grid[s]], w[grid[s]]
        reach = float(tal.abs().sum())  # >= |sum of slope over any subset|
        step = float(ts[1] - ts[0])
        block = max(2, min(n_points, int(2 * _GAMMA_EXP / max(reach * step, 1e-300))))
        rows_chunk = max(1, _CHUNK_ELEMENTS // min(block, n_points))
        acc = torch.zeros(r1 - r0, dtype=lhs.dtype, device=lhs.device)
        sig_lo, sig_hi = bits_lo @ tal[:e_lo], bits_hi @ tal[e_lo:]
        for p0 in range(0, n_points, block):
            p1 = min(n_points, p0 + block)
            tt = ts[p0:p1]
            tm = 0.5 * (tt[0] + tt[-1])
            dt = tt - tm
            gamma = (
                torch.exp(-sig_hi[:, None, None] * dt) * torch.exp(-sig_lo[None, :, None] * dt)
            ).reshape(1 << n_edges, -1)  # (2^E, block): subset index = hi * 2^e_lo + lo
            for q0 in range(r0, r1, rows_chunk):
                q1 = min(r1, q0 + rows_chunk)
                zc = lhs[q0:q1] + tal * tm  # z at the block's centre, (rows, E)
                alpha = torch.exp(-(zc @ bits.T).clamp(min=-_ALPHA_EXP))
                p = torch.reciprocal(alpha @ gamma)
                acc[q0 - r0 : q1 - r0] += torch.sigmoid(temp[s] * (p - 0.5)) @ ws[p0:p1]
        out[r0:r1] = acc
    return out
