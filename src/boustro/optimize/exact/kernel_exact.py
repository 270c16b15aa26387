"""Eq. 1 by the exact model at (angle, offset) pairs, compiled (numba): the certified optimiser's
scoring of its candidate layouts and its spot check.

The same arithmetic as :func:`boustro.optimize.evaluate_grid` with the
:class:`~boustro.models.ExactModel` and :class:`~boustro.objectives.SmithFitness` (the grid of
:func:`boustro.models.transect_positions`, the chords of :func:`boustro.models.line_chords`, a
transect counted when longer than ``1e-12`` of the radius, the weighted statistics of
:func:`boustro.objectives.smith_fitness` with the refined mean, ``-inf`` without a counted
transect), as one loop per pair: the torch code costs about 0.3 ms a call in overheads on a
small polygon. Equal to it to rounding (tests/test_exact_kernel.py); the torch code stays the
library's scoring (any model, any objective, gradients). Plain Python until
:func:`.kernel.compiled` compiles it.
"""

from __future__ import annotations

import math

import numpy as np

__all__: list[str] = []


def _angle_setup(
    normals: np.ndarray, v: np.ndarray, theta: float, across: np.ndarray, along: np.ndarray
) -> tuple[float, float]:
    """The edges' components at ``theta`` (``n_j . n`` and ``n_j . u``, as
    :func:`boustro.models.base._components`) into ``across``, ``along``; returns the vertices'
    extent ``(min, max)`` across the transects."""
    cos, sin = math.cos(theta), math.sin(theta)
    for e in range(normals.shape[0]):
        nx, ny = normals[e, 0], normals[e, 1]
        across[e] = -nx * sin + ny * cos
        along[e] = nx * cos + ny * sin
    h_lo, h_hi = np.inf, -np.inf
    for i in range(v.shape[0]):
        h = v[i, 1] * cos - v[i, 0] * sin
        h_lo, h_hi = min(h_lo, h), max(h_hi, h)
    return h_lo, h_hi


def _layout_value(
    across: np.ndarray,
    along: np.ndarray,
    boffs: np.ndarray,
    h_lo: float,
    h_hi: float,
    radius: float,
    s: float,
    k_count: int,
    m: int,
    offset: float,
    a: float,
    b: float,
    lengths: np.ndarray,
) -> float:
    """Eq. 1 of the layout at ``offset`` by the exact model (``-inf``: nothing counts), the
    angle's components set by :func:`_angle_setup`.

    Lines more than 1e-9 outside the vertices' extent across the transects have no chord
    (the exact model gives them length 0 too: far beyond rounding) and are skipped.
    """
    n_e = len(boffs)
    d = np.fmod(offset, s)  # torch.remainder
    if d != 0 and ((s < 0) != (d < 0)):
        d += s
    tiny = 1e-12 * max(radius, 1e-300)
    total = 0.0
    first = 0.0
    for k in range(k_count):
        c = d + float(k - m) * s
        lengths[k] = 0.0
        if c < h_lo - 1e-9 or c > h_hi + 1e-9:
            continue
        lower, upper = -np.inf, np.inf
        blocked = False
        for e in range(n_e):
            lhs = across[e] * c + boffs[e]
            if along[e] > 0:
                lower = max(lower, -lhs / along[e])
            elif along[e] < 0:
                upper = min(upper, -lhs / along[e])
            elif lhs < 0:
                blocked = True
        length = 0.0 if blocked else max(upper - lower, 0.0)
        if length > tiny:
            lengths[k] = length
            total += 1.0
            first += length
    if not total > 0:
        return -np.inf
    mean = first / total
    residual = 0.0
    for k in range(k_count):
        if lengths[k] > 0:
            residual += lengths[k] - mean
    mean = mean + residual / total
    second = 0.0
    for k in range(k_count):
        if lengths[k] > 0:
            r = lengths[k] - mean
            second += r * r
    var = second / total
    std = math.sqrt(var) if var > 2.220446049250313e-16**2 else 0.0
    value = a * mean + b * (1.0 - std)
    return -np.inf if value != value else value


def _exact_grid(
    normals: np.ndarray,
    boffs: np.ndarray,
    v: np.ndarray,
    radius: float,
    s: float,
    k_count: int,
    m: int,
    thetas: np.ndarray,
    offsets: np.ndarray,
    pairs: bool,
    a: float,
    b: float,
    out: np.ndarray,
) -> None:
    """Eq. 1 of every layout into ``out``: of the pairs ``(thetas[i], offsets[i])`` if
    ``pairs``, else of the grid ``thetas x offsets`` (row-major); ``v`` the vertices, in the
    frame of the half-planes ``normals``, ``boffs``."""
    work = np.empty((3, max(k_count, normals.shape[0])))
    across, along, lengths = work[0], work[1], work[2]
    n_o = 1 if pairs else len(offsets)
    for i in range(len(thetas)):
        h_lo, h_hi = _angle_setup(normals, v, thetas[i], across, along)
        for j in range(n_o):
            offset = offsets[i] if pairs else offsets[j]
            out[i * n_o + j] = _layout_value(
                across, along, boffs, h_lo, h_hi, radius, s, k_count, m, offset, a, b, lengths
            )
