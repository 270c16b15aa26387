"""A lower bound on a routed tour's connecting moves from where its lanes can end.

Every plan of a box of layouts flies lanes on the centre grid's lines ``k`` (the area moves,
not the grid), joined into one path by connecting moves (routed around the area's corners,
never shorter than the straight segment between the two ends they join). Per line ``k`` the
band statistics give, for every area between the sandwich's inner and outer sets: the lanes lie
inside the outer projection ``[A_k, B_k]``; the leftmost lane starts in ``[A_k, a_k]`` and the
rightmost ends in ``[b_k, B_k]`` (``a_k, b_k``: the inner projection's extremes, which some lane
covers); ``count_k`` lanes at least.

**The argument** (docs/mission_time.md, "The lanes' ends"). Call a line *regular* when
``count_k = 1``; its two extreme ends ``e`` each get the charge ``c(e) = min(per_length * D(e) /
2, per_turn / 4)``, ``D(e)`` a lower bound on the distance from ``e`` to every place where the
other end of its move can be without an extra lane paying for it: the two extreme zones of
another line with lanes; on a line with ``count_j >= 2``, also ``[f_j, l_j]`` (the end of its
first inner piece, the start of its last: the lanes holding those pieces end at or beyond
them, and every lane between lies between); a hole pass (the pass drives the hole's own ring:
the hole's box across and along the lines, grown by the box's radius). Then ``sum c(e)`` minus
the two largest charges (the path's two free ends) is at most ``per_length * moves + per_turn *
(lanes - sum count)``:

* a regular line that holds ``n >= 2`` lanes pays its own two charges (``per_turn / 2``) out of
  its extra turns ``per_turn (n - 1)``;
* with one lane, each end's move (half of it counted from each side) reaches another pass: at
  one of the places above (then ``per_length * move / 2 >= c(e)``), or at an end the list
  leaves out, charged ``per_turn / 4`` to its line's extra lanes: an inner end of a regular
  line with ``n >= 2`` lanes (``2 (n - 1)`` of them; with its own two charges ``per_turn n / 2
  <= per_turn (n - 1)``), an end on a line with ``count = 0`` (``2 n`` ends, ``per_turn n / 2``
  of ``per_turn n``), or on a line with ``count >= 2`` an end of a lane left of the lane holding
  the first inner piece (such a lane holds no inner piece: an extra lane, ``m >= 1`` of them
  with ``2 m`` ends and the displaced left end of the first piece's lane, ``(2 m + 1) / 4 <=
  m`` turns), likewise on the right.

Run-ins and run-outs move the ends outward by ``turnaround``: every range is grown by it. Not
for keep-inside plans (boundary passes are further passes) nor headland passes.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

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


def _gap(
    lo: NDArray[np.float64], hi: NDArray[np.float64], lo2: NDArray[np.float64], hi2: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Distance between intervals (0 where they meet; ``inf`` where one is empty: ``nan``)."""
    g = np.maximum(0.0, np.maximum(lo, lo2) - np.minimum(hi, hi2))
    return np.where(np.isnan(g), np.inf, g)


def lane_end_bound(
    st: BandStats, spacing: float, cost: CoverCost, holes: HoleBoxes | None
) -> NDArray[np.float64]:
    """``(L,)`` a lower bound, in cost units, on ``per_length * moves + per_turn * (lanes -
    sum(count))`` of every plan of each layout's sandwich (module docstring)."""
    n_layouts, nb = st.count.shape
    pl, pt = cost.per_length, cost.per_turn
    if pl <= 0 or pt <= 0 or nb == 0:
        return np.zeros(n_layouts)
    cap_dist = pt / (2.0 * pl)  # D beyond which a charge is capped
    window = max(1, math.ceil(cap_dist / spacing))
    t = cost.turnaround
    reg = st.count == 1
    used = st.count >= 1
    many = st.count >= 2
    nan = np.full_like(st.in_lo, np.nan)
    # where the ends that are not charged lie: the two extreme zones of a line with lanes, and
    # on a line with 2+ lanes between the end of its first inner piece and the start of its last
    l_lo, l_hi = np.where(used, st.out_lo - t, nan), np.where(used, st.in_lo, nan)
    r_lo, r_hi = np.where(used, st.in_hi, nan), np.where(used, st.out_hi + t, nan)
    m_lo, m_hi = np.where(many, st.first_hi - t, nan), np.where(many, st.last_lo + t, nan)
    zones = ((l_lo, l_hi), (r_lo, r_hi))
    best = [np.full((n_layouts, nb), np.inf), np.full((n_layouts, nb), np.inf)]
    for off in range(1, window + 1):
        dv2 = (off * spacing) ** 2
        for sign in (1, -1):
            a = slice(0, nb - off) if sign > 0 else slice(off, nb)
            b = slice(off, nb) if sign > 0 else slice(0, nb - off)
            for z, (lo, hi) in enumerate(zones):
                g = np.minimum(
                    np.minimum(_gap(lo[:, a], hi[:, a], l_lo[:, b], l_hi[:, b]),
                               _gap(lo[:, a], hi[:, a], r_lo[:, b], r_hi[:, b])),
                    _gap(lo[:, a], hi[:, a], m_lo[:, b], m_hi[:, b]),
                )  # fmt: skip
                best[z][:, a] = np.minimum(best[z][:, a], np.sqrt(dv2 + g**2))
    if holes is not None and holes.shape[1]:
        v = (np.arange(nb) + st.k0) * spacing  # line centres in the holes' frame
        dv = np.maximum(
            0.0,
            np.maximum(holes[:, None, :, 0] - v[None, :, None], v[None, :, None] - holes[:, None, :, 1]),
        )  # (L, B, H)
        for z, (lo, hi) in enumerate(zones):
            du = np.maximum(
                0.0,
                np.maximum(holes[:, None, :, 2] - hi[:, :, None], lo[:, :, None] - holes[:, None, :, 3]),
            )
            best[z] = np.minimum(best[z], np.sqrt(dv**2 + du**2).min(axis=2))
    charges = [
        np.where(reg, np.minimum(0.5 * pl * np.nan_to_num(b, posinf=cap_dist), pt / 4.0), 0.0)
        for b in best
    ]
    c = np.concatenate(charges, axis=1)
    top2 = -np.partition(-c, 1, axis=1)[:, :2].sum(axis=1) if c.shape[1] >= 2 else c.sum(axis=1)
    return np.maximum(0.0, c.sum(axis=1) - top2)
