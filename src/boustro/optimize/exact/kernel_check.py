"""The certified optimiser's spot check, screened (numba): one polygon a call.

The spot check (:func:`.smith._spot_check`, docs/global_optimum.md) scores a grid of layouts
(90 angles, every edge's direction and normal, 9 offsets) by the exact model and compares its
best with the search's; only a check that beats the search's layout by more than ``1e-12``
changes the answer. The exact model cuts every line by every edge's half-plane (a division an
edge a line, three passes over the lines for the statistics): on the paper's small polygons
the check cost a quarter of the whole optimum. So :func:`_screened_check` scores the grid
first by :func:`_screen_value`: at each angle the polygon's two boundary chains (edges rising
and falling across the transects, each sorted) are walked upwards with the lines, a line's
chord is the difference of its two edges' interpolated ends, and the statistics take one
pass. Away from the vertices (more than ``1e-9`` of the radius across the transects) that is
the exact model's chord to rounding (about ``1e-15``); a layout with a line that close to a
vertex, where the model counts or drops a grazing transect, is scored by the exact model
itself (:func:`.kernel_exact._layout_value`). Where a screened value comes within
:data:`SCREEN_MARGIN` of the search's best, the whole grid is scored by the exact model
(:func:`.kernel_exact._check_into`), so the check's answer is then the same as without the
screen; elsewhere neither can change the result. Plain Python until :func:`.kernel.compiled`
compiles it.
"""

from __future__ import annotations

import math

import numpy as np

from .kernel_exact import _angle_setup, _check_into, _halfplanes_into, _layout_value, _top_pieces
from .kernel_pieces import _LAM, _VALUE, _pieces_one, _structure_one, _structure_scratch

__all__: list[str] = []


#: A screened value this close to the search's best (or above it) sends the check to the
#: exact model: far above the screen's rounding (about 1e-15).
SCREEN_MARGIN = 1e-9

#: Lines closer than this (relative to the radius) to a vertex across the transects are
#: scored by the exact model.
NEAR_VERTEX = 1e-9


def _chains_at(v: np.ndarray, theta: float, ch: np.ndarray, counts: np.ndarray) -> None:
    """The polygon's two boundary chains at ``theta``: ``ch[0]`` its rising edges (across the
    transects, ``h`` as :func:`.kernel_exact._angle_setup` computes it), ``ch[1]`` its falling
    ones, each row ``(h at the lower end, h at the upper end, t at the lower end, dt / dh)``
    (``t`` along the transects), sorted by the lower end; ``counts`` their numbers. Edges with
    ``dh = 0`` are in neither (a line meets them only at a vertex's height)."""
    n = v.shape[0]
    cos, sin = math.cos(theta), math.sin(theta)
    counts[0], counts[1] = 0, 0
    for e in range(n):
        k = e + 1 if e + 1 < n else 0
        h0 = v[e, 1] * cos - v[e, 0] * sin
        t0 = v[e, 0] * cos + v[e, 1] * sin
        h1 = v[k, 1] * cos - v[k, 0] * sin
        t1 = v[k, 0] * cos + v[k, 1] * sin
        dh = h1 - h0
        if dh == 0:
            continue
        c = 0 if dh > 0 else 1
        low, high, t_low = (h0, h1, t0) if dh > 0 else (h1, h0, t1)
        i = counts[c]
        while i > 0 and ch[c, i - 1, 0] > low:  # insertion (the chain is a rotation of sorted)
            ch[c, i] = ch[c, i - 1]
            i -= 1
        ch[c, i, 0], ch[c, i, 1], ch[c, i, 2], ch[c, i, 3] = low, high, t_low, (t1 - t0) / dh
        counts[c] += 1


