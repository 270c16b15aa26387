"""Thin spikes cut off a decomposition's cells before their searches (issue 16's 5 s).

A cell's boundary can fold back on itself: a cut of the slab decomposition through a hole's
vertex, nearly parallel to the hole's next edge, leaves a spike millimetres wide and metres long
(random area 37 of ``benchmarks/mission_time.py``: 3.6 mm by 17 m). Every plan's lane on the
line through it runs its length, but the cover search's lower bound over a box erodes the cell
by the box's radius, which removes the spike as soon as the radius passes its width: the boxes
around the best layouts then stay a few seconds below the plans at their centres until the
smallest radius (a thousandth of a spacing), and the search halves tens of thousands of boxes
(that cell: 11.4 s of random 37's 13 s). A spike thinner than that smallest radius cannot be
resolved by the search; :func:`cut_slivers` cuts it at its base (the foot of the shorter side's
end on the longer side), which changes the cell by less than ``width`` times the spike's length.
The cells are planned whole (the plan covers the spike; a lane may run along it), and a cell
searched without a spike reports no certificate (``certified`` false, ``spikes_cut`` true):
the search's is the cut cell's.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidPolygonError
from ..geometry.region import Region

__all__ = ["cut_slivers", "cut_spikes"]


def cut_spikes(ring: NDArray[np.float64], width: float) -> NDArray[np.float64]:
    """The ring with every spike narrower than ``width`` cut at its base: at a vertex where
    the boundary folds back (its two edges leave it on the same side, an acute angle) and the
    shorter edge's far end lies within ``width`` of the longer edge's line, the vertex moves to
    that end's foot on the longer edge (or goes, where the foot is the longer edge's far end).
    Repeated until no such vertex is left; the ring unchanged (the same array) if none."""
    v = np.asarray(ring, dtype=np.float64)
    for _ in range(len(v)):  # each step moves or removes a vertex of a spike; at most n spikes
        step = _cut_one(v, width)
        if step is None:
            return v
        v = step
    return np.asarray(ring, dtype=np.float64)  # no end in sight: the ring as given


def _cut_one(v: NDArray[np.float64], width: float) -> NDArray[np.float64] | None:
    """The ring with its first spike narrower than ``width`` cut (:func:`cut_spikes`); ``None``
    if there is none. Acute means the edges' cosine above ``1e-9`` (a tip just moved to its foot
    is a right angle, which rounding can make a hair acute), and a vertex whose foot is itself
    is not a spike."""
    if len(v) <= 3:
        return None
    for i in range(len(v)):
        a, p, b = v[i - 1], v[i], v[(i + 1) % len(v)]
        u1, u2 = a - p, b - p
        l1, l2 = float(np.hypot(*u1)), float(np.hypot(*u2))
        if min(l1, l2) <= 0 or float(u1 @ u2) <= 1e-9 * l1 * l2:
            continue
        ul, ll, us = (u1, l1, u2) if l1 >= l2 else (u2, l2, u1)
        if abs(float(ul[0] * us[1] - ul[1] * us[0])) / ll > width:
            continue
        foot = p + ul * (float(ul @ us) / (ll * ll))
        if float(np.hypot(*(foot - p))) <= 1e-12 * ll:
            continue
        near = a if l1 >= l2 else b  # the longer edge's far end
        if float(np.hypot(*(foot - near))) <= width:
            return np.delete(v, i, axis=0)
        out = v.copy()
        out[i] = foot
        return out
    return None


def cut_slivers(cell: Region, width: float) -> Region:
    """The cell with the spikes of its shell and holes narrower than ``width`` cut
    (:func:`cut_spikes`); the cell itself where there is none, or where the cut rings would not
    make a valid region."""
    rings = [r.vertices for r in (cell.shell, *cell.holes)]
    cut = [cut_spikes(r, width) for r in rings]
    if all(c is r for c, r in zip(cut, rings, strict=True)):
        return cell
    try:
        return Region(cut[0], cut[1:])
    except InvalidPolygonError:
        return cell
