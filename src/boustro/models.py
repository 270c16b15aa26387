"""Transect-length models: the exact chords and the paper's differentiable sigmoid integral.

Every model maps (polygon half-planes, angle ``theta``, offset ``d``, spacing ``s``) to the lengths
of the transects of a grid and to a weight per transect saying whether it counts. They share one
interface, :class:`TransectModel`, so the fitness functions and the optimisers take any of them.

Transect grid convention (the same in every frame):

* ``theta`` is the transect DIRECTION in radians, counter-clockwise from ``+x``. Its unit vector
  is ``u = (cos theta, sin theta)``; the transects' left normal is ``n = (-sin theta, cos theta)``.
* Transect ``k`` is the line ``{p : n . p = d + k s}``, ``k`` any integer: ``d`` is the signed
  distance of the grid from the origin (the polygon's vertex mean in the normalised frame) along
  ``n``. The set of lines is periodic in ``d`` with period ``s``, and ``(theta + pi, -d)`` is the
  same set as ``(theta, d)``.
* A point of transect ``k`` is ``p = (d + k s) n + t u``; ``t`` is the along-transect coordinate.

Tensors: ``theta`` and ``offset`` broadcast together to the batch shape ``(*B)``; half-planes may
carry their own leading polygon dimensions ``(*P)`` that broadcast with ``(*B)``. Outputs have shape
``(*, K)`` with ``K`` candidate transects per grid (those that miss the polygon have length 0 and
weight 0, so ``K`` is static and batches stack). dtype and device follow the half-planes.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from typing import Any, NamedTuple, Protocol, runtime_checkable

import torch
import torch.nn.functional as F
from torch.autograd.function import once_differentiable

from .errors import InvalidParameterError, as_number
from .geometry import HalfPlanes

__all__ = [
    "PAPER_WINDOW",
    "Chords",
    "ExactModel",
    "PaperModel",
    "TransectLengths",
    "TransectModel",
    "exact_chords",
    "paper_lengths",
    "transect_positions",
]

#: Half-width of the paper's transect window: transects at ``|n . p| <= 0.5`` only, integrated
#: over ``t`` in ``[-0.5, 0.5]`` (used with ``clip=True`` for faithful reproduction).
PAPER_WINDOW = 0.5


class TransectLengths(NamedTuple):
    """What a model says about the grid of transects.

    Attributes:
        lengths: ``(*, K)`` transect lengths, in the units of the half-planes' frame.
        weights: ``(*, K)`` in ``[0, 1]``: how much each transect counts as "shown" (exact: 0 or
            1; soft: the paper's Eq. 7 indicator).
        positions: ``(*, K)`` signed distance ``d + k s`` of each transect from the origin.
    """

    lengths: torch.Tensor
    weights: torch.Tensor
    positions: torch.Tensor


class Chords(NamedTuple):
    """Exact chords of the transect grid: transect ``k`` spans ``t`` in ``[lower, upper]``."""

    positions: torch.Tensor
    lower: torch.Tensor
    upper: torch.Tensor
    lengths: torch.Tensor


@runtime_checkable
class TransectModel(Protocol):
    """Anything that turns (half-planes, theta, offset, spacing) into :class:`TransectLengths`."""

    @property
    def name(self) -> str: ...

    def __call__(
        self, hp: HalfPlanes, theta: torch.Tensor, offset: torch.Tensor, spacing: float
    ) -> TransectLengths: ...


#: Most transects across one area that boustro plans or scores (a 10 km field at 1 cm): a
#: smaller spacing is refused with a clear error instead of exhausting memory.
MAX_TRANSECTS = 1_000_000
#: Most candidate transects of one (angle, offset) pair in a model's grid, which also covers the
#: model's margin beyond the polygon (32 smoothing lengths for the smooth closed form).
MAX_CANDIDATES = 4 * MAX_TRANSECTS


#: Most integration points per transect of the paper's model (the paper uses 1000; 10^4 is
#: already exact to its temperature's resolution in every benchmark here).
MAX_POINTS_PER_TRANSECT = 1_000_000


def check_spacing(spacing: float, extent: float | None = None) -> float:
    """Return ``spacing`` as a float, or raise if it is not a finite positive number, or (with
    ``extent``, the width to cover in the same units) if more than :data:`MAX_TRANSECTS`
    transects would be needed."""
    s = as_number("spacing", spacing)
    if not math.isfinite(s) or s <= 0:
        raise InvalidParameterError(f"spacing must be a finite number > 0, got {spacing!r}")
    if extent is not None and extent / s > MAX_TRANSECTS:
        raise InvalidParameterError(
            f"spacing {s:.6g} is too small for an area {extent:.6g} across: about "
            f"{extent / s:.3g} transects, more than the {MAX_TRANSECTS} boustro handles"
        )
    return s


def check_finite(name: str, value: float) -> float:
    """Return ``value`` as a float, or raise if it is not a finite number."""
    v = as_number(name, value)
    if not math.isfinite(v):
        raise InvalidParameterError(f"{name} must be a finite number, got {value!r}")
    return v


def _prepare(
    hp: HalfPlanes, theta: torch.Tensor | float, offset: torch.Tensor | float
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]:
    """Angle and offset as tensors of the half-planes' dtype/device, and the per-edge components.

    Returns ``(theta, offset, across, along, b)`` where ``across = n_j . n`` and
    ``along = n_j . u`` have shape ``(*, E)``: edge ``j`` holds at ``(c, t)`` iff
    ``across_j c + along_j t + b_j >= 0``. Rotating the edges instead of the transects is the
    paper's "rotate W, keep B".
    """
    dtype, device = hp.normals.dtype, hp.normals.device
    theta_t = torch.as_tensor(theta, dtype=dtype, device=device)
    offset_t = torch.as_tensor(offset, dtype=dtype, device=device)
    theta_t, offset_t = torch.broadcast_tensors(theta_t, offset_t)
    across, along, b = _components(torch.cos(theta_t), torch.sin(theta_t), hp.normals, hp.offsets)
    return theta_t, offset_t, across, along, b


def _components(
    cos: torch.Tensor, sin: torch.Tensor, normals: torch.Tensor, offsets: torch.Tensor
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """``(across, along, b)`` ``(*, E)``: ``across = n_j . n``, ``along = n_j . u`` of edges
    ``normals (*, E, 2)``, ``offsets (*, E)`` seen from transects at angles ``(cos, sin)``
    ``(*)`` (broadcasting), and the offsets broadcast to their shape."""
    nx, ny = normals[..., 0], normals[..., 1]
    cos, sin = cos[..., None], sin[..., None]
    across = -nx * sin + ny * cos
    along = nx * cos + ny * sin
    return across, along, torch.broadcast_to(offsets, across.shape)


def grid_size(spacing: float, radius: float) -> tuple[int, int]:
    """``(K, m)``: the ``K`` lines ``d mod s + (k - m) s``, ``0 <= k < K``, cover +-radius.

    Raises:
        InvalidParameterError: more than :data:`MAX_CANDIDATES` lines (a tiny spacing, or a
            model whose margin, e.g. a huge smoothing, grows the disc by as much).
    """
    if 2 * radius / spacing > MAX_CANDIDATES:
        raise InvalidParameterError(
            f"{2 * radius / spacing:.3g} candidate transects at spacing {spacing:.6g} across a "
            f"disc of radius {radius:.6g} (the polygon's, grown by the model's margin): more "
            f"than the {MAX_CANDIDATES} boustro handles; use a larger spacing (or a smoothing "
            "below the spacing)"
        )
    m = math.ceil(radius / spacing) + 1
    return 2 * m, m


def transect_positions(offset: torch.Tensor, spacing: float, radius: float) -> torch.Tensor:
    """Positions ``(*, K)`` of every grid line that can meet a disc of ``radius`` at the origin.

    The offset is wrapped into ``[0, spacing)`` first (``torch.remainder``, whose gradient is 1),
    so any offset, however far it has drifted, gives the same static ``K``.
    """
    d, q = _grid(offset, spacing, radius)
    return d[..., None] + q


def _grid(offset: torch.Tensor, spacing: float, radius: float) -> tuple[torch.Tensor, torch.Tensor]:
    """``(d, q)``: the wrapped offset ``(*)`` and the lines' places ``(K,)`` relative to it, so
    that :func:`transect_positions` is ``d[..., None] + q``."""
    spacing = check_spacing(spacing)
    k_count, m = grid_size(spacing, radius)
    k = torch.arange(k_count, dtype=offset.dtype, device=offset.device) - m
    return torch.remainder(offset, spacing), k * spacing


def _window_mask(positions: torch.Tensor, clip: bool) -> torch.Tensor | None:
    if not clip:
        return None
    return (positions >= -PAPER_WINDOW) & (positions < PAPER_WINDOW)


def exact_chords(
    hp: HalfPlanes,
    theta: torch.Tensor | float,
    offset: torch.Tensor | float,
    spacing: float,
    *,
    clip: bool = False,
) -> Chords:
    """Exact chords of a convex polygon's transect grid, in closed form (DESIGN.md sec. 4).

    For transect position ``c`` each edge bounds ``t``: ``t >= -(across c + b) / along`` where
    ``along > 0`` (lower bounds) and ``<=`` where ``along < 0`` (upper bounds); an edge parallel
    to the transects (``along == 0``) either holds for every ``t`` or empties the chord. The chord
    is ``[max lower, min upper]``, its length ``max(0, upper - lower)``: O(E) per transect.

    Differentiable almost everywhere in ``theta`` and ``offset`` (not at transects through
    vertices); denominators are made safe before ``torch.where`` so gradients stay finite.

    Args:
        hp: half-planes ``(*P, E, 2)``, see :func:`boustro.geometry.halfplanes`.
        theta: transect direction(s) in radians, ``(*B)``.
        offset: grid offset(s) in the half-planes' frame, ``(*B)``.
        spacing: transect spacing in the same frame, > 0.
        clip: restrict to the paper's window (``|c| <= 0.5`` and ``t`` in ``[-0.5, 0.5]``).

    Returns:
        :class:`Chords` with tensors ``(*, K)``; transects missing the polygon have length 0 and
        ``lower == upper`` undefined (do not use their endpoints).
    """
    theta, offset, across, along, b = _prepare(hp, theta, offset)
    c = transect_positions(offset, spacing, PAPER_WINDOW if clip else hp.radius)
    across, along, b = across[..., None, :], along[..., None, :], b[..., None, :]
    lhs = across * c[..., :, None] + b  # (*, K, E): edge j holds iff lhs + along t >= 0
    parallel = along == 0
    bound = -lhs / torch.where(parallel, torch.ones_like(along), along)
    inf = torch.as_tensor(math.inf, dtype=c.dtype, device=c.device)
    lower = torch.where(along > 0, bound, -inf).amax(dim=-1)
    upper = torch.where(along < 0, bound, inf).amin(dim=-1)
    if clip:
        lower = lower.clamp(min=-PAPER_WINDOW)
        upper = upper.clamp(max=PAPER_WINDOW)
    blocked = (parallel & (lhs < 0)).any(dim=-1)
    length = torch.where(blocked, torch.zeros_like(lower), (upper - lower).clamp(min=0))
    mask = _window_mask(c, clip)
    if mask is not None:
        length = torch.where(mask, length, torch.zeros_like(length))
    return Chords(torch.broadcast_to(c, length.shape), lower, upper, length)


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
        # Plain autograd (gradients reach the temperature too); Eq. 4 in log space.
        tv = lhs[..., :, None, :] + slope[..., None, None, :] * t[:, None]
        log_p = F.logsigmoid(tv).sum(dim=-1)  # (*, K, P)
        p_sigma = torch.sigmoid(temp_kp * (torch.exp(log_p) - 0.5))  # Eq. 5
        length = torch.trapezoid(p_sigma, dx=dx, dim=-1)
    else:
        batch = lhs.shape[:-2]
        work = lhs.numel() * len(t)  # sigmoids of the every-point evaluation
        # The band's planning costs ~1 ms a call and pays off only where the band is a small
        # share of the points (about 8 tau / (T * 2 half) of them): measured crossover.
        use_band = (
            band
            and work >= _BAND_MIN_WORK
            and float(temp.min()) * 2 * half >= 8 * _band_tau(lhs.dtype)
        )
        length = _SigmoidIntegral.apply(
            lhs.reshape(-1, *lhs.shape[-2:]),
            torch.broadcast_to(slope, (*batch, slope.shape[-1])).reshape(-1, slope.shape[-1]),
            t,
            torch.broadcast_to(temp, batch).reshape(-1),
            dx,
            use_band,
        ).reshape(*batch, lhs.shape[-2])
    mask = _window_mask(c, clip)
    if mask is not None:
        length = torch.where(mask, length, torch.zeros_like(length))
    temp_k = temp[..., None] if temp.ndim else temp
    weight = 2 * torch.sigmoid(temp_k * length) - 1  # Eq. 7
    return TransectLengths(length, weight, torch.broadcast_to(c, length.shape))


@dataclass(frozen=True)
class ExactModel:
    """Exact chord lengths (closed form); weights are 1 for transects of positive length.

    Differentiable almost everywhere, but its gradient ignores transects entering or leaving
    the polygon: use it to score, and a soft model to descend.
    """

    clip: bool = False
    name: str = "exact"

    def __call__(
        self, hp: HalfPlanes, theta: torch.Tensor, offset: torch.Tensor, spacing: float
    ) -> TransectLengths:
        ch = exact_chords(hp, theta, offset, spacing, clip=self.clip)
        # A chord shorter than this is a transect grazing a vertex: rounding, not a transect.
        tiny = 1e-12 * max(hp.radius, 1e-300)
        return TransectLengths(ch.lengths, (ch.lengths > tiny).to(ch.lengths.dtype), ch.positions)


@dataclass(frozen=True)
class PaperModel:
    """The paper's sigmoid-integral model (Eq. 2-7) with its settings; see :func:`paper_lengths`."""

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