def _screen_angle(
    ch: np.ndarray,
    counts: np.ndarray,
    h_lo: float,
    h_hi: float,
    radius: float,
    s: float,
    offsets: np.ndarray,
    a: float,
    b: float,
    sums: np.ndarray,
    vals: np.ndarray,
) -> None:
    """Eq. 1 of the layouts at every offset (ascending, in ``[0, s)``) from the chains of
    :func:`_chains_at` into ``vals`` (``-inf``: no transect counts), NaN where a line passes
    within :data:`NEAR_VERTEX` of a vertex (the caller asks the exact model): the lines of
    all offsets in one sweep upwards. ``sums (4, len(offsets))`` scratch."""
    n_o = len(offsets)
    tiny = 1e-12 * max(radius, 1e-300)
    near = NEAR_VERTEX * radius
    for j in range(n_o):
        vals[j] = 0.0
        sums[0, j], sums[1, j], sums[2, j], sums[3, j] = 0.0, 0.0, 0.0, 0.0
    if h_hi - h_lo <= 2 * near or counts[0] == 0 or counts[1] == 0:
        vals[:] = np.nan
        return
    # the range of lines only: one more on each side is tested as the model does
    k0 = math.ceil((h_lo - offsets[n_o - 1]) / s) - 1
    k1 = math.floor((h_hi - offsets[0]) / s) + 1
    i0, i1 = 0, 0
    last0, last1 = counts[0] - 1, counts[1] - 1
    for k in range(k0, k1 + 1):
        for j in range(n_o):
            c = offsets[j] + float(k) * s
            if c < h_lo - near or c > h_hi + near or vals[j] != vals[j]:
                continue
            if c - h_lo < near or h_hi - c < near:
                vals[j] = np.nan
                continue
            while i0 < last0 and ch[0, i0, 1] <= c:
                i0 += 1
            while i1 < last1 and ch[1, i1, 1] <= c:
                i1 += 1
            lo0, hi0, lo1, hi1 = ch[0, i0, 0], ch[0, i0, 1], ch[1, i1, 0], ch[1, i1, 1]
            if not (lo0 + near <= c <= hi0 - near and lo1 + near <= c <= hi1 - near):
                vals[j] = np.nan  # near a vertex, or not between the chains' ends
                continue
            t0 = ch[0, i0, 2] + (c - lo0) * ch[0, i0, 3]
            t1 = ch[1, i1, 2] + (c - lo1) * ch[1, i1, 3]
            length = abs(t0 - t1)
            if length > tiny:
                if sums[0, j] == 0:
                    sums[3, j] = length  # the sums are of the lengths minus the first
                x = length - sums[3, j]
                sums[0, j] += 1.0
                sums[1, j] += x
                sums[2, j] += x * x
    for j in range(n_o):
        if vals[j] != vals[j]:
            continue
        total = sums[0, j]
        if not total > 0:
            vals[j] = -np.inf
            continue
        m1 = sums[1, j] / total
        var = max(sums[2, j] / total - m1 * m1, 0.0)
        std = math.sqrt(var) if var > 2.220446049250313e-16**2 else 0.0
        value = a * (sums[3, j] + m1) + b * (1.0 - std)
        vals[j] = -np.inf if value != value else value


def _screened_check(
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
    found: float,
    out: np.ndarray,
) -> bool:
    """The spot check's grid scored by :func:`_screen_value` (the exact model where it
    declines): its first best layout into ``out[3:6]`` (angle, offset, fitness); returns
    whether a value came within :data:`SCREEN_MARGIN` of ``found + 1e-12`` (the caller then
    scores the whole grid by the exact model)."""
    n = v.shape[0]
    across, along, lengths = lanes[0], lanes[1], lanes[2]
    ch, counts = np.empty((2, n, 4)), np.empty(2, dtype=np.int64)
    sums, vals = np.empty((4, len(offsets))), np.empty(len(offsets))
    sweep = True  # the offsets ascending in [0, s): one sweep an angle
    for j in range(len(offsets)):
        if not (0.0 <= offsets[j] < s and (j == 0 or offsets[j - 1] < offsets[j])):
            sweep = False
    top, top_i, top_j = -np.inf, 0, 0
    first = True
    for i in range(len(angles)):
        h_lo, h_hi = _angle_setup(normals, v, angles[i], across, along)
        if sweep:
            _chains_at(v, angles[i], ch, counts)
            _screen_angle(ch, counts, h_lo, h_hi, radius, s, offsets, a, b, sums, vals)
        else:
            vals[:] = np.nan
        for j in range(len(offsets)):
            val = vals[j]
            if val != val:
                val = _layout_value(
                    across, along, boffs, h_lo, h_hi, radius, s, k_count, m, offsets[j], a, b,
                    lengths,
                )  # fmt: skip
            if first or val > top:  # np.argmax: the first largest
                top, top_i, top_j = val, i, j
                first = False
    out[3], out[4], out[5] = angles[top_i], offsets[top_j], top
    return not (top <= found + 1e-12 - SCREEN_MARGIN)


