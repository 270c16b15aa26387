"""The paper's differentiable transect model: the sigmoid integral of Eq. 3-7 (PaperModel)."""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from typing import Any, NamedTuple

import torch
import torch.nn.functional as F
from torch.autograd.function import once_differentiable

from .._validate import as_number
from ..errors import InvalidParameterError
from ..geometry import HalfPlanes
from .base import PAPER_WINDOW, TransectLengths, _prepare, _window_mask, transect_positions

__all__ = ["MAX_POINTS_PER_TRANSECT", "PAPER_WINDOW", "PaperModel", "paper_lengths"]

#: Most integration points per transect of the paper's model (the paper uses 1000; 10^4 is
#: already exact to its temperature's resolution in every benchmark here).
MAX_POINTS_PER_TRANSECT = 1_000_000


def _as_temperature(temperature: torch.Tensor | float, like: torch.Tensor) -> torch.Tensor:
    t = torch.as_tensor(temperature, dtype=like.dtype, device=like.device)
    if not torch.all(torch.isfinite(t) & (t > 0)):
        raise InvalidParameterError(f"temperature must be finite and > 0, got {temperature!r}")
    return t


#: Below this many sigmoids (transects x points x edges) a call evaluates every point: the band's
#: fixed planning cost would exceed its saving.
_BAND_MIN_WORK = 1 << 17


def _band_tau(dtype: torch.dtype) -> float:
    """``tau`` with ``sigmoid(tau) == 1`` and ``0.5 - sigmoid(-tau) == 0.5`` in ``dtype``.

    ``1 - sigmoid(x) ~ exp(-x)`` rounds away once it is below ``eps / 8`` (half the spacing of
    floats just under 0.5, a quarter of that just under 1); two units of margin on top absorb
    the rounding of the band's bounds and of ``sigmoid`` itself (float64: 41, float32: 21).
    """
    return float(math.ceil(math.log(8 / torch.finfo(dtype).eps)) + 2)


class _Group(NamedTuple):
    """Ranges ``[start, stop)`` of points of transects ``item``, at most ``width`` points each,
    whose integrand depends only on the edges ``edges: (G, A)`` (the others are saturated)."""

    item: torch.Tensor
    start: torch.Tensor
    stop: torch.Tensor
    edges: torch.Tensor
    width: int


class _Band(NamedTuple):
    """Where the integrand of each transect is not saturated: see :class:`_SigmoidIntegral`.

    ``[lo, hi)`` are the points where no edge has ``tv <= -tau``; ``[c, d)`` (inside it) those
    where every edge has ``tv >= tau``. The band is ``[lo, c)`` and ``[d, hi)``, evaluated in
    ``groups``.
    """

    lo: torch.Tensor
    hi: torch.Tensor
    c: torch.Tensor
    d: torch.Tensor
    groups: list[_Group]
    full_rows: torch.Tensor


