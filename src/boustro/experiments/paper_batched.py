"""The paper's model (Eq. 2-7) for many Table I samples at once, by the library's model code."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

import numpy as np
import torch
from numpy.typing import NDArray

from ..models.paper import paper_line_lengths, paper_weights, trapezoid_scale
from ..models.paper_band import band_tau
from ..objectives.smith import smith_fitness
from .layouts import _Group, _scatter, protocol_groups
from .samples import Protocol, Samples, Statistics, Trapezoid

__all__ = ["BAND_Z", "Method", "paper_model_fitness"]


#: Half-width, in units of ``T * distance``, of the band around the polygon's boundary where the
#: paper's model is evaluated point by point: the library's
#: :func:`~boustro.models.paper_band.band_tau` in float64 (``E exp(-41) < 2e-17`` for ``E <= 9``
#: edges; 41 rather than 40 leaves room for rounding).
BAND_Z = band_tau(torch.float64)

#: How the lengths are evaluated: ``"dense"`` every point, ``"band"`` only the points near the
#: boundary, ``"subsets"`` a matrix product, ``"auto"`` the cheapest (the library's
#: :data:`~boustro.models.paper.Method`, ``"dense"`` being its ``"full"``).
Method = Literal["auto", "dense", "band", "subsets"]

#: The library's trapezoid step of each protocol's (:class:`Protocol`).
_STEP = {"library": "span", "authors": "points"}


def _soft_lengths(
    g: _Group, temperature: float, points: int, method: Method = "auto"
) -> torch.Tensor:
    """The paper's transect lengths (Eq. 3-6) ``(M,)`` of a group (the library's step): its
    lines at their own positions, each sample with its own window half-width, by
    :func:`boustro.models.paper.paper_line_lengths`."""
    return paper_line_lengths(
        g.across,
        g.along,
        g.b,
        g.position,
        g.sample,
        half=g.half,
        temperature=float(temperature),
        points_per_transect=int(points),
        method="full" if method == "dense" else method,
    )


def _soft_fitness(
    g: _Group,
    temperature: float,
    points: int,
    variants: Sequence[tuple[Statistics, Trapezoid]],
    method: Method = "auto",
) -> dict[tuple[Statistics, Trapezoid], torch.Tensor]:
    """Eq. 1 of the paper's model per sample ``(B,)`` for each (statistics, trapezoid step)
    variant (see :class:`Protocol`), from one evaluation of the lengths (the trapezoid step
    only scales them: :func:`~boustro.models.paper.trapezoid_scale`)."""
    library = _scatter(g, _soft_lengths(g, temperature, points, method))
    temp = torch.tensor(float(temperature), dtype=torch.float64)
    out = {}
    for statistics, trapezoid in variants:
        scale = trapezoid_scale(points, _STEP[trapezoid])  # type: ignore[arg-type]
        lengths = library * scale if scale != 1.0 else library
        weights = paper_weights(lengths, temp)  # Eq. 7; 0 where padded (length 0)
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
    authors' window has its own transects), but batched: one call of the library's
    :func:`~boustro.models.paper.paper_line_lengths` per group of samples.

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
