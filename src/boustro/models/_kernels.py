"""Compiled CPU kernels (numba) for the smooth closed form and for Eq. 1 (private).

The CPU path of :func:`boustro.models.smooth.smooth_lengths` (:func:`chords_forward`,
:func:`chords_backward`) and of :func:`boustro.fitness.smith_fitness` (:func:`smith_forward`,
:func:`smith_backward`): the same formulas in one loop per (angle, offset) pair, equal to the
tensor code to rounding (tested). numba is imported on first use; :func:`kernels` returns
``None`` without numba or with ``BOUSTRO_COMPILED=0``.
"""

from __future__ import annotations

import math
import os
from functools import cache
from importlib.util import find_spec
from typing import Any, NamedTuple

import numpy as np

from .._jit import jit, jit_globals

__all__ = ["TAU", "Kernels", "kernels"]

#: Bounds further than this many smoothing lengths below a role's largest, and transects
#: whose ``|z|`` exceeds it, take the hard path (``exp(-40) = 4.2e-18``).
TAU = 40.0


def _edge(
    cos: float,
    sin: float,
    nx: float,
    ny: float,
    b: float,
    d: float,
    h: float,
    far: float,
    eps: float,
    big: float,
) -> tuple[bool, float, float, float, float]:
    """Edge ``(nx, ny, b)`` seen from transects at angle ``(cos, sin)``:
    ``(lower, along, scale, alpha, slope)``; its bound is ``v = alpha + slope (d + q)`` in units
    of ``h``.

    ``across = n_j . n`` and ``along = n_j . u``; the edge bounds ``t`` from below where
    ``along > 0`` or ``|along| < eps`` (parallel: then moved out by ``4 eps (|b| + far)`` and
    taken with ``along = eps``), else from above. ``scale = -1 / (|along| h)``,
    ``alpha = b scale`` and ``slope = across scale``, both clamped to ``+-big``.
    """
    across = -nx * sin + ny * cos
    along = nx * cos + ny * sin
    parallel = abs(along) < eps
    if parallel:
        b += 4.0 * eps * (abs(b) + far)
    scale = -1.0 / (max(abs(along), eps) * h)
    alpha = min(max(b * scale, -big), big)
    slope = min(max(across * scale, -big), big)
    return parallel or along > 0, along, scale, alpha, slope


def _finite(cos: float, sin: float, d: float, h: float) -> bool:
    """Whether a pair's angle, offset and smoothing are finite numbers."""
    return math.isfinite(cos) and math.isfinite(sin) and math.isfinite(d) and math.isfinite(h)


def _windows(clip: bool, n_lower: int, n_edges: int, bound: float) -> tuple[float, float]:
    """The window bounds ``(w_low, w_up)`` of a pair's roles, ``bound = -window / h`` or
    ``-inf`` for none: both with ``clip``; otherwise only for a role the pair has no edge of
    (a sliver whose edges are all parallel to the transects up to eps)."""
    low = bound if clip or n_lower == 0 else -np.inf
    up = bound if clip or n_lower == n_edges else -np.inf
    return low, up


def _edges(
    cos: float,
    sin: float,
    normals: np.ndarray,
    offsets: np.ndarray,
    d: float,
    h: float,
    settings: tuple[bool, float, float, float, float],
    edges: tuple[np.ndarray, ...],
) -> tuple[float, float]:
    """A pair's edges (:func:`_edge`) into ``edges = (lower, along, scale, alpha, slope,
    shift)``, ``(E,)`` each, ``shift = alpha + slope d``; returns its window bounds
    (:func:`_windows`)."""
    lower, along, scale, alpha, slope, shift = edges
    clip, window, far, eps, big = settings
    n_lower = 0
    for e in range(normals.shape[0]):
        low, al, sc, a0, s1 = _edge(
            cos, sin, normals[e, 0], normals[e, 1], offsets[e], d, h, far, eps, big
        )
        lower[e], along[e], scale[e], alpha[e], slope[e] = low, al, sc, a0, s1
        shift[e] = a0 + s1 * d
        n_lower += low
    return _windows(clip, n_lower, normals.shape[0], -window / h)


