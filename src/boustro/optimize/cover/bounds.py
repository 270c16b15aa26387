"""Lower bounds on the cost of every plan whose area lies in a sandwich (per layout)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .bands import BandStats
from .cost import CoverCost
from .ends import HoleBoxes, lane_end_bound
from .one_tree import Multipliers, one_tree_bound
from .piece_ends import piece_end_bound
from .sandwich import Level
from .u_turns import u_turn_moves

__all__ = ["lower_bounds"]


def _interval_gap(
    a_lo: NDArray[np.float64],
    a_hi: NDArray[np.float64],
    b_lo: NDArray[np.float64],
    b_hi: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Distance between the intervals ``[a_lo, a_hi]`` and ``[b_lo, b_hi]`` (0 if they meet)."""
    return np.maximum(0.0, np.maximum(a_lo, b_lo) - np.minimum(a_hi, b_hi))


def _boustrophedon_moves(st: BandStats, spacing: float) -> NDArray[np.float64]:
    """The shortest moves between consecutive lines of a boustrophedon over one lane per line,
    each end anywhere between the inner and the outer projection's extreme, on the better start
    side; ``nan`` where the lines holding lanes are not contiguous."""
    used = st.count >= 1
    pair = used[:, :-1] & used[:, 1:]
    right = _interval_gap(st.in_hi[:, :-1], st.out_hi[:, :-1], st.in_hi[:, 1:], st.out_hi[:, 1:])
    left = _interval_gap(st.out_lo[:, :-1], st.in_lo[:, :-1], st.out_lo[:, 1:], st.in_lo[:, 1:])
    right = np.sqrt(spacing**2 + np.where(pair, right, 0.0) ** 2)
    left = np.sqrt(spacing**2 + np.where(pair, left, 0.0) ** 2)
    parity = np.arange(pair.shape[1]) % 2 == 0
    even = np.where(pair, np.where(parity, right, left), 0.0).sum(axis=1)
    odd = np.where(pair, np.where(parity, left, right), 0.0).sum(axis=1)
    moves = np.minimum(even, odd)
    contiguous = pair.sum(axis=1) == np.maximum(used.sum(axis=1) - 1, 0)
    return np.where(contiguous, moves, np.nan)


