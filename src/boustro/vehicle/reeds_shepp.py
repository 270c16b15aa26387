"""Reeds-Shepp paths: the shortest path of bounded curvature, forwards and backwards.

The closed forms of Reeds and Shepp (1990) for the five families CSC, CCC, CCCC, CCSC and
CCSCC, each with its time-flipped, reflected and backwards variants, as written in OMPL's
``ReedsSheppStateSpace`` (44 candidates that hold the 48 words of Reeds and Shepp); vectorised
over numpy arrays. Segment lengths are signed (negative: driven backwards), in turn radii.
:func:`reeds_shepp_length` gives the shortest length between poses ``(x, y, heading)``,
:func:`reeds_shepp_path` the shortest word.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .curves import Word, to_local
from .dubins import _check_radius, _local

__all__ = ["reeds_shepp_length", "reeds_shepp_path", "reeds_shepp_paths", "reeds_shepp_words"]

_ZERO = 10 * np.finfo(np.float64).eps
_PI = math.pi
Arr = NDArray[np.float64]
_NAN = np.nan


def _m2p(x: Arr) -> Arr:
    """Angles in ``(-pi, pi]`` (OMPL's ``mod2pi`` for Reeds-Shepp)."""
    v = np.fmod(x, 2 * _PI)
    v = np.where(v < -_PI, v + 2 * _PI, v)
    return np.where(v > _PI, v - 2 * _PI, v)


def _polar(x: Arr, y: Arr) -> tuple[Arr, Arr]:
    return np.hypot(x, y), np.arctan2(y, x)


def _tau_omega(u: Arr, v: Arr, xi: Arr, eta: Arr, phi: Arr) -> tuple[Arr, Arr]:
    delta = _m2p(u - v)
    a = np.sin(u) - np.sin(delta)
    b = np.cos(u) - np.cos(delta) - 1
    t1 = np.arctan2(eta * a - xi * b, xi * a + eta * b)
    t2 = 2 * (np.cos(delta) - np.cos(v) - np.cos(u)) + 3
    tau = np.where(t2 < 0, _m2p(t1 + _PI), _m2p(t1))
    return tau, _m2p(tau - u + v - phi)


def _out(ok: Arr, *parts: Arr) -> Arr:
    arr = np.stack(np.broadcast_arrays(*parts), axis=-1).astype(np.float64)
    arr[~(ok & np.all(np.isfinite(arr), axis=-1))] = _NAN
    return arr


def _lsl(x: Arr, y: Arr, phi: Arr) -> Arr:  # LpSpLp
    u, t = _polar(x - np.sin(phi), y - 1 + np.cos(phi))
    v = _m2p(phi - t)
    return _out((t >= -_ZERO) & (v >= -_ZERO), t, u, v)


def _lsr(x: Arr, y: Arr, phi: Arr) -> Arr:  # LpSpRp
    u1, t1 = _polar(x + np.sin(phi), y - 1 - np.cos(phi))
    u1 = u1 * u1
    u = np.sqrt(np.maximum(u1 - 4, 0))
    t = _m2p(t1 + np.arctan2(2.0, u))
    v = _m2p(t - phi)
    return _out((u1 >= 4) & (t >= -_ZERO) & (v >= -_ZERO), t, u, v)


def _lrl(x: Arr, y: Arr, phi: Arr) -> Arr:  # LpRmL
    u1, theta = _polar(x - np.sin(phi), y - 1 + np.cos(phi))
    u = -2 * np.arcsin(np.minimum(u1 / 4, 1.0))
    t = _m2p(theta + 0.5 * u + _PI)
    v = _m2p(phi - t + u)
    return _out((u1 <= 4) & (t >= -_ZERO) & (u <= _ZERO), t, u, v)


def _lrlr_a(x: Arr, y: Arr, phi: Arr) -> Arr:  # LpRupLumRm
    xi, eta = x + np.sin(phi), y - 1 - np.cos(phi)
    rho = 0.25 * (2 + np.hypot(xi, eta))
    u = np.arccos(np.minimum(rho, 1.0))
    t, v = _tau_omega(u, -u, xi, eta, phi)
    return _out((rho <= 1) & (t >= -_ZERO) & (v <= _ZERO), t, u, v)


def _lrlr_b(x: Arr, y: Arr, phi: Arr) -> Arr:  # LpRumLumRp
    xi, eta = x + np.sin(phi), y - 1 - np.cos(phi)
    rho = (20 - xi * xi - eta * eta) / 16
    u = -np.arccos(np.clip(rho, -1.0, 1.0))
    t, v = _tau_omega(u, u, xi, eta, phi)
    ok = (rho >= 0) & (rho <= 1) & (u >= -_PI / 2) & (t >= -_ZERO) & (v >= -_ZERO)
    return _out(ok, t, u, v)


def _lrsl(x: Arr, y: Arr, phi: Arr) -> Arr:  # LpRmSmLm
    rho, theta = _polar(x - np.sin(phi), y - 1 + np.cos(phi))
    r = np.sqrt(np.maximum(rho * rho - 4, 0))
    u = 2 - r
    t = _m2p(theta + np.arctan2(r, -2.0))
    v = _m2p(phi - 0.5 * _PI - t)
    return _out((rho >= 2) & (t >= -_ZERO) & (u <= _ZERO) & (v <= _ZERO), t, u, v)


def _lrsr(x: Arr, y: Arr, phi: Arr) -> Arr:  # LpRmSmRm
    xi, eta = x + np.sin(phi), y - 1 - np.cos(phi)
    rho, theta = _polar(-eta, xi)
    t = theta
    u = 2 - rho
    v = _m2p(t + 0.5 * _PI - phi)
    return _out((rho >= 2) & (t >= -_ZERO) & (u <= _ZERO) & (v <= _ZERO), t, u, v)


def _lrslr(x: Arr, y: Arr, phi: Arr) -> Arr:  # LpRmSLmRp
    xi, eta = x + np.sin(phi), y - 1 - np.cos(phi)
    rho, _ = _polar(xi, eta)
    u = 4 - np.sqrt(np.maximum(rho * rho - 4, 0))
    t = _m2p(np.arctan2((4 - u) * xi - 2 * eta, -2 * xi + (u - 4) * eta))
    v = _m2p(t - phi)
    return _out((rho >= 2) & (u <= _ZERO) & (t >= -_ZERO) & (v >= -_ZERO), t, u, v)


_H = 0.5 * _PI
# (primitive, letters, segment lengths from the primitive's (t, u, v) and a sign s (+1, or -1
# when time-flipped), backwards variant?)
_Assemble = Callable[[Arr, Arr, Arr, float], list[Arr]]
_FAMILIES: list[tuple[Callable[[Arr, Arr, Arr], Arr], str, _Assemble, bool]] = [
    (_lsl, "LSL", lambda t, u, v, s: [s * t, s * u, s * v], False),
    (_lsr, "LSR", lambda t, u, v, s: [s * t, s * u, s * v], False),
    (_lrl, "LRL", lambda t, u, v, s: [s * t, s * u, s * v], False),
    (_lrl, "LRL", lambda t, u, v, s: [s * v, s * u, s * t], True),
    (_lrlr_a, "LRLR", lambda t, u, v, s: [s * t, s * u, -s * u, s * v], False),
    (_lrlr_b, "LRLR", lambda t, u, v, s: [s * t, s * u, s * u, s * v], False),
    (_lrsl, "LRSL", lambda t, u, v, s: [s * t, -s * _H + 0 * t, s * u, s * v], False),
    (_lrsr, "LRSR", lambda t, u, v, s: [s * t, -s * _H + 0 * t, s * u, s * v], False),
    (_lrsl, "LSRL", lambda t, u, v, s: [s * v, s * u, -s * _H + 0 * t, s * t], True),
    (_lrsr, "RSRL", lambda t, u, v, s: [s * v, s * u, -s * _H + 0 * t, s * t], True),
    (
        _lrslr,
        "LRSLR",
        lambda t, u, v, s: [s * t, -s * _H + 0 * t, s * u, -s * _H + 0 * t, s * v],
        False,
    ),
]

_SWAP = str.maketrans("LR", "RL")


def reeds_shepp_words(x: ArrayLike, y: ArrayLike, phi: ArrayLike) -> list[tuple[str, Arr]]:
    """Every word from ``(0, 0, 0)`` to ``(x, y, phi)`` (turn radii): ``(letters, (..., k)
    signed segment lengths)``, NaN where the word does not exist; 44 candidates (the 48 words)."""
    x, y, phi = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in (x, y, phi)))
    xb = x * np.cos(phi) + y * np.sin(phi)
    yb = x * np.sin(phi) - y * np.cos(phi)
    out: list[tuple[str, Arr]] = []
    with np.errstate(invalid="ignore", divide="ignore"):
        for prim, letters, assemble, backwards in _FAMILIES:
            px, py = (xb, yb) if backwards else (x, y)
            for flip, reflect in ((False, False), (True, False), (False, True), (True, True)):
                qx = -px if flip else px
                qy = -py if reflect else py
                qphi = -phi if flip != reflect else phi
                tuv = prim(qx, qy, qphi)
                s = -1.0 if flip else 1.0
                parts = assemble(tuv[..., 0], tuv[..., 1], tuv[..., 2], s)
                word = letters.translate(_SWAP) if reflect else letters
                out.append((word, np.stack(np.broadcast_arrays(*parts), axis=-1)))
    return out


