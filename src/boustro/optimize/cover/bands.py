"""Per-band lane statistics of a transect grid over a region, for many layouts at once.

For a layout ``(theta, d)`` line ``k`` is ``n . (p - o) = d + k s`` with ``u = (cos theta,
sin theta)``, ``n = (-sin theta, cos theta)``; its *band* is ``|n . (p - o) - c_k| <= reach``.
The lane a coverage-guaranteed plan flies on line ``k`` spans the projection onto the line of
the band's part of the area (merged where pieces overlap), minus the line's parts inside holes
(:func:`boustro.plan.lanes.region_lanes`). The projection of a compact set is the projection of
its boundary, so each band's projection is the union of the projections of the boundary edges
clipped to the band and of the area's chords on the band's two edge lines: computed here from
the edges in ``O(E + crossings)`` per layout, with no decomposition of the area.

:func:`band_stats` evaluates a *sandwich*: an inner set (contained in every area the layouts of
a leaf can see) and an outer set (containing each), and returns per layout and band the
quantities the certified bounds need (:mod:`boustro.optimize.cover.bounds`). With inner = outer
= the area it is the exact lane statistics of one layout. numba compiles the loop on first use.
"""

from __future__ import annotations

from functools import cache
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..._jit import compiled
from .band_lines import (
    _band_intervals,
    _count_pieces,
    _hole_chords,
    _minus,
    _project,
    jit_into,
)
from .rigid import (
    RigidBoxes,
    _hole_extents,
    _rigid_cuts,
    _split_gaps,
    _split_pieces,
    jit_wide,
    split_rings,
)

__all__ = ["BandStats", "EdgeSet", "RigidBoxes", "band_stats", "edge_set"]


class EdgeSet(NamedTuple):
    """The boundary of a region as edges: ``(E, 4)`` rows ``x1, y1, x2, y2`` (plan units) and
    ``hole (E,)``: ``-1`` for an edge of an outer ring, else the index of the ORIGINAL hole it
    belongs to (several rings of a set may map to one original hole).

    ``chords`` (an inner set's, ``(C, 4)`` edges of closed rings; ``None``: the set's own hole
    edges): the rings whose chords on a line are the parts a lane loses to holes, in place of
    the set's own hole rings. The inner set of a sandwich passes the union of the holes dilated
    by its radius: where a hole lies nearer the boundary (or another hole) than twice the
    radius the erosion merges it with the outside, and its own rings no longer say that the
    line's part across it is a hole of every sandwiched area (:mod:`.sandwich`)."""

    xy: NDArray[np.float64]
    hole: NDArray[np.int64]
    chords: NDArray[np.float64] | None = None


def edge_set(
    rings: list[NDArray[np.float64]],
    holes: list[int],
    chords: list[NDArray[np.float64]] | None = None,
) -> EdgeSet:
    """The :class:`EdgeSet` of closed ``rings`` (``(m, 2)``, not repeated), ``holes[i]`` the
    original hole of ring ``i`` or ``-1`` for an outer ring; ``chords``: the rings of
    :attr:`EdgeSet.chords`."""
    if chords is not None:
        return edge_set(rings, holes)._replace(chords=edge_set(chords, [0] * len(chords)).xy)
    rows, ids = [], []
    for ring, h in zip(rings, holes, strict=True):
        ring = np.asarray(ring, dtype=np.float64)
        if len(ring) < 3:
            continue
        nxt = np.roll(ring, -1, axis=0)
        rows.append(np.concatenate([ring, nxt], axis=1))
        ids.append(np.full(len(ring), int(h), dtype=np.int64))
    if not rows:
        return EdgeSet(np.zeros((0, 4)), np.zeros(0, dtype=np.int64))
    return EdgeSet(np.concatenate(rows), np.concatenate(ids))