def _envelope(
    lower: np.ndarray,
    shift: np.ndarray,
    slope: np.ndarray,
    q: np.ndarray,
    start_low: float,
    start_up: float,
    ml: np.ndarray,
    ml2: np.ndarray,
    mu: np.ndarray,
    mu2: np.ndarray,
    il: np.ndarray,
    iu: np.ndarray,
) -> None:
    """Per transect ``k``: the largest and second largest lower bound ``ml, ml2`` and upper
    bound ``mu, mu2`` (in units of ``h``; the roles start at ``start_low``, ``start_up``: the
    window bound or ``-inf``), and the edges ``il, iu`` that give the largest (``E``: the
    window; held as floats, which keeps the loops over ``k`` branch-free and vectorised)."""
    n_edges = shift.shape[0]
    for k in range(q.shape[0]):
        ml[k] = start_low
        mu[k] = start_up
        ml2[k] = -np.inf
        mu2[k] = -np.inf
        il[k] = n_edges
        iu[k] = n_edges
    for e in range(n_edges):
        s0, s1, index = shift[e], slope[e], float(e)
        top, second, which = (ml, ml2, il) if lower[e] else (mu, mu2, iu)
        for k in range(q.shape[0]):
            x = s0 + s1 * q[k]
            m = top[k]
            second[k] = max(second[k], min(m, x))
            which[k] = index if x > m else which[k]
            top[k] = max(m, x)


def _is_near(ml: float, ml2: float, mu: float, mu2: float) -> bool:
    """Whether a transect takes the soft path: a competing bound within ``TAU`` of its role's
    largest, or ``|z| < TAU``."""
    return (ml2 > ml - TAU) | (mu2 > mu - TAU) | (abs(ml + mu) < TAU)


def _tail(t: float) -> float:
    """``exp(t)`` for ``t <= 0`` (a bound ``t`` smoothing lengths below its role's largest),
    0 below ``-TAU``."""
    return math.exp(t) if t > -TAU else 0.0


def _sums(
    lower: np.ndarray,
    shift: np.ndarray,
    slope: np.ndarray,
    qk: float,
    w_low: float,
    w_up: float,
    ml: float,
    mu: float,
) -> tuple[float, float]:
    """``sum(exp(v - largest))`` of each role at one transect (terms below ``-TAU`` dropped);
    ``w_low``, ``w_up``: the window bounds, ``-inf`` for none."""
    sl = _tail(w_low - ml)
    su = _tail(w_up - mu)
    for e in range(shift.shape[0]):
        x = shift[e] + slope[e] * qk
        if lower[e]:
            sl += _tail(x - ml)
        else:
            su += _tail(x - mu)
    return sl, su


def _softplus_sigmoid(z: float, h: float) -> tuple[float, float]:
    """``(h softplus(z), sigmoid(z))``, the step and ``max(0, z)`` beyond ``|z| >= TAU``."""
    if z >= TAU:
        return h * z, 1.0
    if z <= -TAU:
        return 0.0, 0.0
    if z > 0:
        t = math.exp(-z)
        return h * (z + math.log1p(t)), 1.0 / (1.0 + t)
    t = math.exp(z)
    return h * math.log1p(t), t / (1.0 + t)


