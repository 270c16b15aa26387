"""Lanes of one transect grid over a region: segments cut at the boundary and the holes."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError
from ..geometry import Polygon
from ..geometry.region import Region, as_region
from ..models import check_spacing
from .cells import _TOL, _crossings, _frame, trapezoids
from .types import Layout

__all__ = [
    "Lanes",
    "region_lanes",
]


# -- lanes ------------------------------------------------------------------------------------
class Lanes(NamedTuple):
    """Lane segments of one transect grid (plan units).

    Segment ``i`` lies on line ``k[i]`` (position ``c[i]`` from ``origin`` along the left normal
    of ``angle``) and spans ``t0[i] <= t <= t1[i]`` along it; sorted by line, then along it.
    ``cut`` lists the holes that cut any lane (their parts of the lines were removed).
    """

    angle: float
    origin: NDArray[np.float64]
    k: NDArray[np.int64]
    c: NDArray[np.float64]
    t0: NDArray[np.float64]
    t1: NDArray[np.float64]
    cut: frozenset[int]

    def points(self, t: ArrayLike) -> NDArray[np.float64]:
        u, n = _frame(self.angle)
        t = np.asarray(t, float)
        return self.origin + self.c[:, None] * n + t[..., None] * u

    @property
    def segments(self) -> NDArray[np.float64]:
        """``(T, 2, 2)`` the segments from ``t0`` to ``t1``."""
        return np.stack([self.points(self.t0), self.points(self.t1)], axis=1)


def _merge_intervals(
    key: NDArray[np.int64], lo: NDArray[np.float64], hi: NDArray[np.float64], tol: float
) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]:
    order = np.lexsort((lo, key))
    key, lo, hi = key[order], lo[order], hi[order]
    out_k: list[int] = []
    out_lo: list[float] = []
    out_hi: list[float] = []
    for kk, a, b in zip(key, lo, hi, strict=True):
        if out_k and out_k[-1] == kk and a <= out_hi[-1] + tol:
            out_hi[-1] = max(out_hi[-1], b)
        else:
            out_k.append(int(kk))
            out_lo.append(float(a))
            out_hi.append(float(b))
    return np.array(out_k, dtype=np.int64), np.array(out_lo), np.array(out_hi)


def _intervals_on_lines(
    edges: NDArray[np.float64],
    u: NDArray[np.float64],
    n: NDArray[np.float64],
    c: NDArray[np.float64],
) -> list[list[tuple[float, float]]]:
    t, _, count = _crossings(edges, u, n, c)
    out = []
    for row, cnt in zip(t, count, strict=True):
        out.append([(float(row[i]), float(row[i + 1])) for i in range(0, int(cnt) - 1, 2)])
    return out


def _subtract(
    pieces: list[tuple[float, float]], cuts: list[tuple[float, float]], tol: float
) -> tuple[list[tuple[float, float]], bool]:
    out, changed = pieces, False
    for g0, g1 in cuts:
        nxt = []
        for a, b in out:
            if g1 <= a or g0 >= b:
                nxt.append((a, b))
                continue
            changed = True
            if g0 - a > tol:
                nxt.append((a, g0))
            if b - g1 > tol:
                nxt.append((g1, b))
        out = nxt
    return out, changed


def region_lanes(
    cover: Region | Polygon | ArrayLike,
    spacing: float,
    angle: float,
    offset: float = 0.0,
    *,
    reach: float | None = None,
    holes: Sequence[Polygon] = (),
    layout: Layout = "guaranteed",
    origin: ArrayLike | None = None,
) -> Lanes:
    """Lane segments covering ``cover`` at one transect grid, never entering ``holes``.

    Args:
        cover: the region (or cell) the lanes must cover, plan units.
        spacing, angle, offset: the grid; ``offset`` from ``origin`` (default: the cover's
            vertex mean), as everywhere in boustro.
        reach: half-width of each lane's band (default ``spacing / 2``).
        holes: obstacles no lane may enter (the area's holes; those of ``cover`` itself are
            avoided anyway).
        layout: ``"guaranteed"`` (each lane spans the projection of band ∩ cover, module
            docstring) or ``"chords"`` (the lines' exact segments inside the cover).
    """
    r = as_region(cover)
    s = check_spacing(spacing, extent=r.diameter)
    reach = s / 2 if reach is None else float(reach)
    o = r.centre if origin is None else np.asarray(origin, dtype=np.float64)
    _, n = _frame(angle)
    tol = _TOL * r.diameter
    vc = (r.vertices - o) @ n
    k_min = math.floor((vc.min() - reach - offset) / s) - 1
    k_max = math.ceil((vc.max() + reach - offset) / s) + 1
    ks = np.arange(k_min, k_max + 1)
    if layout == "guaranteed":
        key, lo, hi = _band_intervals(r, angle, o, s, offset, reach)
    elif layout == "chords":
        key, lo, hi = _chord_intervals(r, angle, o, ks, offset + ks * s)
    else:
        raise InvalidParameterError(f"layout must be 'guaranteed' or 'chords', got {layout!r}")
    per_line: dict[int, list[tuple[float, float]]] = {int(kk): [] for kk in np.unique(key)}
    for kk, a, b in zip(key, lo, hi, strict=True):
        per_line[int(kk)].append((float(a), float(b)))
    cut = _cut_holes(per_line, holes, angle, o, s, offset, tol)
    out_k, out_lo, out_hi = [], [], []
    for kk in sorted(per_line):
        for a, b in sorted(per_line[kk]):
            out_k.append(kk)
            out_lo.append(a)
            out_hi.append(b)
    k_arr = np.array(out_k, dtype=np.int64)
    return Lanes(
        float(angle),
        o,
        k_arr,
        np.asarray(offset + k_arr * s, dtype=np.float64),
        np.array(out_lo, dtype=np.float64),
        np.array(out_hi, dtype=np.float64),
        frozenset(cut),
    )


Intervals = tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]


def _band_intervals(
    r: Region, angle: float, o: NDArray[np.float64], s: float, offset: float, reach: float
) -> Intervals:
    """``(line index, t_lo, t_hi)`` of the guaranteed layout: each lane spans the projection of
    its band ∩ cover onto its line (from the trapezoids, in closed form), merged per line."""
    tol = _TOL * r.diameter
    tr = trapezoids(r, angle, o)
    lo_k = np.floor((tr.a - reach - offset) / s).astype(np.int64) + 1
    hi_k = np.ceil((tr.b + reach - offset) / s).astype(np.int64) - 1
    counts = np.maximum(hi_k - lo_k + 1, 0)
    which = np.repeat(np.arange(len(tr.a)), counts)
    first = np.repeat(np.cumsum(counts) - counts, counts)
    k = lo_k[which] + (np.arange(len(which)) - first)
    c = offset + k * s
    alpha = np.maximum(tr.a[which], c - reach)
    beta = np.minimum(tr.b[which], c + reach)
    ok = beta - alpha > tol
    which, k, alpha, beta = which[ok], k[ok], alpha[ok], beta[ok]
    width = np.where(tr.b - tr.a > 0, tr.b - tr.a, 1.0)[which]
    fa, fb = (alpha - tr.a[which]) / width, (beta - tr.a[which]) / width
    te = lambda f: tr.te_a[which] + (tr.te_b[which] - tr.te_a[which]) * f  # noqa: E731
    tx = lambda f: tr.tx_a[which] + (tr.tx_b[which] - tr.tx_a[which]) * f  # noqa: E731
    lo = np.minimum(te(fa), te(fb))
    hi = np.maximum(tx(fa), tx(fb))
    return _merge_intervals(k, lo, hi, tol)


def _chord_intervals(
    r: Region, angle: float, o: NDArray[np.float64], ks: NDArray[np.int64], cs: NDArray[np.float64]
) -> Intervals:
    """``(line index, t_lo, t_hi)`` of the chords layout: the lines' segments inside the cover."""
    tol = _TOL * r.diameter
    u, n = _frame(angle)
    rows = _intervals_on_lines(r.edges - o, u, n, cs)
    key_l, lo_l, hi_l = [], [], []
    for kk, row in zip(ks, rows, strict=True):
        for a, b in row:
            if b - a > tol:
                key_l.append(int(kk))
                lo_l.append(a)
                hi_l.append(b)
    return np.array(key_l, dtype=np.int64), np.array(lo_l), np.array(hi_l)


def _cut_holes(
    per_line: dict[int, list[tuple[float, float]]],
    holes: Sequence[Polygon],
    angle: float,
    o: NDArray[np.float64],
    s: float,
    offset: float,
    tol: float,
) -> set[int]:
    """Cut out (in place) the parts of each line inside a hole, where the lines at c - eps and
    c + eps are inside it too (a line along a hole's edge, or through its extreme vertex, is not
    cut). Returns the indices of the holes that cut a lane."""
    u, n = _frame(angle)
    cut: set[int] = set()
    eps = 1e-7 * max(s, tol)
    for h_index, hole in enumerate(holes):
        he = np.stack([hole.vertices, np.roll(hole.vertices, -1, axis=0)], axis=1) - o
        hc = he[:, :, :] @ n
        lines_hit = [kk for kk in per_line if hc.min() < offset + kk * s < hc.max()]
        if not lines_hit:
            continue
        cpos = offset + np.array(lines_hit, dtype=np.float64) * s
        at = _intervals_on_lines(he, u, n, cpos)
        below = _intervals_on_lines(he, u, n, cpos - eps)
        above = _intervals_on_lines(he, u, n, cpos + eps)
        for kk, g_at, g_lo, g_hi in zip(lines_hit, at, below, above, strict=True):
            gaps = [
                (x0, x1)
                for x0, x1 in g_at
                if any(min(x1, b1) > max(x0, b0) for b0, b1 in g_lo)
                and any(min(x1, b1) > max(x0, b0) for b0, b1 in g_hi)
            ]
            if gaps:
                per_line[kk], changed = _subtract(per_line[kk], gaps, tol)
                if changed:
                    cut.add(h_index)
    return cut
