"""Dubins paths: the shortest forward-only path of bounded curvature between two poses.

The closed forms of the six words (LSL, RSR, LSR, RSL, RLR, LRL; Shkel and Lumelsky 2001, in the
formulation of A. Walker's ``dubins`` library), vectorised over numpy arrays: :func:`dubins_words`
gives every word's segment lengths (NaN where the word does not exist), :func:`dubins_length` the
shortest, :func:`dubins_path` the shortest word between two poses and
:func:`boustro.vehicle.curves.sample_word` its waypoints. Poses are ``(x, y, heading)``, headings
in radians counter-clockwise from +x, lengths in the poses' units.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError
from .curves import Word, mod2pi, to_local

__all__ = ["DUBINS_WORDS", "dubins_length", "dubins_path", "dubins_paths", "dubins_words"]

#: The six words, in the order of :func:`dubins_words`.
DUBINS_WORDS = ("LSL", "RSR", "LSR", "RSL", "RLR", "LRL")

#: Rounding tolerated under a square root or an arccosine (squared lengths in turn radii).
_EPS = 1e-9


def _check_radius(radius: float) -> float:
    r = float(radius)
    if not math.isfinite(r) or r <= 0:
        raise InvalidParameterError(f"turn radius must be a finite number > 0, got {radius!r}")
    return r


def dubins_words(x: ArrayLike, y: ArrayLike, phi: ArrayLike) -> dict[str, NDArray[np.float64]]:
    """Segment lengths ``(..., 3)`` of every word from the pose ``(0, 0, 0)`` to ``(x, y, phi)``
    (coordinates in turn radii; arcs in radians, the straight in radii); NaN where the word
    does not exist."""
    x, y, phi = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in (x, y, phi)))
    d = np.hypot(x, y)
    theta = np.arctan2(y, x)
    a, b = mod2pi(-theta), mod2pi(phi - theta)
    sa, sb, ca, cb = np.sin(a), np.sin(b), np.cos(a), np.cos(b)
    cab = np.cos(a - b)
    out: dict[str, NDArray[np.float64]] = {}
    with np.errstate(invalid="ignore"):
        p2 = 2 + d * d - 2 * cab + 2 * d * (sa - sb)
        t1 = np.arctan2(cb - ca, d + sa - sb)
        out["LSL"] = _stack(mod2pi(t1 - a), _sqrt(p2), mod2pi(b - t1))
        p2 = 2 + d * d - 2 * cab + 2 * d * (sb - sa)
        t1 = np.arctan2(ca - cb, d - sa + sb)
        out["RSR"] = _stack(mod2pi(a - t1), _sqrt(p2), mod2pi(t1 - b))
        p = _sqrt(-2 + d * d + 2 * cab + 2 * d * (sa + sb))
        t2 = np.arctan2(-ca - cb, d + sa + sb) - np.arctan2(-2.0, p)
        out["LSR"] = _stack(mod2pi(t2 - a), p, mod2pi(t2 - b))
        p = _sqrt(-2 + d * d + 2 * cab - 2 * d * (sa + sb))
        t2 = np.arctan2(ca + cb, d - sa - sb) - np.arctan2(2.0, p)
        out["RSL"] = _stack(mod2pi(a - t2), p, mod2pi(b - t2))
        c = (6 - d * d + 2 * cab + 2 * d * (sa - sb)) / 8
        ph = np.arctan2(ca - cb, d - sa + sb)
        p = mod2pi(2 * math.pi - _acos(c))
        t = mod2pi(a - ph + mod2pi(p / 2))
        out["RLR"] = _stack(t, p, mod2pi(a - b - t + mod2pi(p)))
        c = (6 - d * d + 2 * cab + 2 * d * (sb - sa)) / 8
        ph = np.arctan2(ca - cb, d + sa - sb)
        p = mod2pi(2 * math.pi - _acos(c))
        t = mod2pi(-a - ph + p / 2)
        out["LRL"] = _stack(t, p, mod2pi(b - a - t + mod2pi(p)))
    return out


def _sqrt(x: NDArray[np.float64]) -> NDArray[np.float64]:
    """``sqrt(x)``, 0 for ``x`` negative by rounding only (a path with no straight), NaN below."""
    return np.sqrt(np.where(x > -_EPS, np.maximum(x, 0.0), np.nan))


def _acos(x: NDArray[np.float64]) -> NDArray[np.float64]:
    """``arccos(x)``, clipped where ``|x|`` exceeds 1 by rounding only, NaN beyond."""
    return np.arccos(np.where(np.abs(x) <= 1 + _EPS, np.clip(x, -1.0, 1.0), np.nan))


def _stack(*parts: NDArray[np.float64]) -> NDArray[np.float64]:
    arr = np.stack(np.broadcast_arrays(*parts), axis=-1)
    bad = ~np.all(np.isfinite(arr), axis=-1)
    arr[bad] = np.nan
    return arr


def _local(start: ArrayLike, goal: ArrayLike, radius: float):
    s = np.asarray(start, dtype=np.float64)
    g = np.asarray(goal, dtype=np.float64)
    if s.shape[-1] != 3 or g.shape[-1] != 3:
        raise InvalidParameterError("poses must be (x, y, heading) triples")
    x, y, phi = to_local(s, g)
    return x / radius, y / radius, phi


def dubins_length(start: ArrayLike, goal: ArrayLike, radius: float) -> NDArray[np.float64]:
    """Length of the shortest Dubins path between poses ``(..., 3)`` (broadcast), in the poses'
    units.

    Example:
        >>> round(float(dubins_length((0, 0, 0), (0, 2, math.pi), 1.0)), 6)  # a half circle
        3.141593
    """
    r = _check_radius(radius)
    words = dubins_words(*_local(start, goal, r))
    total = np.stack([np.nansum(np.abs(w), axis=-1) for w in words.values()], axis=-1)
    exists = np.stack([np.all(np.isfinite(w), axis=-1) for w in words.values()], axis=-1)
    return r * np.min(np.where(exists, total, np.inf), axis=-1)


def dubins_path(start: ArrayLike, goal: ArrayLike, radius: float) -> Word:
    """The shortest Dubins word between two poses (lengths in radii; ``length`` in units)."""
    r = _check_radius(radius)
    words = dubins_words(*_local(start, goal, r))
    best = min((float(np.sum(w)), name) for name, w in words.items() if np.all(np.isfinite(w)))
    lengths = tuple(float(v) for v in words[best[1]])
    return Word(best[1], lengths, r * best[0])


#: Rank of each word of :data:`DUBINS_WORDS` by name: :func:`dubins_path` breaks ties of
#: length by the name.
_RANK = np.argsort(np.argsort(np.array(DUBINS_WORDS)))


def dubins_paths(starts: ArrayLike, goals: ArrayLike, radius: float) -> list[Word]:
    """:func:`dubins_path` of each pair of poses ``(M, 3)``, the closed forms evaluated for all
    pairs at once (the same word and lengths as one pair at a time)."""
    r = _check_radius(radius)
    s = np.asarray(starts, dtype=np.float64).reshape(-1, 3)
    g = np.asarray(goals, dtype=np.float64).reshape(-1, 3)
    words = dubins_words(*_local(s, g, r))
    lengths = np.stack([words[name] for name in DUBINS_WORDS], axis=1)  # (M, 6, 3)
    exists = np.all(np.isfinite(lengths), axis=-1)
    total = np.where(exists, np.sum(lengths, axis=-1), np.inf)
    low = total.min(axis=1, initial=np.inf)
    pick = np.argmin(np.where(total == low[:, None], _RANK[None], len(_RANK)), axis=1)
    out = []
    for i, k in enumerate(pick):
        if not exists[i, k]:  # no word (never for finite poses): dubins_path's error
            out.append(dubins_path(s[i], g[i], r))
            continue
        row = lengths[i, k]
        out.append(Word(DUBINS_WORDS[k], tuple(float(v) for v in row), r * float(total[i, k])))
    return out