class BandStats(NamedTuple):
    """Per layout ``l`` and band ``b`` (line ``k = k0 + b``), arrays ``(L, B)``:

    * ``length``: measure of the inner set's band projection minus the chords of its holes
      (:attr:`EdgeSet.chords`) on the line (a lower bound on the lane length any sandwiched
      area gets);
    * ``count``: pieces of the outer projection minus the outer set's hole chords that hold
      inner length (a lower bound on the lanes on the line);
    * ``in_lo, in_hi, out_lo, out_hi``: the extremes of the inner and outer projections
      (``nan`` where empty);
    * ``cut (L, H)``: original holes whose outer-set chord overlaps the inner projection on some
      line (a hole every sandwiched plan cuts, hence passes around);
    * ``rigid (L, H)``: original holes that every plan of the box cuts, by the box's rigid
      motions (:func:`band_stats` with ``rigid``; all false without): a line ``k`` lies
      strictly inside the hole's extent across the lines shrunk by ``m = delta rho + eta``
      (``rho``: the hole's farthest vertex from the origin; every point of the hole moves by
      at most ``m``), so it crosses every moved hole (connected), and one inner projection
      interval of band ``k`` covers the hole's extent along the line grown by ``m``, so the
      chord lies inside every such plan's lane; or a convex, isolated hole is wider than the
      spacing across every line direction of the box (:func:`~.rigid._wide_cut`);
    * ``first_hi, last_lo``: the end of the first and the start of the last piece of the inner
      projection minus the chords of its holes (``nan`` where none): the lane holding the
      first piece ends at ``first_hi`` or beyond (:mod:`~boustro.optimize.cover.ends`);
    * ``pieces (L, B, 4)``: of the outer pieces ``count`` counts, the end of the first, the
      start of the second, the start of the last, the end of the one before (``nan`` if fewer
      than two; :mod:`~boustro.optimize.cover.piece_ends`);
    * ``first_lo, last_hi``: the start of the first and the end of the last of those inner
      pieces (``nan`` where none): the counted lane holding the first starts at ``first_lo`` or
      before, the one holding the last ends at ``last_hi`` or beyond
      (:mod:`~boustro.optimize.cover.extremes`).
    """

    k0: int
    length: NDArray[np.float64]
    count: NDArray[np.int64]  # type: ignore[assignment]  # (shadows tuple.count)
    in_lo: NDArray[np.float64]
    in_hi: NDArray[np.float64]
    out_lo: NDArray[np.float64]
    out_hi: NDArray[np.float64]
    cut: NDArray[np.bool_]
    rigid: NDArray[np.bool_]
    first_hi: NDArray[np.float64]
    last_lo: NDArray[np.float64]
    pieces: NDArray[np.float64]
    first_lo: NDArray[np.float64]
    last_hi: NDArray[np.float64]


