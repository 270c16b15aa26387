"""The smooth closed form: differentiable transect lengths in O(edges) per transect.

The paper integrates a product of sigmoids along every transect (Eq. 3-6). For a convex polygon
the integral has a closed form (DESIGN.md sec. 4): transect ``c`` meets edge ``j`` where
``across_j c + along_j t + b_j = 0``, which bounds ``t`` from below where ``along_j > 0`` and from
above where ``along_j < 0``, and the chord is ``[max of the lower bounds, min of the upper
bounds]``. This module replaces the hard ``max``/``min``/``max(0, .)`` by their smooth versions
with ONE smoothing length ``h``:

* ``lower = h * logsumexp(l_j / h)`` over the lower bounds (and the window bound ``-W``),
* ``upper = -h * logsumexp(-u_j / h)`` over the upper bounds (and ``+W``),
* ``D = upper - lower``, ``length = h * softplus(D / h)``, ``weight = sigmoid(D / h)``.

``h`` is a LENGTH in the half-planes' frame (a fraction of the diameter in the normalised frame),
so it means the same on every edge and every polygon. The weight is the derivative of the length
with respect to ``D`` (``d/dD h softplus(D/h) = sigmoid(D/h)``): the length is the integral of the
weight, exactly as ``max(0, D)`` is the integral of the step ``D > 0``. As ``h -> 0`` the model
tends to the exact chords, with ``|length - exact| <= 2 h log(E + 1)`` for every transect
(``E`` edges, padding included), and its gradients to the exact gradients away from breakpoints.

Temperature: the paper's sigmoids ``sigmoid(T v)`` (``v`` a signed distance in the normalised
frame, unit normals) switch over a width ``~1/T``; here the switch between two competing bounds is
``sigmoid((l_1 - l_2) / h)`` and the switch of the weight is ``sigmoid(D / h)``, so ``h = 1 / T``
makes the two models' logistic transitions the same width (see ``docs/closed_form.md``).

Gradient safety (no ``inf`` or ``NaN`` in values or gradients, for any input):

* bounds are computed as ``-a_j / (|along_j| h)`` and clamped to ``[-F/h, F/h]`` with ``F`` just
  outside the window: a bound at ``+-F`` is either inactive or empties the chord, so the clamp
  changes no exact length, and its zero gradient is the exact one there;
* an edge parallel to the transects (``|along_j|`` below machine epsilon, padding included)
  plays a lower bound with ``along = eps``: ``-F`` where it holds, ``+F`` where it does not (the
  transect misses the polygon), with no division by zero;
* the entries of the other role in each log-sum-exp are ``-F/h`` rather than ``-inf`` (they
  weigh ``exp(-64)`` against the window bound), so nothing infinite reaches autograd;
* the window bounds ``+-W`` (the paper's ``0.5`` with ``clip``, else the polygon's disc grown
  by ``32 h``) make a transect whose bounds all lie far outside the polygon come out empty.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import torch
import torch.nn.functional as F

from .errors import InvalidParameterError, as_number
from .geometry import HalfPlanes
from .models import (
    PAPER_WINDOW,
    ExactModel,
    TransectLengths,
    _prepare,
    _window_mask,
    check_spacing,
    transect_positions,
)

__all__ = [
    "DEFAULT_SMOOTHING",
    "SmoothModel",
    "length_error_bound",
    "smooth_lengths",
    "smoothing_from_temperature",
    "temperature_from_smoothing",
]

#: Default smoothing length (normalised frame: 1e-4 of the polygon's diameter, the paper's
#: ``T = 10000``). See ``docs/closed_form.md`` for the fidelity it buys.
DEFAULT_SMOOTHING = 1.0e-4

#: Margin in units of ``h``: the window sits this far outside the polygon's disc (and the grid
#: of candidate transects covers the disc grown by as much), and the far bound ``F`` twice as
#: far outside the window, so that a transect with no chord at all weighs ``sigmoid(-64)``.
_MARGIN = 32.0


def smoothing_from_temperature(temperature: float) -> float:
    """The smoothing length ``h = 1 / T`` matching the paper's temperature ``T``."""
    t = float(temperature)
    if not (math.isfinite(t) and t > 0):
        raise InvalidParameterError(f"temperature must be finite and > 0, got {temperature!r}")
    return 1.0 / t


def temperature_from_smoothing(smoothing: float) -> float:
    """The paper's temperature ``T = 1 / h`` matching a smoothing length ``h`` (> 0)."""
    h = float(smoothing)
    if not (math.isfinite(h) and h > 0):
        raise InvalidParameterError(f"smoothing must be finite and > 0, got {smoothing!r}")
    return 1.0 / h


