"""Holes that every plan of a box of layouts cuts, from the box's rigid motions (see
:class:`~boustro.optimize.cover.bands.BandStats`, field ``rigid``); the loop is compiled by
numba with the rest of :mod:`~boustro.optimize.cover.bands`."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..._jit import jit_globals

__all__ = ["WIDE_CUTS", "RigidBoxes", "SplitRings", "jit_wide", "split_rings", "wide_rings"]

#: The rigid cuts' and split gaps' holes are the holes eroded by this many planner's ``eps``
#: (``1e-7 max(spacing, tol)``: :func:`boustro.plan.lanes._cut_holes` cuts a line only where
#: the lines at ``c - eps`` and ``c + eps`` cross the hole too): a line through the eroded hole
#: passes within a disc of radius above ``eps`` of the hole (the buffer's arcs are inscribed:
#: at least ``0.98`` of this radius), so the planner cuts it there; near a thin hole's sharp tip
#: (thinner than ``eps``) it does not (a review: a 1 mm fence's tip 2 mm off a line; a 1 um
#: thin hole the planner never cuts, whose rigid cut and pass the bound counted).
SPLIT_ERODE = 4.0


class SplitRings(NamedTuple):
    """The rings of the holes eroded for the split gaps (:func:`split_rings`): vertices ``xy
    (V, 2)`` (ring ``j``: rows ``start[j]:start[j + 1]``) and the hole each comes from,
    ``parent (J,)``."""

    xy: NDArray[np.float64]
    start: NDArray[np.int64]
    parent: NDArray[np.int64]
    wide: NDArray[np.float64] | None = None  # per ring: :func:`wide_rings`


def split_rings(
    holes: list[NDArray[np.float64]],
    spacing: float,
    tol: float,
    shell: NDArray[np.float64] | None = None,
    reach: float = 0.0,
) -> SplitRings:
    """The holes (rings ``(n, 2)``) eroded by ``SPLIT_ERODE * 1e-7 * max(spacing, tol)``, one
    ring per connected part (a hole thinner than that anywhere gives none there); with the
    area's ``shell`` and the lanes' ``reach``, also :func:`wide_rings` (else no width test)."""
    import shapely  # lazily: ``import boustro`` does not load shapely

    r = SPLIT_ERODE * 1e-7 * max(spacing, tol)
    rings: list[NDArray[np.float64]] = []
    parent: list[int] = []
    for h, ring in enumerate(holes):
        eroded = shapely.Polygon(ring).buffer(-r, quad_segs=8)
        for part in getattr(eroded, "geoms", [eroded]):
            if part.is_empty or part.area <= 0:
                continue
            rings.append(np.asarray(part.exterior.coords, dtype=np.float64)[:-1])
            parent.append(h)
    xy = np.concatenate(rings) if rings else np.zeros((0, 2))
    start = np.concatenate([[0], np.cumsum([len(g) for g in rings])]).astype(np.int64)
    out = SplitRings(xy, start, np.asarray(parent, dtype=np.int64))
    if shell is None or reach <= 0:
        return out
    return out._replace(wide=wide_rings(out, holes, shell, reach, tol))


#: Whether a convex, isolated hole wider than the spacing across every line direction of a box
#: is a rigid cut of the box (:func:`wide_rings`, :func:`_rigid_cuts`): issue 21's 6 m holes
#: span a 10 m band, so no inner piece covers them at a box of metres (docs/scale.md, "Holes
#: wider than the spacing (fifteenth round)").
WIDE_CUTS = True

#: The least turn (its sine) at every vertex of a hole for :func:`wide_rings`: no two edges are
#: (nearly) one straight piece.
WIDE_TURN = 1e-6

#: :func:`wide_rings` admits a hole whose edges are all shorter than ``2 reach`` less this many
#: planner's tolerances (``tol``, :data:`boustro.plan.cells._TOL` times the area's diameter):
#: the planner drops a band's slab thinner than ``tol`` (``lanes._band_intervals``), so an edge
#: across the lines within ``tol`` of the band's width leaves its lane uncut (docs/scale.md).
WIDE_EDGE_TOLS = 8.0


def wide_rings(
    rings: SplitRings,
    holes: list[NDArray[np.float64]],
    shell: NDArray[np.float64],
    reach: float,
    tol: float,
) -> NDArray[np.float64]:
    """Per ring of ``rings``: its diameter (largest distance between two of its vertices) where
    the hole it comes from is the ring's only part, strictly convex (every vertex turns by a
    sine of at least :data:`WIDE_TURN`, one way), every edge shorter than ``2 reach`` (a lane's
    band) less :data:`WIDE_EDGE_TOLS` ``tol`` (the planner's tolerance, plan units), and at
    least ``reach`` from the ``shell``'s boundary and from every other hole; else ``nan`` (no
    width test, :func:`_rigid_cuts`)."""
    import shapely  # lazily: ``import boustro`` does not load shapely

    wide = np.full(len(rings.parent), np.nan)
    if not WIDE_CUTS:
        return wide
    polys = [shapely.Polygon(h) for h in holes]
    boundary = shapely.LinearRing(shell)
    parts = np.bincount(rings.parent, minlength=len(holes))
    for j, h in enumerate(rings.parent):
        ring = np.asarray(holes[h], dtype=np.float64)
        e = np.roll(ring, -1, axis=0) - ring
        length = np.hypot(e[:, 0], e[:, 1])
        if parts[h] != 1 or length.min() <= 0 or length.max() >= 2 * reach - WIDE_EDGE_TOLS * tol:
            continue
        nxt = np.roll(e, -1, axis=0)
        sine = (e[:, 0] * nxt[:, 1] - e[:, 1] * nxt[:, 0]) / (length * np.roll(length, -1))
        if not (np.all(sine >= WIDE_TURN) or np.all(sine <= -WIDE_TURN)):
            continue
        if shapely.distance(polys[h], boundary) < reach:
            continue
        if any(g != h and shapely.distance(polys[h], p) < reach for g, p in enumerate(polys)):
            continue
        v = rings.xy[rings.start[j] : rings.start[j + 1]]
        wide[j] = max(float(np.hypot(*(v - p).T).max()) for p in v)  # O(len(v)) memory
    return wide


class RigidBoxes(NamedTuple):
    """The holes' vertices ``xy (V, 2)`` (hole ``h``: rows ``start[h]:start[h + 1]``) and the
    boxes' half-widths ``delta`` (angle) and ``eta`` (offset), ``(L,)``: for ``rigid``; the
    holes eroded for the rigid cuts and split gaps, ``split`` (:func:`split_rings`; without,
    :func:`~.bands.band_stats` erodes ``xy`` itself)."""

    xy: NDArray[np.float64]
    start: NDArray[np.int64]
    delta: NDArray[np.float64]
    eta: NDArray[np.float64]
    split: SplitRings | None = None


def _hole_extents(hxy, hstart, cs, sn, ox, oy, delta, eta, tol, ext):
    """Per ring ``h``, ``ext[h] = (n_lo, n_hi, u_lo, u_hi, m)``: its extents across and along
    the lines of the layout and ``m = delta rho + eta + tol``, the most any of its points moves
    in the box (``rho``: its farthest vertex from the origin)."""
    for h in range(hstart.shape[0] - 1):
        n_lo, n_hi, u_lo, u_hi, rho = np.inf, -np.inf, np.inf, -np.inf, 0.0
        for v in range(hstart[h], hstart[h + 1]):
            x, y = hxy[v, 0] - ox, hxy[v, 1] - oy
            nv, uv = -sn * x + cs * y, cs * x + sn * y
            n_lo, n_hi = min(n_lo, nv), max(n_hi, nv)
            u_lo, u_hi = min(u_lo, uv), max(u_hi, uv)
            rho = max(rho, math.sqrt(x * x + y * y))
        ext[h, 0], ext[h, 1], ext[h, 2], ext[h, 3] = n_lo, n_hi, u_lo, u_hi
        ext[h, 4] = delta * rho + eta + tol


def _rigid_cuts(ext, parent, d, s, k0, nb, i_start, i_m, i_lo, i_hi, rigid, wide, delta, tol):
    """``rigid[parent[h]]``: the hole of ring ``h`` (of the holes eroded past the planner's eps,
    :func:`split_rings`: a line through them is cut by the planner; extents ``ext`` from
    :func:`_hole_extents`) is cut by every plan of the box (:class:`BandStats`), by one line
    through it at every layout or (:func:`_wide_cut`) by its width."""
    for h in range(ext.shape[0]):
        if rigid[parent[h]]:
            continue
        n_lo, n_hi, u_lo, u_hi, m = ext[h, 0], ext[h, 1], ext[h, 2], ext[h, 3], ext[h, 4]
        if _wide_cut(n_lo, n_hi, m, wide[h], delta, tol, d, s, k0, nb):
            rigid[parent[h]] = True
            continue
        ka = max(math.ceil((n_lo + m - d) / s), k0)
        kb = min(math.floor((n_hi - m - d) / s), k0 + nb - 1)
        for k in range(ka, kb + 1):
            c = d + k * s
            if not (n_lo + m < c < n_hi - m):
                continue
            b = k - k0
            found = False
            for j in range(i_start[b], i_start[b] + i_m[b]):
                if i_lo[j] <= u_lo - m and i_hi[j] >= u_hi + m:
                    found = True
                    break
            if found:
                rigid[parent[h]] = True
                break


def _wide_cut(n_lo, n_hi, m, wide, delta, tol, d, s, k0, nb):
    """Whether a ring of :func:`wide_rings` (``wide``: its diameter, ``nan`` if none; extents
    across ``n_lo, n_hi`` and motion ``m`` from :func:`_hole_extents`) is cut by every plan of
    a box of angles ``+- delta``: its width across the lines at every angle of the box is at
    least ``n_hi - n_lo - wide delta - 2 tol`` (a rotation by ``a`` turns the lines' normal by
    ``2 sin(a / 2) <= a``, so each pair of its points' distance across changes by at most
    ``wide a``; a shift changes no width); above the spacing, the open extent across of every
    moved ring holds a line, which crosses the ring (connected), so the planner cuts that line
    there (:func:`split_rings`), and the lane on it enters the chord of the convex, isolated
    hole (docs/scale.md, "Holes wider than the spacing"). Every line that may cross it (within
    ``m`` of its extent) must be one of the box's ``nb`` lines from ``k0``."""
    if not (n_hi - n_lo - wide * delta - 2.0 * tol > s):  # false for nan
        return False
    ka = math.ceil((n_lo - m - d) / s)
    kb = math.floor((n_hi + m - d) / s)
    return ka >= k0 and kb <= k0 + nb - 1