def _leaf(
    inner_xy,
    inner_hole,
    outer_xy,
    outer_hole,
    chord_xy,
    cs,
    sn,
    d,
    s,
    r_in,
    r_out,
    ox,
    oy,
    k0,
    nb,
    tol,
    length,
    count,
    in_lo,
    in_hi,
    out_lo,
    out_hi,
    cut,
    delta,
    eta,
    rigid,
    first_hi,
    last_lo,
    pieces,
    sxy,
    sstart,
    sparent,
    split,
    swide,
    first_lo,
    last_hi,
):
    ih1, ih2, it1, it2 = _project(inner_xy, cs, sn, ox, oy)
    oh1, oh2, ot1, ot2 = _project(outer_xy, cs, sn, ox, oy)
    i_start, i_m, i_lo, i_hi = _band_intervals(ih1, ih2, it1, it2, d, s, r_in, k0, nb)
    o_start, o_m, o_lo, o_hi = _band_intervals(oh1, oh2, ot1, ot2, d, s, r_out, k0, nb)
    # the holes eroded past the planner's eps (:func:`.rigid.split_rings`): their extents, the
    # rigid cuts and the split gaps
    n_h = sstart.shape[0] - 1
    ext = np.empty((n_h, 5))
    if delta >= 0:
        _hole_extents(sxy, sstart, cs, sn, ox, oy, delta, eta, tol, ext)
        _rigid_cuts(ext, sparent, d, s, k0, nb, i_start, i_m, i_lo, i_hi, rigid, swide, delta, tol)
    # chords where the lines tau either side cross the hole too (the planner's rule, with its
    # 1e-7 spacings): the inner set's tau within its holes' margin over the real ones (the
    # sandwich's pad, tol), the outer set's beyond the planner's (fewer chords: a lower bound)
    tau_out = 1.5e-7 * max(s, tol)
    # the inner set's holes: the holes dilated by its radius, merged with the outside or not
    ch1, ch2, ct1, ct2 = _project(chord_xy, cs, sn, ox, oy)
    chord_hole = np.zeros(chord_xy.shape[0], dtype=np.int64)
    gi_start, gi_t, _gi_h = _hole_chords(ch1, ch2, ct1, ct2, chord_hole, d, s, k0, nb, tol / 2)
    go_start, go_t, go_h = _hole_chords(oh1, oh2, ot1, ot2, outer_hole, d, s, k0, nb, tau_out)
    # scratch for the pieces of one band (no arrays allocated per band)
    room = 1
    for b in range(nb):
        room = max(room, i_m[b] + gi_start[b + 1] - gi_start[b] + 1)
        room = max(room, o_m[b] + go_start[b + 1] - go_start[b] + 1)
    plo, phi = np.empty(room), np.empty(room)
    qlo, qhi = np.empty(room), np.empty(room)
    # the holes' split gaps (:func:`.rigid._split_gaps`): every plan of the box has a gap there
    any_split = delta >= 0 and split.any()
    glo, ghi = np.empty(n_h + 1), np.empty(n_h + 1)
    slo, shi = np.empty(room + n_h), np.empty(room + n_h)
    llo, lhi = np.empty(room + n_h), np.empty(room + n_h)
    split_row = np.empty(4)
    for b in range(nb):
        p0, m = i_start[b], i_m[b]
        q0, mo = o_start[b], o_m[b]
        if m > 0:
            in_lo[b] = i_lo[p0]
            in_hi[b] = i_hi[p0 + m - 1]
        if mo > 0:
            out_lo[b] = o_lo[q0]
            out_hi[b] = o_hi[q0 + mo - 1]
        if m == 0:
            continue
        g = gi_t[gi_start[b] : gi_start[b + 1]]
        n_p = _minus(i_lo[p0 : p0 + m], i_hi[p0 : p0 + m], m, g[0::2], g[1::2], tol, plo, phi)
        total = 0.0
        for q in range(n_p):
            total += phi[q] - plo[q]
        length[b] = total
        if n_p > 0:
            first_hi[b] = phi[0]
            last_lo[b] = plo[n_p - 1]
            first_lo[b] = plo[0]
            last_hi[b] = phi[n_p - 1]
        go = go_t[go_start[b] : go_start[b + 1]]
        gh = go_h[go_start[b] : go_start[b + 1]]
        n_q = _minus(o_lo[q0 : q0 + mo], o_hi[q0 : q0 + mo], mo, go[0::2], go[1::2], 0.0, qlo, qhi)
        # outer pieces holding inner length; split at the split gaps where that counts more
        c = _count_pieces(qlo, qhi, qlo, qhi, n_q, plo, phi, n_p, tol, pieces[b])
        ng = 0
        if any_split:
            ng = _split_gaps(sxy, sstart, ext, split, cs, sn, ox, oy, d + (k0 + b) * s, glo, ghi)
        if ng > 0:
            n_s = _split_pieces(qlo, qhi, n_q, glo, ghi, ng, slo, shi, llo, lhi)
            c_s = _count_pieces(slo, shi, llo, lhi, n_s, plo, phi, n_p, tol, split_row)
            if c_s > c:
                c = c_s
                pieces[b, :] = split_row
        count[b] = c
        # holes whose outer chord overlaps the inner projection
        for q in range(0, go.shape[0] - 1, 2):
            a, bb = go[q], go[q + 1]
            for j in range(m):
                if min(bb, i_hi[p0 + j]) - max(a, i_lo[p0 + j]) > tol:
                    cut[gh[q]] = True
                    break


def _all(
    inner_xy,
    inner_hole,
    outer_xy,
    outer_hole,
    chord_xy,
    cs,
    sn,
    d,
    s,
    r_in,
    r_out,
    ox,
    oy,
    k0,
    nb,
    n_holes,
    tol,
    delta,
    eta,
    sxy,
    sstart,
    sparent,
    split,
    swide,
):
    n = cs.shape[0]
    length = np.zeros((n, nb))
    count = np.zeros((n, nb), dtype=np.int64)
    in_lo = np.full((n, nb), np.nan)
    in_hi = np.full((n, nb), np.nan)
    out_lo = np.full((n, nb), np.nan)
    out_hi = np.full((n, nb), np.nan)
    cut = np.zeros((n, max(n_holes, 1)), dtype=np.bool_)
    rigid = np.zeros((n, max(n_holes, 1)), dtype=np.bool_)
    first_hi = np.full((n, nb), np.nan)
    last_lo = np.full((n, nb), np.nan)
    pieces = np.full((n, nb, 4), np.nan)
    first_lo = np.full((n, nb), np.nan)
    last_hi = np.full((n, nb), np.nan)
    for leaf in range(n):
        _leaf(
            inner_xy,
            inner_hole,
            outer_xy,
            outer_hole,
            chord_xy,
            cs[leaf],
            sn[leaf],
            d[leaf],
            s,
            r_in,
            r_out,
            ox,
            oy,
            k0,
            nb,
            tol,
            length[leaf],
            count[leaf],
            in_lo[leaf],
            in_hi[leaf],
            out_lo[leaf],
            out_hi[leaf],
            cut[leaf],
            delta[leaf],
            eta[leaf],
            rigid[leaf],
            first_hi[leaf],
            last_lo[leaf],
            pieces[leaf],
            sxy,
            sstart,
            sparent,
            split,
            swide,
            first_lo[leaf],
            last_hi[leaf],
        )
    return (length, count, in_lo, in_hi, out_lo, out_hi, cut, rigid, first_hi, last_lo, pieces,
            first_lo, last_hi)  # fmt: skip


