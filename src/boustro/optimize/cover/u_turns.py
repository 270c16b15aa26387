"""The least length of a vehicle's U-turns between lanes (a floor of the moves with a radius).

A move that leaves a lane heading ``d`` and enters a lane flown ``-d`` turns the vehicle's
heading (its orientation, with reverse) by ``pi`` (mod ``2 pi``). With curvature at most ``1/R``
(``|theta'| <= 1/R`` per unit of path, forward or reverse) its length ``L`` satisfies, for an
along-offset ``a`` and a lateral offset ``w`` (across ``d``) between its ends, ``|dp| =
sqrt(a^2 + w^2)``:

* ``L >= pi R``: the orientation rotates by at least ``pi``.
* ``L >= |dp| + (pi - 2) R`` (forward or reverse): for the unit vector ``e`` along ``dp`` split
  ``L = int |e . p'| + int (1 - |e . p'|)``; the first is at least ``|dp|``; in the second
  ``|e . p'| = |cos(theta - alpha)|`` (reverse flips ``p'``, not its absolute product) and
  ``ds >= R |dtheta|``, so it is at least ``R |H(theta_end) - H(theta_0)|`` with ``H(t) =
  int_0^t (1 - |cos(u - alpha)|) du`` nondecreasing and ``H(t + pi) - H(t) = pi - 2`` for
  every ``t``; ``theta_end - theta_0 = pi + 2 k pi``, so at least ``(pi - 2) R``.
* forward only (Dubins): ``L >= pi R + | |w| - 2R |``. The left circle's centre ``c_L = p + R
  (-sin theta, cos theta)`` moves at speed ``1 - R theta' >= 0``, so ``L - R (theta_end -
  theta_0) >= |c_L(end) - c_L(0)| >= |w - 2R|`` (heading ``0`` to ``pi + 2 k pi``, ``w`` to
  the left); for ``k >= 0`` that is ``L >= pi R + |w - 2R|``; for ``k <= -1`` the right circle's
  centre (speed ``1 + R theta'``) gives ``L >= pi R + |w + 2R|``. Equal to the half circle for
  ``w = 2R`` and to Dubins's ``pi R + w - 2R`` for ``w >= 2R``; for ``w < 2R`` above ``pi R``.
* forward only, ``|w| < 2R`` (the bulb): ``L >= B(w) = R (pi + 2 acos(|w| / 2R))`` for every
  along-offset, the least Dubins U-turn (an RL or LR word: a turn by ``acos(|w| / 2R)`` away,
  then ``pi`` plus as much back; ``2 pi R`` at ``w = 0``, ``pi R`` at ``2R``). Proof: a
  shortest forward path of curvature at most ``1/R`` between two poses exists and is a word
  CSC or CCC of arcs of radius ``R`` (some possibly empty) and, for CCC, a middle arc longer
  than ``pi R`` (Dubins 1957), so it suffices that every such word from ``(0, 0, 0)`` to a
  heading ``pi`` (mod ``2 pi``) at a lateral ``v``, ``|v| < 2R``, has length ``>= B(v)``. Take
  ``R = 1`` (lengths scale with ``R``); arcs turn by ``t, p, q >= 0``, the straight is ``s``.
  ``B <= 2 pi``, so a word turning ``2 pi`` in all is long enough; reflecting ``y`` swaps L and
  R and maps ``(v, pi)`` to ``(-v, -pi)``, the same heading, and ``B`` depends on ``|v|``: so
  only LSL, LSR and LRL turning less than ``2 pi`` remain. A left arc from heading ``h`` by
  ``t`` moves ``y`` by ``cos h - cos(h + t)``, a right one by ``cos(h - t) - cos h``.
  LSL: ``t + q = pi``, ``v = (1 - cos t) + s sin t + (cos t + 1) >= 2`` (``t`` in ``[0, pi]``).
  LSR: ``t - q = +-pi``: with ``u = min(t, q)`` in ``[0, pi/2)`` the length is ``pi + 2u + s``
  and ``v = -2 cos t + s sin t = +-(2 cos u - s sin u)``. With ``x = s / 2``: if ``u + x >=
  pi/2`` the length is ``>= 2 pi >= B``; else ``f(x) = cos u - x sin u - cos(u + x)`` has
  ``f(0) = 0`` and ``f' = sin(u + x) - sin u >= 0``, so ``|v| / 2 = cos u - x sin u >= cos(u +
  x)`` and ``acos(|v| / 2) <= u + x``: the length ``pi + 2 (u + x) >= B``. LRL (middle arc
  ``p > pi``): ``t - p + q = pi`` turns ``pi + 2p > 3 pi``; else ``t - p + q = -pi``, ``p = pi +
  g``, ``t + q = g``, the length ``pi + 2g``, ``v = 2 (1 - cos t + cos(t - p)) = 2 (1 - cos t -
  cos q)``; ``g >= pi/2`` is long enough, else ``cos t + cos q = 2 cos(g/2) cos((t - q)/2) >=
  2 cos^2(g/2) = 1 + cos g`` (``|t - q| <= g``), so ``v / 2 <= -cos g < 0``, ``|v| / 2 >= cos
  g`` and ``acos(|v| / 2) <= g``. So ``L >= B(w)`` for every along-offset (and ``B`` is reached:
  tight). ``B`` is above ``pi R + 2R - |w|`` (``acos(x) >= 1 - x`` on ``[0, 1]``). Its slope is
  infinite at ``2R``, so it is taken at the lateral offset raised by :data:`LATERAL_SLACK` of
  ``w + R`` (a lane end on its line up to rounding: the plan's turn between the real ends, a
  lateral rounding away, is at least the floor there; it gives up at most ``2R sqrt(3e-9)``, a
  ten-thousandth of ``R``, at ``w`` near ``2R``). Reeds-Shepp keeps the first two floors (a
  vehicle that reverses needs no bulb: its cusps turn it within ``2R``).

The plans of the convex planner with a vehicle (:func:`boustro.vehicle.lane_order`: the
boustrophedon or every other lane, each lane flown against the one before) have one lane per
line and every move is such a U-turn between lanes ``1 <= j <= 2`` lines apart
(:data:`CONVEX_MAX_LINES`): its lateral offset is exactly ``j * spacing`` (the ends lie on
their lines). :func:`u_turn_moves` bounds the sum of
``M`` such moves from below by the larger of ``M * min_j f(j)`` and ``span + M (pi - 2) R``
(``f(j)`` the larger of the floors above at ``w = j spacing``, ``span`` the lateral distance
the moves must cover). Where the lines that every plan of the layouts fills with lanes include
both parities, a plan's order steps at least once from one parity to the other, a move across
an odd number of lines (one, for the convex planner's): a plan's ``M' >= M`` moves are at
least ``min_{j odd} f(j) + (M' - 1) min_j f(j)``, so one of the ``M`` is charged the odd
least (at 10 m spacing and 8 m forward, 39.5 m instead of 29.1 m: the skip pattern's one move
of one line is a bulb). A move of the plan that is not flown as a turn (a turn that would leave
the field or enter a hole keeps its straight move), a lane shorter than the heading's
threshold (``1e-12``, :mod:`boustro.plan.vehicle_path`) or a hole pass (a closed polygonal
loop whose exit heading is not its entry heading) break the premise, so the floor is only
given to the search for the convex planner's plans without headland passes or keep-inside
(:func:`boustro.mission.cover.plan_cover`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["CONVEX_MAX_LINES", "UTurns", "bulb", "u_turn_moves"]

#: The most lines a move of the convex planner's plans crosses: its lanes lie on consecutive
#: lines (a convex area meets an interval of them) flown in :func:`boustro.vehicle.lane_order`'s
#: boustrophedon (1 line a move) or every other lane (2 lines, and one move of 1).
CONVEX_MAX_LINES = 2

#: The floors are shaved by this share: a plan's turn is a closed form evaluated in floats
#: (a half circle ``pi R`` by an arccosine), equal to a floor in exact arithmetic.
SHAVE = 1e-9

#: The bulb (forward only, lanes closer than ``2R``) is taken at a lateral offset raised by this
#: share of ``w + R``: its slope is infinite at ``2R``, where a rounding of the lanes' positions
#: would otherwise move it by the square root of that rounding.
LATERAL_SLACK = 1e-9


@dataclass(frozen=True)
class UTurns:
    """A vehicle's turns between lanes flown in opposite directions: ``radius`` (plan units,
    > 0), whether it may ``reverse`` (Reeds-Shepp; else Dubins, forward only) and, where known,
    the most lines a move crosses (``max_lines``: 2 for the convex planner's orders,
    :data:`CONVEX_MAX_LINES`; ``None``: any)."""

    radius: float
    reverse: bool = False
    max_lines: int | None = None

    def floor(self, lateral: float) -> float:
        """The least length of a U-turn whose ends lie ``lateral`` apart across the lanes."""
        r, w = self.radius, abs(lateral)
        out = max(math.pi * r, w + (math.pi - 2.0) * r)
        if not self.reverse:
            out = max(out, math.pi * r + abs(w - 2.0 * r), bulb(r, w + LATERAL_SLACK * (w + r)))
        return out

    def least(self, spacing: float) -> float:
        """The least :meth:`floor` over lanes ``j`` lines apart (``j spacing``), ``1 <= j <=
        max_lines``: the floors are nonincreasing in ``j`` while ``j spacing <= 2 radius`` (the
        bulb decreases; it is concave there, ``acos`` being concave on ``[0, 1]``) and
        nondecreasing from there on, so the least is at one of the two ``j`` around ``2 radius /
        spacing``."""
        j = max(1, math.floor(2.0 * self.radius / spacing))
        if self.max_lines is not None:
            j = min(j, self.max_lines)
            if j == self.max_lines:
                return self.floor(j * spacing)
        return min(self.floor(j * spacing), self.floor((j + 1) * spacing))

    def least_odd(self, spacing: float) -> float:
        """The least :meth:`floor` over lanes an odd number of lines apart, at most
        ``max_lines`` (:meth:`least` where that is not known)."""
        if self.max_lines is None:
            return self.least(spacing)
        return min(self.floor(j * spacing) for j in range(1, self.max_lines + 1, 2))


def bulb(radius: float, lateral: float) -> float:
    """The least forward-only (Dubins) U-turn of radius ``radius`` whose ends lie ``lateral``
    apart across the lanes, over every along-offset, below ``2 radius`` (the module's proof:
    ``R (pi + 2 acos(|w| / 2R))``); the half circle ``pi R`` from ``2R`` on."""
    return radius * (math.pi + 2.0 * math.acos(min(abs(lateral) / (2.0 * radius), 1.0)))


def u_turn_moves(
    turns: UTurns,
    n_moves: NDArray[np.int64],
    span: NDArray[np.float64],
    spacing: float,
    mixed: NDArray[np.bool_] | None = None,
) -> NDArray[np.float64]:
    """A floor of the total length of ``n_moves`` U-turns between lanes on distinct lines of
    spacing ``spacing`` whose lateral offsets add up to at least ``span`` (per layout); where
    ``mixed`` (the lanes' lines include both parities) one of them crosses an odd number of
    lines (:meth:`UTurns.least_odd`)."""
    m = np.maximum(n_moves, 0).astype(np.float64)
    least = turns.least(spacing)
    each = m * least
    if mixed is not None:
        each = each + np.where(mixed & (m > 0), turns.least_odd(spacing) - least, 0.0)
    along = np.where(m > 0, span + m * (math.pi - 2.0) * turns.radius, 0.0)
    return (1.0 - SHAVE) * np.maximum(each, along)
