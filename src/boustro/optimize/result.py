"""The one result type of every optimiser, and the canonical form of a layout."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["OptimizeResult", "canonical"]


@dataclass(frozen=True)
class OptimizeResult:
    """The answer of any optimiser, in the user's units.

    Attributes:
        angle: best transect direction, radians in ``[0, pi)``.
        offset: best grid offset, user units in ``[0, spacing)``.
        fitness: objective value at (angle, offset) with the exact model.
        spacing: the spacing searched, user units.
        method: name of the optimiser.
        evaluations: number of (angle, offset) pairs evaluated (by any model; a gradient
            evaluation counts as one).
        seconds: wall time of the search.
        upper_bound: a certified upper bound on the fitness over all layouts, where the method
            gives one (``global``); else ``None``.
        history: optional ``(steps, 3)`` array of (angle, offset, fitness) of the best so far.
        info: method-specific extras (e.g. the number of starts).

    >>> r = OptimizeResult(0.5, 0.1, 0.9, 0.25, "demo", 1, 0.0, upper_bound=0.95)
    >>> round(r.gap, 4)
    0.05
    """

    angle: float
    offset: float
    fitness: float
    spacing: float
    method: str
    evaluations: int
    seconds: float
    upper_bound: float | None = None
    history: NDArray[np.float64] | None = None
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def gap(self) -> float | None:
        """``upper_bound - fitness``: how far from optimal the answer can be, if certified."""
        return None if self.upper_bound is None else self.upper_bound - self.fitness


def canonical(angle: float, offset: float, spacing: float) -> tuple[float, float]:
    """The same transect grid with ``angle`` in ``[0, pi)`` and ``offset`` in ``[0, spacing)``."""
    turns = math.floor(angle / math.pi)
    angle -= turns * math.pi
    if angle >= math.pi:  # rounding: pi is the next half-turn, angle 0 with the offset flipped
        angle, turns = 0.0, turns + 1
    if turns % 2:
        offset = -offset
    offset = math.fmod(offset, spacing)
    if offset < 0:
        offset += spacing
    if offset >= spacing:
        offset = 0.0
    return angle, offset