def chords_forward(
    geometry: tuple[np.ndarray, ...],
    settings: tuple[bool, float, float, float, float],
    length: np.ndarray,
    weight: np.ndarray,
    active: np.ndarray,
) -> None:
    """Soft lengths and weights ``(N, K)`` of the transects ``c = d + q_k``.

    ``geometry = (cos, sin, poly, normals, offsets, d, h, q)``: the pairs' angles, polygon
    (``normals[poly], offsets[poly]``), wrapped offset and smoothing ``(N,)``, and the grid
    ``q`` ``(K,)``; ``settings = (clip, window, far, eps, big)`` (:func:`_edge`,
    :func:`_windows`). With the edges' bounds ``v = alpha + slope (d + q)`` of :func:`_edge`
    and the windows' ``-window / h``, ``z = -(lse(lower v) + lse(upper v))``, the length is
    ``h softplus(z)`` and the weight ``sigmoid(z)``. ``active[0, n, k]`` and
    ``active[1, n, k]`` receive the edges of the largest lower and upper bound (``E``: the
    window), ``active[0, n, k] = -1`` where the soft path was taken.
    """
    cos, sin, poly, normals, offsets, d, h, q = geometry
    n_edges, n_k = normals.shape[1], q.shape[0]
    ml, ml2 = np.empty(n_k, dtype=q.dtype), np.empty(n_k, dtype=q.dtype)
    mu, mu2 = np.empty(n_k, dtype=q.dtype), np.empty(n_k, dtype=q.dtype)
    il, iu = np.empty(n_k, dtype=q.dtype), np.empty(n_k, dtype=q.dtype)
    lower = np.empty(n_edges, dtype=np.bool_)
    along, scale = np.empty(n_edges, dtype=q.dtype), np.empty(n_edges, dtype=q.dtype)
    alpha, slope = np.empty(n_edges, dtype=q.dtype), np.empty(n_edges, dtype=q.dtype)
    shift = np.empty(n_edges, dtype=q.dtype)
    edges = (lower, along, scale, alpha, slope, shift)
    for n in range(h.shape[0]):
        hn = h[n]
        p = poly[n]
        if not _finite(cos[n], sin[n], d[n], hn):  # a NaN angle or offset: NaN, as it came
            for k in range(n_k):
                length[n, k] = np.nan
                weight[n, k] = np.nan
                active[0, n, k] = 0
                active[1, n, k] = 0
            continue
        w_low, w_up = _edges(cos[n], sin[n], normals[p], offsets[p], d[n], hn, settings, edges)
        _envelope(lower, shift, slope, q, w_low, w_up, ml, ml2, mu, mu2, il, iu)
        near = False
        for k in range(n_k):  # the hard path everywhere, branch-free
            zh = -(ml[k] + mu[k])
            length[n, k] = hn * max(zh, 0.0)
            weight[n, k] = 1.0 if zh > 0 else 0.0
            active[0, n, k] = il[k]
            active[1, n, k] = iu[k]
            near |= _is_near(ml[k], ml2[k], mu[k], mu2[k])
        if near:  # then the soft path where it applies
            for k in range(n_k):
                if _is_near(ml[k], ml2[k], mu[k], mu2[k]):
                    sl, su = _sums(lower, shift, slope, q[k], w_low, w_up, ml[k], mu[k])
                    z = -(ml[k] + mu[k]) - math.log(sl * su)
                    length[n, k], weight[n, k] = _softplus_sigmoid(z, hn)
                    active[0, n, k] = -1


def _hard_grads(
    active: np.ndarray,
    n: int,
    gz: np.ndarray,
    q: np.ndarray,
    edges: tuple[np.ndarray, ...],
    windows: bool,
    scratch: tuple[np.ndarray, np.ndarray, np.ndarray],
    edge_grads: tuple[np.ndarray, np.ndarray],
) -> tuple[bool, float]:
    """The hard path of :func:`chords_backward` for pair ``n``: one-hot at the largest bounds,
    summed edge by edge (branch-free) into ``edge_grads``; returns (any transect on the soft
    path, the window bounds' gradient)."""
    lower = edges[0]
    gh_k, gq_k, top = scratch
    g_shift, g_slope = edge_grads
    n_edges, n_k = lower.shape[0], q.shape[0]
    soft = False
    g_window = 0.0
    for k in range(n_k):
        low, up = active[0, n, k], active[1, n, k]
        soft |= low < 0
        gh_k[k] = gz[k] if low >= 0 else 0.0
        gq_k[k] = gh_k[k] * q[k]
        top[0, k] = low
        top[1, k] = up
    for role in range(2):
        for e in range(n_edges + windows):
            if e < n_edges and lower[e] != (role == 0):
                continue
            acc, acc_q, index = 0.0, 0.0, float(e)
            for k in range(n_k):
                hit = top[role, k] == index
                acc += gh_k[k] if hit else 0.0
                acc_q += gq_k[k] if hit else 0.0
            if e < n_edges:
                g_shift[e] -= acc
                g_slope[e] -= acc_q
            else:
                g_window -= acc
    return soft, g_window