def length_error_bound(smoothing: float, n_edges: int) -> float:
    """Bound on ``|smooth length - exact length|`` of any transect: ``2 h log(E + 1)``.

    The soft max of ``n`` numbers exceeds their max by at most ``h log n`` (here ``n = E + 1``:
    the ``E`` edges' entries and the window), and ``h softplus(x/h)`` exceeds ``max(0, x)`` by
    at most ``h log 2``. A chord that exists is shortened by at most ``2 h log(E + 1)`` and
    lengthened by at most ``h log 2``; an empty one gets at most ``h log 2``.
    """
    return float(smoothing) * 2.0 * math.log(n_edges + 1.0)


def _as_smoothing(
    smoothing: torch.Tensor | float, like: torch.Tensor
) -> tuple[torch.Tensor | float, float]:
    """``(h, max h)``, validated. A number stays a Python float (fewer tensor operations, no
    device synchronisation); a tensor takes the dtype and device of ``like``."""
    if isinstance(smoothing, torch.Tensor):
        h = smoothing.to(dtype=like.dtype, device=like.device)
        if not bool(torch.all(torch.isfinite(h) & (h >= 0))):
            raise InvalidParameterError(f"smoothing must be finite and >= 0, got {smoothing!r}")
        if h.ndim > 0 and not bool(torch.all(h > 0)):
            raise InvalidParameterError(
                "smoothing must be > 0 everywhere (a scalar 0 gives the exact model)"
            )
        return h, float(h.detach().max())
    value = as_number("smoothing", smoothing)
    if not (math.isfinite(value) and value >= 0):
        raise InvalidParameterError(f"smoothing must be finite and >= 0, got {smoothing!r}")
    return value, value


def _logsumexp(x: torch.Tensor) -> torch.Tensor:
    """``logsumexp`` over the last dimension whose backward reuses the forward's exponentials.

    ``torch.logsumexp`` recomputes ``exp`` in its backward; here autograd keeps ``exp``'s
    result. The shift ``m`` is detached: the value does not depend on it, so neither does the
    gradient.
    """
    m = x.detach().amax(dim=-1, keepdim=True)
    return (m + torch.log(torch.exp(x - m).sum(dim=-1, keepdim=True)))[..., 0]


