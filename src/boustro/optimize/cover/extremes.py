"""Where a counted line's outermost counted lanes start and end, for the 1-tree bound
(:mod:`~boustro.optimize.cover.one_tree`; docs/mission_time.md, "The lines' extremes").

Per layout and line ``k`` with ``count_k >= 1`` the band statistics give the inner pieces ``[p_j,
q_j]`` (the inner projection minus the dilated holes' chords, pieces longer than ``tol``) only
through ``first_hi = q_0`` and ``last_lo = p_last``, and the inner projection's extremes ``in_lo
<= p_0``, ``in_hi >= q_last``. Every inner piece lies in a counted outer piece (it holds inner
length), so the plan's first counted lane (the one holding ``p_0``) starts at or before ``p_0``,
and its last ends at or beyond ``q_last``: the premise of the collapse is ``p_0``, ``q_last``,
not ``in_lo``, ``in_hi``. They differ where a hole's chord covers the inner projection's end (a
hole within the box's radius of the area's edge, the band reaching past it: the inner projection
then runs on beyond the hole while no lane is counted there) or where the projection's end
piece is shorter than ``tol``. So per line:

* one inner piece (``last_lo < first_hi``; with two or more, ``last_lo >= first_hi``): ``p_0 =
  last_lo`` and ``q_last = first_hi`` exactly; the ranges ``[p_0 - t, p_0]`` and ``[q_last,
  q_last + t]``;
* more, and no box of a dilated hole (``chords``) reaches within ``CUT_ROOM`` spacings of
  ``in_lo`` on the line: no chord cuts the projection there, ``p_0 = in_lo`` (the range
  ``[in_lo - t, in_lo]``; the same at ``in_hi``);
* else only ``in_lo <= p_0 <= first_hi`` is known: the range ``[in_lo - t, first_hi]`` (and
  ``[last_lo, in_hi + t]``). A plan's start ``e = p - r`` (``p <= p_0`` where its lane's covered
  part starts, run-in ``r <= t``) lies in it, or before ``in_lo - t``: moved to ``in_lo - t`` it
  moves by ``in_lo - t - e <= in_lo - p``, the lane's length outside the inner projection that
  no other term counts (module docstring of :mod:`~boustro.optimize.cover.one_tree`).

Left open: a line crossing a hole (two or more inner pieces) whose inner projection's first
interval, far from every hole, is shorter than ``tol`` (1e-9 of the diameter) and followed by a
gap of the projection (a spike of the inner set grazing the band's edge): ``p_0`` is then past
the gap and the second case wrongly takes ``in_lo``. The band statistics do not say; exporting
``p_0`` and ``q_last`` from the band kernel closes it (and makes the third case exact).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .bands import BandStats

__all__ = ["CUT_ROOM", "line_extremes"]

#: How near (in spacings, along the line) a dilated hole's box must come to the inner
#: projection's extreme to count as cutting it: far above ``tol``, the pieces ``_minus`` drops.
CUT_ROOM = 1e-3


def _cut(
    st: BandStats, spacing: float, chords: NDArray[np.float64] | None, at: NDArray[np.float64]
) -> NDArray[np.bool_]:
    """``(L, B)``: some box of ``chords`` ``(L, H, 4)`` (``v_lo, v_hi, u_lo, u_hi``) holds line
    ``k`` and reaches within ``CUT_ROOM`` spacings of ``at`` along it (all true without boxes)."""
    if chords is None:
        return np.ones(at.shape, dtype=bool)
    if chords.shape[1] == 0:
        return np.zeros(at.shape, dtype=bool)
    v = (st.k0 + np.arange(at.shape[1])) * spacing
    room = CUT_ROOM * spacing
    c = chords[:, None, :, :]
    across = (c[..., 0] <= v[None, :, None]) & (c[..., 1] >= v[None, :, None])
    along = (c[..., 2] <= at[..., None] + room) & (c[..., 3] >= at[..., None] - room)
    return np.any(across & along, axis=2)


def line_extremes(
    st: BandStats, spacing: float, turnaround: float, chords: NDArray[np.float64] | None
) -> NDArray[np.float64]:
    """``(L, B, 4)``: per layout and line, the range ``[lo, hi]`` of its first counted lane's
    start and of its last counted lane's end, run-ins of ``turnaround`` included (module
    docstring; ``nan`` where no lane is counted). ``chords`` ``(L, H, 4)``: boxes in each
    layout's frame that hold the inner set's dilated holes (the holes' boxes grown by at least
    the dilation); ``None``: not known (the third case wherever two pieces or more)."""
    t = turnaround
    one = st.last_lo < st.first_hi
    with np.errstate(invalid="ignore"):
        cut_lo = _cut(st, spacing, chords, st.in_lo)
        cut_hi = _cut(st, spacing, chords, st.in_hi)
    out = np.empty((*st.count.shape, 4))
    out[..., 0] = np.where(one, st.last_lo, st.in_lo) - t
    out[..., 1] = np.where(one, st.last_lo, np.where(cut_lo, st.first_hi, st.in_lo))
    out[..., 2] = np.where(one, st.first_hi, np.where(cut_hi, st.last_lo, st.in_hi))
    out[..., 3] = np.where(one, st.first_hi, st.in_hi) + t
    return out
