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


def _halfplanes_into(v: np.ndarray, normals: np.ndarray, boffs: np.ndarray) -> float:
    """:func:`boustro.geometry.polygon.edge_halfplanes` of ``v`` into ``normals (N, 2)`` and
    ``boffs (N,)``, the same operations (so the same numbers); returns the largest distance of
    a vertex from the origin (``max(np.linalg.norm(v, axis=1))``)."""
    n = v.shape[0]
    radius = -np.inf
    for i in range(n):
        k = (i + 1) % n
        nx, ny = v[i, 1] - v[k, 1], v[k, 0] - v[i, 0]
        off = v[i, 0] * v[k, 1] - v[k, 0] * v[i, 1]
        norm = math.sqrt(nx * nx + ny * ny)
        normals[i, 0], normals[i, 1], boffs[i] = nx / norm, ny / norm, off / norm
        r = math.sqrt(v[i, 0] * v[i, 0] + v[i, 1] * v[i, 1])
        radius = r if r > radius else radius
    return radius


def _top_pieces(value: np.ndarray, top: np.ndarray) -> int:
    """The (at most 3) pieces of largest finite ``value``, from the largest down, into ``top``;
    returns how many, or -1 when two finite values tie there (their order would be numpy's
    sort's, which the caller then asks numpy for) or a value is ``+inf``."""
    count = 0
    for p in range(len(value)):
        x = value[p]
        if x == np.inf:
            return -1  # first in numpy's order, and not a candidate: let numpy order them
        if not math.isfinite(x):
            continue
        if count < 4:  # keep the 4 largest, in order (the 4th only to see a tie at the 3rd)
            k = count
            count += 1
        elif x > value[top[3]]:
            k = 3
        else:
            if x == value[top[3]]:
                top[3] = p  # an equal value at the 4th place: only equality matters there
            continue
        while k > 0 and value[top[k - 1]] < x:
            top[k] = top[k - 1]
            k -= 1
        top[k] = p
    kept = min(count, 3)
    for k in range(min(count - 1, 3)):
        if value[top[k]] == value[top[k + 1]]:
            return -1
    return kept


def _check_into(
    v: np.ndarray,
    normals: np.ndarray,
    boffs: np.ndarray,
    radius: float,
    s: float,
    k_count: int,
    m: int,
    a: float,
    b: float,
    angles: np.ndarray,
    offsets: np.ndarray,
    lanes: np.ndarray,
    out: np.ndarray,
) -> None:
    """The spot check of :func:`_finish` (:func:`.smith._spot_check`): the first best layout of
    the grid ``angles x offsets`` by the exact model into ``out[3:6]`` (angle, offset,
    fitness); ``lanes (3, max(k_count, N))`` scratch."""
    across, along, lengths = lanes[0], lanes[1], lanes[2]
    top, top_i, top_j = -np.inf, 0, 0
    first = True
    for i in range(len(angles)):
        h_lo, h_hi = _angle_setup(normals, v, angles[i], across, along)
        for j in range(len(offsets)):
            val = _layout_value(
                across, along, boffs, h_lo, h_hi, radius, s, k_count, m, offsets[j], a, b, lengths
            )
            if first or val > top:  # np.argmax: the first largest
                top, top_i, top_j = val, i, j
                first = False
    out[3], out[4], out[5] = angles[top_i], offsets[top_j], top