def _band(lhs: torch.Tensor, slope: torch.Tensor, t: torch.Tensor, k: int, target: int) -> _Band:
    """Index ranges of the band of each transect ``lhs, slope: (N * K, E)`` on the points ``t``.

    Batch rows whose band would cost more than their full evaluation (a gathered point costs
    about twice a point of the full kernel: low temperatures, edges nearly parallel to the
    transects) are left to the full kernel: ``full_rows``, whose transects get ``lo = c = d = 0,
    hi = P`` and no band groups.
    """
    n_points, n_edges = len(t), lhs.shape[-1]
    tau = _band_tau(lhs.dtype)
    pos, neg = slope > 0, slope < 0
    safe = torch.where(pos | neg, slope, torch.ones_like(slope))
    big = torch.full_like(lhs, math.inf)

    def half_lines(level: float) -> tuple[torch.Tensor, torch.Tensor]:
        # Per edge, the index range of {p : lhs + slope t_p > level} (level < 0) or >= level.
        x = torch.where(pos | neg, (level - lhs) / safe, big)
        right = level < 0
        lower = torch.searchsorted(t, torch.where(pos, x, -big).contiguous(), right=right)
        upper = torch.searchsorted(t, torch.where(neg, x, big).contiguous(), right=not right)
        flat_ok = (pos | neg) | ((lhs > level) if right else (lhs >= level))
        return lower, torch.where(flat_ok, upper, torch.zeros_like(upper))

    def interval(lower: torch.Tensor, upper: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        lo = lower.amax(dim=-1)
        return lo, torch.maximum(lo, upper.amin(dim=-1))

    lo, hi = interval(*half_lines(-tau))
    in_lower, in_upper = half_lines(tau)
    c, d = interval(in_lower, in_upper)
    c, d = torch.minimum(torch.maximum(c, lo), hi), torch.minimum(torch.maximum(d, lo), hi)
    empty = d <= c  # no inside: split the band in two halves
    mid = lo + (hi - lo + 1) // 2
    c, d = torch.where(empty, mid, c), torch.where(empty, mid, torch.maximum(c, d))

    # Units: the two band ranges of each transect. Edge j is saturated (s_j == 1, 1 - s_j == 0)
    # over a unit inside its own tv_j >= tau range: it can be left out of that unit exactly.
    items = torch.arange(len(lo), device=lo.device).repeat(2)
    start, stop = torch.cat([lo, d]), torch.cat([c, hi])
    keep = torch.nonzero(stop > start).squeeze(-1)
    items, start, stop = items[keep], start[keep], stop[keep]
    saturated = (in_lower[items] <= start[:, None]) & (stop[:, None] <= in_upper[items])
    active = (n_edges - saturated.sum(dim=-1)).clamp_(min=1)
    width = stop - start
    cost = torch.zeros(len(lo) // k, dtype=torch.int64, device=lo.device)
    cost.index_add_(0, items // k, width * active)
    full = 2 * cost > k * n_points * n_edges
    full_rows = torch.nonzero(full).squeeze(-1)
    full_items = full.repeat_interleave(k)
    part = torch.nonzero(~full_items[items]).squeeze(-1)
    items, start, stop, saturated = items[part], start[part], stop[part], saturated[part]
    active, width = active[part], width[part]
    zero = torch.zeros_like(lo)
    lo, c, d = (torch.where(full_items, zero, x) for x in (lo, c, d))
    hi = torch.where(full_items, torch.full_like(hi, n_points), hi)
    edges = torch.argsort(saturated.to(torch.int8), dim=-1, stable=True)  # active edges first
    key = active * (n_points + 1) + width
    order = torch.argsort(key)
    items, start, stop, edges = items[order], start[order], stop[order], edges[order]
    keys, widths, counts = key[order].tolist(), width[order].tolist(), active[order].tolist()
    groups: list[_Group] = []
    i = 0
    while i < len(keys):
        # Sorted by (active edges, width): a group pads to its widest unit, at most twice its
        # narrowest, and all its units have the same number of active edges.
        a, cap = counts[i], min(2 * widths[i], n_points)
        size = max(1, target // (cap * a))
        j = min(bisect.bisect_right(keys, a * (n_points + 1) + cap, lo=i), i + size)
        s = slice(i, j)
        groups.append(_Group(items[s], start[s], stop[s], edges[s, :a], widths[j - 1]))
        i = j
    return _Band(lo, hi, c, d, groups, full_rows)


def _group_points(
    g: _Group, lhs: torch.Tensor, slope: torch.Tensor, t: torch.Tensor, w: torch.Tensor
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]:
    """``lhs, slope: (G, A)`` of the active edges; ``t_p, w_p: (G, width)``, padding ``w_p = 0``."""
    p = g.start[:, None] + torch.arange(g.width, device=t.device)
    valid = p < g.stop[:, None]
    p = p.clamp_(max=len(t) - 1).view(-1)
    tp = t.index_select(0, p).view(valid.shape)
    wp = torch.where(valid, w.index_select(0, p).view(valid.shape), 0.0)
    return lhs[g.item].gather(1, g.edges), slope[g.item].gather(1, g.edges), tp, wp


def _band_integrand(
    lhs: torch.Tensor, slope: torch.Tensor, tp: torch.Tensor, temp: torch.Tensor
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """``(P_sigma, P, sigmoid(tv))`` of Eq. 5 and 4 at the points ``tp: (G, Q)`` of each item."""
    tv = lhs[:, None, :] + slope[:, None, :] * tp[..., None]  # same rounding as the full kernel
    sig = torch.sigmoid(tv)
    p = sig.prod(dim=-1)
    return torch.sigmoid(temp[:, None] * (p - 0.5)), p, sig


class _SigmoidIntegral(torch.autograd.Function):
    """Eq. 4-6 fused: lengths ``(N, K)`` from ``tv = lhs[n, k, j] + slope[n, j] * t[p]``.

    The ``(N, K, P, E)`` tensor of the paper's model dominates its cost and memory. This saves
    only the small inputs and recomputes in the backward pass with the analytic derivative: with
    ``s_j = sigmoid(tv_j)``, ``P = prod_j s_j`` (Eq. 4), ``q = sigmoid(T (P - 0.5))`` (Eq. 5),
    ``L = trapezoid(q)`` (Eq. 6), ``dL / dtv_j = w_p T q (1 - q) P (1 - s_j)``. That derivative
    has no division (the autograd of ``prod`` divides by ``s_j`` and gives NaN where a sigmoid
    underflows to 0), so it is as stable as the log-space product: in float64 ``P`` underflows
    only below 1e-308, where ``q`` and its gradient are saturated anyway. Same values as the
    log-space form to rounding (tests compare the two).

    Band evaluation (``band=True``), exact to rounding: with ``tau`` from :func:`_band_tau`
    (41 in float64, 21 in float32), where every ``tv_j >= tau`` each sigmoid rounds to 1, so
    ``P == 1`` and ``q == sigmoid(T / 2)`` exactly, and ``1 - s_j == 0`` so the derivative is
    exactly 0; where some ``tv_j <= -tau``, ``P <= exp(-tau)`` so ``P - 0.5 == -0.5`` and
    ``q == sigmoid(-T / 2)`` exactly. Both sets are index ranges of ``p`` (intersections of
    half-lines in ``t``), summed in closed form; only the band between them (for transects
    crossing the polygon, ``~2 * 2 tau / |slope|`` points around the two crossings) is evaluated,
    gathered and padded in groups of items of similar width; items whose band covers most of
    the transect (near-parallel edges, low ``T``) take every point. Values equal the full
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
        dx: float,
        band: bool = True,
    ) -> torch.Tensor:
        ctx.save_for_backward(lhs, slope, t, temp)
        ctx.dx = dx
        ctx.plan = None
        if not band or lhs.numel() == 0:
            return _full_lengths(lhs, slope, t, temp, dx)
        n, k, _ = lhs.shape
        lhs_i, slope_i, temp_i = _items(lhs, slope, temp)
        plan = ctx.plan = _band(lhs_i, slope_i, t, k, _TARGET)
        w = _trapezoid_weights(t, dx)
        n_points = len(t)

        def span(lo: torch.Tensor, hi: torch.Tensor) -> torch.Tensor:  # sum of w over [lo, hi)
            some = hi > lo
            ends = (some & (lo == 0)).to(lhs.dtype) + (some & (hi == n_points)).to(lhs.dtype)
            return dx * (hi - lo).to(lhs.dtype) - (dx / 2) * ends

        one, zero = torch.ones_like(temp_i), torch.zeros_like(temp_i)
        q_in = torch.sigmoid(temp_i * (one - 0.5))  # P == 1 exactly
        q_out = torch.sigmoid(temp_i * (zero - 0.5))  # P - 0.5 == -0.5 exactly
        outside = span(torch.zeros_like(plan.lo), plan.lo)
        outside = outside + span(plan.hi, torch.full_like(plan.hi, n_points))
        out = q_in * span(plan.c, plan.d) + q_out * outside
        for g in plan.groups:
            lhs_g, slope_g, tp, wp = _group_points(g, lhs_i, slope_i, t, w)
            q = _band_integrand(lhs_g, slope_g, tp, temp_i[g.item])[0]
            out.index_add_(0, g.item, (q * wp).sum(dim=-1))
        out = out.view(n, k)
        rows = plan.full_rows
        if len(rows):
            out[rows] = _full_lengths(lhs[rows], slope[rows], t, temp[rows], dx)
        return out

    @staticmethod
    @once_differentiable
    def backward(ctx: Any, grad: torch.Tensor) -> tuple[torch.Tensor | None, ...]:
        lhs, slope, t, temp = ctx.saved_tensors
        w = _trapezoid_weights(t, ctx.dx)
        plan: _Band | None = ctx.plan
        if plan is None:
            g_lhs, g_slope = _full_grads(lhs, slope, t, temp, w, grad)
            return g_lhs, g_slope, None, None, None, None
        n, k, e = lhs.shape
        lhs_i, slope_i, temp_i = _items(lhs, slope, temp)
        grad_i = grad.reshape(-1)
        g_lhs_i, g_slope_i = torch.zeros_like(lhs_i), torch.zeros_like(lhs_i)
        for g in plan.groups:
            lhs_g, slope_g, tp, wp = _group_points(g, lhs_i, slope_i, t, w)
            tmp = temp_i[g.item]
            q, p, sig = _band_integrand(lhs_g, slope_g, tp, tmp)
            g_p = grad_i[g.item, None] * wp * tmp[:, None] * q * (1 - q) * p
            g_tv = g_p[..., None] * (1 - sig)  # (G, width, A)
            at = (g.item[:, None] * e + g.edges).view(-1)
            g_lhs_i.view(-1).index_add_(0, at, g_tv.sum(dim=1).view(-1))
            g_slope_i.view(-1).index_add_(0, at, torch.einsum("gqa,gq->ga", g_tv, tp).reshape(-1))
        g_lhs, g_slope = g_lhs_i.view(n, k, e), g_slope_i.view(n, k, e).sum(dim=1)
        rows = plan.full_rows
        if len(rows):
            g_lhs[rows], g_slope[rows] = _full_grads(
                lhs[rows], slope[rows], t, temp[rows], w, grad[rows]
            )
        return g_lhs, g_slope, None, None, None, None


def _full_lengths(
    lhs: torch.Tensor, slope: torch.Tensor, t: torch.Tensor, temp: torch.Tensor, dx: float
) -> torch.Tensor:
    """Eq. 4-6 at every point, in chunks of rows: ``(N, K)``."""
    out = [
        torch.trapezoid(_sigmoid_integrand(lhs, slope, t, temp, rows)[0], dx=dx, dim=-1)
        for rows in _chunks(lhs, len(t))
    ]
    return torch.cat(out) if out else lhs.new_zeros(lhs.shape[:-1])


def _full_grads(
    lhs: torch.Tensor,
    slope: torch.Tensor,
    t: torch.Tensor,
    temp: torch.Tensor,
    w: torch.Tensor,
    grad: torch.Tensor,
) -> tuple[torch.Tensor, torch.Tensor]:
    """Gradients of :func:`_full_lengths` with respect to ``lhs`` and ``slope``."""
    g_lhs, g_slope = torch.zeros_like(lhs), torch.zeros_like(slope)
    for rows in _chunks(lhs, len(t)):
        q, p, sig = _sigmoid_integrand(lhs, slope, t, temp, rows)
        g_p = grad[rows, :, None] * w * temp[rows, None, None] * q * (1 - q) * p
        g_tv = g_p[..., None] * (1 - sig)  # (c, K, P, E)
        g_lhs[rows] = g_tv.sum(dim=2)
        g_slope[rows] = torch.einsum("ckpe,p->ce", g_tv, t)
    return g_lhs, g_slope


#: Elements of the ``(items, points, edges)`` tensor per step of the fused kernel.
_TARGET = 1 << 18


def _items(
    lhs: torch.Tensor, slope: torch.Tensor, temp: torch.Tensor
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """``lhs, slope: (N * K, E)`` and ``temp: (N * K)``, one row per transect."""
    n, k, e = lhs.shape
    return (
        lhs.reshape(n * k, e),
        slope.repeat_interleave(k, dim=0),
        temp.repeat_interleave(k, dim=0),
    )


def _trapezoid_weights(t: torch.Tensor, dx: float) -> torch.Tensor:
    w = torch.full_like(t, dx)
    w[0] = w[-1] = dx / 2
    return w


def _chunks(lhs: torch.Tensor, n_points: int, target: int = _TARGET) -> list[slice]:
    """Row slices of the batch whose ``(c, K, P, E)`` tensor holds about ``target`` elements."""
    per_row = max(1, lhs.shape[-2] * lhs.shape[-1] * n_points)
    step = max(1, target // per_row)
    return [slice(i, i + step) for i in range(0, lhs.shape[0], step)]


def _sigmoid_integrand(
    lhs: torch.Tensor, slope: torch.Tensor, t: torch.Tensor, temp: torch.Tensor, rows: slice
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """``(P_sigma, P, sigmoid(tv))`` of Eq. 5 and 4 for a chunk of rows."""
    tv = lhs[rows, :, None, :] + (slope[rows, None, :] * t[:, None])[:, None]
    sig = torch.sigmoid(tv)
    p = sig.prod(dim=-1)
    return torch.sigmoid(temp[rows, None, None] * (p - 0.5)), p, sig


def _autograd_lengths(
    lhs: torch.Tensor, slope: torch.Tensor, t: torch.Tensor, temp_kp: torch.Tensor, dx: float
) -> torch.Tensor:
    """Eq. 4-6 by plain autograd (gradients reach the temperature too), Eq. 4 in log space."""
    tv = lhs[..., :, None, :] + slope[..., None, None, :] * t[:, None]
    log_p = F.logsigmoid(tv).sum(dim=-1)  # (*, K, P)
    p_sigma = torch.sigmoid(temp_kp * (torch.exp(log_p) - 0.5))  # Eq. 5
    return torch.trapezoid(p_sigma, dx=dx, dim=-1)


def _fused_lengths(
    lhs: torch.Tensor,
    slope: torch.Tensor,
    t: torch.Tensor,
    temp: torch.Tensor,
    dx: float,
    *,
    band: bool,
    half: float,
) -> torch.Tensor:
    """Eq. 4-6 by :class:`_SigmoidIntegral` (chunked, analytic backward, band where it pays)."""
    batch = lhs.shape[:-2]
    work = lhs.numel() * len(t)  # sigmoids of the every-point evaluation
    # The band's planning costs ~1 ms a call and pays off only where the band is a small
    # share of the points (about 8 tau / (T * 2 half) of them): measured crossover.
    use_band = (
        band and work >= _BAND_MIN_WORK and float(temp.min()) * 2 * half >= 8 * _band_tau(lhs.dtype)
    )
    return _SigmoidIntegral.apply(
        lhs.reshape(-1, *lhs.shape[-2:]),
        torch.broadcast_to(slope, (*batch, slope.shape[-1])).reshape(-1, slope.shape[-1]),
        t,
        torch.broadcast_to(temp, batch).reshape(-1),
        dx,
        use_band,
    ).reshape(*batch, lhs.shape[-2])


def paper_lengths(
    hp: HalfPlanes,
    theta: torch.Tensor | float,
    offset: torch.Tensor | float,
    spacing: float,
    *,
    temperature: torch.Tensor | float = 1000.0,
    points_per_transect: int = 1000,
    clip: bool = False,
    band: bool = True,
) -> TransectLengths:
    """The paper's differentiable transect lengths and "shown" weights (Eq. 3-7).

    For each transect and each of ``points_per_transect`` points along it:
    ``P = prod_j sigmoid(T (n_j . p + b_j))`` (Eq. 4; its gradient is computed without division,
    so a factor that underflows to 0 never makes a NaN), ``P_sigma = sigmoid(T (P - 0.5))``
    (Eq. 5), the length is the trapezoid integral of ``P_sigma`` along the
    transect (Eq. 6) and the weight is ``S = 2 sigmoid(T L) - 1`` (Eq. 7).

    Fully vectorised, no Python loop over transects or points: the ``(*, K, points, E)`` work
    runs in cache-sized chunks of the batch with an analytic backward, and only where the
    integrand is not saturated to rounding (the points within ``~40 / T`` of an edge crossing;
    the rest are summed in closed form, same values to rounding: see :class:`_SigmoidIntegral`),
    so memory stays bounded however large the batch. A temperature
    tensor that requires grad takes plain autograd through the log-space product instead, so
    gradients reach the temperature too.

    Args:
        hp: half-planes of convex polygon(s) (:func:`boustro.geometry.halfplanes`).
        theta, offset, spacing: see :func:`exact_chords`.
        temperature: ``Temp`` of the paper, > 0; a tensor broadcasting with the batch is allowed.
        points_per_transect: trapezoid points per transect (>= 2).
        clip: the paper's window: transects with ``|c| <= 0.5`` integrated over
            ``t`` in ``[-0.5, 0.5]``. A polygon centred on its vertex mean can reach beyond 0.5
            (a triangle does), so this under-measures such polygons; by default the integral
            spans ``[-radius, radius]``, the whole polygon, with ``radius`` the batch's largest
            (:attr:`HalfPlanes.radius`): the points, hence the quadrature error, of one polygon
            depend on the others in its batch (by up to 1e-4 in fitness at T = 1000 with 1000
            points; the exact and smooth models do not).
        band: evaluate only the unsaturated band of points near the boundary and sum the
            saturated rest in closed form (equal to rounding, see :class:`_SigmoidIntegral`)
            where that is faster: large calls at high temperature; ``False`` always evaluates
            every point, as the paper does.

    Returns:
        :class:`TransectLengths` ``(*, K)``.
    """
    points = as_number("points_per_transect", points_per_transect)
    if not (points == int(points) and 2 <= points <= MAX_POINTS_PER_TRANSECT):
        raise InvalidParameterError(
            f"points_per_transect must be an integer in [2, {MAX_POINTS_PER_TRANSECT}], got "
            f"{points_per_transect!r}"
        )
    theta, offset, across, along, b = _prepare(hp, theta, offset)
    temp = _as_temperature(temperature, across)
    half = PAPER_WINDOW if clip else hp.radius
    c = transect_positions(offset, spacing, half)
    t = torch.linspace(-half, half, int(points_per_transect), dtype=c.dtype, device=c.device)
    temp_e = temp[..., None] if temp.ndim else temp  # broadcasts with (*, E)
    temp_kp = temp_e[..., None] if temp.ndim else temp  # broadcasts with (*, K, P)
    dx = 2 * half / (int(points_per_transect) - 1)
    # T v[..., k, p, j] = T (across_j c_k + b_j) + T along_j t_p: two small factors.
    lhs = (temp_e * across)[..., None, :] * c[..., :, None] + (temp_e * b)[..., None, :]
    slope = temp_e * along  # (*, E)
    if isinstance(temperature, torch.Tensor) and temperature.requires_grad:
        length = _autograd_lengths(lhs, slope, t, temp_kp, dx)
    else:
        length = _fused_lengths(lhs, slope, t, temp, dx, band=band, half=half)
    mask = _window_mask(c, clip)
    if mask is not None:
        length = torch.where(mask, length, torch.zeros_like(length))
    temp_k = temp[..., None] if temp.ndim else temp
    weight = 2 * torch.sigmoid(temp_k * length) - 1  # Eq. 7
    return TransectLengths(length, weight, torch.broadcast_to(c, length.shape))


@dataclass(frozen=True)
class PaperModel:
    """The paper's sigmoid-integral model (Eq. 2-7) with its settings; see :func:`paper_lengths`.

    Example:
        >>> from boustro.geometry import Polygon, halfplanes
        >>> hp = halfplanes(Polygon([(0, 0), (4, 0), (4, 3), (0, 3)]))  # normalised: 0.8 x 0.6
        >>> model = PaperModel(points_per_transect=200)
        >>> out = model(hp, torch.tensor(0.0), torch.tensor(0.05), 0.2)
        >>> [round(x, 3) for x in out.lengths[out.weights > 0.5].tolist()]
        [0.804, 0.804, 0.804]
    """

    temperature: float = 1000.0
    points_per_transect: int = 1000
    clip: bool = False
    band: bool = True
    name: str = "paper"

    def __call__(
        self, hp: HalfPlanes, theta: torch.Tensor, offset: torch.Tensor, spacing: float
    ) -> TransectLengths:
        return paper_lengths(
            hp,
            theta,
            offset,
            spacing,
            temperature=self.temperature,
            points_per_transect=self.points_per_transect,
            clip=self.clip,
            band=self.band,
        )
