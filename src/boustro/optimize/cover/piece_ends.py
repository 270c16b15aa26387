"""A lower bound on a routed tour's connecting moves from where EVERY counted piece's lane ends,
the hole passes contracted (docs/mission_time.md, "Every piece's ends").

A second charging of the lane ends (beside :mod:`~boustro.optimize.cover.ends`, the larger of
the two is used). Per line ``k`` with ``count_k >= 1`` the charged ends are the leftmost end (in
``[A_k - t, a_k]``) and the rightmost (in ``[b_k, B_k + t]``) and, with ``count_k >= 2``, the
end of the lane holding the first inner piece (in ``[first_hi_k, P1_k + t]``, ``P1_k`` the end
of the first counted outer piece, :attr:`BandStats.pieces`) and the start of the lane holding
the last (in ``[PL_k - t, last_lo_k]``).

**Hole passes are contracted.** A hole pass is a closed loop: it is entered and left at the
same point ``x``, so the two moves beside it are at least ``|e - x| + |x - f| >= |e - f|``, a
straight move between the two lane ends ``e, f`` around it (a pass at either end of the tour
drops its move, making a lane end a free end). The bound is about that tour of lanes only.

**Every end of a line with lanes lies in a place.** On a line ``j`` with ``count_j >= 1`` let
``P`` and ``Q`` be the lanes holding its first and last inner pieces: lanes before ``P`` and
``P``'s start lie in ``[A_j, a_j]``, lanes after ``Q`` and ``Q``'s end in ``[b_j, B_j]``, and
every other end (``P``'s end, ``Q``'s start, the lanes between) in ``[first_hi_j, last_lo_j]``
(when ``P = Q``, its end is in ``[b_j, B_j]``). These three zones (grown by the run-ins ``t``)
are the *places* of line ``j``.

**The charges.** An end ``e`` on line ``k`` gets ``v(e) = min(D(e) / 2, T + D0(e))``, with ``T
= per_turn / (2 per_length)``, ``D(e)`` the distance from its zone to the places of the other
lines with lanes and to its own line's *own places* (where another lane of its line lies when
the line has no extra lane: beyond ``first_hi_k`` for the leftmost end, from the second counted
piece's start ``P2_k`` on for the first piece's lane's end; symmetric on the right), and
``D0(e)`` the distance to the lines with ``count = 0`` whose outer projection is not empty.
Per line the charges add up to at most ``2 T``. Then ``sum - (the two largest v)`` is at most
``moves + (per_turn / per_length) * sum_k (lanes_k - count_k)``:

* every non-free charged end ``e`` has a (contracted) move to an end ``f``. If ``f`` lies in a
  place of ``e``, the move is at least ``D(e)``; half of it pays ``v(e)`` (the other half, if
  ``f`` is charged, pays ``f``);
* if ``f`` is on another line with lanes, it lies in a place (above). If it is on a line
  ``j`` with ``count_j = 0``, that line's ``E_j = n_j`` extra lanes have ``2 E_j`` ends, each
  paying ``T`` (``per_turn / 2``) from their ``per_turn E_j``, ``f`` uncharged, and the whole
  move ``>= D0(e)`` pays the rest;
* if ``f`` is on ``e``'s own line outside its own places, that line has an extra lane
  (``E_k >= 1``): its charges, at most ``2 T`` in all, are paid from its ``per_turn E_k``.
"""

from __future__ import annotations

import math
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..._jit import compiled
from .bands import BandStats
from .cost import CoverCost

__all__ = ["piece_end_bound"]


def _gap(lo, hi, lo2, hi2):
    """Distance between the intervals ``[lo, hi]`` and ``[lo2, hi2]`` (0 where they meet)."""
    return max(max(lo, lo2) - min(hi, hi2), 0.0)