def jit_wide() -> None:
    """Swap :func:`_wide_cut` for its compiled version here, where the compiled
    :func:`_rigid_cuts` looks it up (:func:`~.bands._compiled`)."""
    jit_globals(globals(), ("_wide_cut",))


def _split_gaps(hxy, hstart, ext, split, cs, sn, ox, oy, c, glo, ghi):
    """The *split gaps* of the line at ``c`` (across), sorted and merged into ``glo, ghi``;
    returns their number. A hole whose extent across the lines, shrunk by its ``m``, holds
    ``c`` strictly is crossed by the line at every rigid image of the box (its points move by
    at most ``m``; it is connected). The points of a moved hole on the line come from points
    of the hole within ``m`` of it (across) and moved by at most ``m`` (along): its chord lies
    in the hole's part in the slab ``|n - c| <= m``, its extent along the line grown by ``m``
    (the hole's edges clipped to the slab). Every plan of the box has a gap in its lanes
    there, however thin the hole (a sandwich's outer set may erode it away); only the rings
    whose ``split[h]`` is true."""
    ng = 0
    for h in range(ext.shape[0]):
        m = ext[h, 4]
        if not (split[h] and ext[h, 0] + m < c < ext[h, 1] - m):
            continue
        u_lo, u_hi = np.inf, -np.inf
        v0, v1 = hstart[h], hstart[h + 1]
        for v in range(v0, v1):
            w = v + 1 if v + 1 < v1 else v0
            x1, y1 = hxy[v, 0] - ox, hxy[v, 1] - oy
            x2, y2 = hxy[w, 0] - ox, hxy[w, 1] - oy
            n1, n2 = -sn * x1 + cs * y1, -sn * x2 + cs * y2
            t1, t2 = cs * x1 + sn * y1, cs * x2 + sn * y2
            a, b = max(min(n1, n2), c - m), min(max(n1, n2), c + m)
            if a > b:
                continue
            if n1 == n2:
                ta, tb = t1, t2
            else:
                ta = t1 + (a - n1) * (t2 - t1) / (n2 - n1)
                tb = t1 + (b - n1) * (t2 - t1) / (n2 - n1)
            u_lo, u_hi = min(u_lo, ta, tb), max(u_hi, ta, tb)
        glo[ng], ghi[ng] = u_lo - m, u_hi + m
        ng += 1
    # sort by start (insertion sort, few holes), then merge overlapping gaps
    for q in range(1, ng):
        a, b = glo[q], ghi[q]
        j = q - 1
        while j >= 0 and glo[j] > a:
            glo[j + 1], ghi[j + 1] = glo[j], ghi[j]
            j -= 1
        glo[j + 1], ghi[j + 1] = a, b
    n = 0
    for q in range(ng):
        if n > 0 and glo[q] <= ghi[n - 1]:
            ghi[n - 1] = max(ghi[n - 1], ghi[q])
        else:
            glo[n], ghi[n] = glo[q], ghi[q]
            n += 1
    return n


def _split_pieces(qlo, qhi, n_q, glo, ghi, ng, slo, shi, llo, lhi):
    """The pieces ``qlo, qhi`` (sorted, disjoint) split at the split gaps ``glo, ghi``: per
    sub-piece its *strict* extent ``[slo, shi]`` (the piece minus the gaps: points of two
    sub-pieces are never in one lane of a plan of the box, a real hole's chord lies between)
    and its *loose* one ``[llo, lhi]`` (a lane holding a point of the strict extent lies in
    it: it ends before the chord, at most at the gap's end); returns their number."""
    n = 0
    g = 0
    for q in range(n_q):
        a, b = qlo[q], qhi[q]
        while g < ng and ghi[g] <= a:
            g += 1
        cur, loose = a, a
        gg = g
        while gg < ng and glo[gg] < b:
            if glo[gg] > cur:
                slo[n], shi[n], llo[n], lhi[n] = cur, glo[gg], loose, min(b, ghi[gg])
                n += 1
            cur = max(cur, ghi[gg])
            loose = max(a, glo[gg])
            gg += 1
        if b > cur:
            slo[n], shi[n], llo[n], lhi[n] = cur, b, loose, b
            n += 1
    return n
