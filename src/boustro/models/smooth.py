"""The smooth closed form: differentiable transect lengths in O(edges) per transect.

The exact chord ``[max lower bounds, min upper bounds]`` with ``max``/``min``/``max(0, .)``
replaced by smooth versions at ONE smoothing length ``h`` (a length in the half-planes' frame):
``length = h softplus(D / h)``, ``weight = sigmoid(D / h)``, ``|length - exact| <= 2 h log(E + 1)``;
``h = 1 / T`` matches the paper's temperature. Two evaluations of the same formula: the compiled
CPU kernels (:mod:`boustro.models._kernels`; :data:`COMPILED` ``= False`` or
``BOUSTRO_COMPILED=0`` turns them off) and the tensor code ``_SoftChords`` elsewhere.
See ``docs/closed_form.md``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from .._torch import Function, autograd_function, torch
from .._torch import functional as F
from .._validate import as_number, check_spacing
from ..errors import InvalidParameterError
from ..geometry import HalfPlanes
from . import _kernels
from .base import PAPER_WINDOW, TransectLengths, _components, _grid, _prepare, _window_mask
from .exact import ExactModel

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

#: Margin in units of ``h``: the grid of candidate transects covers the polygon's disc grown by
#: this much (so a transect just outside the polygon, whose soft length is not yet 0, is on the
#: grid), and the fallback window ``-W`` sits there.
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


#: Below this many (slot, pair, transect) elements, ``_SoftChords`` evaluates every transect's
#: softplus and sigmoid and reduces the backward pass in whole-tensor operations: for small calls
#: (an optimiser's few starts) the count of operations, not of elements, sets the cost.
_SPARSE_MIN = 1 << 15


@autograd_function
class _SoftChords(Function):
    """Soft chords ``(softplus(z), sigmoid(z))``, ``(N, K)``, from the edges' components.

    Inputs ``across, along, b`` ``(N, E)`` (edge ``j`` holds at ``(c, t)`` iff
    ``across_j c + along_j t + b_j >= 0``), positions ``c`` ``(N, K)``, the smoothing ``h`` (a
    float, or an ``(N, 1)`` tensor), and the slot layout: ``slot`` ``(N, E)`` puts each edge in
    a slot, lower edges in ``[0, n_low)``, upper ones in ``[n_low, S)``; ``windows`` lists the
    slots that hold the window bound ``-window / h``, each with the pairs it applies to
    (``None``: all); the rest are ``-inf``.

    Per slot ``v[s, n, k] = alpha[s, n] + beta[s, n] c[n, k]`` with ``alpha = -b / (|along| h)``,
    ``beta = -across / (|along| h)``: the lower bound ``l / h`` of a lower edge, minus the upper
    bound ``-u / h`` of an upper one. ``z = -logsumexp(lower slots) - logsumexp(upper slots)``
    is ``D / h``. The backward pass is analytic: ``dz / dv[s] = -softmax(role of s)[s]``,
    ``d softplus / dz = sigmoid``, ``d sigmoid / dz = sigmoid (1 - sigmoid)``, and
    ``d alpha / d b = d beta / d across = -1 / (|along| h)``,
    ``d alpha / d along = -alpha / along``, ``d beta / d along = -beta / along``,
    ``d (alpha, beta) / d h = -(alpha, beta) / h``; zero where a clamp holds (``|along|`` below
    ``eps``, ``|alpha|`` or ``|beta|`` at ``sqrt(float max)``).
    """

    @staticmethod
    def forward(
        ctx: Any,
        across: torch.Tensor,
        along: torch.Tensor,
        b: torch.Tensor,
        c: torch.Tensor,
        h: torch.Tensor | float,
        slot: torch.Tensor,
        n_low: int,
        n_slots: int,
        windows: list[tuple[int, torch.Tensor | None]],
        window: float,
    ) -> tuple[torch.Tensor, torch.Tensor]:
        dtype = c.dtype
        eps, big = torch.finfo(dtype).eps, torch.finfo(dtype).max ** 0.5
        floor = math.log(torch.finfo(dtype).tiny) + 1.0
        n_pairs = c.shape[0]
        scale = along.abs().clamp_(min=eps).mul_(h).reciprocal_().neg_()  # -1 / (|along| h)
        alpha_e = (b * scale).clamp_(-big, big)
        beta_e = (across * scale).clamp_(-big, big)
        alpha = torch.full((n_slots, n_pairs), -math.inf, dtype=dtype, device=c.device)
        alpha.scatter_(0, slot.T, alpha_e.T)
        beta = torch.zeros_like(alpha).scatter_(0, slot.T, beta_e.T)
        w_h = torch.as_tensor(-window / h, dtype=dtype, device=c.device).reshape(-1)
        w_h = torch.broadcast_to(w_h, (n_pairs,))  # the window bound -W / h (beta = 0)
        for index, where in windows:  # the pairs it applies to (None: all)
            alpha[index] = w_h if where is None else torch.where(where, w_h, -math.inf)

        v = torch.addcmul(alpha[:, :, None], beta[:, :, None], c)  # (S, N, K)
        lower, upper = v[:n_low], v[n_low:]
        z_hard = lower.amax(0)
        m_upper = upper.amax(0)
        lower.sub_(z_hard)
        upper.sub_(m_upper)
        v.clamp_(min=floor).exp_()  # in place: v now holds exp(v - max of its role)
        sum_lower, sum_upper = lower.sum(0), upper.sum(0)
        z_hard.add_(m_upper).neg_()  # D / h of the hard extrema
        spread = sum_lower * sum_upper  # >= 1; exactly 1 where no bound competes
        if v.numel() < _SPARSE_MIN:  # small calls: fewer operations beat fewer elements
            z = z_hard - torch.log(spread)
            soft, weight = F.softplus(z, threshold=_kernels.TAU), torch.sigmoid(z)
        else:
            soft = torch.relu(z_hard)
            weight = (z_hard > 0).to(dtype)
            near = (spread != 1.0) | (z_hard.abs() < -floor)
            idx = near.view(-1).nonzero().squeeze(1)
            if idx.numel():
                z = z_hard.view(-1)[idx] - torch.log(spread.view(-1)[idx])
                soft.view(-1)[idx] = F.softplus(z, threshold=_kernels.TAU)
                weight.view(-1)[idx] = torch.sigmoid(z)
        if any(ctx.needs_input_grad[:5]):
            lower.div_(sum_lower)  # softmax weights of each role
            upper.div_(sum_upper)
            ctx.save_for_backward(v, c, alpha, beta, weight, along, alpha_e, beta_e, scale, slot)
            ctx.h = h
        return soft, weight

    @staticmethod
    def backward(
        ctx: Any, grad_soft: torch.Tensor, grad_weight: torch.Tensor
    ) -> tuple[torch.Tensor | None, ...]:
        softmax, c, alpha, beta, weight, along, alpha_e, beta_e, scale, slot = ctx.saved_tensors
        grad_z = (grad_soft + grad_weight * (1.0 - weight)).mul_(weight).neg_()
        if softmax.numel() < _SPARSE_MIN:  # dL / dv = -softmax * grad_z, in three operations
            grad_v = softmax * grad_z
            grad_alpha, grad_beta = grad_v.sum(2), (grad_v * c).sum(2)
            grad_c = (grad_v * beta[:, :, None]).sum(0)
        else:
            # The same reduced slot by slot: each slot is a contiguous (N, K) slab, and no
            # (S, N, K) temporary is allocated (the allocation costs more than the loop).
            grad_zc = grad_z * c
            grad_alpha = torch.empty_like(beta)
            grad_beta = torch.empty_like(beta)
            grad_c = torch.zeros_like(c)  # sum_s softmax[s] * beta[s]
            for s, w in enumerate(softmax):
                torch.sum(w * grad_z, dim=1, out=grad_alpha[s])
                torch.sum(w * grad_zc, dim=1, out=grad_beta[s])
                grad_c.addcmul_(w, beta[s, :, None])
            grad_c.mul_(grad_z)
        big = torch.finfo(c.dtype).max ** 0.5
        eps = torch.finfo(c.dtype).eps
        ga = torch.where(alpha_e.abs() < big, grad_alpha.gather(0, slot.T).T, 0.0)
        gb = torch.where(beta_e.abs() < big, grad_beta.gather(0, slot.T).T, 0.0)
        grad_along = torch.where(along.abs() >= eps, (ga * alpha_e + gb * beta_e) / along, 0.0)
        grad_h = None
        if ctx.needs_input_grad[4]:  # alpha and beta (windows included) are proportional to 1/h
            terms = torch.where(alpha.abs() < big, grad_alpha * alpha, 0.0)  # not -inf, clamped
            terms += torch.where(beta.abs() < big, grad_beta * beta, 0.0)
            grad_h = -(terms.sum(0) / ctx.h[:, 0])[:, None]
        nothing = (None,) * 5  # slot, n_low, n_slots, windows, window
        return gb * scale, grad_along.neg_(), ga * scale, grad_c, grad_h, *nothing


#: Use the compiled CPU kernels (:mod:`boustro.models._kernels`) where they apply: CPU tensors of
#: float32 or float64, numba installed, calls of at least :data:`COMPILED_MIN` elements.
#: ``False`` forces the tensor code everywhere (tests hold the two to the same values and
#: gradients).
COMPILED = True

#: Smallest call, in (angle, offset) pairs x candidate transects, that takes the compiled
#: kernels. Below it a call costs well under a millisecond either way, and a process that makes
#: only such calls (``boustro plan``, scoring a layout) does not import numba (half a second,
#: a few seconds the first time it compiles the kernels).
COMPILED_MIN = 1 << 14


def _compiled_kernels(x: torch.Tensor, elements: int) -> _kernels.Kernels | None:
    """The compiled kernels if they apply to a call on tensors like ``x`` with ``elements``
    (pair, transect) elements, else ``None``."""
    if not COMPILED or elements < COMPILED_MIN or x.device.type != "cpu":
        return None
    if x.dtype not in (torch.float32, torch.float64):
        return None
    return _kernels.kernels()


def _numpy(x: torch.Tensor) -> Any:
    return x.detach().contiguous().numpy()


@autograd_function
class _CompiledChords(Function):
    """Soft lengths and weights ``(N, K)`` by the compiled kernels: the same model as
    :class:`_SoftChords` (roles, clamps, windows), evaluated and differentiated per pair in one
    loop. Inputs: ``cos, sin`` of the angles, wrapped offsets ``d`` and smoothing ``h``, all
    ``(N,)``; each pair's polygon ``poly`` ``(N,)`` into ``normals`` ``(P, E, 2)`` and
    ``offsets`` ``(P, E)`` (constants); the grid ``q`` ``(K,)``: transect ``k`` at
    ``d + q_k``; ``windows = (clip, window, far)`` (:func:`smooth_lengths`).

    Every input is saved (an in-place change before the backward pass is an error, as for any
    autograd function). Asked for a differentiable gradient (``create_graph``), the backward
    pass differentiates the tensor code on the same inputs instead.
    """

    @staticmethod
    def forward(
        ctx: Any,
        cos: torch.Tensor,
        sin: torch.Tensor,
        d: torch.Tensor,
        h: torch.Tensor,
        poly: torch.Tensor,
        normals: torch.Tensor,
        offsets: torch.Tensor,
        q: torch.Tensor,
        windows: tuple[bool, float, float],
        kernels: _kernels.Kernels,
    ) -> tuple[torch.Tensor, torch.Tensor]:
        info = torch.finfo(d.dtype)
        settings = (*windows, info.eps, info.max**0.5)
        length = torch.empty((d.shape[0], q.shape[0]), dtype=d.dtype)
        weight = torch.empty_like(length)
        # the largest bounds' edges (E: a window), -1 on the soft path
        index = np.int8 if normals.shape[1] < 127 else np.int32
        active = np.empty((2, *length.shape), dtype=index)
        inputs = (cos, sin, poly, normals, offsets, d, h, q)
        geometry = tuple(_numpy(x) for x in inputs)
        kernels.chords_forward(geometry, settings, length.numpy(), weight.numpy(), active)
        ctx.save_for_backward(*inputs, length, weight)
        ctx.settings, ctx.active, ctx.kernels = settings, active, kernels
        return length, weight

    @staticmethod
    def backward(
        ctx: Any, grad_length: torch.Tensor, grad_weight: torch.Tensor
    ) -> tuple[torch.Tensor | None, ...]:
        *inputs, length, weight = ctx.saved_tensors
        cos, sin, poly, normals, offsets, d, h, q = inputs
        need = ctx.needs_input_grad[:4]  # cos, sin, d, h
        if torch.is_grad_enabled():  # create_graph: a gradient that is itself differentiable
            along_with = [x for x, n in zip((cos, sin, d, h), need, strict=True) if n]
            across, along, b = _components(cos, sin, normals[poly], offsets[poly])
            clip, window, far = ctx.settings[:3]
            outputs = _tensor_lengths(across, along, b, d[:, None] + q, h, clip, window, far)
            grads = torch.autograd.grad(
                outputs, along_with, (grad_length, grad_weight), create_graph=True
            )
            found = iter(grads)
            return (*(next(found) if n else None for n in need), *(None,) * 6)
        out = [torch.empty(length.shape[0], dtype=length.dtype) for _ in range(4)]
        ctx.kernels.chords_backward(
            tuple(_numpy(x) for x in inputs),
            ctx.settings,
            (length.numpy(), weight.numpy(), ctx.active),
            _numpy(grad_length),
            _numpy(grad_weight),
            bool(need[3]),
            tuple(g.numpy() for g in out),  # cos, sin, d, h
        )
        return (*(g if n else None for g, n in zip(out, need, strict=True)), *(None,) * 6)


def _check_smoothing_floor(h: torch.Tensor | float, radius: float, dtype: torch.dtype) -> None:
    """Refuse a smoothing so small that it is numerically the exact model: the floor keeps every
    bound / h far below the clamp at sqrt(float max)."""
    h_min = float(h.detach().min()) if isinstance(h, torch.Tensor) else h
    floor = float(radius) * torch.finfo(dtype).max ** -0.25
    if h_min < floor:
        raise InvalidParameterError(
            f"smoothing {h_min:g} is below {floor:.3g} ({dtype}, this polygon): "
            "numerically the exact model: use smoothing=0 (or the exact model) for it"
        )


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

    Example:
        >>> from boustro.geometry import Polygon, halfplanes
        >>> hp = halfplanes(Polygon([(0, 0), (4, 0), (4, 3), (0, 3)]))  # normalised: 0.8 x 0.6
        >>> out = smooth_lengths(hp, 0.0, 0.05, 0.2, smoothing=1e-3)
        >>> [round(x, 4) for x in out.lengths[out.weights > 0.5].tolist()]
        [0.8, 0.8, 0.8]
    """
    spacing = check_spacing(spacing)
    dtype, device = hp.normals.dtype, hp.normals.device
    theta_t = torch.as_tensor(theta, dtype=dtype, device=device)
    offset_t = torch.as_tensor(offset, dtype=dtype, device=device)
    h, h_max = _as_smoothing(smoothing, theta_t)
    if h_max == 0.0:  # a scalar 0: the exact model
        return ExactModel(clip=clip)(hp, theta_t, offset_t, spacing)
    _check_smoothing_floor(h, hp.radius, dtype)
    margin = _MARGIN * h_max
    window = PAPER_WINDOW if clip else hp.radius + margin
    # Roles: an edge with |along| below machine epsilon is parallel to the transects (its
    # bound -b / along would be rounding noise) and plays a lower bound with along = eps; its
    # offset moves out by 4 eps (|b| + far), just above the rounding of b, so that a transect
    # exactly on it is inside (as in exact_chords). With clip, the window bounds +-0.5 join
    # both roles of every pair; without it, a window -W joins the role of a pair that has no
    # edge of it (a sliver whose edges are all parallel to the transects up to eps).
    far = window + 2.0 * margin
    theta_t, offset_t = torch.broadcast_tensors(theta_t, offset_t)
    d, q = _grid(offset_t, spacing, window)
    c = d[..., None] + q  # (*B, K): transect_positions
    pairs = math.prod(torch.broadcast_shapes(theta_t.shape, hp.offsets.shape[:-1]))
    kernels = _compiled_kernels(theta_t, pairs * c.shape[-1])
    if kernels is not None and not (hp.normals.requires_grad or hp.offsets.requires_grad):
        length, weight = _compiled_lengths(kernels, hp, theta_t, d, q, h, clip, window, far)
    else:
        _, _, across, along, b = _prepare(hp, theta_t, offset_t)
        length, weight = _tensor_lengths(across, along, b, c, h, clip, window, far)
    mask = _window_mask(c, clip)
    if mask is not None:
        zero = torch.zeros_like(length)
        length = torch.where(mask, length, zero)
        weight = torch.where(mask, weight, zero)
    return TransectLengths(length, weight, c)


