"""The certified shortest-path layout (branch and bound, convex in the offset)."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..._torch import torch
from ...errors import NoTransectError
from ...geometry import Polygon, halfplanes
from ...models import (
    check_spacing,
    exact_chords,
)
from ...objectives import GRAZE, path_length
from ...scoring import as_polygon
from ..result import OptimizeResult, canonical
from .search import _BATCH, _branch_and_bound, _check_count, _check_tol
from .structure import Array, _check_work, _runs, _Structure, _structure

__all__ = ["shortest_path_optimum"]


@dataclass
class _PathPieces:
    """Every piece's transects and their ends as affine functions of ``lam`` ``(M, P, K)``."""

    valid: NDArray[np.bool_]
    run: NDArray[np.intp]  # run (segment) of each transect
    u0: Array  # upper end t at lam = 0
    ub: Array  # its slope in lam
    d0: Array
    db: Array
    pos: Array  # position of each transect at lam = 0


def _path_pieces(st: _Structure, s: float) -> _PathPieces:
    """Expand every piece's runs into its transects, in order of position."""
    cnt = st.count
    j_count = cnt.shape[-1]
    total = cnt.sum(axis=-1)
    k_count = max(int(total.max()) if total.size else 0, 1)
    cum = np.cumsum(cnt, axis=-1)
    start = cum - cnt
    t = np.arange(k_count, dtype=np.float64)
    run = (t[:, None] >= cum[..., None, :]).sum(axis=-1)  # (M, P, K)
    valid = t < total[..., None]
    run = np.minimum(run, j_count - 1)

    def gather(arr: Array) -> Array:
        return np.take_along_axis(np.broadcast_to(arr, cnt.shape), run, axis=-1)

    i = t - gather(start)
    x0 = st.x[:, None, :-1]
    wx = st.x[:, None, 1:] - x0
    wxs = gather(np.where(wx > 0, wx, 1.0))
    rel = gather(st.rel_lo) + i * s
    phi = rel / wxs
    scale = st.width[..., None] / wxs
    out = []
    for chain in (st.tu, st.td):
        c0 = gather(chain[:, None, :-1])
        c1 = gather(chain[:, None, 1:])
        out.append(((1.0 - phi) * c0 + phi * c1, (c1 - c0) * scale))
    pos = gather(x0) + rel
    zero = np.zeros_like(phi)
    return _PathPieces(
        valid,
        run,
        np.where(valid, out[0][0], zero),
        np.where(valid, out[0][1], zero),
        np.where(valid, out[1][0], zero),
        np.where(valid, out[1][1], zero),
        np.where(valid, pos, zero),
    )


def _path_minimise(pp: _PathPieces, s: float) -> tuple[Array, Callable[[Array], Array]]:
    """Unconstrained minimiser ``lam*`` in ``[0, 1]`` of the (convex) path length of every piece
    and start side ``(2, M, P)``, and a function evaluating the length at any ``lam``."""
    length0 = ((pp.u0 - pp.d0) * pp.valid).sum(axis=-1)
    length1 = ((pp.ub - pp.db) * pp.valid).sum(axis=-1)
    pair = pp.valid[..., 1:] & pp.valid[..., :-1]
    du0, dub = np.diff(pp.u0, axis=-1), np.diff(pp.ub, axis=-1)
    dd0, ddb = np.diff(pp.d0, axis=-1), np.diff(pp.db, axis=-1)
    even = (np.arange(du0.shape[-1]) % 2) == 0
    # start 0: first move on the upper side; start 1: on the lower side
    x0 = np.stack([np.where(even, du0, dd0), np.where(even, dd0, du0)]) * pair
    x1 = np.stack([np.where(even, dub, ddb), np.where(even, ddb, dub)]) * pair
    s2 = s * s

    def value(lam: Array) -> Array:
        z = x0 + x1 * lam[..., None]
        moves = (np.sqrt(s2 + z * z) * pair).sum(axis=-1)
        return length0 + length1 * lam + moves

    def slope(lam: Array) -> tuple[Array, Array]:
        z = x0 + x1 * lam[..., None]
        r = np.sqrt(s2 + z * z)
        d1 = length1 + (z * x1 / r * pair).sum(axis=-1)
        d2 = (s2 * x1 * x1 / r**3 * pair).sum(axis=-1)
        return d1, d2

    shape = x0.shape[:-1]
    lo, hi = np.zeros(shape), np.ones(shape)
    g0, _ = slope(lo)
    g1, _ = slope(hi)
    lam = np.full(shape, 0.5)
    for _ in range(40):
        g, h = slope(lam)
        lo = np.where(g > 0, lo, lam)
        hi = np.where(g > 0, lam, hi)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = lam - g / h
        inside = np.isfinite(step) & (step > lo) & (step < hi)
        new = np.where(inside, step, 0.5 * (lo + hi))
        if np.all(np.abs(new - lam) <= 1e-15):
            lam = new
            break
        lam = new
    lam = np.where(g0 >= 0, 0.0, np.where(g1 <= 0, 1.0, lam))
    return lam, value