_ETAS = (0.0, 1e-9, 1e-6, 1e-3)


def _finish(
    v: np.ndarray,
    s: float,
    thetas: np.ndarray,
    a: float,
    b: float,
    max_candidates: float,
    check_angles: np.ndarray,
    check_offsets: np.ndarray,
    tops: np.ndarray,
    check: bool,
    out: np.ndarray,
) -> None:
    """What :func:`.smith.global_optimum` does after its search, in one call: the best layout
    near the closed-form optimum (:func:`.smith._attained` at ``thetas``) and the spot check's
    best layout (:func:`.smith._spot_check` on ``check_angles x check_offsets``), scored by
    the exact model with the polygon's half-planes (:func:`_halfplanes_into`), the same
    operations in the same order. ``tops (R, 4)``: at each angle the number of pieces and the
    pieces whose maximisers are candidates (the largest values first: numpy's
    ``argsort(-value)`` keeps them), or ``tops[0, 0] = -1`` to find them here, except at a
    tie; ``check``: whether to do the spot check (after the candidates: screened against
    their best, :mod:`.kernel_check`). ``out (7,)``: fitness, angle, offset; the check's
    angle, offset, fitness; then 0, or 1 where the caller must do it all itself (too many
    lines for the model), or 2 where it must give ``tops`` (two pieces' values tie: their
    order is numpy's sort's; nothing is done)."""
    n = v.shape[0]
    out[6] = 1.0
    normals, boffs = np.empty((n, 2)), np.empty(n)
    radius = _halfplanes_into(v, normals, boffs)
    if 2 * radius / s > max_candidates:
        return  # grid_size refuses it: the caller raises its error
    m = int(np.ceil(radius / s)) + 1
    k_count = 2 * m
    h, t, x, tu, td, pc, fam, rn, mo, cc, work, iwork = _structure_scratch(n)
    top = np.empty(4, dtype=np.int64)
    lanes = np.empty((3, max(k_count, n)))
    across, along, lengths = lanes[0], lanes[1], lanes[2]
    best, best_theta, best_d = -np.inf, thetas[0], 0.0
    for row in range(len(thetas)):
        theta = thetas[row]
        _structure_one(v, s, theta, h, t, x, tu, td, pc, fam, rn, work, iwork)
        _pieces_one(rn, a, b, mo, cc)
        if tops[0, 0] < 0:
            kept = _top_pieces(mo[:, _VALUE], top)
            if kept < 0:
                out[6] = 2.0
                return
        else:
            kept = tops[row, 0]
            top[:3] = tops[row, 1:]
        if kept == 0:
            continue
        h_lo, h_hi = _angle_setup(normals, v, theta, across, along)
        row_best, row_d = -np.inf, 0.0
        first = True
        for k in range(kept):
            p = top[k]
            lam = mo[p, _LAM]
            for eta in _ETAS:
                lam_p = eta if eta > lam else lam  # Python's min(max(lam, eta), 1 - eta)
                upper = 1.0 - eta
                lam_p = upper if upper < lam_p else lam_p
                offset = pc[p, 0] + lam_p * pc[p, 1]
                val = _layout_value(
                    across, along, boffs, h_lo, h_hi, radius, s, k_count, m, offset, a, b,
                    lengths,
                )  # fmt: skip
                if first or val > row_best:  # np.argmax: the first largest
                    row_best, row_d = val, offset
                    first = False
        if row_best > best:
            best, best_theta, best_d = row_best, theta, row_d
    out[0], out[1], out[2] = best, best_theta, best_d
    if check and _screened_check(
        v, normals, boffs, radius, s, k_count, m, a, b, check_angles, check_offsets, lanes, best,
        out
    ):  # fmt: skip
        _check_into(v, normals, boffs, radius, s, k_count, m, a, b, check_angles, check_offsets,
                    lanes, out)  # fmt: skip
    out[6] = 0.0
