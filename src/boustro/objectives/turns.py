"""Fewest transects (turns + 1), minimised, and the count that covers a strip."""

from __future__ import annotations

import math
from dataclasses import dataclass

from .._torch import torch
from ..models import Chords, TransectLengths
from .base import BaseObjective
from .registry import register_objective

__all__ = ["GRAZE", "FewestTransects", "coverage_count"]

#: Chords at most this long (relative to the frame's radius 1) are a transect grazing a vertex,
#: not a transect: the same rule as :class:`~boustro.models.ExactModel`.
GRAZE = 1e-12


@register_objective("fewest_transects")
@dataclass(frozen=True)
class FewestTransects(BaseObjective):
    """The number of transects that cross the polygon (turns + 1); **minimised**.

    On exact lengths it is the count of transects longer than zero; on a soft model's lengths it
    is the sum of the "shown" weights (Eq. 7), a differentiable surrogate.

    The count with full coverage at angle ``theta`` is ``ceil(width(theta) / spacing)``
    (:func:`coverage_count`), minimised by the polygon's minimum-width direction, which is
    parallel to one of its edges (rotating calipers); see
    :func:`boustro.global_opt.fewest_transects_optimum`.

    >>> from boustro.models import ExactModel
    >>> from boustro.geometry import Polygon, halfplanes
    >>> hp = halfplanes(Polygon([(0, 0), (1, 0), (1, 1), (0, 1)]))
    >>> FewestTransects().sense, int(FewestTransects()(ExactModel()(hp, 0.0, 0.05, 0.2)))
    ('min', 4)
    """

    name: str = "fewest_transects"
    maximise: bool = False
    needs_chords: bool = False

    def __call__(self, tl: TransectLengths | Chords) -> torch.Tensor:
        if isinstance(tl, Chords):
            return (tl.lengths > GRAZE).to(tl.lengths.dtype).sum(dim=-1)
        return tl.weights.sum(dim=-1)


def coverage_count(width: float, spacing: float) -> int:
    """Fewest transects whose swaths (half a spacing each side) cover a strip of ``width``.

    ``ceil(width / spacing)``, with a width that is a whole number of spacings up to rounding
    (relative 1e-12) counted as that number: the transects then sit half a spacing from each
    side.
    """
    ratio = width / spacing
    k = math.floor(ratio)
    return int(k) if ratio - k <= 1e-12 * max(1.0, ratio) else int(k) + 1
