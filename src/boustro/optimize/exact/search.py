"""Branch and bound over the angle, shared by the certified exact optimisers."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..._validate import as_number
from ...errors import InvalidParameterError
from .structure import Array, event_angles

__all__ = ["MIN_TOL"]


#: Angles evaluated per batch (bounds the memory of the (M, n, n - 1) arrays).
_BATCH = 2048


#: Most children an interval is cut into in one round.
_MAX_CHILDREN = 16


#: Intervals narrower than this (radians) are not cut further.
_MIN_WIDTH = 1e-13


@dataclass
class _Search:
    """Outcome of a branch and bound in the normalised frame."""

    theta: float
    lo: float  # the event-free interval of the best centre angle
    hi: float
    offset: float
    value: float
    upper_bound: float
    evaluations: int
    rounds: int
    events: int
    converged: bool


def _branch_and_bound(
    v: Array,
    s: float,
    evaluate: Any,
    tol: float,
    max_evaluations: int,
) -> _Search:
    """Maximise over the angle: ``evaluate(lo, hi, threshold) -> (value, offset, upper_bound,
    order)`` on intervals ``[lo, hi]`` (see :func:`_evaluate_smith`)."""
    edges = event_angles(v, s)
    lo, hi = edges[:-1].copy(), edges[1:].copy()
    g, d, ub, order = evaluate(lo, hi, -math.inf)
    evaluations = len(lo)
    k = int(np.argmax(g))
    best, best_theta, best_d = float(g[k]), 0.5 * (lo[k] + hi[k]), float(d[k])
    best_iv = (float(lo[k]), float(hi[k]))
    closed = -math.inf  # largest bound of the intervals already discarded
    rounds = 0
    converged = True
    while True:
        keep = ub > best + tol
        if np.any(~keep):
            closed = max(closed, float(ub[~keep].max()))
        lo, hi, g, ub, order = lo[keep], hi[keep], g[keep], ub[keep], order[keep]
        if len(lo) == 0:
            break
        width = hi - lo
        stuck = width < _MIN_WIDTH
        if np.any(stuck):
            closed = max(closed, float(ub[stuck].max()))
            keep = ~stuck
            lo, hi, g, ub, order, width = (x[keep] for x in (lo, hi, g, ub, order, width))
            converged = False
            if len(lo) == 0:
                break
        if evaluations >= max_evaluations:
            closed = max(closed, float(ub.max()))
            converged = False
            break
        rounds += 1
        err = ub - g
        with np.errstate(invalid="ignore", over="ignore"):
            # first-order bounds shrink like the width, second-order ones like its square
            parts = np.where(np.isfinite(err), np.ceil((err / tol) ** (1.0 / order)), _MAX_CHILDREN)
        parts = np.clip(parts, 2, _MAX_CHILDREN).astype(np.int64)
        idx = np.repeat(np.arange(len(lo)), parts)
        j = np.arange(len(idx)) - np.repeat(np.cumsum(parts) - parts, parts)
        kk = parts[idx]
        clo = lo[idx] + width[idx] * (j / kk)
        chi = np.where(j + 1 == kk, hi[idx], lo[idx] + width[idx] * ((j + 1) / kk))
        lo, hi = clo, chi
        g, d, ub, order = evaluate(lo, hi, best + tol)
        evaluations += len(lo)
        k = int(np.argmax(g))
        if g[k] > best:
            best, best_theta, best_d = float(g[k]), 0.5 * (lo[k] + hi[k]), float(d[k])
            best_iv = (float(lo[k]), float(hi[k]))
    upper = max(closed, best)
    return _Search(
        best_theta, *best_iv, best_d, best, upper, evaluations, rounds, len(edges) - 1, converged
    )


def _check_count(name: str, value: int) -> int:
    if int(value) != value or value < 1:
        raise InvalidParameterError(f"{name} must be an integer >= 1, got {value!r}")
    return int(value)


#: Smallest certified gap asked for: below it float64 rounding in the bounds (about 1e-12 of the
#: fitness) could make a certificate claim more than it proves.
MIN_TOL = 1e-10


def _check_tol(tol: float) -> float:
    t = as_number("tol", tol)
    if not (t >= MIN_TOL and math.isfinite(t)):
        raise InvalidParameterError(
            f"tol must be a finite number >= {MIN_TOL:g} (float64 rounding), got {tol!r}"
        )
    return t
