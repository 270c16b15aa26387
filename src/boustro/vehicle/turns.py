"""Turns between lanes: the curve from the end of one lane to the start of the next, its length
for the mission-time objective, and the lane order (boustrophedon, or flying every other lane).

:func:`turn_length` is the turn between two parallel lanes driven in opposite directions,
vectorised; :func:`turn_between` the turn (length and waypoints) between any two poses;
:func:`lane_order` chooses between the plain boustrophedon order and the skip pattern of
fixed-wing surveys (every other lane out, the lanes between on the way back) by the total length
of the turns, which matters when ``2 * turn_radius > spacing``: a U-turn to the next lane is then
a bulb (three arcs), to the lane after next a plain half circle.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .curves import Word, sample_word
from .dubins import DUBINS_WORDS, _local, dubins_length, dubins_path, dubins_paths, dubins_words
from .model import Vehicle
from .reeds_shepp import (
    reeds_shepp_length,
    reeds_shepp_path,
    reeds_shepp_paths,
    reeds_shepp_words,
)

__all__ = [
    "Turn",
    "every_turn",
    "lane_order",
    "pose_length",
    "skip_order",
    "turn_between",
    "turn_length",
    "turns_between",
]


def pose_length(vehicle: Vehicle, start: ArrayLike, goal: ArrayLike) -> NDArray[np.float64]:
    """Length of the vehicle's shortest path between poses ``(..., 3)`` (broadcast): Dubins,
    Reeds-Shepp, or the straight line for a vehicle without a turn radius."""
    s = np.asarray(start, dtype=np.float64)
    g = np.asarray(goal, dtype=np.float64)
    if vehicle.turn_radius == 0:
        return np.asarray(np.hypot(g[..., 0] - s[..., 0], g[..., 1] - s[..., 1]))
    f = reeds_shepp_length if vehicle.reverse else dubins_length
    return f(s, g, vehicle.turn_radius)


def turn_length(
    vehicle: Vehicle, spacing_gap: ArrayLike, along_offset: ArrayLike = 0.0
) -> NDArray[np.float64]:
    """Length of the turn between two parallel lanes driven in opposite directions.

    The first lane ends at the origin heading along +x; the next starts ``along_offset`` further
    along x (negative: behind) and ``spacing_gap`` to the side (either side: the turn is
    symmetric), heading along -x. Vectorised over numpy arrays (broadcast).

    Example:
        >>> v = Vehicle(turn_radius=6.0)
        >>> round(float(turn_length(v, 12.0)), 4)  # a half circle: pi * 6
        18.8496
        >>> bool(turn_length(v, 10.0) > turn_length(v, 20.0))  # 2R > spacing: a bulb
        True
    """
    gap = np.abs(np.asarray(spacing_gap, dtype=np.float64))
    along = np.asarray(along_offset, dtype=np.float64)
    gap, along = np.broadcast_arrays(gap, along)
    start = np.zeros((*gap.shape, 3))
    goal = np.stack([along, gap, np.full(gap.shape, math.pi)], axis=-1)
    return pose_length(vehicle, start, goal)


class Turn(NamedTuple):
    """A turn: its waypoints ``(P, 2)`` (first the start, last the end), headings ``(P,)``,
    gear of the move to each waypoint (``-1`` backwards), length, and the word driven."""

    points: NDArray[np.float64]
    headings: NDArray[np.float64]
    gear: NDArray[np.int64]
    length: float
    word: str


def turn_between(
    vehicle: Vehicle, start: ArrayLike, goal: ArrayLike, tolerance: float = 0.05
) -> Turn:
    """The vehicle's shortest turn from pose ``start`` to pose ``goal`` (``(x, y, heading)``),
    densified so that no chord departs from the curve by more than ``tolerance``."""
    s = np.asarray(start, dtype=np.float64)
    g = np.asarray(goal, dtype=np.float64)
    if vehicle.turn_radius == 0:
        pts = np.stack([s[:2], g[:2]])
        return Turn(
            pts,
            np.array([s[2], g[2]]),
            np.ones(2, dtype=np.int64),
            float(np.linalg.norm(g[:2] - s[:2])),
            "S",
        )
    path = reeds_shepp_path if vehicle.reverse else dubins_path
    word: Word = path(s, g, vehicle.turn_radius)
    poses, gear = sample_word(s, word, vehicle.turn_radius, tolerance)
    poses[-1] = g  # exact at the goal (the sampled end differs by rounding only)
    return Turn(poses[:, :2], poses[:, 2], gear, word.length, word.letters)


def turns_between(
    vehicle: Vehicle, starts: ArrayLike, goals: ArrayLike, tolerance: float = 0.05
) -> list[Turn]:
    """:func:`turn_between` of each pair of poses ``(M, 3)``, the words found for all pairs at
    once (:func:`~boustro.vehicle.dubins.dubins_paths`; the same turns)."""
    s = np.asarray(starts, dtype=np.float64).reshape(-1, 3)
    g = np.asarray(goals, dtype=np.float64).reshape(-1, 3)
    if vehicle.turn_radius == 0 or len(s) == 0:
        return [turn_between(vehicle, a, b, tolerance) for a, b in zip(s, g, strict=True)]
    paths = reeds_shepp_paths if vehicle.reverse else dubins_paths
    out = []
    for a, b, word in zip(s, g, paths(s, g, vehicle.turn_radius), strict=True):
        poses, gear = sample_word(a, word, vehicle.turn_radius, tolerance)
        poses[-1] = b
        out.append(Turn(poses[:, :2], poses[:, 2], gear, word.length, word.letters))
    return out


def every_turn(
    vehicle: Vehicle, start: ArrayLike, goal: ArrayLike, tolerance: float = 0.05
) -> list[Turn]:
    """Every turn of the vehicle from pose ``start`` to pose ``goal``, shortest first: the six
    Dubins words that exist (forward only) or the Reeds-Shepp candidates (with ``reverse``),
    each densified as in :func:`turn_between`; the first is :func:`turn_between`'s length.
    What a planner tries when the shortest turn leaves the field (a longer loop the other way,
    or a manoeuvre with reversing, may stay inside)."""
    s = np.asarray(start, dtype=np.float64)
    g = np.asarray(goal, dtype=np.float64)
    r = vehicle.turn_radius
    if r == 0:
        return [turn_between(vehicle, s, g, tolerance)]
    x, y, phi = _local(s, g, r)
    if vehicle.reverse:
        found = [(w, np.asarray(v, dtype=np.float64)) for w, v in reeds_shepp_words(x, y, phi)]
    else:
        words = dubins_words(x, y, phi)
        found = [(w, np.asarray(words[w], dtype=np.float64)) for w in DUBINS_WORDS]
    exists = [(float(np.sum(np.abs(v))), w, v) for w, v in found if np.all(np.isfinite(v))]
    out, seen = [], set()
    for total, letters, v in sorted(exists, key=lambda e: e[0]):
        key = (letters, tuple(np.round(v, 9)))
        if key in seen:  # the same word from two of the Reeds-Shepp candidates
            continue
        seen.add(key)
        word = Word(letters, tuple(float(e) for e in v), r * total)
        poses, gear = sample_word(s, word, r, tolerance)
        if np.linalg.norm(poses[-1, :2] - g[:2]) > 1e-6 * max(r, 1.0):  # rounding: not a path
            continue
        poses[-1] = g
        out.append(Turn(poses[:, :2], poses[:, 2], gear, word.length, letters))
    return out


def skip_order(n: int) -> list[int]:
    """Every other lane out, the lanes between back: ``0, 2, 4, ..., 5, 3, 1``."""
    evens = list(range(0, n, 2))
    odds = list(range(1, n, 2))
    return evens + odds[::-1]


def lane_order(
    vehicle: Vehicle,
    lanes: NDArray[np.float64],
) -> tuple[list[int], NDArray[np.float64], float]:
    """The lane order with the shorter total turn length.

    Args:
        lanes: ``(T, 2, 2)`` parallel lanes ``[start, end]`` in boustrophedon order (each
            driven against the previous one), plan units.

    Returns:
        ``(order, lanes in that order and direction, total turn length)``: the boustrophedon
        order or :func:`skip_order` (flying every other lane), whichever turns less; each lane
        driven against the one before it.
    """
    candidates = [list(range(len(lanes)))]
    if len(lanes) >= 3 and vehicle.turn_radius > 0:
        candidates.append(skip_order(len(lanes)))
    best: tuple[float, list[int], NDArray[np.float64]] | None = None
    for order in candidates:
        driven = _alternate(lanes, order)
        total = float(np.sum(_turns(vehicle, driven)))
        if best is None or total < best[0] - 1e-9:
            best = (total, order, driven)
    assert best is not None
    return best[1], best[2], best[0]


def _alternate(lanes: NDArray[np.float64], order: list[int]) -> NDArray[np.float64]:
    """``lanes[order]``, the first as given and each next one against the one before it."""
    d0 = lanes[0, 1] - lanes[0, 0]
    out = lanes[order].copy()
    for i in range(len(out)):
        want = 1.0 if i % 2 == 0 else -1.0
        if np.dot(out[i, 1] - out[i, 0], d0) * want < 0:
            out[i] = out[i, ::-1]
    return out


def _turns(vehicle: Vehicle, driven: NDArray[np.float64]) -> NDArray[np.float64]:
    """Turn lengths between consecutive driven lanes (``(T - 1,)``)."""
    if len(driven) < 2:
        return np.zeros(0)
    heading = _headings(driven)
    start = np.concatenate([driven[:-1, 1], heading[:-1, None]], axis=1)
    goal = np.concatenate([driven[1:, 0], heading[1:, None]], axis=1)
    return pose_length(vehicle, start, goal)


def _headings(driven: NDArray[np.float64]) -> NDArray[np.float64]:
    d = driven[:, 1] - driven[:, 0]
    return np.arctan2(d[:, 1], d[:, 0])
