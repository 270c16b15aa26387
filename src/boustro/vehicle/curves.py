"""Paths of curvature-bounded vehicles as words of arcs and straights, and their waypoints.

A word is a string of letters ``L`` (left arc), ``S`` (straight), ``R`` (right arc) and signed
lengths in units of the turn radius (radians for arcs; negative: driven backwards). Dubins and
Reeds-Shepp paths (:mod:`.dubins`, :mod:`.reeds_shepp`) are words; :func:`sample_word` turns
one into waypoints, exactly on the curve, densified so that the chord between two consecutive
waypoints departs from the arc by at most a tolerance.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

__all__ = ["Word", "arc_step", "end_pose", "mod2pi", "sample_word", "to_local"]

_STEER = {"L": 1.0, "S": 0.0, "R": -1.0}


class Word(NamedTuple):
    """A path: its letters, signed segment lengths (turn radii) and total length (metres)."""

    letters: str
    lengths: tuple[float, ...]
    length: float


def mod2pi(x: NDArray[np.float64] | float) -> NDArray[np.float64]:
    """Angles in ``[0, 2 pi)``."""
    return np.mod(x, 2 * math.pi)


def to_local(
    start: NDArray[np.float64], goal: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """``(x, y, phi)`` of the goal pose in the start pose's frame (``(..., 3)`` poses)."""
    dx, dy = goal[..., 0] - start[..., 0], goal[..., 1] - start[..., 1]
    c, s = np.cos(start[..., 2]), np.sin(start[..., 2])
    return dx * c + dy * s, -dx * s + dy * c, goal[..., 2] - start[..., 2]


def _advance(pose: NDArray[np.float64], letter: str, ell: NDArray[np.float64], radius: float):
    """Poses ``(n, 3)`` after driving ``ell`` (signed, turn radii) of ``letter`` from ``pose``."""
    x, y, h = pose
    k = _STEER[letter]
    if k == 0.0:
        return np.stack(
            [x + radius * ell * math.cos(h), y + radius * ell * math.sin(h), np.full_like(ell, h)],
            axis=-1,
        )
    h1 = h + k * ell
    return np.stack(
        [
            x + k * radius * (np.sin(h1) - math.sin(h)),
            y - k * radius * (np.cos(h1) - math.cos(h)),
            h1,
        ],
        axis=-1,
    )


def arc_step(radius: float, tolerance: float) -> float:
    """The largest angle (radians) of an arc of ``radius`` whose chord departs from it by at
    most ``tolerance`` (the sagitta ``radius (1 - cos(step / 2))``)."""
    if tolerance >= radius:
        return math.pi / 2
    return max(2.0 * math.acos(1.0 - tolerance / radius), 1e-4)


def end_pose(start: NDArray[np.float64], word: Word, radius: float) -> NDArray[np.float64]:
    """The pose reached by driving ``word`` from ``start`` (exact)."""
    pose = np.asarray(start, dtype=np.float64)
    for letter, ell in zip(word.letters, word.lengths, strict=True):
        pose = _advance(pose, letter, np.array([ell]), radius)[0]
    return pose


def sample_word(
    start: NDArray[np.float64], word: Word, radius: float, tolerance: float
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Waypoints ``(P, 3)`` (x, y, heading) of ``word`` driven from ``start``, the first the
    start and the last the end, every arc cut into steps of :func:`arc_step`; and the gear of
    the segment leading to each waypoint (``+1`` forward, ``-1`` backwards; ``+1`` for the
    first). Straight segments keep their two ends only; cusps (a change of gear) are waypoints.
    """
    step = arc_step(radius, tolerance)
    pose = np.asarray(start, dtype=np.float64)
    out = [pose[None]]
    gear = [np.array([1])]
    for letter, ell in zip(word.letters, word.lengths, strict=True):
        if abs(ell) < 1e-12:
            continue
        n = 1 if letter == "S" else max(1, math.ceil(abs(ell) / step))
        poses = _advance(pose, letter, ell * np.arange(1, n + 1) / n, radius)
        out.append(poses)
        gear.append(np.full(n, 1 if ell > 0 else -1))
        pose = poses[-1]
    return np.concatenate(out), np.concatenate(gear)
