"""The paper's model (Eq. 2-7) for many Table I samples at once: dense, band or subsets."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Literal

import numpy as np
import torch
import torch.nn.functional as F
from numpy.typing import NDArray

from ..models import chord_bounds
from ..objectives.smith import smith_fitness
from .layouts import _Group, _scatter, protocol_groups
from .samples import Protocol, Samples, Statistics, Trapezoid

__all__ = ["BAND_Z", "Method", "paper_model_fitness"]


#: Half-width, in units of ``T * distance``, of the band around the polygon's boundary where the
#: paper's model is evaluated point by point (:func:`_soft_lengths`). ``E exp(-41) < 2e-17`` for
#: ``E <= 9`` edges; 41 rather than 40 leaves room for rounding in the classification.
BAND_Z = 41.0

#: Elements (points x edges) of one batched evaluation (4 MB of float64). Small enough that the
#: allocator reuses its blocks: with 32 MB blocks a third of the time went to page faults.
_CHUNK_ELEMENTS = 1 << 19


def _bounds(
    a: torch.Tensor, along: torch.Tensor, delta: float
) -> tuple[torch.Tensor, torch.Tensor]:
    """The ``t``-interval where ``a_j + along_j t >= delta`` for every edge ``j``: ``(M,)`` x 2,
    by the library's :func:`~boustro.models.chord_bounds`.

    ``lo > hi`` where it is empty. Edges with ``|along| <= 1e-12`` count as parallel.
    """
    lower, upper, blocked = chord_bounds(a, along, delta=delta, parallel_tol=1e-12)
    inf = torch.tensor(math.inf, dtype=a.dtype)
    return torch.where(blocked, inf, lower), torch.where(blocked, -inf, upper)


class _Soft:
    """What every evaluation path of the paper's model needs for one group and setting."""

    def __init__(self, g: _Group, temperature: float, points: int) -> None:
        self.g = g
        self.temperature = float(temperature)
        self.temp = torch.tensor(self.temperature, dtype=torch.float64)
        self.points = int(points)
        self.dx = 2 * g.half / (self.points - 1)  # (B,), the library's trapezoid step
        ta, tb, self.tal = self.temp * g.across, self.temp * g.b, self.temp * g.along
        # T v = (T across) c + (T b) + (T along) t: the library's factors, the same arithmetic.
        self.lhs = ta[g.sample] * g.position[:, None] + tb[g.sample]  # (M, E)
        self.shared_t = bool(torch.all(g.half == g.half[0]))
        if self.shared_t:
            h = float(g.half[0])
            self.t_grid = torch.linspace(-h, h, self.points, dtype=torch.float64)
        else:
            self.t_grid = torch.stack(
                [
                    torch.linspace(-float(h), float(h), self.points, dtype=torch.float64)
                    for h in g.half
                ]
            )  # (B, P)
        counts = torch.bincount(g.sample, minlength=len(g.index))
        self.row_end = torch.cumsum(counts, 0)
        self.row_start = self.row_end - counts

    def t(self, b: int) -> torch.Tensor:
        return self.t_grid if self.shared_t else self.t_grid[b]

    def trapezoid_weights(self, b: int, p0: int, p1: int) -> torch.Tensor:
        w = torch.full((p1 - p0,), float(self.dx[b]), dtype=torch.float64)
        if p0 == 0:
            w[0] *= 0.5
        if p1 == self.points:
            w[-1] *= 0.5
        return w

    def p_sigma(self, log_p: torch.Tensor) -> torch.Tensor:
        """Eq. 5 from Eq. 4 in log space."""
        return torch.sigmoid(self.temp * (torch.exp(log_p) - 0.5))


