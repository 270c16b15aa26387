"""The band evaluation of the paper's integral: only the points where it is not saturated."""

from __future__ import annotations

import bisect
import math
from typing import NamedTuple

from .._torch import torch

__all__ = ["band_tau", "integrand"]


def band_tau(dtype: torch.dtype) -> float:
    """``tau`` with ``sigmoid(tau) == 1`` and ``0.5 - sigmoid(-tau) == 0.5`` in ``dtype``.

    ``1 - sigmoid(x) ~ exp(-x)`` rounds away once it is below ``eps / 8`` (half the spacing of
    floats just under 0.5, a quarter of that just under 1); two units of margin on top absorb
    the rounding of the band's bounds and of ``sigmoid`` itself (float64: 41, float32: 21).

    >>> band_tau(torch.float64), band_tau(torch.float32)
    (41.0, 21.0)
    """
    return float(math.ceil(math.log(8 / torch.finfo(dtype).eps)) + 2)


_band_tau = band_tau  # the former private name


class _Group(NamedTuple):
    """Ranges ``[start, stop)`` of points of lines ``item``, at most ``width`` points each,
    whose integrand depends only on the edges ``edges: (G, A)`` (the others are saturated)."""

    item: torch.Tensor
    start: torch.Tensor
    stop: torch.Tensor
    edges: torch.Tensor
    width: int


class _Band(NamedTuple):
    """Where the integrand of each line is not saturated: see ``_SigmoidIntegral``.

    ``[lo, hi)`` are the points where no edge has ``tv <= -tau``; ``[c, d)`` (inside it) those
    where every edge has ``tv >= tau``. The band is ``[lo, c)`` and ``[d, hi)``, evaluated in
    ``groups``; the lines of the blocks ``full_rows`` (whose band would cost more than all their
    points) get ``lo = c = d = 0, hi = P`` and no groups. ``points``: the points of the band
    and of those blocks.
    """

    lo: torch.Tensor
    hi: torch.Tensor
    c: torch.Tensor
    d: torch.Tensor
    groups: list[_Group]
    full_rows: torch.Tensor
    points: int


def _searchsorted(
    t: torch.Tensor, grid: torch.Tensor, values: torch.Tensor, right: bool
) -> torch.Tensor:
    """``searchsorted(t[grid[m]], values[m])`` for the lines ``values: (M, E)``, ``t: (G, P)``."""
    if len(t) == 1:
        return torch.searchsorted(t[0], values.contiguous(), right=right)
    order = torch.argsort(grid, stable=True)
    counts = torch.bincount(grid, minlength=len(t))
    first = torch.cumsum(counts, 0) - counts
    rank = torch.arange(len(grid), device=grid.device) - first[grid[order]]
    width = int(counts.max()) if len(grid) else 0
    padded = values.new_full((len(t), width, values.shape[-1]), math.inf)
    padded[grid[order], rank] = values[order]
    found = torch.searchsorted(t, padded.view(len(t), -1), right=right).view(padded.shape)
    out = torch.empty_like(values, dtype=torch.int64)
    out[order] = found[grid[order], rank]
    return out


def _half_lines(
    lhs: torch.Tensor, slope: torch.Tensor, t: torch.Tensor, grid: torch.Tensor, level: float
) -> tuple[torch.Tensor, torch.Tensor]:
    """Per edge, the index range of ``{p : lhs + slope t_p > level}`` (``level < 0``) or
    ``>= level`` on the points ``t[grid]`` of each line."""
    pos, neg = slope > 0, slope < 0
    safe = torch.where(pos | neg, slope, torch.ones_like(slope))
    big = torch.full_like(lhs, math.inf)
    x = torch.where(pos | neg, (level - lhs) / safe, big)
    right = level < 0
    lower = _searchsorted(t, grid, torch.where(pos, x, -big), right)
    upper = _searchsorted(t, grid, torch.where(neg, x, big), not right)
    flat_ok = (pos | neg) | ((lhs > level) if right else (lhs >= level))
    return lower, torch.where(flat_ok, upper, torch.zeros_like(upper))