def smooth_lengths(
    hp: HalfPlanes,
    theta: torch.Tensor | float,
    offset: torch.Tensor | float,
    spacing: float,
    *,
    smoothing: torch.Tensor | float = DEFAULT_SMOOTHING,
    clip: bool = False,
) -> TransectLengths:
    """Smooth closed-form transect lengths and "shown" weights (module docstring).

    Per transect: O(E) work, no sampling along the transect. Batched over leading dimensions,
    no Python loop over transects; dtype and device follow the half-planes.

    Args:
        hp: half-planes ``(*P, E, 2)`` of convex polygon(s), see
            :func:`boustro.geometry.halfplanes`.
        theta: transect direction(s), radians, ``(*B)``.
        offset: grid offset(s) in the half-planes' frame, ``(*B)``.
        spacing: transect spacing in the same frame, > 0.
        smoothing: the smoothing length ``h`` (same frame as the half-planes; ``1 / T`` maps to
            the paper's temperature ``T``), a float or a tensor broadcasting with ``(*B)``,
            ``>= 0``. Exactly ``0`` (a scalar) gives the exact model (lengths and 0/1 weights of
            :class:`boustro.models.ExactModel`).
        clip: the paper's window: transects at ``|c| < 0.5`` only, chords cut to
            ``t`` in ``[-0.5, 0.5]`` (softly, as one more bound on each side).

    Returns:
        :class:`~boustro.models.TransectLengths` ``(*, K)``. The candidate grid covers the
        polygon's disc grown by ``32 h`` (so ``K`` can exceed the exact model's by a few when
        ``h`` is not small against the spacing); candidates far from the polygon have length
        and weight ~0.

    Raises:
        InvalidParameterError: bad spacing or smoothing.
    """
    spacing = check_spacing(spacing)
    theta, offset, across, along, b = _prepare(hp, theta, offset)
    h, h_max = _as_smoothing(smoothing, across)
    if h_max == 0.0:  # a scalar 0: the exact model
        return ExactModel(clip=clip)(hp, theta, offset, spacing)
    margin = _MARGIN * h_max
    window = PAPER_WINDOW if clip else hp.radius + margin
    far = window + 2.0 * margin
    c = transect_positions(offset, spacing, window)  # (*, K)
    h_k: torch.Tensor | float = h  # broadcasts with (*, K)
    h_ke: torch.Tensor | float = h  # with (*, K, E)
    h_kre: torch.Tensor | float = h  # with (*, K, 2, E)
    if isinstance(h, torch.Tensor) and h.ndim > 0:
        h_k, h_ke, h_kre = h[..., None], h[..., None, None], h[..., None, None, None]

    # Per edge (small tensors, (*, E)): an edge with |along| below machine epsilon is parallel to
    # the transects (its bound -a / along would be rounding noise). It plays a lower bound with
    # along = +eps, and its offset moves out by 4 eps (|b| + far), just above the rounding of a,
    # so that a transect exactly on it is inside (as in exact_chords); its bound is then -far
    # (inactive) where it holds and +far (empty chord) where it does not, never a division by 0.
    eps = torch.finfo(along.dtype).eps
    parallel = along.abs() < eps
    is_lower = parallel | (along > 0)
    b = torch.where(parallel, b + 4.0 * eps * (b.abs() + far), b)
    # v = -a / |along| / h: the lower bound l / h for a lower edge, minus the upper bound -u / h
    # for an upper edge, so that both soft maxima are log-sum-exps of v.
    scale = -1.0 / (torch.where(parallel, eps, along.abs())[..., None, :] * h_ke)  # (*, 1, E)

    # a[..., k, j] = across_j c_k + b_j: edge j holds at (c_k, t) iff a + along_j t >= 0.
    a = torch.addcmul(b[..., None, :], across[..., None, :], c[..., :, None])  # (*, K, E)
    far_h = far / h_kre  # |bounds| >= far are clamped: beyond the window, or no chord at all
    v = torch.clamp((a * scale)[..., None, :], -far_h, far_h)  # type: ignore[arg-type]
    # Role mask (*, 1, 2, E): row 0 the lower edges, row 1 the upper ones; the other role's
    # entries are -far / h, i.e. exp(-64) below the window bound: negligible, never -inf, so
    # every log-sum-exp and its gradient stay finite.
    role = torch.stack([is_lower, ~is_lower], dim=-2)[..., None, :, :]
    lse = _logsumexp(torch.where(role, v, -far_h))  # (*, K, 2)
    w_h = torch.as_tensor(window / h_k, dtype=a.dtype, device=a.device)
    soft_lower = torch.logaddexp(lse[..., 0], -w_h)  # lower / h, window -W included
    soft_minus_upper = torch.logaddexp(lse[..., 1], -w_h)  # -upper / h, window +W included
    z = -soft_minus_upper - soft_lower  # D / h with D = upper - lower
    length = h_k * F.softplus(z)
    weight = torch.sigmoid(z)
    mask = _window_mask(c, clip)
    if mask is not None:
        zero = torch.zeros_like(length)
        length = torch.where(mask, length, zero)
        weight = torch.where(mask, weight, zero)
    return TransectLengths(length, weight, c)


@dataclass(frozen=True)
class SmoothModel:
    """The smooth closed form with its settings; see :func:`smooth_lengths`.

    Args:
        smoothing: smoothing length ``h`` in the half-planes' frame (normalised: a fraction of
            the diameter), ``>= 0``; ``0`` is the exact model. ``h = 1 / T`` for the paper's
            temperature ``T`` (:meth:`from_temperature`).
        clip: the paper's window (reproduction only).
    """

    smoothing: float = DEFAULT_SMOOTHING
    clip: bool = False
    name: str = "soft"

    def __post_init__(self) -> None:
        h = self.smoothing
        ok = isinstance(h, (int, float)) and not isinstance(h, bool)
        if not (ok and math.isfinite(h) and h >= 0):
            raise InvalidParameterError(f"smoothing must be a finite number >= 0, got {h!r}")

    @classmethod
    def from_temperature(cls, temperature: float, *, clip: bool = False) -> SmoothModel:
        """The model whose smoothing matches the paper's temperature: ``h = 1 / T``."""
        return cls(smoothing=smoothing_from_temperature(temperature), clip=clip)

    def with_temperature(self, temperature: float) -> SmoothModel:
        """This model (same ``clip`` and ``name``) at the smoothing ``h = 1 / T``."""
        return replace(self, smoothing=smoothing_from_temperature(temperature))

    @property
    def temperature(self) -> float:
        """The paper's temperature with the same transition width, ``1 / h`` (inf at h = 0)."""
        return math.inf if self.smoothing == 0 else 1.0 / self.smoothing

    def __call__(
        self, hp: HalfPlanes, theta: torch.Tensor, offset: torch.Tensor, spacing: float
    ) -> TransectLengths:
        return smooth_lengths(hp, theta, offset, spacing, smoothing=self.smoothing, clip=self.clip)
