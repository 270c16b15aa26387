"""A lower bound on a routed tour's connecting moves from where its lanes can end.

Every plan of a box of layouts flies lanes on the centre grid's lines ``k`` (the area moves,
not the grid), joined into one path by connecting moves (routed around the area's corners,
never shorter than the straight segment between the two ends they join). Per line ``k`` the
band statistics give, for every area between the sandwich's inner and outer sets: the lanes lie
inside the outer projection ``[A_k, B_k]``; the leftmost lane starts in ``[A_k, a_k]`` and the
rightmost ends in ``[b_k, B_k]`` (``a_k, b_k``: the inner projection's extremes, which some lane
covers); ``count_k`` lanes at least.

**The argument** (docs/mission_time.md, "The lanes' ends"). Every line with ``count_k >= 1``
has its leftmost end in ``[A_k, a_k]`` and its rightmost in ``[b_k, B_k]``; each of these two
ends ``e`` gets the charge ``c(e) = min(per_length * D(e) / 2, per_turn / 4)``, ``D(e)`` a lower
bound on the distance from ``e`` to every place where the other end of its move can be without
an extra lane paying for it: the two extreme zones of another line with lanes; on a line with
``count_j >= 2``, also ``[f_j, l_j]`` (the end of its first inner piece, the start of its last:
the lanes holding those pieces end at or beyond them, and every lane between lies between); on
``e``'s own line, when ``count_k >= 2``, beyond ``f_k`` (for the leftmost end; before ``l_k``
for the rightmost): another lane of the line starts after the first piece's lane ends; a hole
pass (the pass drives the hole's own ring: the hole's box across and along the lines, grown by
the box's radius). Then ``sum c(e)`` minus the two largest charges (the path's two free ends)
is at most ``per_length * moves + per_turn * sum_k (lanes_k - count_k)``. With ``E_k = lanes_k -
count_k`` extra lanes on line ``k``:

* a line with ``E_k >= 1`` pays its own two charges (``per_turn / 2``) out of ``per_turn E_k``;
* with ``E_k = 0`` (one lane per counted piece, no other: the extreme lanes hold the first and
  the last inner piece), each end's move (half of it counted from each side) reaches another
  pass: at one of the places above (then ``per_length * move / 2 >= c(e)``), or at an end the
  list leaves out, charged ``per_turn / 4`` to its line ``j``, which then has ``E_j >= 1``: at
  most ``2 E_j`` such ends (on a line with ``count_j = 0`` its ``2 n_j`` ends; with ``count_j =
  1`` the ``2 (n_j - 1)`` inner ends; with ``count_j >= 2``, ``m`` lanes without an inner piece
  beside the first piece's lane hold ``2 m`` such ends, that lane's displaced end included, and
  ``m <= E_j``), so with its own two charges ``per_turn / 2 + per_turn E_j / 2 <= per_turn E_j``.

Run-ins and run-outs move the ends outward by ``turnaround``: every range is grown by it. Not
for keep-inside plans (boundary passes are further passes) nor headland passes.
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

__all__ = ["HoleBoxes", "hole_boxes", "lane_end_bound"]

#: ``(L, H, 4)``: per layout and hole, ``v_lo, v_hi`` (across the lines, in the grid's frame
#: ``n . (p - o) - d``) and ``u_lo, u_hi`` (along them), grown by the box's radius.
HoleBoxes = NDArray[np.float64]


def hole_boxes(
    hole_xy: NDArray[np.float64],
    hole_start: NDArray[np.int64],
    theta: NDArray[np.float64],
    d: NDArray[np.float64],
    origin: NDArray[np.float64],
    grow: float,
) -> HoleBoxes:
    """The box of each hole in each layout's frame (lines at ``v = k * spacing``), grown by
    ``grow`` on every side: it holds the hole of every rigid image whose points moved by at
    most ``grow``, hence that image's hole pass."""
    n_holes = len(hole_start) - 1
    out = np.zeros((len(theta), n_holes, 4))
    if n_holes == 0:
        return out
    xy = hole_xy - origin
    cs, sn = np.cos(theta)[:, None], np.sin(theta)[:, None]
    v = -sn * xy[None, :, 0] + cs * xy[None, :, 1] - d[:, None]
    u = cs * xy[None, :, 0] + sn * xy[None, :, 1]
    for h in range(n_holes):
        sl = slice(int(hole_start[h]), int(hole_start[h + 1]))
        out[:, h, 0] = v[:, sl].min(axis=1) - grow
        out[:, h, 1] = v[:, sl].max(axis=1) + grow
        out[:, h, 2] = u[:, sl].min(axis=1) - grow
        out[:, h, 3] = u[:, sl].max(axis=1) + grow
    return out


