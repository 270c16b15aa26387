"""Eq. 1 of Smith et al. (SSRR 2022), ``a * mean(L) + b * (1 - std(L))``: maximised."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from .._torch import Function, autograd_function, torch
from .._validate import as_number
from ..errors import InvalidParameterError
from ..models import TransectLengths, smooth
from ..models import _kernels as _compiled
from .base import BaseObjective
from .registry import register_objective

__all__ = ["SmithFitness", "safe_sqrt", "smith_fitness", "transect_count"]

Statistics = Literal["weighted", "paper"]


def safe_sqrt(x: torch.Tensor) -> torch.Tensor:
    """``sqrt(max(x, 0))`` whose gradient is 0, not inf or NaN, where ``x <= tiny``."""
    tiny = torch.finfo(x.dtype).eps ** 2
    positive = x > tiny
    return torch.where(positive, torch.sqrt(torch.where(positive, x, torch.ones_like(x))), 0.0)


def transect_count(weights: torch.Tensor) -> torch.Tensor:
    """The (soft) number of transects that count, ``(*)`` from weights ``(*, K)``."""
    return weights.sum(dim=-1)


#: Default weights of :func:`smith_fitness` count a chord when it is longer than this fraction
#: of the longest one: shorter ones are rounding noise (a transect through a vertex).
NOISE = 1e-12


def _check_weight(name: str, value: object) -> None:
    v = as_number(name, value)
    if not (v >= 0 and math.isfinite(v)):
        raise InvalidParameterError(f"{name} must be finite and >= 0, got {value!r}")


def smith_fitness(
    lengths: torch.Tensor,
    weights: torch.Tensor | None = None,
    *,
    a: float = 0.5,
    b: float = 0.5,
    statistics: Statistics = "weighted",
) -> torch.Tensor:
    """Eq. 1 of the paper, ``a * mean + b * (1 - std)``, batched over leading dimensions.

    Args:
        lengths: ``(*, K)`` transect lengths (normalised frame for the paper's scale).
        weights: ``(*, K)`` in ``[0, 1]``; default: 1 for chords longer than :data:`NOISE` times
            the longest, else 0.
        a, b: weights of the mean and of ``1 - std`` (the paper uses 0.5 and 0.5).
        statistics: ``"weighted"`` (default): ``mean = sum(w L) / sum(w)``,
            ``var = sum(w (L - mean)^2) / sum(w)``; ``"paper"``: what the authors' code
            computes, ``mean = sum(L) / sum(w)``, ``var = sum((w (L - mean))^2) / sum(w)``
            (equal for 0/1 weights; use it to reproduce Table I, not to optimise).

    Returns:
        ``(*)`` fitness, to be maximised. ``f = b`` where no transect counts.

    >>> import torch
    >>> round(float(smith_fitness(torch.tensor([0.5, 1.0, 0.5]))), 4)
    0.7155
    """
    if statistics not in ("weighted", "paper"):
        raise InvalidParameterError(f"statistics must be 'weighted' or 'paper', got {statistics!r}")
    _check_weight("a", a)
    _check_weight("b", b)
    if weights is None:
        # counted: chords longer than rounding noise (the exact model's rule, relative here)
        noise = NOISE * lengths.detach().abs().amax(dim=-1, keepdim=True)
        weights = (lengths > noise).to(lengths.dtype)
    elif weights.shape != lengths.shape:
        raise InvalidParameterError(
            f"weights shape {tuple(weights.shape)} differs from lengths {tuple(lengths.shape)}"
        )
    numbers = not any(isinstance(x, torch.Tensor) for x in (a, b))  # else a gradient may be due
    if statistics == "weighted" and numbers:
        kernels = _compiled_kernels(lengths, weights)
        if kernels is not None:
            return _CompiledSmith.apply(lengths, weights, float(a), float(b), kernels)
    return _smith_tensor(lengths, weights, a, b, statistics)


def _smith_tensor(
    lengths: torch.Tensor,
    weights: torch.Tensor,
    a: float | torch.Tensor,
    b: float | torch.Tensor,
    statistics: Statistics,
) -> torch.Tensor:
    """Eq. 1 by tensor operations (any device; differentiable to any order)."""
    total = weights.sum(dim=-1)
    denom = torch.where(total > 0, total, torch.ones_like(total))
    if statistics == "weighted":
        mean = (weights * lengths).sum(dim=-1) / denom
        with torch.no_grad():  # refined once: equal lengths give var 0; gradient of mean
            residual = (weights * (lengths - mean[..., None])).sum(dim=-1) / denom
        mean = mean + residual
        var = (weights * (lengths - mean[..., None]) ** 2).sum(dim=-1) / denom
    else:
        mean = torch.where(total > 0, lengths.sum(dim=-1) / denom, 0.0)
        var = ((weights * (lengths - mean[..., None])) ** 2).sum(dim=-1) / denom
    return a * mean + b * (1 - safe_sqrt(var))


def _compiled_kernels(lengths: torch.Tensor, weights: torch.Tensor) -> _compiled.Kernels | None:
    """The compiled kernels (:mod:`boustro._compiled`) if they apply: the rules of
    :func:`boustro.smooth._compiled_kernels` (read at call time), weights like lengths, and a
    gradient to compute (a forward pass alone is cheap either way; scoring a grid, as
    ``boustro plan`` does, need not import numba)."""
    grad = torch.is_grad_enabled() and (lengths.requires_grad or weights.requires_grad)
    if not grad or weights.dtype != lengths.dtype or not lengths.shape[-1]:
        return None
    return smooth._compiled_kernels(lengths, lengths.numel())


@autograd_function
class _CompiledSmith(Function):
    """Eq. 1 with weighted statistics by the compiled kernels, batched over leading dims.

    Its backward pass is the kernel's; asked for a differentiable gradient (``create_graph``),
    it differentiates the tensor formula instead (:func:`_smith_tensor`, the same values).
    """

    @staticmethod
    def forward(
        ctx: Any,
        lengths: torch.Tensor,
        weights: torch.Tensor,
        a: float,
        b: float,
        kernels: _compiled.Kernels,
    ) -> torch.Tensor:
        ctx.save_for_backward(lengths, weights)
        lengths, weights = torch.broadcast_tensors(lengths, weights)
        shape, k = lengths.shape[:-1], lengths.shape[-1]
        flat = [x.detach().reshape(-1, k).contiguous() for x in (lengths, weights)]
        tiny = torch.finfo(lengths.dtype).eps ** 2
        out = torch.empty(flat[0].shape[0], dtype=lengths.dtype)
        moments = np.empty((3, out.shape[0]), dtype=flat[0].numpy().dtype)  # W, mean, var
        kernels.smith_forward(flat[0].numpy(), flat[1].numpy(), a, b, tiny, out.numpy(), moments)
        ctx.constants = (a, b, tiny, kernels, moments)
        return out.reshape(shape)

    @staticmethod
    def backward(ctx: Any, grad: torch.Tensor) -> tuple[torch.Tensor | None, ...]:
        lengths, weights = ctx.saved_tensors
        a, b, tiny, kernels, moments = ctx.constants
        need = ctx.needs_input_grad[:2]
        if torch.is_grad_enabled():  # create_graph: a gradient that is itself differentiable
            inputs = [x for x, n in zip((lengths, weights), need, strict=True) if n]
            f = _smith_tensor(lengths, weights, a, b, "weighted")
            grads = iter(torch.autograd.grad(f, inputs, grad, create_graph=True))
            return (*(next(grads) if n else None for n in need), None, None, None)
        full, k = torch.broadcast_shapes(lengths.shape, weights.shape), lengths.shape[-1]
        flat = [x.detach().expand(full).reshape(-1, k).contiguous() for x in (lengths, weights)]
        g = grad.detach().reshape(-1).contiguous().to(lengths.dtype)
        g_lengths, g_weights = torch.empty_like(flat[0]), torch.empty_like(flat[1])
        kernels.smith_backward(
            flat[0].numpy(),
            flat[1].numpy(),
            moments,
            a,
            b,
            tiny,
            g.numpy(),
            g_lengths.numpy(),
            g_weights.numpy(),
        )
        out = [g_lengths.reshape(full), g_weights.reshape(full)]
        # an input broadcast in the forward pass gets the sum over the broadcast dimensions
        for i, x in enumerate((lengths, weights)):
            if x.shape != full:
                out[i] = out[i].sum_to_size(x.shape)
        return (*(o if n else None for o, n in zip(out, need, strict=True)), None, None, None)


@register_objective("smith")
@dataclass(frozen=True)
class SmithFitness(BaseObjective):
    """Eq. 1 as an objective object: holds ``a``, ``b``, the statistics; maximised.

    >>> SmithFitness().sense, SmithFitness(a=1.0, b=0.0).a
    ('max', 1.0)
    """

    a: float = 0.5
    b: float = 0.5
    statistics: Statistics = "weighted"
    name: str = "smith"
    maximise: bool = True

    def __post_init__(self) -> None:
        for key in ("a", "b"):
            _check_weight(key, getattr(self, key))

    def __call__(self, tl: TransectLengths) -> torch.Tensor:
        return smith_fitness(tl.lengths, tl.weights, a=self.a, b=self.b, statistics=self.statistics)