def _interval(lower: torch.Tensor, upper: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    lo = lower.amax(dim=-1)
    return lo, torch.maximum(lo, upper.amin(dim=-1))


class _Units(NamedTuple):
    """The two band ranges of each line (``[lo, c)`` and ``[d, hi)``) that are not empty."""

    item: torch.Tensor
    start: torch.Tensor
    stop: torch.Tensor
    saturated: torch.Tensor  # (U, E): edge saturated (s_j == 1) over the whole unit
    active: torch.Tensor
    width: torch.Tensor


def _units(
    lo: torch.Tensor,
    c: torch.Tensor,
    d: torch.Tensor,
    hi: torch.Tensor,
    in_lower: torch.Tensor,
    in_upper: torch.Tensor,
) -> _Units:
    n_edges = in_lower.shape[-1]
    items = torch.arange(len(lo), device=lo.device).repeat(2)
    start, stop = torch.cat([lo, d]), torch.cat([c, hi])
    keep = torch.nonzero(stop > start).squeeze(-1)
    items, start, stop = items[keep], start[keep], stop[keep]
    # Edge j is saturated over a unit inside its own tv_j >= tau range: left out exactly.
    saturated = (in_lower[items] <= start[:, None]) & (stop[:, None] <= in_upper[items])
    active = (n_edges - saturated.sum(dim=-1)).clamp_(min=1)
    return _Units(items, start, stop, saturated, active, stop - start)


def _groups(u: _Units, n_points: int, target: int) -> list[_Group]:
    """Units sorted by (active edges, width) and cut into groups that pad to their widest
    unit, at most twice their narrowest, all with the same number of active edges."""
    edges = torch.argsort(u.saturated.to(torch.int8), dim=-1, stable=True)  # active first
    key = u.active * (n_points + 1) + u.width
    order = torch.argsort(key)
    items, start, stop, edges = u.item[order], u.start[order], u.stop[order], edges[order]
    keys, widths, counts = key[order].tolist(), u.width[order].tolist(), u.active[order].tolist()
    groups: list[_Group] = []
    i = 0
    while i < len(keys):
        a, cap = counts[i], min(2 * widths[i], n_points)
        size = max(1, target // (cap * a))
        j = min(bisect.bisect_right(keys, a * (n_points + 1) + cap, lo=i), i + size)
        s = slice(i, j)
        groups.append(_Group(items[s], start[s], stop[s], edges[s, :a], widths[j - 1]))
        i = j
    return groups


def _band(
    lhs: torch.Tensor,
    slope: torch.Tensor,
    t: torch.Tensor,
    grid: torch.Tensor,
    k: int,
    target: int,
) -> _Band:
    """The band of each line ``lhs, slope: (N * K, E)`` on its points ``t[grid]``.

    Blocks of ``k`` lines whose band would cost more than their full evaluation (a gathered
    point costs about twice a point of the full kernel: low temperatures, edges nearly
    parallel to the transects) are left to the full kernel: ``full_rows``.
    """
    n_points, n_edges = t.shape[-1], lhs.shape[-1]
    tau = band_tau(lhs.dtype)
    lo, hi = _interval(*_half_lines(lhs, slope, t, grid, -tau))
    in_lower, in_upper = _half_lines(lhs, slope, t, grid, tau)
    c, d = _interval(in_lower, in_upper)
    c, d = torch.minimum(torch.maximum(c, lo), hi), torch.minimum(torch.maximum(d, lo), hi)
    empty = d <= c  # no inside: split the band in two halves
    mid = lo + (hi - lo + 1) // 2
    c, d = torch.where(empty, mid, c), torch.where(empty, mid, torch.maximum(c, d))
    u = _units(lo, c, d, hi, in_lower, in_upper)
    cost = torch.zeros(len(lo) // k, dtype=torch.int64, device=lo.device)
    cost.index_add_(0, u.item // k, u.width * u.active)
    full = 2 * cost > k * n_points * n_edges
    full_items = full.repeat_interleave(k)
    part = torch.nonzero(~full_items[u.item]).squeeze(-1)
    u = _Units(*(x[part] for x in u))
    zero = torch.zeros_like(lo)
    lo, c, d = (torch.where(full_items, zero, x) for x in (lo, c, d))
    hi = torch.where(full_items, torch.full_like(hi, n_points), hi)
    points = int((hi - lo).sum() - (d - c).sum())
    groups = _groups(u, n_points, target)
    return _Band(lo, hi, c, d, groups, torch.nonzero(full).squeeze(-1), points)


def _group_points(
    g: _Group,
    lhs: torch.Tensor,
    slope: torch.Tensor,
    t: torch.Tensor,
    w: torch.Tensor,
    grid: torch.Tensor,
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]:
    """``lhs, slope: (G, A)`` of the active edges; ``t_p, w_p: (G, width)``, padding
    ``w_p = 0``; ``t, w: (grids, P)`` and ``grid: (M,)`` the grid of each line."""
    n_points = t.shape[-1]
    p = g.start[:, None] + torch.arange(g.width, device=t.device)
    valid = p < g.stop[:, None]
    p = p.clamp_(max=n_points - 1)
    if len(t) > 1:  # one grid per block: its row of the flattened points
        p = p + grid[g.item, None] * n_points
    p = p.view(-1)
    tp = t.reshape(-1).index_select(0, p).view(valid.shape)
    wp = torch.where(valid, w.reshape(-1).index_select(0, p).view(valid.shape), 0.0)
    return lhs[g.item].gather(1, g.edges), slope[g.item].gather(1, g.edges), tp, wp


def integrand(
    tv: torch.Tensor, temp: torch.Tensor
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """``(P_sigma, P, sigmoid(tv))`` of Eq. 5 and 4 from ``T v: (..., E)``, ``temp`` broadcasting
    with ``(...)``: the one integrand of every evaluation of the paper's model.

    >>> q, p, s = integrand(torch.tensor([[50.0, 50.0]], dtype=torch.float64), torch.tensor(10.0))
    >>> round(float(q), 4), float(p)
    (0.9933, 1.0)
    """
    sig = torch.sigmoid(tv)
    p = sig.prod(dim=-1)
    return torch.sigmoid(temp * (p - 0.5)), p, sig


def _band_integrand(
    lhs: torch.Tensor, slope: torch.Tensor, tp: torch.Tensor, temp: torch.Tensor
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """:func:`integrand` at the points ``tp: (G, Q)`` of each item."""
    tv = lhs[:, None, :] + slope[:, None, :] * tp[..., None]  # same rounding as the full kernel
    return integrand(tv, temp[:, None])