def lower_bounds(
    st: BandStats,
    level: Level,
    cost: CoverCost,
    spacing: float,
    *,
    boustrophedon: bool,
    ends: HoleBoxes | None = None,
    runins: bool = True,
    tour_below: float | None = None,
    walls: NDArray[np.float64] | None = None,
    tour_keep: NDArray[np.float64] | None = None,
    tour_skipped: NDArray[np.bool_] | None = None,
    multipliers: Multipliers | None = None,
    tour_steps: int | None = None,
    tour_branch: tuple[int, float] | None = None,
) -> NDArray[np.float64]:
    """``(L,)`` a lower bound on the cost of every plan of the layouts' grids over any area
    between ``level``'s inner and outer sets.

    Lanes: at least the inner projection minus its holes' chords (the holes dilated by the
    sandwich's radius, :attr:`~.bands.EdgeSet.chords`) on each line, at
    least one lane per piece of the outer projection (minus the outer set's hole chords) that
    holds such length, each with its run-in and run-out. Hole passes: every original hole whose
    outer-set chord overlaps the inner projection is cut in every such plan, so it gets its pass
    (a closed loop around it: at least the perimeter of the convex hull of its outer-set
    remains) and one more turn; so does every hole that ``st.rigid`` says every plan of the box
    cuts, with the perimeter of its own convex hull (the plans of a box are rigid images of the
    area, and a pass around a hole is at least that long). Moves: a path visiting lines
    ``k_min .. k_max`` travels at least ``(k_max - k_min) spacing`` across them; with
    ``boustrophedon`` (the convex planner: one lane
    per line, consecutive lines joined end to end) each move is at least the distance between
    the ranges of its two ends. With ``ends`` (the holes' boxes, :func:`~.ends.hole_boxes`; a
    routed tour without boundary or headland passes) the moves and extra lanes are also at least
    :func:`~.ends.lane_end_bound` and :func:`~.piece_ends.piece_end_bound`, and the largest
    is taken; with ``tour_below`` too, where that bound is below it (and below ``tour_keep``,
    per layout, if given), the 1-tree bound (:func:`~.one_tree.one_tree_bound`, its moves past
    ``walls``; its steps stop once the layout's bound reaches ``tour_below``); the layouts
    below ``tour_below`` but not below ``tour_keep`` are marked in ``tour_skipped`` (an output,
    filled when given with ``tour_keep``; ``multipliers``: the 1-tree's starts, kept;
    ``tour_steps``: its subgradient steps, default :data:`~.one_tree.ONE_TREE_STEPS`;
    ``tour_branch``: its branching, :func:`~.one_tree.one_tree_bound`'s ``branch``).
    With ``cost.u_turns`` (the convex planner's plans with a vehicle, whose every move is a
    U-turn; the caller's premise) the moves are at least :func:`~.u_turns.u_turn_moves` of one
    move fewer than the lines with lanes, across the span, one of them across an odd number of
    lines where those lines have both parities. ``runins=False`` (an area with
    holes: the planner cuts a run-in or run-out that would enter a hole) counts no run-ins or
    run-outs in the lanes' length.
    """
    n_lanes = st.count.sum(axis=1)
    holes = level.hole_perimeter.shape[0]
    cut = st.cut[:, :holes]
    rigid = st.rigid[:, :holes] & ~cut  # cut by every rigid image: a pass as long as the hole
    n_passes = cut.sum(axis=1) + rigid.sum(axis=1)
    perimeter = (
        (cut * level.hole_perimeter[None, :]).sum(axis=1)
        + (rigid * level.hull_perimeter[None, :]).sum(axis=1)
        if holes
        else 0.0
    )
    used = st.count >= 1
    idx = np.arange(st.count.shape[1])
    k_max = np.where(used, idx, -1).max(axis=1)
    k_min = np.where(used, idx, st.count.shape[1]).min(axis=1)
    moves = np.where(n_lanes > 0, (k_max - k_min) * spacing, 0.0)
    if boustrophedon:
        exact = _boustrophedon_moves(st, spacing)
        moves = np.where(np.isfinite(exact), np.maximum(moves, exact), moves)
    if cost.u_turns is not None:  # every move a U-turn across lines (the convex planner's)
        mixed = (used & (idx % 2 == 1)).any(axis=1) & (used & (idx % 2 == 0)).any(axis=1)
        n_moves = used.sum(axis=1) - 1
        moves = np.maximum(moves, u_turn_moves(cost.u_turns, n_moves, moves, spacing, mixed))
    turns = np.maximum(n_lanes + n_passes - 1, 0)
    runs = 2.0 * cost.turnaround * n_lanes if runins else 0.0
    if ends is not None:  # the larger of the two bounds on the moves (and extra lanes)
        fixed = st.length.sum(axis=1) + runs + perimeter
        move_cost = np.maximum(cost.per_length * moves, lane_end_bound(st, spacing, cost, ends))
        move_cost = np.maximum(move_cost, piece_end_bound(st, spacing, cost))
        out = cost.per_length * fixed + move_cost + cost.per_turn * turns + cost.fixed
        if tour_below is not None:  # the tour's structure, where it may matter
            enough = tour_below - (out - move_cost)  # the moves' cost that rules the layout out
            todo = out < tour_below
            if tour_keep is not None:
                if tour_skipped is not None:
                    tour_skipped[:] = todo & (out >= tour_keep)
                todo &= out < tour_keep
            tree = one_tree_bound(
                st, spacing, cost, todo=todo, walls=walls, enough=enough,
                multipliers=multipliers, steps=tour_steps, branch=tour_branch,
            )  # fmt: skip
            out = out + np.maximum(tree - move_cost, 0.0)
        return out
    length = st.length.sum(axis=1) + runs + moves + perimeter
    return cost.per_length * length + cost.per_turn * turns + cost.fixed