def _charges(count, out_lo, in_lo, in_hi, out_hi, first_hi, last_lo, pieces, s, t, half, window):
    """Per layout: ``sum_k min(sum of line k's v(e), 2 half)`` minus the two path ends' charges
    (module docstring; plain Python, compiled by numba on first use)."""
    n_layouts, nb = count.shape
    out = np.zeros(n_layouts)
    zlo, zhi = np.empty(4), np.empty(4)
    olo, ohi = np.empty(4), np.empty(4)
    vals = np.empty(4)
    for la in range(n_layouts):
        total, m1, m2, lanes, lone = 0.0, 0.0, 0.0, 0, 0.0
        for k in range(nb):
            c = count[la, k]
            if c < 1:
                continue
            zlo[0], zhi[0] = out_lo[la, k] - t, in_lo[la, k]
            zlo[1], zhi[1] = in_hi[la, k], out_hi[la, k] + t
            olo[0], ohi[0] = math.inf, -math.inf  # one lane: no other lane on the line
            olo[1], ohi[1] = math.inf, -math.inf
            n_z = 2
            if c >= 2:
                olo[0], ohi[0] = first_hi[la, k] - t, out_hi[la, k] + t
                olo[1], ohi[1] = out_lo[la, k] - t, last_lo[la, k] + t
                zlo[2], zhi[2] = first_hi[la, k], pieces[la, k, 0] + t
                olo[2], ohi[2] = pieces[la, k, 1] - t, out_hi[la, k] + t
                zlo[3], zhi[3] = pieces[la, k, 2] - t, last_lo[la, k]
                olo[3], ohi[3] = out_lo[la, k] - t, pieces[la, k, 3] + t
                n_z = 4
            near = 0  # count-0 lines with an outer projection within half: look that far
            for off in range(1, min(window, int(half / s) + 1) + 1):
                for j in (k - off, k + off):
                    if 0 <= j < nb and count[la, j] == 0 and not math.isnan(out_lo[la, j]):
                        near = off
            line = 0.0
            for z in range(n_z):
                lo, hi = zlo[z], zhi[z]
                d0 = half  # beyond it the other term is the cap
                for off in range(1, near + 1):
                    dv = off * s
                    if dv >= d0:
                        break
                    for j in (k - off, k + off):
                        if j < 0 or j >= nb or count[la, j] != 0 or math.isnan(out_lo[la, j]):
                            continue
                        g = _gap(lo, hi, out_lo[la, j] - t, out_hi[la, j] + t)
                        d0 = min(d0, math.sqrt(dv * dv + g * g))
                best = min(4.0 * half, 2.0 * (half + d0))
                if olo[z] <= ohi[z]:
                    best = min(best, _gap(lo, hi, olo[z], ohi[z]))
                for off in range(1, window + 1):
                    dv = off * s
                    if dv >= best:
                        break
                    for j in (k - off, k + off):
                        if j < 0 or j >= nb or count[la, j] < 1:
                            continue
                        g = max(max(lo, out_lo[la, j] - t) - min(hi, in_lo[la, j]), 0.0)
                        g2 = max(max(lo, in_hi[la, j]) - min(hi, out_hi[la, j] + t), 0.0)
                        g = min(g, g2)
                        if g > 0.0 and first_hi[la, j] <= last_lo[la, j]:
                            g2 = max(
                                max(lo, first_hi[la, j] - t) - min(hi, last_lo[la, j] + t), 0.0
                            )
                            g = min(g, g2)
                        best = min(best, math.sqrt(dv * dv + g * g))
                vals[z] = 0.5 * best
                line += vals[z]
            total += min(line, 2.0 * half)
            # the lanes' largest charges: ends 0 and 2 are one lane's, 1 and 3 another's
            if n_z == 2:
                lane_max = (max(vals[0], vals[1]), -1.0)
                lone = vals[0] + vals[1]
            else:
                lane_max = (max(vals[0], vals[2]), max(vals[1], vals[3]))
            for v in lane_max:
                if v < 0:
                    continue
                lanes += 1
                if v > m1:
                    m1, m2 = v, m1
                elif v > m2:
                    m2 = v
        free = lone if lanes == 1 else m1 + m2  # one lane: both its ends may be free
        out[la] = max(0.0, total - free)
    return out


@cache
def _compiled() -> Any:
    """The loop compiled by numba (cached on disk), or the plain Python one without numba."""
    return compiled(globals(), "_charges", ("_gap",))


def piece_end_bound(st: BandStats, spacing: float, cost: CoverCost) -> NDArray[np.float64]:
    """``(L,)`` a lower bound, in cost units, on ``per_length * moves + per_turn * (lanes -
    sum(count))`` of every plan of each layout's sandwich (module docstring)."""
    n_layouts = st.count.shape[0]
    pl, pt = cost.per_length, cost.per_turn
    cols = np.nonzero((st.count >= 1).any(axis=0))[0]
    if pl <= 0 or pt <= 0 or not len(cols):
        return np.zeros(n_layouts)
    half = pt / (2.0 * pl)
    window = max(1, math.ceil(4.0 * half / spacing))
    # the lines that may hold lanes in some layout (count-0 lines matter for D0)
    may = np.nonzero(np.isfinite(st.out_lo).any(axis=0))[0]
    c0, c1 = int(may[0]), int(may[-1]) + 1

    def crop(a: NDArray[Any]) -> NDArray[Any]:
        return np.ascontiguousarray(a[:, c0:c1])

    sums = _compiled()(
        crop(st.count), crop(st.out_lo), crop(st.in_lo), crop(st.in_hi), crop(st.out_hi),
        crop(st.first_hi), crop(st.last_lo), crop(st.pieces), float(spacing),
        float(cost.turnaround), float(half), int(window),
    )  # fmt: skip
    return pl * sums
