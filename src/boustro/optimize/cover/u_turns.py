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

The plans of the convex planner with a vehicle (:func:`boustro.vehicle.lane_order`: the
boustrophedon or every other lane, each lane flown against the one before) have one lane per
line and every move is such a U-turn between lanes ``1 <= j <= 2`` lines apart
(:data:`CONVEX_MAX_LINES`): its lateral offset is exactly ``j * spacing`` (the ends lie on
their lines). :func:`u_turn_moves` bounds the sum of
``M`` such moves from below by the larger of ``M * min_j f(j)`` and ``span + M (pi - 2) R``
(``f(j)`` the larger of the floors above at ``w = j spacing``, ``span`` the lateral distance
the moves must cover). A move of the plan that is not flown as a turn (a turn that would leave
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

__all__ = ["CONVEX_MAX_LINES", "UTurns", "u_turn_moves"]

#: The most lines a move of the convex planner's plans crosses: its lanes lie on consecutive
#: lines (a convex area meets an interval of them) flown in :func:`boustro.vehicle.lane_order`'s
#: boustrophedon (1 line a move) or every other lane (2 lines, and one move of 1).
CONVEX_MAX_LINES = 2

#: The floors are shaved by this share: a plan's turn is a closed form evaluated in floats
#: (a half circle ``pi R`` by an arccosine), equal to a floor in exact arithmetic.
SHAVE = 1e-9


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
            out = max(out, math.pi * r + abs(w - 2.0 * r))
        return out

    def least(self, spacing: float) -> float:
        """The least :meth:`floor` over lanes ``j`` lines apart (``j spacing``), ``1 <= j <=
        max_lines``: the floors are convex in ``j`` and nondecreasing once ``j spacing >= 2
        radius``."""
        j = max(1, math.floor(2.0 * self.radius / spacing))
        if self.max_lines is not None:
            j = min(j, self.max_lines)
            if j == self.max_lines:
                return self.floor(j * spacing)
        return min(self.floor(j * spacing), self.floor((j + 1) * spacing))


def u_turn_moves(
    turns: UTurns, n_moves: NDArray[np.int64], span: NDArray[np.float64], spacing: float
) -> NDArray[np.float64]:
    """A floor of the total length of ``n_moves`` U-turns between lanes on distinct lines of
    spacing ``spacing`` whose lateral offsets add up to at least ``span`` (per layout)."""
    m = np.maximum(n_moves, 0).astype(np.float64)
    each = m * turns.least(spacing)
    along = np.where(m > 0, span + m * (math.pi - 2.0) * turns.radius, 0.0)
    return (1.0 - SHAVE) * np.maximum(each, along)
