"""Where a counted line's outermost counted lanes start and end, for the 1-tree bound
(:mod:`~boustro.optimize.cover.one_tree`; docs/mission_time.md, "The lines' extremes").

Per layout and line ``k`` with ``count_k >= 1`` the band kernel exports the start ``p_0 =
first_lo`` of the first inner piece and the end ``q = last_hi`` of the last (the inner
projection minus the dilated holes' chords, pieces longer than ``tol``;
:class:`~boustro.optimize.cover.bands.BandStats`). Every inner piece lies in a counted outer
piece (it holds inner length), so the plan's first counted lane (the one holding the first inner
piece) starts at or before ``p_0`` and its last ends at or beyond ``q``: the premise of the
collapse is ``p_0``, ``q``, not the inner projection's extremes ``in_lo <= p_0``, ``in_hi >=
q``. They differ where a hole's chord covers the inner projection's end (a hole within the box's
radius of the area's edge, the band reaching past it: the inner projection then runs on beyond
the hole while no lane is counted there) or where the projection's end interval is shorter than
``tol`` (a spike of the inner set grazing the band's edge, followed by a gap). The ranges are
``[p_0 - t, p_0]`` and ``[q, q + t]`` on every counted line (``t`` the run-in).

Before, the band statistics gave the inner pieces only through ``first_hi = q_0`` and ``last_lo
= p_last``, and this module told the cases apart with boxes holding the dilated holes: exact on
one inner piece, ``in_lo`` where no box came near it (wrong on the spike above), else the wider
``[in_lo - t, first_hi]``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .bands import BandStats

__all__ = ["line_extremes"]


def line_extremes(st: BandStats, turnaround: float) -> NDArray[np.float64]:
    """``(L, B, 4)``: per layout and line, the range ``[lo, hi]`` of its first counted lane's
    start and of its last counted lane's end, run-ins of ``turnaround`` included: ``[first_lo -
    t, first_lo]`` and ``[last_hi, last_hi + t]`` (module docstring; ``nan`` where the line has
    no inner piece, hence no counted lane)."""
    t = turnaround
    out = np.empty((*st.count.shape, 4))
    out[..., 0] = st.first_lo - t
    out[..., 1] = st.first_lo
    out[..., 2] = st.last_hi
    out[..., 3] = st.last_hi + t
    return out
