"""The moves of a ``keep_inside`` plan on top of its boundary passes (issue 16): the bound of
:mod:`~.inside_bound` adds the moves between lanes that no pass holding a counted contour
stretch can serve to the length of those stretches, where it took the larger of the two.

**The argument** (docs/mission_time.md, "Keep-inside: moves on top of passes"). A plan's path
drives its lanes and passes whole, one after another, joined by moves. Take the lanes on the
lines ``k`` the bound counts (``count_k >= 1``: every plan of the box has a lane there) in the
order the path drives them, ``L_1 .. L_n``; between ``L_i`` and ``L_{i+1}`` lies a
*connector*: the run-out, the moves, any passes and uncounted lanes, the run-in. The path's
length is the counted lanes, the run-ins and run-outs, the connectors without them and what
comes before ``L_1`` and after ``L_n``. A counted stretch (:mod:`~.inside_bound`'s ``P``) lies
in one pass (the planner keeps a flagged run of samples whole), a pass in one connector or in
the path's head or tail. So with ``T`` the connectors holding a counted stretch, the
non-lane path is at least ``P`` (the stretches, on whichever connectors hold them) plus the
length of the connectors not in ``T``, each at least its travel across the lines (lanes and
run-ins run along them). Cut the lanes' sequence at the connectors of ``T``: it falls into
``|T| + 1`` groups, and the connectors inside a group travel across at least the span of its
lines. The groups' spans cover every line with lanes but at most ``|T|`` gaps between
consecutive such lines (the union of ``|T| + 1`` intervals has at most ``|T|`` holes, each
inside one gap, since the lines are in the union), so they add up to at least ``C`` (the
lines' span, ``(k_max - k_min) s``) less the ``|T|`` largest gaps (:func:`line_moves`).

``|T|`` is at most the number of passes holding a counted stretch (:func:`pass_count`): the
planner keeps the contour's flagged runs per ring and drives runs less than ``MERGE_GAP = 2``
spacings apart along the ring as one pass (``plan/contour._runs``, which also joins the first
and last run of a ring), and a run reaches at least over its stretch's core (the unflagged
samples that end it lie outside the core). So two counted cores of one ring whose gap along
the ring is under two spacings are in one pass: the counted cores of a ring (sorted along it)
fall into as many passes at most as there are gaps of two spacings or more between
consecutive ones round the ring (one if none). A stretch counted by the rule near the lanes'
direction (:func:`~.inside_bound._near_lengths`) counts one pass for each part of its union
of flagged stretches (each holds a run of consecutive flagged samples) and is not merged.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["MERGE_SPACINGS", "line_moves", "pass_count"]

#: The planner's merge gap (``plan/contour.MERGE_GAP`` spacings, a later layer: not imported)
#: less a millionth for rounding: counted cores of one ring closer than this along it lie in
#: one pass.
MERGE_SPACINGS = 2.0 * (1 - 1e-6)


def pass_count(
    arc: NDArray[np.float64],
    total: NDArray[np.float64],
    ring: NDArray[np.int64],
    far: NDArray[np.bool_],
    near_parts: NDArray[np.int64] | None,
    spacing: float,
) -> NDArray[np.int64]:
    """``(L,)`` an upper bound on the passes holding a counted stretch (module docstring):
    ``arc (S, 2)`` each stretch's core along its ring (arc lengths, ascending per ring in
    stretch order), ``total (S,)`` its ring's length, ``far (L, S)`` the stretches counted
    whole by the angle rule, ``near_parts (L, S)`` the parts counted by the rule near the lanes'
    direction (0 where none)."""
    n_l = far.shape[0]
    out = np.zeros(n_l, dtype=np.int64)
    if near_parts is not None:
        out += near_parts.sum(axis=1)
    if not far.any():
        return out
    merge = MERGE_SPACINGS * spacing
    for r in np.unique(ring):
        cols = np.flatnonzero(ring == r)
        if not far[:, cols].any():
            continue
        order = cols[np.argsort(arc[cols, 0], kind="stable")]
        f = far[:, order]  # (L, m), the ring's stretches along it
        lo, hi = arc[order, 0], arc[order, 1]
        m = len(order)
        idx = np.where(f, np.arange(m)[None, :], -1)
        last = np.maximum.accumulate(idx, axis=1)  # the last counted at or before each
        prev = np.concatenate([np.full((n_l, 1), -1), last[:, :-1]], axis=1)
        final = last[:, -1]  # the ring's last counted stretch (the first one's predecessor)
        wrap = prev < 0
        p = np.where(wrap, final[:, None], prev)
        gap = lo[None, :] - hi[np.maximum(p, 0)] + np.where(wrap, total[order[0]], 0.0)
        breaks = (f & (gap >= merge)).sum(axis=1)
        out += np.where(f.any(axis=1), np.maximum(breaks, 1), 0)
    return out


def line_moves(
    count: NDArray[np.int64], spacing: float, passes: NDArray[np.int64]
) -> NDArray[np.float64]:
    """``(L,)`` the connectors' travel across the lines outside ``passes`` connectors (module
    docstring): the span of the lines with ``count >= 1`` less the ``passes`` largest gaps
    between consecutive ones (0 where they take it all)."""
    used = count >= 1
    n_l, nb = used.shape
    idx = np.where(used, np.arange(nb)[None, :], -1)
    prev = np.concatenate([np.full((n_l, 1), -1), np.maximum.accumulate(idx, axis=1)[:, :-1]], 1)
    gaps = np.where(used & (prev >= 0), (np.arange(nb)[None, :] - prev) * spacing, 0.0)
    top = -np.sort(-gaps, axis=1)  # descending
    cum = np.concatenate([np.zeros((n_l, 1)), np.cumsum(top, axis=1)], axis=1)
    span = cum[:, -1]
    taken = cum[np.arange(n_l), np.minimum(passes, nb)]
    return np.maximum(span - taken, 0.0)