def _compiled_lengths(
    kernels: _kernels.Kernels,
    hp: HalfPlanes,
    theta: torch.Tensor,
    d: torch.Tensor,
    q: torch.Tensor,
    h: torch.Tensor | float,
    clip: bool,
    window: float,
    far: float,
) -> tuple[torch.Tensor, torch.Tensor]:
    """:func:`smooth_lengths` by the compiled kernels (CPU): ``(lengths, weights)``, for the
    grid of ``models._grid`` (wrapped offsets ``d``, transect ``k`` at ``d + q_k``)."""
    dtype, n_k = theta.dtype, q.shape[0]
    polygons, n_edges = hp.offsets.shape[:-1], hp.offsets.shape[-1]
    batch = torch.broadcast_shapes(theta.shape, polygons)
    poly = torch.arange(math.prod(polygons)).reshape(polygons).expand(batch).reshape(-1)
    normals = hp.normals.detach().reshape(-1, n_edges, 2).contiguous()
    offsets = hp.offsets.detach().reshape(-1, n_edges).contiguous()
    theta = theta.expand(batch).reshape(-1)
    cos, sin = torch.cos(theta), torch.sin(theta)
    d = d.expand(batch).reshape(-1)
    h_n = torch.broadcast_to(torch.as_tensor(h, dtype=dtype), batch).reshape(-1)
    windows = (clip, window, far)
    length, weight = _CompiledChords.apply(
        cos, sin, d, h_n, poly, normals, offsets, q, windows, kernels
    )
    return length.reshape((*batch, n_k)), weight.reshape((*batch, n_k))