@cache
def _compiled() -> Any:
    """The loop compiled by numba (cached on disk), or the plain Python one without numba."""
    helpers = ("_rigid_cuts", "_hole_extents", "_split_gaps", "_split_pieces", "_leaf")
    return compiled(globals(), "_all", helpers, [lambda: jit_into(globals()), jit_wide])


def band_stats(
    inner: EdgeSet,
    outer: EdgeSet,
    angles: NDArray[np.float64],
    offsets: NDArray[np.float64],
    spacing: float,
    reach: float,
    origin: NDArray[np.float64],
    k_range: tuple[int, int],
    n_holes: int,
    tol: float,
    *,
    inner_reach: float | None = None,
    rigid: RigidBoxes | None = None,
    split: bool = True,
) -> BandStats:
    """:class:`BandStats` of the layouts ``(angles[l], offsets[l])`` for lines ``k`` in
    ``k_range`` (inclusive; it must hold every line whose band meets the outer set); with
    ``rigid``, also the holes every plan of each box cuts (``BandStats.rigid``) and, with
    ``split``, the lines that the holes the outer set lost (eroded away: thinner than the
    sandwich's radius) split in every plan of the box (:func:`~.rigid._split_gaps`: a line's
    ``count`` and ``pieces`` from its outer pieces split there where that counts more
    lanes)."""
    k0, k1 = k_range
    fn = _compiled()
    angles = np.ascontiguousarray(angles, dtype=np.float64)
    if rigid is None:  # delta < 0: no rigid test
        rigid = RigidBoxes(np.zeros((0, 2)), np.zeros(1, dtype=np.int64),
                           np.full(len(angles), -1.0), np.zeros(len(angles)))  # fmt: skip
    chords = inner.xy[inner.hole >= 0] if inner.chords is None else inner.chords
    # the split gaps of the holes the outer set lost (eroded away): elsewhere its own hole
    # chords split the lines (and the search's path stays that of the bound without them)
    gone = np.zeros(len(rigid.start) - 1, dtype=np.bool_)
    if split:
        gone[:] = True
        gone[outer.hole[(outer.hole >= 0) & (outer.hole < len(gone))]] = False
    # the holes eroded past the planner's eps: the rigid cuts' and the split gaps' holes
    rings = rigid.split
    if rings is None:
        holes = [rigid.xy[a:b] for a, b in zip(rigid.start[:-1], rigid.start[1:], strict=True)]
        rings = split_rings(holes, float(spacing), float(tol))
    gone_ring = gone[rings.parent]
    wide = np.full(len(rings.parent), np.nan) if rings.wide is None else rings.wide
    out = fn(
        np.ascontiguousarray(inner.xy), np.ascontiguousarray(inner.hole),
        np.ascontiguousarray(outer.xy), np.ascontiguousarray(outer.hole),
        np.ascontiguousarray(chords, dtype=np.float64),
        np.cos(angles), np.sin(angles), np.ascontiguousarray(offsets, dtype=np.float64),
        float(spacing), float(reach if inner_reach is None else inner_reach), float(reach),
        float(origin[0]), float(origin[1]), int(k0), int(k1 - k0 + 1), int(n_holes), float(tol),
        np.ascontiguousarray(rigid.delta, dtype=np.float64),
        np.ascontiguousarray(rigid.eta, dtype=np.float64),
        np.ascontiguousarray(rings.xy, dtype=np.float64),
        np.ascontiguousarray(rings.start, dtype=np.int64),
        np.ascontiguousarray(rings.parent, dtype=np.int64), np.ascontiguousarray(gone_ring),
        np.ascontiguousarray(wide, dtype=np.float64),
    )  # fmt: skip
    return BandStats(int(k0), *out)