def _evaluate_path(
    v: Array, s: float, lo: Array, hi: Array, coverage: bool
) -> tuple[Array, Array, Array, Array]:
    """Negated shortest path (to maximise) at every interval's centre, the offset attaining it,
    the negated lower bound over the interval, and the bound's order (1), as
    :func:`_branch_and_bound` wants them."""
    g = np.full(len(lo), -np.inf)
    d = np.zeros(len(lo))
    ub = np.full(len(lo), -np.inf)
    batch = max(16, _BATCH // 8)
    for start in range(0, len(lo), batch):
        sl = slice(start, start + batch)
        mid = 0.5 * (lo[sl] + hi[sl])
        half = 0.5 * (hi[sl] - lo[sl])
        st = _structure(v, s, mid)
        pp = _path_pieces(st, s)
        lam, value = _path_minimise(pp, s)  # (2, M, P)
        width = st.width
        has = st.count.sum(axis=-1) > 0
        wsafe = np.where(width > 0, width, 1.0)
        if coverage:
            total = st.count.sum(axis=-1).astype(np.intp)
            last = np.maximum(total - 1, 0)[..., None]
            first_pos = pp.pos[..., 0]
            last_pos = np.take_along_axis(pp.pos, last, axis=-1)[..., 0]
            hmin, hmax = st.x[:, :1], st.x[:, -1:]
            lam_hi = (hmin + 0.5 * s - first_pos) / wsafe
            lam_lo = (hmax - 0.5 * s - last_pos) / wsafe
            # a margin moves by at most 2 (two t-differences, each <= the diameter 1) per radian
            slack = 2.0 * half[:, None] / wsafe
        else:
            lam_lo = np.zeros(width.shape)
            lam_hi = np.ones(width.shape)
            slack = np.zeros(width.shape)
        a_lo, a_hi = np.maximum(lam_lo, 0.0), np.minimum(lam_hi, 1.0)
        feasible = has & (a_lo <= a_hi) & (width > 0)
        exact_lam = np.clip(lam, a_lo, a_hi)
        exact = np.where(feasible, value(exact_lam), np.inf)  # (2, M, P)
        r_lo, r_hi = np.maximum(lam_lo - slack, 0.0), np.minimum(lam_hi + slack, 1.0)
        relaxed_ok = has & (r_lo <= r_hi)
        relaxed = np.where(relaxed_ok, value(np.clip(lam, r_lo, r_hi)), np.inf)
        # first-order drift of the whole path over the interval
        ru = _runs(v, st, half, s, second=False)
        assert ru.end_drift is not None
        ends = np.maximum(ru.end_drift[0], ru.end_drift[1])
        drift = (st.count * (ru.drift + 2.0 * ends)).sum(axis=-1)
        drift = np.where(np.isnan(drift), np.inf, drift)
        lower = np.where(relaxed_ok, relaxed - drift, np.inf).min(axis=0)  # over start sides
        flat = exact.reshape(2, len(mid), -1)
        best = np.argmin(flat.transpose(1, 0, 2).reshape(len(mid), -1), axis=1)
        side_k, piece = np.divmod(best, flat.shape[2])
        rows = np.arange(len(mid))
        g[sl] = -flat[side_k, rows, piece]
        d[sl] = st.beta[rows, piece] + exact_lam[side_k, rows, piece] * width[rows, piece]
        ub[sl] = -lower.min(axis=1)
    return g, d, ub, np.ones(len(lo))


def _layout_path(
    v: Array, s_n: float, theta: float, offsets: Array, coverage: bool
) -> tuple[Array, Array]:
    """Exact path length (normalised frame) of layouts at one angle and several offsets, ``inf``
    where the swaths fail to cover the polygon (if ``coverage``), and their transect counts."""
    hp = halfplanes(Polygon(v), normalise=False)
    ch = exact_chords(
        hp,
        torch.tensor(float(theta), dtype=torch.float64),
        torch.as_tensor(offsets, dtype=torch.float64),
        s_n,
    )
    total = path_length(ch).numpy().copy()
    lengths = ch.lengths.numpy()
    pos = ch.positions.numpy()
    shown = lengths > GRAZE
    count = shown.sum(axis=1)
    total = np.where(count > 0, total, np.inf)
    if coverage:
        h = v[:, 1] * math.cos(theta) - v[:, 0] * math.sin(theta)
        first = np.where(shown, pos, np.inf).min(axis=1)
        last = np.where(shown, pos, -np.inf).max(axis=1)
        slack = 1e-9 * s_n
        ok = (first - h.min() <= 0.5 * s_n + slack) & (h.max() - last <= 0.5 * s_n + slack)
        total = np.where(ok, total, np.inf)
    return total, count


def shortest_path_optimum(
    polygon: Polygon | ArrayLike,
    spacing: float,
    *,
    coverage: bool = True,
    rtol: float = 1e-6,
    max_evaluations: int = 500_000,
    progress: bool | None = None,
) -> OptimizeResult:
    """The layout with the shortest boustrophedon path, with a certified lower bound.

    The path (:class:`~boustro.objectives.ShortestPath`) is every transect plus the straight
    move between consecutive transects' ends, alternating sides, starting on the better side. On
    a piece of the offset circle the transects and the sides of the moves are fixed and every
    end moves linearly, so the path is convex in the offset: it is minimised exactly (safeguarded
    Newton). Branch and bound over the angle as for Eq. 1, with a first-order bound on how far
    every transect end can move over an angle interval.

    Args:
        polygon: convex polygon, user units.
        spacing: transect spacing, user units, > 0.
        coverage: only layouts whose swaths cover the polygon (first and last transects within
            half a spacing of its extremes), as a planner needs; False: any layout.
        rtol: relative optimality gap to certify (of the area / spacing, the path's scale).
        max_evaluations: cap on angle evaluations (the bound stays valid, ``converged`` False).
        progress: accepted for the common optimiser interface; the search shows no bar.

    Returns:
        :class:`~boustro.optimize.OptimizeResult` with ``method="shortest_path"``, ``fitness`` =
        the path length in the polygon's units (minimised: ``upper_bound`` is None), and
        ``info["lower_bound"]`` (polygon units) <= every layout's path, ``info["gap"]``,
        ``info["n_transects"]``, ``info["converged"]``.
    """
    t0 = time.perf_counter()
    del progress
    poly = as_polygon(polygon).require_convex("the shortest-path optimiser")
    spacing = check_spacing(spacing, extent=poly.diameter)
    _check_work(poly, spacing, "the shortest-path optimiser")
    rtol = _check_tol(rtol)
    frame = poly.frame
    v = frame.to_normalised(poly.vertices)
    s_n = spacing / frame.scale
    tol = rtol * (poly.area / frame.scale**2) / s_n

    def evaluate(lo: Array, hi: Array, threshold: float) -> tuple[Array, Array, Array, Array]:
        return _evaluate_path(v, s_n, lo, hi, coverage)

    with np.errstate(all="ignore"):  # infinities are meant: they mark missing bounds
        search = _branch_and_bound(
            v, s_n, evaluate, tol, _check_count("max_evaluations", max_evaluations)
        )
    best = (math.inf, search.theta, search.offset, 0)
    for theta in (search.theta, search.lo, search.hi):
        offsets = search.offset + s_n * np.array([0.0, 1e-9, -1e-9, 1e-6, -1e-6])
        total, count = _layout_path(v, s_n, float(theta), offsets, coverage)
        k = int(np.argmin(total))
        if total[k] < best[0]:
            best = (float(total[k]), float(theta), float(offsets[k]), int(count[k]))
    value, theta, d, n_transects = best
    if not math.isfinite(value):
        raise NoTransectError("no layout found (this is a bug: please report the polygon)")
    lower = -search.upper_bound
    angle, offset = canonical(theta, d * frame.scale, spacing)
    return OptimizeResult(
        angle=angle,
        offset=offset,
        fitness=value * frame.scale,
        spacing=spacing,
        method="shortest_path",
        evaluations=search.evaluations,
        seconds=time.perf_counter() - t0,
        upper_bound=None,
        info={
            "objective": "shortest_path",
            "maximise": False,
            "lower_bound": min(lower, value) * frame.scale,
            "gap": max(value - lower, 0.0) * frame.scale,
            "n_transects": n_transects,
            "coverage": coverage,
            "events": search.events,
            "rounds": search.rounds,
            "converged": search.converged,
            "rtol": rtol,
        },
    )
