"""The paper's differentiable transect model: the sigmoid integral of Eq. 3-7 (PaperModel)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from .._torch import functional as F
from .._torch import torch
from .._validate import as_number
from ..errors import InvalidParameterError
from ..geometry import HalfPlanes
from .base import PAPER_WINDOW, TransectLengths, _prepare, _window_mask, transect_positions
from .paper_band import (  # noqa: F401 (the private names are re-exported for old imports)
    _Band,
    _band,
    _band_integrand,
    _band_tau,
    _Group,
    _group_points,
    band_tau,
)
from .paper_integral import (  # noqa: F401 (the private names are re-exported for old imports)
    _TARGET,
    _chunks,
    _full_grads,
    _full_lengths,
    _Grids,
    _items,
    _plan,
    _sigmoid_integrand,
    _SigmoidIntegral,
    _trapezoid_weights,
)
from .paper_subsets import subsets_blocks, subsets_lengths

__all__ = [
    "MAX_POINTS_PER_TRANSECT",
    "PAPER_WINDOW",
    "Method",
    "PaperModel",
    "Trapezoid",
    "paper_lengths",
    "paper_line_lengths",
    "paper_weights",
    "trapezoid_scale",
]

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


def _autograd_lengths(
    lhs: torch.Tensor, slope: torch.Tensor, t: torch.Tensor, temp_kp: torch.Tensor, dx: float
) -> torch.Tensor:
    """Eq. 4-6 by plain autograd (gradients reach the temperature too), Eq. 4 in log space."""
    tv = lhs[..., :, None, :] + slope[..., None, None, :] * t[:, None]
    log_p = F.logsigmoid(tv).sum(dim=-1)  # (*, K, P)
    p_sigma = torch.sigmoid(temp_kp * (torch.exp(log_p) - 0.5))  # Eq. 5
    return torch.trapezoid(p_sigma, dx=dx, dim=-1)


#: How :func:`paper_line_lengths` evaluates the integral: ``"full"`` every point, ``"band"``
#: only the unsaturated band (:class:`_SigmoidIntegral`), ``"subsets"`` a matrix product over the
#: subsets of the edges (forward only, :func:`~boustro.models.paper_subsets.subsets_lengths`),
#: ``"auto"`` the cheapest by a cost model.
Method = Literal["auto", "full", "band", "subsets"]

#: The trapezoid step of Eq. 6: ``"span"``, ``2 half / (points - 1)`` (the points span the
#: window, the library's), or ``"points"``, ``2 half / points`` (the authors' ``1 / points``
#: for their window of half-width 0.5): every length times ``(points - 1) / points``.
Trapezoid = Literal["span", "points"]


def trapezoid_scale(points: int, trapezoid: Trapezoid = "span") -> float:
    """The factor of the lengths of the trapezoid step ``trapezoid`` over the ``"span"`` step.

    >>> trapezoid_scale(100, "points"), trapezoid_scale(100)
    (0.99, 1.0)
    """
    if trapezoid not in ("span", "points"):
        raise InvalidParameterError(f"trapezoid must be 'span' or 'points', got {trapezoid!r}")
    return (points - 1) / points if trapezoid == "points" else 1.0


def paper_weights(lengths: torch.Tensor, temperature: torch.Tensor | float) -> torch.Tensor:
    """Eq. 7, the "shown" weight of a transect: ``S = 2 sigmoid(T L) - 1`` (0 for length 0).

    >>> round(float(paper_weights(torch.tensor(0.01), 100.0)), 4)
    0.4621
    """
    return 2 * torch.sigmoid(temperature * lengths) - 1


def _costs(
    n_edges: int, lines: int, polygons: int, points: int, band_points: int, blocks: float
) -> dict[str, float]:
    """Estimated nanoseconds of each method (measured on a 2-core CPU)."""
    n_sub = 1 << n_edges
    return {
        "band": (40.0 + 8.0 * n_edges) * band_points,
        "full": (25.0 + 5.0 * n_edges) * lines * points,
        "subsets": (10.0 + 0.15 * n_sub) * lines * points
        + n_sub * (polygons * points + 10.0 * lines * blocks),
    }


def _lines_lengths(
    lhs: torch.Tensor,
    slope: torch.Tensor,
    sample: torch.Tensor,
    t: torch.Tensor,
    dx: torch.Tensor,
    grid: torch.Tensor,
    temp: torch.Tensor,
    method: str,
) -> torch.Tensor:
    """Eq. 4-6 of the lines ``lhs: (M, E)`` of polygons ``sample: (M,)`` (with ``slope: (S, E)``,
    ``temp: (S,)``, points ``t[grid]: (S, P)`` of steps ``dx[grid]``) by ``method``."""
    differentiable = torch.is_grad_enabled() and (lhs.requires_grad or slope.requires_grad)
    lines = (lhs[:, None, :], slope[sample], t, temp[sample], dx)
    plan = None
    if method in ("band", "auto") and lhs.numel():
        plan = _plan(*lines[:2], lines[3], _Grids(t, dx, grid[sample]))
    if method == "auto":
        span = t[grid, -1] - t[grid, 0]
        band_points = plan.points if plan is not None else 0
        costs = _costs(
            lhs.shape[-1],
            len(lhs),
            len(slope),
            t.shape[-1],
            band_points,
            subsets_blocks(slope, span),
        )
        if differentiable:
            del costs["subsets"]
        method = min(costs, key=costs.__getitem__)
    if method == "subsets":
        if differentiable:
            raise InvalidParameterError("method='subsets' has no gradient")
        return _subsets_lengths(lhs, slope, sample, t, dx, grid, temp)
    band = plan if method == "band" and plan is not None else False
    return _SigmoidIntegral.apply(*lines, band, grid[sample])[:, 0]


def _subsets_lengths(
    lhs: torch.Tensor,
    slope: torch.Tensor,
    sample: torch.Tensor,
    t: torch.Tensor,
    dx: torch.Tensor,
    grid: torch.Tensor,
    temp: torch.Tensor,
) -> torch.Tensor:
    """:func:`subsets_lengths` with the lines sorted by polygon, its guard by every point."""
    order = None
    if len(sample) > 1 and bool((sample[1:] < sample[:-1]).any()):
        order = torch.argsort(sample, stable=True)
        lhs, sample = lhs[order], sample[order]
    counts = torch.bincount(sample, minlength=len(slope))
    start = torch.cat([counts.new_zeros(1), torch.cumsum(counts, 0)])
    out = subsets_lengths(lhs, slope, start, t, _trapezoid_weights(t, dx), grid, temp)
    bad = torch.nonzero(~torch.isfinite(out)).squeeze(-1)
    if len(bad):  # cannot happen (see its bounds); every point as a guard
        g = _Grids(t, dx, grid[sample[bad]])
        out[bad] = _full_lengths(
            lhs[bad, None, :], slope[sample[bad]], temp[sample[bad]], g, slice(None)
        )[:, 0]
    if order is not None:
        out = torch.empty_like(out).index_copy_(0, order, out)
    return out


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
    """Eq. 4-6 of a grid ``lhs: (*, K, E)`` by :class:`_SigmoidIntegral` (chunked, analytic
    backward, band where it pays)."""
    batch = lhs.shape[:-2]
    work = lhs.numel() * len(t)  # sigmoids of the every-point evaluation
    # The band's planning costs ~1 ms a call and pays off only where the band is a small
    # share of the points (about 8 tau / (T * 2 half) of them): measured crossover.
    use_band = (
        band and work >= _BAND_MIN_WORK and float(temp.min()) * 2 * half >= 8 * band_tau(lhs.dtype)
    )
    return _SigmoidIntegral.apply(
        lhs.reshape(-1, *lhs.shape[-2:]),
        torch.broadcast_to(slope, (*batch, slope.shape[-1])).reshape(-1, slope.shape[-1]),
        t,
        torch.broadcast_to(temp, batch).reshape(-1),
        dx,
        use_band,
    ).reshape(*batch, lhs.shape[-2])


def _grids(half: torch.Tensor, points: int) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """The points ``(grids, P)`` and steps ``(grids,)`` of each half-width, the grid of each
    polygon (one grid if they are all equal)."""
    if len(half) and bool(torch.all(half == half[0])):
        half, grid = half[:1], torch.zeros(len(half), dtype=torch.int64)
    else:
        grid = torch.arange(len(half))
    t = torch.stack([torch.linspace(-float(h), float(h), points, dtype=half.dtype) for h in half])
    return t, 2 * half / (points - 1), grid


def paper_line_lengths(
    across: torch.Tensor,
    along: torch.Tensor,
    b: torch.Tensor,
    positions: torch.Tensor,
    sample: torch.Tensor | None = None,
    *,
    half: torch.Tensor | float,
    temperature: torch.Tensor | float = 1000.0,
    points_per_transect: int = 1000,
    trapezoid: Trapezoid = "span",
    method: Method = "auto",
) -> torch.Tensor:
    """The paper's lengths (Eq. 3-6) of lines at GIVEN positions, ragged: ``(M,)``.

    The lines-level counterpart of :func:`paper_lengths`, as :func:`line_chords` is of
    :func:`exact_chords`: line ``m`` is ``n . p = positions[m]`` of polygon ``sample[m]``, whose
    edges seen from the lines are ``across, along, b: (S, E)`` (edge ``j`` holds where
    ``across_j c + along_j t + b_j >= 0``), integrated over ``t`` in ``[-half, half]`` at
    ``points_per_transect`` points.

    Args:
        across, along, b: ``(S, E)`` per polygon (:func:`~boustro.models.base._components`).
        positions: ``(M,)`` the lines' positions ``c``.
        sample: ``(M,)`` long, the polygon of each line (default: line ``m`` of polygon ``m``).
        half: the integration half-width, a float or one per polygon ``(S,)``.
        temperature: ``T`` (> 0), a float or one per polygon ``(S,)``.
        points_per_transect: trapezoid points per line (>= 2).
        trapezoid: the step of Eq. 6 (:data:`Trapezoid`).
        method: see :data:`Method`; all equal to rounding.

    Example:
        >>> one = torch.tensor([[0.0, 0.0, 1.0, -1.0]], dtype=torch.float64)  # |t| <= 0.4
        >>> across, along = one[:, [2, 3, 0, 1]], one  # and |c| <= 0.3
        >>> b = torch.tensor([[0.3, 0.3, 0.4, 0.4]], dtype=torch.float64)
        >>> at = torch.tensor([0.0, 0.29, 0.5], dtype=torch.float64)
        >>> sample = torch.zeros(3, dtype=torch.long)
        >>> L = paper_line_lengths(across, along, b, at, sample, half=0.5, points_per_transect=101)
        >>> [round(x, 3) for x in L.tolist()]
        [0.8, 0.8, 0.0]
    """
    points = _check_points(points_per_transect)
    sample = torch.arange(len(positions)) if sample is None else sample
    temp = _as_temperature(temperature, across)
    temp = torch.broadcast_to(temp, across.shape[:1])
    half_t = torch.broadcast_to(torch.as_tensor(half, dtype=across.dtype), across.shape[:1])
    t, dx, grid = _grids(half_t, points)
    ta, tb = temp[:, None] * across, temp[:, None] * b
    # T v = (T across) c + (T b) + (T along) t: the factors of paper_lengths, same arithmetic.
    lhs = ta[sample] * positions[:, None] + tb[sample]
    length = _lines_lengths(lhs, temp[:, None] * along, sample, t, dx, grid, temp, method)
    scale = trapezoid_scale(points, trapezoid)
    return length * scale if scale != 1.0 else length


def _check_points(points_per_transect: int) -> int:
    points = as_number("points_per_transect", points_per_transect)
    if not (points == int(points) and 2 <= points <= MAX_POINTS_PER_TRANSECT):
        raise InvalidParameterError(
            f"points_per_transect must be an integer in [2, {MAX_POINTS_PER_TRANSECT}], got "
            f"{points_per_transect!r}"
        )
    return int(points)


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
    trapezoid: Trapezoid = "span",
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
        trapezoid: the step of Eq. 6 (:data:`Trapezoid`); Eq. 7 from the scaled lengths.

    Returns:
        :class:`TransectLengths` ``(*, K)``.
    """
    points = _check_points(points_per_transect)
    theta, offset, across, along, b = _prepare(hp, theta, offset)
    temp = _as_temperature(temperature, across)
    half = PAPER_WINDOW if clip else hp.radius
    c = transect_positions(offset, spacing, half)
    t = torch.linspace(-half, half, int(points_per_transect), dtype=c.dtype, device=c.device)
    temp_e = temp[..., None] if temp.ndim else temp  # broadcasts with (*, E)
    temp_kp = temp_e[..., None] if temp.ndim else temp  # broadcasts with (*, K, P)
    dx = 2 * half / (points - 1)
    # T v[..., k, p, j] = T (across_j c_k + b_j) + T along_j t_p: two small factors.
    lhs = (temp_e * across)[..., None, :] * c[..., :, None] + (temp_e * b)[..., None, :]
    slope = temp_e * along  # (*, E)
    if isinstance(temperature, torch.Tensor) and temperature.requires_grad:
        length = _autograd_lengths(lhs, slope, t, temp_kp, dx)
    else:
        length = _fused_lengths(lhs, slope, t, temp, dx, band=band, half=half)
    scale = trapezoid_scale(points, trapezoid)
    if scale != 1.0:
        length = length * scale
    mask = _window_mask(c, clip)
    if mask is not None:
        length = torch.where(mask, length, torch.zeros_like(length))
    temp_k = temp[..., None] if temp.ndim else temp
    weight = paper_weights(length, temp_k)  # Eq. 7
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
    trapezoid: Trapezoid = "span"

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
            trapezoid=self.trapezoid,
        )
