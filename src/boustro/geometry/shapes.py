"""Named shapes of the paper: the parallelogram of its Figure 1 and the authors' spacing."""

from __future__ import annotations

__all__ = ["PAPER_PARALLELOGRAM", "PAPER_SPACING"]

#: The parallelogram of the paper's Figure 1, in the authors' units.
PAPER_PARALLELOGRAM: tuple[tuple[float, float], ...] = ((8, 4), (8, 10), (4, 8), (4, 2))
#: The transect spacing the authors' scripts use with it (0.0559 of the normalised frame).
PAPER_SPACING = 0.5