def reeds_shepp_length(start: ArrayLike, goal: ArrayLike, radius: float) -> Arr:
    """Length of the shortest Reeds-Shepp path between poses ``(..., 3)`` (broadcast).

    Example:
        >>> round(float(reeds_shepp_length((0, 0, 0), (-3, 0, 0), 1.0)), 6)  # straight back
        3.0
    """
    r = _check_radius(radius)
    words = reeds_shepp_words(*_local(start, goal, r))
    total = np.stack([np.sum(np.abs(w), axis=-1) for _, w in words], axis=-1)
    return r * np.min(np.where(np.isfinite(total), total, np.inf), axis=-1)


def reeds_shepp_path(start: ArrayLike, goal: ArrayLike, radius: float) -> Word:
    """The shortest Reeds-Shepp word between two poses (signed lengths in radii)."""
    r = _check_radius(radius)
    words = reeds_shepp_words(*_local(start, goal, r))
    best = min(
        ((float(np.sum(np.abs(w))), i) for i, (_, w) in enumerate(words) if np.all(np.isfinite(w))),
    )
    letters, w = words[best[1]]
    return Word(letters, tuple(float(v) for v in w), r * best[0])


def reeds_shepp_paths(starts: ArrayLike, goals: ArrayLike, radius: float) -> list[Word]:
    """:func:`reeds_shepp_path` of each pair of poses ``(M, 3)``, the candidates evaluated for
    all pairs at once (the same word and lengths as one pair at a time)."""
    r = _check_radius(radius)
    s = np.asarray(starts, dtype=np.float64).reshape(-1, 3)
    g = np.asarray(goals, dtype=np.float64).reshape(-1, 3)
    words = reeds_shepp_words(*_local(s, g, r))
    exists = np.stack([np.all(np.isfinite(w), axis=-1) for _, w in words], axis=1)
    total = np.stack([np.sum(np.abs(w), axis=-1) for _, w in words], axis=1)
    pick = np.argmin(np.where(exists, total, np.inf), axis=1)  # ties: the first candidate
    out = []
    for i, k in enumerate(pick):
        if not exists[i, k]:  # no word: reeds_shepp_path's error
            out.append(reeds_shepp_path(s[i], g[i], r))
            continue
        letters, w = words[k]
        out.append(Word(letters, tuple(float(v) for v in w[i]), r * float(total[i, k])))
    return out


_ = to_local  # re-used by callers through .curves