def _lengths_dense(s: _Soft, rows: torch.Tensor | None = None) -> torch.Tensor:
    """Every point of every transect (or of ``rows``): the library's tensor, sample by sample,
    in chunks of transects; in-place where the library allocates."""
    g = s.g
    m = len(g.position)
    selected = torch.ones(m, dtype=torch.bool) if rows is None else torch.zeros(m, dtype=torch.bool)
    if rows is not None:
        selected[rows] = True
    n_edges = s.lhs.shape[-1]
    out = torch.zeros(m, dtype=torch.float64)
    chunk = max(1, _CHUNK_ELEMENTS // (s.points * n_edges))
    for b in range(len(g.index)):
        r0, r1 = int(s.row_start[b]), int(s.row_end[b])
        mine = torch.nonzero(selected[r0:r1])[:, 0] + r0
        if len(mine) == 0:
            continue
        tal_t = s.tal[b] * s.t(b)[:, None]  # (P, E): the library's (T along) * t
        for start in range(0, len(mine), chunk):
            r = mine[start : start + chunk]
            tv = s.lhs[r, None, :] + tal_t
            p = torch.exp(F.logsigmoid(tv).sum(dim=-1))  # Eq. 4
            del tv
            p_sigma = torch.sigmoid_(p.sub_(0.5).mul_(s.temp))  # Eq. 5
            out[r] = torch.trapezoid(p_sigma, dx=float(s.dx[b]), dim=-1)  # Eq. 6
    return out if rows is None else out[rows]


#: ``|exponent|`` bounds of the subset expansion (:func:`_lengths_subsets`): the point factors
#: stay in ``[exp(-300), exp(300)]``, the transect factors are capped at ``exp(400)``, so no
#: product or sum of 2^9 of them overflows and none is 0 x inf.
_GAMMA_EXP = 300.0
_ALPHA_EXP = 400.0


def _lengths_subsets(s: _Soft) -> torch.Tensor:
    """Eq. 3-6 by a matrix product: ``1 / P = prod_j (1 + exp(-z_j)) = sum_S alpha_S gamma_S``.

    On a transect ``z_j(t) = lhs_j + tal_j t``. Around a centre ``t_m``,
    ``exp(-z_j(t)) = exp(-z_j(t_m)) exp(-tal_j (t - t_m))``, so the product over the edges
    expands into a sum over the ``2^E`` subsets ``S`` of the edges of (a factor of the transect,
    ``alpha``) x (a factor of the point, ``gamma``): one ``(K, 2^E) @ (2^E, points)`` matrix
    product per sample instead of ``K x points x E`` log-sigmoids. All terms are positive (no
    cancellation); the points are cut into blocks short enough that ``gamma`` stays within
    ``exp(+-300)``. A transect factor above ``exp(400)`` is capped there: the point is then
    outside by so much that ``P < exp(-100)``, and Eq. 5 gives the same value to the last bit.
    """
    g = s.g
    n_edges = s.lhs.shape[-1]
    n_sub = 1 << n_edges
    bits = ((torch.arange(n_sub)[:, None] >> torch.arange(n_edges)) & 1).to(torch.float64)
    e_lo = n_edges // 2
    bits_lo = bits[: 1 << e_lo, :e_lo]  # subsets of the first e_lo edges (low bits)
    bits_hi = bits[:: 1 << e_lo, e_lo:]  # subsets of the others (high bits)
    out = torch.zeros(len(g.position), dtype=torch.float64)
    for b in range(len(g.index)):
        r0, r1 = int(s.row_start[b]), int(s.row_end[b])
        if r0 == r1:
            continue
        tal = s.tal[b]
        reach = float(tal.abs().sum())  # >= |sum of tal over any subset|
        t = s.t(b)
        step = float(t[1] - t[0])
        block = max(2, min(s.points, int(2 * _GAMMA_EXP / max(reach * step, 1e-300))))
        rows_chunk = max(1, _CHUNK_ELEMENTS // min(block, s.points))
        acc = torch.zeros(r1 - r0, dtype=torch.float64)
        sig_lo, sig_hi = bits_lo @ tal[:e_lo], bits_hi @ tal[e_lo:]
        for p0 in range(0, s.points, block):
            p1 = min(s.points, p0 + block)
            tt = t[p0:p1]
            tm = 0.5 * (tt[0] + tt[-1])
            dt = tt - tm
            gamma = (
                torch.exp(-sig_hi[:, None, None] * dt) * torch.exp(-sig_lo[None, :, None] * dt)
            ).reshape(n_sub, -1)  # (2^E, block): subset index = hi * 2^e_lo + lo
            w = s.trapezoid_weights(b, p0, p1)
            for q0 in range(r0, r1, rows_chunk):
                q1 = min(r1, q0 + rows_chunk)
                zc = s.lhs[q0:q1] + tal * tm  # z at the block's centre, (rows, E)
                alpha = torch.exp(-(zc @ bits.T).clamp(min=-_ALPHA_EXP))
                p = torch.reciprocal(alpha @ gamma)
                acc[q0 - r0 : q1 - r0] += torch.sigmoid(s.temp * (p - 0.5)) @ w
        out[r0:r1] = acc
    bad = ~torch.isfinite(out)
    if bool(bad.any()):  # cannot happen (see the bounds above); the direct way as a guard
        out[bad] = _lengths_dense(s, torch.nonzero(bad)[:, 0])
    return out


def _band_counts(s: _Soft) -> dict[str, torch.Tensor]:
    """Per transect, the index ranges of the "in" points and of the band (:func:`_soft_lengths`)."""
    g = s.g
    a = g.across[g.sample] * g.position[:, None] + g.b[g.sample]
    along = g.along[g.sample]
    lo_in, hi_in = _bounds(a, along, BAND_Z / s.temperature)
    lo_d, hi_d = _bounds(a, along, -BAND_Z / s.temperature)
    h_m, dx_m = g.half[g.sample], s.dx[g.sample]
    last = s.points - 1

    def index(x: torch.Tensor, ceil: bool, shift: int, low: int, high: int) -> torch.Tensor:
        f = (x + h_m) / dx_m
        f = (torch.ceil(f) if ceil else torch.floor(f)) + shift
        return torch.nan_to_num(f, nan=float(low)).clamp(low, high).to(torch.long)

    # One point of margin on each side for the rounding of linspace and of the bounds.
    p_lo_in = index(lo_in, True, 1, 0, s.points)
    p_hi_in = index(hi_in, False, -1, -1, last)
    p_lo_d = index(lo_d, False, -1, 0, s.points)
    p_hi_d = index(hi_d, True, 1, -1, last)
    n_in = (p_hi_in - p_lo_in + 1).clamp(min=0)
    has_in = n_in > 0
    n_d = (p_hi_d - p_lo_d + 1).clamp(min=0)
    n1 = torch.where(has_in, (p_lo_in - p_lo_d).clamp(min=0), n_d)
    n2 = torch.where(has_in, (p_hi_d - p_hi_in).clamp(min=0), torch.zeros_like(n_d))
    return {
        "p_lo_in": p_lo_in,
        "p_hi_in": p_hi_in,
        "p_lo_d": p_lo_d,
        "p_hi_d": p_hi_d,
        "n_in": n_in,
        "has_in": has_in,
        "n1": n1,
        "n2": n2,
    }


def _lengths_band(s: _Soft, c: dict[str, torch.Tensor]) -> torch.Tensor:
    """Only the points near the boundary, point by point (ragged); the others at Eq. 5's
    limits ``sigmoid(T / 2)`` (inside) and ``sigmoid(-T / 2)`` (outside)."""
    g = s.g
    m = len(g.position)
    n_edges = s.lhs.shape[-1]
    last = s.points - 1
    dx_m = s.dx[g.sample]
    n1, n2, has_in = c["n1"], c["n2"], c["has_in"]
    s2 = c["p_hi_in"] + 1
    lengths = torch.zeros(m, dtype=torch.float64)
    per = n1 + n2
    budget = max(s.points, _CHUNK_ELEMENTS // n_edges)
    cum = torch.cumsum(per, 0)
    begin = 0
    while begin < m:  # chunks of whole transects, about `budget` points each
        done = int(cum[begin - 1]) if begin else 0
        end = min(m, max(begin + 1, int(torch.searchsorted(cum, done + budget, right=True))))
        rows = torch.arange(begin, end)
        starts = torch.stack([c["p_lo_d"][rows], s2[rows]], dim=-1).flatten()
        counts = torch.stack([n1[rows], n2[rows]], dim=-1).flatten()
        seg = torch.repeat_interleave(torch.arange(len(counts)), counts)
        first = torch.repeat_interleave(torch.cumsum(counts, 0) - counts, counts)
        pi = starts[seg] + (torch.arange(len(seg)) - first)
        ti = rows.repeat_interleave(2)[seg]
        t = s.t_grid[pi] if s.shared_t else s.t_grid[g.sample[ti], pi]
        tv = s.lhs[ti] + s.tal[g.sample[ti]] * t[:, None]
        p_sigma = s.p_sigma(F.logsigmoid(tv).sum(dim=-1))
        weight = torch.where((pi == 0) | (pi == last), 0.5, 1.0).to(torch.float64) * dx_m[ti]
        lengths.index_add_(0, ti, p_sigma * weight)
        begin = end
    f64 = torch.float64
    n_in = c["n_in"]
    ends_in = (has_in & (c["p_lo_in"] == 0)).to(f64) + (has_in & (c["p_hi_in"] == last)).to(f64)
    band_first = (n1 > 0) & (c["p_lo_d"] == 0)
    band_last = torch.where(has_in, n2 > 0, n1 > 0) & (c["p_hi_d"] == last)
    ends_out = 2.0 - ends_in - band_first.to(f64) - band_last.to(f64)
    n_out = s.points - n_in - n1 - n2
    w_in = dx_m * (n_in.to(f64) - 0.5 * ends_in)
    w_out = dx_m * (n_out.to(f64) - 0.5 * ends_out)
    return lengths + w_in * torch.sigmoid(s.temp / 2) + w_out * torch.sigmoid(-s.temp / 2)


Method = Literal["auto", "dense", "band", "subsets"]


def _soft_lengths(
    g: _Group, temperature: float, points: int, method: Method = "auto"
) -> torch.Tensor:
    """The paper's transect lengths (Eq. 3-6) ``(M,)``, equal to
    :func:`boustro.models.paper_lengths`' to rounding, by the cheapest of three ways:
    ``"dense"`` (the library's tensor), ``"band"`` (only the points near the boundary) and
    ``"subsets"`` (a matrix product, :func:`_lengths_subsets`). ``"auto"`` picks the cheapest
    by a cost model in nanoseconds per point, measured on a 2-core CPU."""
    s = _Soft(g, temperature, points)
    if method == "dense":
        return _lengths_dense(s)
    if method == "subsets":
        return _lengths_subsets(s)
    counts = _band_counts(s)
    if method == "band":
        return _lengths_band(s, counts)
    n_edges, n_sub = s.lhs.shape[-1], 1 << s.lhs.shape[-1]
    m, points = len(g.position), s.points
    reach = float((s.tal.abs().sum(dim=-1) * 2 * g.half).max())
    blocks = max(1.0, reach / (2 * _GAMMA_EXP))
    costs = {
        "band": (40.0 + 8.0 * n_edges) * float((counts["n1"] + counts["n2"]).sum()),
        "dense": (25.0 + 5.0 * n_edges) * m * points,
        "subsets": (10.0 + 0.15 * n_sub) * m * points
        + n_sub * (len(g.index) * points + 10.0 * m * blocks),
    }
    best = min(costs, key=costs.__getitem__)
    if best == "band":
        return _lengths_band(s, counts)
    return _lengths_dense(s) if best == "dense" else _lengths_subsets(s)


def _soft_fitness(
    g: _Group,
    temperature: float,
    points: int,
    variants: Sequence[tuple[Statistics, Trapezoid]],
    method: Method = "auto",
) -> dict[tuple[Statistics, Trapezoid], torch.Tensor]:
    """Eq. 1 of the paper's model per sample ``(B,)`` for each (statistics, trapezoid step)
    variant (see :class:`Protocol`), from one evaluation of the lengths."""
    library = _scatter(g, _soft_lengths(g, temperature, points, method))
    temp = torch.tensor(float(temperature), dtype=torch.float64)
    out = {}
    for statistics, trapezoid in variants:
        # The authors' step 1 / points instead of 2 half / (points - 1): with the window's half
        # of 0.5, every length times (points - 1) / points.
        lengths = library * ((points - 1) / points) if trapezoid == "authors" else library
        weights = 2 * torch.sigmoid(temp * lengths) - 1  # Eq. 7; 0 where padded (length 0)
        out[(statistics, trapezoid)] = smith_fitness(lengths, weights, statistics=statistics)
    return out


def paper_model_fitness(
    samples: Samples,
    protocol: Protocol,
    temperature: float,
    points: int,
    groups: list[_Group] | None = None,
    method: Method = "auto",
) -> NDArray[np.float64]:
    """The paper's model's fitness (Eq. 1-7) of every sample under ``protocol``, ``(N,)``.

    Equal, to rounding, to ``smith_fitness(*PaperModel(T, points, clip)(hp, angle, offset,
    spacing)[:2], statistics=...)`` called once per sample (for the ``"paper"`` window; the
    authors' window has its own transects), but batched and with the savings of
    :func:`_soft_lengths` (every point, the band near the boundary, or the subset expansion).

    >>> from boustro.experiments import PROTOCOLS, draw_samples
    >>> paper_model_fitness(draw_samples(2), PROTOCOLS[0], 1000.0, 100).round(4).tolist()
    [0.6845, 0.6951]
    """
    out = np.full(len(samples), np.nan)
    groups = protocol_groups(samples, protocol) if groups is None else groups
    with torch.no_grad():
        for g in groups:
            f = _soft_fitness(g, temperature, points, [protocol.variant], method)
            out[g.index] = f[protocol.variant].numpy()
    return out