def _soft_grads(
    active: np.ndarray,
    n: int,
    gz: np.ndarray,
    q: np.ndarray,
    edges: tuple[np.ndarray, ...],
    windows: tuple[float, float],
    edge_grads: tuple[np.ndarray, np.ndarray],
    g_window: float,
) -> float:
    """The soft path of :func:`chords_backward` for pair ``n``: the softmax weights of each
    role, into ``edge_grads``; returns the window bounds' gradient, ``g_window`` updated."""
    lower, shift, slope = edges[0], edges[5], edges[4]
    w_low, w_up = windows
    g_shift, g_slope = edge_grads
    n_edges = lower.shape[0]
    for k in range(q.shape[0]):
        g = gz[k]
        if active[0, n, k] >= 0 or g == 0.0:
            continue
        qk = q[k]
        ml, mu = w_low, w_up
        for e in range(n_edges):
            x = shift[e] + slope[e] * qk
            if lower[e]:
                ml = max(ml, x)
            else:
                mu = max(mu, x)
        sl, su = _sums(lower, shift, slope, qk, w_low, w_up, ml, mu)
        for e in range(n_edges):
            x = shift[e] + slope[e] * qk
            share = g * (_tail(x - ml) / sl if lower[e] else _tail(x - mu) / su)
            g_shift[e] -= share
            g_slope[e] -= share * qk
        g_window -= g * (_tail(w_low - ml) / sl + _tail(w_up - mu) / su)
    return g_window


def _chain_grads(
    edges: tuple[np.ndarray, ...],
    edge_grads: tuple[np.ndarray, np.ndarray],
    normals: np.ndarray,
    d: float,
    hn: float,
    gh: float,
    limits: tuple[float, float],
) -> tuple[float, float, float, float]:
    """``(g_cos, g_sin, g_d, g_h)`` of one pair from the edges' gradients: ``v = shift + slope q``
    with ``shift = alpha + slope d``, then through the clamps, and ``across = -nx sin + ny cos``,
    ``along = nx cos + ny sin``. ``gh`` starts at the window bounds' share (``-window / h`` is
    proportional to ``1 / h``)."""
    _, along, scale, alpha, slope, _ = edges
    g_shift, g_slope = edge_grads
    eps, big = limits
    gd = 0.0
    gc = 0.0
    gs = 0.0
    for e in range(along.shape[0]):
        gd += g_shift[e] * slope[e]
        ga = g_shift[e] if abs(alpha[e]) < big else 0.0
        gb = g_slope[e] + g_shift[e] * d
        gb = gb if abs(slope[e]) < big else 0.0
        terms = ga * alpha[e] + gb * slope[e]
        g_across = gb * scale[e]
        g_along = -terms / along[e] if abs(along[e]) >= eps else 0.0
        nx, ny = normals[e, 0], normals[e, 1]
        gc += g_across * ny + g_along * nx
        gs += -g_across * nx + g_along * ny
        gh += terms
    return gc, gs, gd, gh