def _tensor_lengths(
    across: torch.Tensor,
    along: torch.Tensor,
    b: torch.Tensor,
    c: torch.Tensor,
    h: torch.Tensor | float,
    clip: bool,
    window: float,
    far: float,
) -> tuple[torch.Tensor, torch.Tensor]:
    """:func:`smooth_lengths` by tensor operations (any device): ``(lengths, weights)``."""
    dtype, device = across.dtype, across.device
    batch, n_edges, n_k = across.shape[:-1], across.shape[-1], c.shape[-1]
    eps = torch.finfo(dtype).eps
    with torch.no_grad():
        parallel = along.abs() < eps
        lower = (parallel | (along > 0)).reshape(-1, n_edges)
        n_pairs = lower.shape[0]
        n_lower_row = lower.sum(-1, keepdim=True)
        # Slots per role: the batch's most edges of that role, then the window bound. Unused
        # slots are -inf: nothing in a soft max.
        most_lower, least_lower, any_parallel = (
            torch.stack([n_lower_row.max(), n_lower_row.min(), parallel.sum()]).tolist()
            if n_pairs
            else (0, 0, 0)
        )
        lower_window = clip or least_lower == 0
        upper_window = clip or most_lower == n_edges
        n_low = most_lower + lower_window
        n_slots = n_low + n_edges - least_lower + upper_window
        rank = torch.cumsum(lower, -1) - 1  # the lower edges fill slots 0.., the upper n_low..
        slot = torch.where(lower, rank, n_low - rank - 1 + torch.arange(n_edges, device=device))
    if any_parallel:
        b = torch.where(parallel, b + 4.0 * eps * (b.abs() + far), b)
    across, along, b = (x.reshape(-1, n_edges) for x in (across, along, b))
    h_n = torch.broadcast_to(h, batch).reshape(-1, 1) if isinstance(h, torch.Tensor) else h
    windows: list[tuple[int, torch.Tensor | None]] = []
    if lower_window:  # with clip for every pair, else for the pairs with no lower edge
        windows.append((n_low - 1, None if clip else n_lower_row[:, 0] == 0))
    if upper_window:
        windows.append((n_slots - 1, None if clip else n_lower_row[:, 0] == n_edges))
    c_n = torch.broadcast_to(c, (*batch, n_k)).reshape(-1, n_k)
    soft, weight = _SoftChords.apply(
        across, along, b, c_n, h_n, slot, n_low, n_slots, windows, window
    )
    return (soft * h_n).reshape((*batch, n_k)), weight.reshape((*batch, n_k))


@dataclass(frozen=True)
class SmoothModel:
    """The smooth closed form with its settings; see :func:`smooth_lengths`.

    Args:
        smoothing: smoothing length ``h`` in the half-planes' frame (normalised: a fraction of
            the diameter), ``>= 0``; ``0`` is the exact model. ``h = 1 / T`` for the paper's
            temperature ``T`` (:meth:`from_temperature`).
        clip: the paper's window (reproduction only).

    Example:
        >>> from boustro.geometry import Polygon, halfplanes
        >>> hp = halfplanes(Polygon([(0, 0), (4, 0), (4, 3), (0, 3)]))  # normalised: 0.8 x 0.6
        >>> out = SmoothModel(smoothing=1e-3)(hp, torch.tensor(0.0), torch.tensor(0.05), 0.2)
        >>> [round(x, 4) for x in out.lengths[out.weights > 0.5].tolist()]
        [0.8, 0.8, 0.8]
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