def _ends(count, out_lo, in_lo, in_hi, out_hi, first_hi, last_lo, holes, k0, s, t, cap, window):
    """Per layout: the sum of ``min(D(e), cap)`` over the extreme ends ``e`` of the lines with
    lanes, minus its two largest terms (plain Python, compiled by numba on first use)."""
    n_layouts, nb = count.shape
    n_holes = holes.shape[1]
    out = np.zeros(n_layouts)
    for la in range(n_layouts):
        total, m1, m2 = 0.0, 0.0, 0.0
        for k in range(nb):
            if count[la, k] < 1:
                continue
            v = (k0 + k) * s
            for z in range(2):
                lo = out_lo[la, k] - t if z == 0 else in_hi[la, k]
                hi = in_lo[la, k] if z == 0 else out_hi[la, k] + t
                best = cap
                if count[la, k] >= 2:  # another lane of the line: beyond the first inner piece
                    p_lo = first_hi[la, k] - t if z == 0 else out_lo[la, k] - t
                    p_hi = out_hi[la, k] + t if z == 0 else last_lo[la, k] + t
                    best = min(best, max(max(lo, p_lo) - min(hi, p_hi), 0.0))
                for off in range(1, window + 1):
                    dv = off * s
                    if dv >= best:
                        break
                    for j in (k - off, k + off):
                        if j < 0 or j >= nb or count[la, j] < 1:
                            continue
                        g = max(max(lo, out_lo[la, j] - t) - min(hi, in_lo[la, j]), 0.0)
                        g = min(g, max(max(lo, in_hi[la, j]) - min(hi, out_hi[la, j] + t), 0.0))
                        if count[la, j] >= 2:
                            m_lo, m_hi = first_hi[la, j] - t, last_lo[la, j] + t
                            g = min(g, max(max(lo, m_lo) - min(hi, m_hi), 0.0))
                        best = min(best, math.sqrt(dv * dv + g * g))
                for h in range(n_holes):
                    dv = max(max(holes[la, h, 0] - v, v - holes[la, h, 1]), 0.0)
                    du = max(max(holes[la, h, 2] - hi, lo - holes[la, h, 3]), 0.0)
                    best = min(best, math.sqrt(dv * dv + du * du))
                total += best
                if best > m1:
                    m1, m2 = best, m1
                elif best > m2:
                    m2 = best
        out[la] = max(0.0, total - m1 - m2)
    return out


@cache
def _compiled() -> Any:
    """The loop compiled by numba (cached on disk), or the plain Python one without numba."""
    return compiled(globals(), "_ends")


def lane_end_bound(
    st: BandStats, spacing: float, cost: CoverCost, holes: HoleBoxes | None
) -> NDArray[np.float64]:
    """``(L,)`` a lower bound, in cost units, on ``per_length * moves + per_turn * (lanes -
    sum(count))`` of every plan of each layout's sandwich (module docstring)."""
    n_layouts = st.count.shape[0]
    pl, pt = cost.per_length, cost.per_turn
    used = st.count >= 1
    cols = np.nonzero(used.any(axis=0))[0]
    if pl <= 0 or pt <= 0 or not len(cols):
        return np.zeros(n_layouts)
    c0, c1 = int(cols[0]), int(cols[-1]) + 1  # the lines that hold lanes in some layout
    cap_dist = pt / (2.0 * pl)  # D beyond which a charge is capped at per_turn / 4
    window = max(1, math.ceil(cap_dist / spacing))
    if holes is None:
        holes = np.zeros((n_layouts, 0, 4))

    def crop(a: NDArray[Any]) -> NDArray[Any]:
        return np.ascontiguousarray(a[:, c0:c1])

    sums = _compiled()(
        crop(st.count), crop(st.out_lo), crop(st.in_lo), crop(st.in_hi), crop(st.out_hi),
        crop(st.first_hi), crop(st.last_lo), np.ascontiguousarray(holes, dtype=np.float64),
        int(st.k0 + c0), float(spacing), float(cost.turnaround), float(cap_dist), int(window),
    )  # fmt: skip
    return 0.5 * pl * sums