def chords_backward(
    geometry: tuple[np.ndarray, ...],
    settings: tuple[bool, float, float, float, float],
    outputs: tuple[np.ndarray, np.ndarray, np.ndarray],
    g_length: np.ndarray,
    g_weight: np.ndarray,
    need_h: bool,
    grads: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
) -> None:
    """Gradients of ``sum(g_length * length + g_weight * weight)`` with respect to
    ``cos, sin, d`` and (with ``need_h``) ``h``, into ``grads`` (four ``(N,)`` arrays), from
    the ``outputs = (length, weight, active)`` of :func:`chords_forward`: ``dz/dv =
    -softmax`` of the role (one-hot at the largest bounds off the soft path),
    ``d length / dz = h weight``, ``d weight / dz = weight (1 - weight)``,
    ``d length / dh = length / h`` at fixed ``z``, and the chain rule through the clamps (zero
    where a clamp holds) as in :class:`boustro.models.smooth._SoftChords`."""
    cos, sin, poly, normals, offsets, d, h, q = geometry
    bound, eps, big = -settings[1], settings[3], settings[4]
    length, weight, active = outputs
    g_cos, g_sin, g_d, g_h = grads
    n_edges, n_k = normals.shape[1], q.shape[0]
    gz, gh_k = np.empty(n_k, dtype=q.dtype), np.empty(n_k, dtype=q.dtype)
    gq_k = np.empty(n_k, dtype=q.dtype)
    top = np.empty((2, n_k), dtype=q.dtype)  # the largest bounds' edges, as floats
    lower = np.empty(n_edges, dtype=np.bool_)
    along, scale = np.empty(n_edges, dtype=q.dtype), np.empty(n_edges, dtype=q.dtype)
    alpha, slope = np.empty(n_edges, dtype=q.dtype), np.empty(n_edges, dtype=q.dtype)
    shift = np.empty(n_edges, dtype=q.dtype)
    edges = (lower, along, scale, alpha, slope, shift)
    g_shift, g_slope = np.empty(n_edges, dtype=q.dtype), np.empty(n_edges, dtype=q.dtype)
    edge_grads = (g_shift, g_slope)
    scratch = (gh_k, gq_k, top)
    for n in range(h.shape[0]):
        hn = h[n]
        p = poly[n]
        if not _finite(cos[n], sin[n], d[n], hn):  # NaN in, NaN out
            g_cos[n] = g_sin[n] = g_d[n] = g_h[n] = np.nan
            continue
        w_low, w_up = _edges(cos[n], sin[n], normals[p], offsets[p], d[n], hn, settings, edges)
        any_grad = False
        for k in range(n_k):
            w = weight[n, k]
            gz[k] = (g_length[n, k] * hn + g_weight[n, k] * (1.0 - w)) * w
            any_grad |= gz[k] != 0.0
        explicit_h = 0.0  # d length / d h at fixed z: length / h
        if need_h:
            for k in range(n_k):
                explicit_h += g_length[n, k] * length[n, k]
        g_window = 0.0
        for e in range(n_edges):
            g_shift[e] = 0.0
            g_slope[e] = 0.0
        soft = False
        if any_grad:
            windows = w_low > -np.inf or w_up > -np.inf
            soft, g_window = _hard_grads(active, n, gz, q, edges, windows, scratch, edge_grads)
        if soft:
            g_window = _soft_grads(active, n, gz, q, edges, (w_low, w_up), edge_grads, g_window)
        gc, gs, gd, gh = _chain_grads(
            edges, edge_grads, normals[p], d[n], hn, g_window * bound / hn, (eps, big)
        )
        g_cos[n] = gc
        g_sin[n] = gs
        g_d[n] = gd
        g_h[n] = (explicit_h - gh) / hn if need_h else 0.0


def _moments(lengths: np.ndarray, weights: np.ndarray, n: int) -> tuple[float, float, float]:
    """``(W, mean, var)`` of row ``n``, weighted; ``W`` the weights' sum, 1 where it is 0.

    The mean is refined once by the weighted mean of the residuals, as in
    :func:`boustro.fitness._smith_tensor`: equal lengths give a variance of exactly 0.
    """
    total, first = 0.0, 0.0
    for k in range(lengths.shape[1]):
        total += weights[n, k]
        first += weights[n, k] * lengths[n, k]
    denom = total if total > 0 else 1.0
    mean = first / denom
    residual = 0.0
    for k in range(lengths.shape[1]):
        residual += weights[n, k] * (lengths[n, k] - mean)
    mean += residual / denom
    second = 0.0
    for k in range(lengths.shape[1]):
        r = lengths[n, k] - mean
        second += weights[n, k] * r * r
    return denom, mean, second / denom


