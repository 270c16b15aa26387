"""Fitness functions of transect lengths (layer 3): they work on exact and soft lengths alike.

The fitness of Smith et al. (SSRR 2022), the paper's Eq. 1, is MAXIMISED::

    f = a * mean(L) + b * (1 - std(L))

over the transects that count (population std). With lengths in the normalised frame (diameter 1)
every length is at most 1 and the std at most 1/2, so ``f`` lies in ``[b/2, a + b]``.

Weights generalise "the transects with length > 0": exact lengths have 0/1 weights, the paper's
soft model has the Eq. 7 indicator ``S``. Two ways to weight the statistics are offered:

* ``statistics="weighted"`` (default): ``mean = sum(w L) / sum(w)`` and
  ``var = sum(w (L - mean)^2) / sum(w)``. Equals the discrete definition exactly for 0/1 weights.
* ``statistics="paper"``: what the authors' released code computes,
  ``mean = sum(L) / sum(w)`` and ``var = sum((w (L - mean))^2) / sum(w)``. It also equals the
  discrete definition for 0/1 weights, but at low temperature, where every ``S`` is well below 1,
  it inflates the mean (to about 2 at ``T = 1``). This is why the paper's Table I reports an error
  near 0.5 at ``T = 1``; use it to reproduce Table I, not to optimise.

Degenerate cases are defined, never NaN: no transect that counts (``sum(w) == 0``) gives
``mean = std = 0`` and ``f = b``; equal lengths give ``std = 0`` with a finite (zero) gradient.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import torch

from .errors import InvalidParameterError, as_number
from .models import TransectLengths

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
        statistics: ``"weighted"`` (default) or ``"paper"``; see the module docstring.

    Returns:
        ``(*)`` fitness, to be maximised. ``f = b`` where no transect counts.
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
    total = weights.sum(dim=-1)
    denom = torch.where(total > 0, total, torch.ones_like(total))
    if statistics == "weighted":
        mean = (weights * lengths).sum(dim=-1) / denom
        var = (weights * (lengths - mean[..., None]) ** 2).sum(dim=-1) / denom
    else:
        mean = torch.where(total > 0, lengths.sum(dim=-1) / denom, 0.0)
        var = ((weights * (lengths - mean[..., None])) ** 2).sum(dim=-1) / denom
    return a * mean + b * (1 - safe_sqrt(var))


@dataclass(frozen=True)
class SmithFitness:
    """Eq. 1 as an objective object: holds ``a``, ``b``, the statistics; maximised."""

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