def smith_forward(
    lengths: np.ndarray,
    weights: np.ndarray,
    a: float,
    b: float,
    tiny: float,
    out: np.ndarray,
    moments: np.ndarray,
) -> None:
    """Eq. 1 with weighted statistics per row of ``(M, K)`` lengths and weights (see
    :func:`boustro.fitness.smith_fitness`): ``a mean + b (1 - std)``, ``b`` where the weights
    sum to 0, ``std = 0`` where ``var <= tiny``; ``moments`` ``(3, M)`` receives each row's
    ``(W, mean, var)`` for :func:`smith_backward`."""
    for n in range(lengths.shape[0]):
        denom, mean, var = _moments(lengths, weights, n)
        std = math.sqrt(var) if var > tiny else 0.0
        out[n] = a * mean + b * (1.0 - std)
        moments[0, n], moments[1, n], moments[2, n] = denom, mean, var


def smith_backward(
    lengths: np.ndarray,
    weights: np.ndarray,
    moments: np.ndarray,
    a: float,
    b: float,
    tiny: float,
    g: np.ndarray,
    g_lengths: np.ndarray,
    g_weights: np.ndarray,
) -> None:
    """Gradients of ``sum(g * smith_forward(...))``, from the forward pass's ``moments``: with
    ``r = L - mean``, ``df/dL = (w / W) (a - b r / std)`` and
    ``df/dw = (a r - b (r^2 - var) / (2 std)) / W`` (``W`` the weights' sum, 1 where it is 0;
    the ``std`` terms vanish where ``var <= tiny``)."""
    for n in range(lengths.shape[0]):
        denom, mean, var = moments[0, n], moments[1, n], moments[2, n]
        half_inv_std = 0.5 / math.sqrt(var) if var > tiny else 0.0
        c1 = a * g[n] / denom
        c3 = -b * half_inv_std * g[n] / denom
        for k in range(lengths.shape[1]):
            r = lengths[n, k] - mean
            g_lengths[n, k] = weights[n, k] * (c1 + 2.0 * c3 * r)
            g_weights[n, k] = c1 * r + c3 * (r * r - var)


class Kernels(NamedTuple):
    """The compiled kernels (numba dispatchers with the signatures of the functions above)."""

    chords_forward: Any
    chords_backward: Any
    smith_forward: Any
    smith_backward: Any


@cache
def kernels() -> Kernels | None:
    """The compiled kernels, or ``None`` where numba is missing or ``BOUSTRO_COMPILED=0``.

    Compiling happens on each kernel's first call per dtype (about a second each, once per
    machine where the on-disk cache is writable).
    """
    if os.environ.get("BOUSTRO_COMPILED", "1").strip() in ("0", "false", "no", "off"):
        return None
    if find_spec("numba") is None:  # pragma: no cover - numba is a dependency
        return None
    # sums may be reordered (vectorised reductions); nothing else of fast-math
    options: dict[str, Any] = {"nogil": True, "error_model": "numpy", "fastmath": {"reassoc"}}
    # The helpers first: the kernels call them by their module-level names, which from here on
    # are compiled functions (numba resolves those names when it compiles a kernel, on its
    # first call).
    helpers = "_edge _finite _windows _envelope _is_near _tail _sums _softplus_sigmoid".split()
    jit_globals(globals(), helpers, inline="never", **options)
    inlined = ("_edges", "_moments", "_hard_grads", "_soft_grads", "_chain_grads")
    jit_globals(globals(), inlined, inline="always", **options)  # faster loops in the kernels
    functions = (chords_forward, chords_backward, smith_forward, smith_backward)
    return Kernels(*(jit(f, inline="never", **options) for f in functions))
