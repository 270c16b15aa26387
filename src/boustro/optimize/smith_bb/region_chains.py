"""The chain bound of a region's box: segment ends tied to the boundary chains (numba).

:mod:`.region_kernel` bounds each line's segments by the components of the outer set ``O`` and
the pieces of the inner set ``I``. Where a line runs within ``eps`` of a reflex vertex, a hole's
vertex or an edge along the line, a component holds two pieces that may be one segment or two,
and a free segment may lie in a gap; that bound takes the options with independent lengths (a
segment to the component's end AND a free segment in the same gap), so boxes across such an
event never close. This bound ties the segment ends to the chains they lie on and the lines'
options to one motion of the box (docs/global_optimum.md, section 10, "The chain bound"):

* the real boundary is cut into chains that stay monotone across the lines for every angle of
  the box (as :func:`.region_kernel._chain_counts`); a moved chain crosses a line (half-open
  rule) exactly when its two end vertices lie on different sides of it;
* every point moves by at most ``eps``: a vertex farther than ``eps`` from the line keeps its
  side; the side of each of the (at most :data:`MAX_NEAR`) near ones is enumerated. Chain
  ``k``'s crossing lies in ``X_k``, the along-line range of its points within ``eps`` of the
  line grown by ``eps``; the crossings, sorted, pair into the segments, and the ``j``-th
  smallest crossing lies between the ``j``-th smallest low and high ends of the ``X``, so
  segment ``j`` has a length in ``[LO[2j+1] - HI[2j], HI[2j+1] - LO[2j]]``;
* a motion of the box is a rotation by ``alpha`` (``|alpha| <= delta``) and a shift ``eta'``
  (``|eta'| <= eta``); a vertex ``(h, t)`` is below line ``c`` when ``h cos(alpha) - t
  sin(alpha) <= c + eta'``: linear in ``(sin(alpha), eta')`` up to ``h (1 - cos(alpha))``, which
  is taken at its worst. A combination of sides (over all the box's uncertain lines) is kept
  only if some motion meets all its conditions (:func:`_feasible`, a two-variable check);
* an edge along a line (both ends near, crossed) is cut into :data:`SPLIT` pieces, one option
  per piece holding the crossing (its ends on the edge's ends' sides): the crossing positions
  of lines along parallel edges move together;
* each vertex condition must hold with :data:`DEGENERATE` / 2 of room: the bound leaves out the
  layouts at which a vertex lies that near a line (where vertices align exactly, a combination
  that no open set of motions gives holds on a set of zero width; the exact value there is a
  limit that robust scoring, at 1e-9, never reports). A segment of at most ``tiny`` (uncounted
  by the evaluator) puts a vertex within :func:`near_margin` of the line, at most that room, so
  only a sharper or thinner region needs the uncounted variants.

The bound is the largest exact maximum (:func:`.kernel._sup_w`) over the feasible
combinations of the uncertain lines' options with the sure lines' segments, found depth
first; it applies to boxes with at most :data:`MAX_LINES` uncertain lines, :data:`MAX_NEAR`
vertices near a line and :data:`MAX_COMBOS` feasibility checks (``inf`` otherwise: the caller
keeps its own bound).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from ..._jit import jit_globals
from . import kernel
from .kernel import _sup_w

__all__ = [
    "MAX_COMBOS",
    "MAX_LINES",
    "MAX_NEAR",
    "chain_bound",
    "edge_lengths",
    "near_margin",
    "prepare",
]

#: Most uncertain lines (``u > r``) of a box for the chain bound.
MAX_LINES = 8
#: Most vertices within ``eps`` of one line (``2^k`` sides).
MAX_NEAR = 5
#: Most feasibility checks of (partial) combinations of the lines' options per box.
MAX_COMBOS = 4096
#: Most options of one line (sides of its near vertices, pieces of an edge along it, uncounted
#: variants).
MAX_OPTIONS = 160
#: Pieces of an edge along a line (the crossing's position on it, tied to the box's motion).
SPLIT = 32
#: Added to each crossing range (rounding of the projections, normalised frame of radius 1).
X_SLACK = 1e-12
#: A combination of sides is taken as possible only if it holds with this much room
#: (normalised frame, about 1e-9 m on a 100 m field): where lines pass exactly through several
#: aligned vertices at once (a rectilinear area at a multiple of its spacing), a combination
#: that no real motion gives can still hold on a set narrower than float rounding (1e-16);
#: such layouts are rounding artefacts (robust scoring ignores them at 1e-9, region.py).
DEGENERATE = 1e-11
#: Largest :func:`near_margin` of a region whose short segments need no variants (the layouts
#: that cut them put a vertex within ``DEGENERATE / 2`` of a line); a sharper or thinner
#: region: ``-1``, every segment that may be at most ``tiny`` long may also be uncounted.
MARGIN_CAP = 0.5 * DEGENERATE


def _edge_class(xy, i, cs, sn, sdelta, ln):
    """``(class, h1, h2)`` of edge ``i`` (length ``ln[i]``): its ends' across-coordinates
    ``h`` and ``+-1`` where ``h`` rises (falls) along it for every angle of the box, 0 where it
    may turn parallel."""
    h1 = -sn * xy[i, 0] + cs * xy[i, 1]
    h2 = -sn * xy[i, 2] + cs * xy[i, 3]
    cls = 0
    if abs(h2 - h1) > ln[i] * sdelta * (1.0 + 1e-9) + 1e-15:
        cls = 1 if h2 > h1 else -1
    return cls, h1, h2


def edge_lengths(xy):
    """``ln[i]``: the length of edge ``i`` (``math.hypot``, as :func:`_edge_class` reads it)."""
    ln = np.empty(xy.shape[0])
    for i in range(xy.shape[0]):
        ln[i] = math.hypot(xy[i, 2] - xy[i, 0], xy[i, 3] - xy[i, 1])
    return ln


def _chains(xy, rings, cs, sn, sdelta, ln, ci, cf):
    """The chains of the real rings: ``ci[k] = (first edge, end edge, class, end vertex)``
    (a vertex is the index of the edge it starts), ``cf[k] = (low, high)`` of their
    across-coordinate ``h``; class ``+-1``: monotone for every angle of the box, 0: one edge
    that may turn parallel to the lines (edge lengths ``ln``, :func:`edge_lengths`). Returns
    their count."""
    n = 0
    for r in range(rings.shape[0] - 1):
        i = rings[r]
        cls, h1, h2 = 0, 0.0, 0.0
        cj, g1, g2 = 0, 0.0, 0.0
        if i < rings[r + 1]:
            cls, h1, h2 = _edge_class(xy, i, cs, sn, sdelta, ln)
        while i < rings[r + 1]:
            lo_h, hi_h = min(h1, h2), max(h1, h2)
            j = i + 1
            while j < rings[r + 1]:  # the class of edge j is carried to the next chain
                cj, g1, g2 = _edge_class(xy, j, cs, sn, sdelta, ln)
                if cls == 0 or cj != cls:
                    break
                lo_h, hi_h = min(lo_h, g2), max(hi_h, g2)
                j += 1
            ci[n, 0], ci[n, 1], ci[n, 2] = i, j, cls
            ci[n, 3] = j if j < rings[r + 1] else rings[r]
            cf[n, 0], cf[n, 1] = lo_h, hi_h
            n += 1
            i = j
            if j < rings[r + 1]:
                cls, h1, h2 = cj, g1, g2
    return n


def _crossing_range(xy, i0, i1, cs, sn, c, eps):
    """``(xa, xb)``: where along line ``c`` a chain of edges ``i0:i1`` moved by at most ``eps``
    can cross it (its points within ``eps`` of the line, grown by ``eps``); ``xa > xb``: none
    found (rounding at the strip's edge)."""
    xa, xb = np.inf, -np.inf
    for i in range(i0, i1):
        h1 = -sn * xy[i, 0] + cs * xy[i, 1]
        h2 = -sn * xy[i, 2] + cs * xy[i, 3]
        if max(h1, h2) < c - eps or min(h1, h2) > c + eps:
            continue
        ua, ub = 0.0, 1.0
        if h1 != h2:
            ua = (c - eps - h1) / (h2 - h1)
            ub = (c + eps - h1) / (h2 - h1)
            if ua > ub:
                ua, ub = ub, ua
            ua, ub = max(ua, 0.0), min(ub, 1.0)
        t1 = cs * xy[i, 0] + sn * xy[i, 1]
        t2 = cs * xy[i, 2] + sn * xy[i, 3]
        ta = t1 + ua * (t2 - t1)
        tb = t1 + ub * (t2 - t1)
        xa = min(xa, ta, tb)
        xb = max(xb, ta, tb)
    return xa - eps - X_SLACK, xb + eps + X_SLACK


def _feasible(ct, cr, cup, n, su, eta):
    """Whether some motion of the box, ``u = sin(rotation)`` in ``[-su, su]`` and shift
    ``eta' `` in ``[-eta, eta]``, meets the ``n`` conditions ``eta' >= cr - ct u`` (``cup``
    False) or ``eta' <= cr - ct u`` (``cup`` True): every lower bound of ``eta'`` below every
    upper one, pair by pair an interval of ``u``."""
    ulo, uhi = -su, su
    for i in range(n + 1):  # lower bounds (the last: the box's -eta)
        if i < n and cup[i]:
            continue
        li = cr[i] if i < n else -eta
        ti = ct[i] if i < n else 0.0
        for j in range(n + 1):  # upper bounds (the last: the box's eta)
            if j < n and not cup[j]:
                continue
            uj = cr[j] if j < n else eta
            tj = ct[j] if j < n else 0.0
            k = tj - ti
            rhs = uj - li
            if k > 0.0:
                uhi = min(uhi, rhs / k)
            elif k < 0.0:
                ulo = max(ulo, rhs / k)
            elif rhs < 0.0:
                return False
            if ulo > uhi:
                return False
    return True


def _side(xy, v, cs, sn, c, near, nn, mask):
    """Whether vertex ``v`` lies on the line or below it (``h' <= c'``): its bit in ``mask``
    if it is one of the ``near`` vertices, else its side at the box centre."""
    for g in range(nn):
        if near[g] == v:
            return ((mask >> g) & 1) == 1
    return -sn * xy[v, 0] + cs * xy[v, 1] <= c


def _collect(xy, ci, cf, nch, cs, sn, c, eps, reach, rel, xa, xb, near, nh, nt):
    """The chains that may cross line ``c`` (``rel``, their crossing ranges ``xa, xb``) and
    their ends within ``reach`` of it (``near``, with ``h, t`` in ``nh, nt``): ``(chains,
    near vertices)``, ``-1`` near vertices if too many (or rounding)."""
    nn, nrel = 0, 0
    for k in range(nch):
        if not (cf[k, 0] - eps <= c <= cf[k, 1] + eps):
            continue
        a0, b0 = _crossing_range(xy, ci[k, 0], ci[k, 1], cs, sn, c, eps)
        if a0 > b0:
            return nrel, -1
        rel[nrel], xa[nrel], xb[nrel] = k, a0, b0
        nrel += 1
        for v in (ci[k, 0], ci[k, 3]):
            hv = -sn * xy[v, 0] + cs * xy[v, 1]
            if abs(hv - c) <= reach and _near_index(near, nn, v) < 0:
                if nn >= MAX_NEAR:
                    return nrel, -1
                near[nn], nh[nn] = v, hv
                nt[nn] = cs * xy[v, 0] + sn * xy[v, 1]
                nn += 1
    return nrel, nn


def _near_index(near, nn, v):
    """The index of vertex ``v`` among the ``nn`` near ones, ``-1`` if not near."""
    for g in range(nn):
        if near[g] == v:
            return g
    return -1


def _condition(ct, cr, cup, g, h, t, c, cd, below, wide):
    """Condition ``g`` (:func:`_feasible`'s form): a point ``(h, t)`` on the line or below it
    (``below``: ``h' <= c'``, i.e. ``eta' >= h cos - c - t u``) or above, widened by ``wide``."""
    if below:
        ct[g], cr[g], cup[g] = t, min(h, h * cd) - c - wide, False
    else:
        ct[g], cr[g], cup[g] = t, max(h, h * cd) - c + wide, True


def _emit(lo_s, hi_s, m, tiny, low, drop, opt, olo, ohi, oc, c0, c1, first):
    """Append the option of crossings ``lo_s/hi_s[:m]`` (sorted here) and conditions
    ``c0:c1``, in the variants in which ``low`` to ``drop`` segments that may be at most
    ``tiny`` long are uncounted. Returns its most segments, ``-1`` if the line has too many
    options."""
    lo_s[:m] = np.sort(lo_s[:m])
    hi_s[:m] = np.sort(hi_s[:m])
    optional = 0
    for j in range(m // 2):
        if lo_s[2 * j + 1] - hi_s[2 * j] <= tiny:
            optional += 1
    if optional > 3 or oc[0] - first + (1 << optional) > MAX_OPTIONS:
        return -1
    most = 0
    for variant in range(1 << optional):
        dropped = 0
        for j in range(optional):
            dropped += (variant >> j) & 1
        if dropped > drop or dropped < low:
            continue
        p = oc[0]
        opt[p, 0], opt[p, 2], opt[p, 3] = oc[1], c0, c1
        bit = 0
        for j in range(m // 2):
            slo = lo_s[2 * j + 1] - hi_s[2 * j]
            if slo <= tiny:
                bit += 1
                if (variant >> (bit - 1)) & 1:
                    continue  # this variant leaves the segment uncounted
            olo[oc[1]] = max(slo, 0.0)
            ohi[oc[1]] = max(hi_s[2 * j + 1] - lo_s[2 * j], 0.0)
            oc[1] += 1
        opt[p, 1] = oc[1]
        most = max(most, oc[1] - opt[p, 0])
        oc[0] += 1
    return most


def _line_options(xy, ci, cf, nch, cs, sn, su, cd, eta, c, eps, tiny, margin, opt, olo, ohi,
                  oc, ct, cr, cup):  # fmt: skip
    """Append line ``c``'s options: every side of the line for each vertex within ``eps`` of
    it that some motion of the box allows, with the segments that the chains then form
    (``opt[p] = (first segment, end, first condition, end)``, segments ``olo/ohi``, conditions
    ``ct, cr, cup`` as :func:`_feasible`'s). An edge along the line (both ends near, crossed)
    is cut into :data:`SPLIT` pieces, one option per piece holding the crossing (the piece's
    ends on the edge's ends' sides). ``oc = [options, segments, conditions]`` is advanced;
    returns the most segments of an option, ``-1`` if too many. ``margin >= 0``: a segment of
    length at most ``tiny`` puts a vertex within ``margin <= DEGENERATE / 2`` of the line, a
    layout the bound leaves out (module doc); ``margin < 0``: any segment that may be that
    short may be uncounted."""
    wide = -0.5 * DEGENERATE  # each condition must hold with this much room
    near = np.empty(MAX_NEAR, dtype=np.int64)
    nh, nt = np.empty(MAX_NEAR), np.empty(MAX_NEAR)
    rel = np.empty(nch, dtype=np.int64)
    xa, xb = np.empty(nch), np.empty(nch)
    nrel, nn = _collect(xy, ci, cf, nch, cs, sn, c, eps, eps, rel, xa, xb, near, nh, nt)
    if nn < 0:
        return -1
    lo_b, hi_b = np.empty(nrel), np.empty(nrel)
    lo_s, hi_s = np.empty(nrel), np.empty(nrel)
    first, most = oc[0], 0
    for mask in range(1 << nn):
        n0 = oc[2]
        for g in range(nn):
            _condition(ct, cr, cup, n0 + g, nh[g], nt[g], c, cd, (mask >> g) & 1 == 1, wide)
        if not _feasible(ct[n0:], cr[n0:], cup[n0:], nn, su, eta):
            continue
        oc[2] += nn
        m, edge, spot, below = 0, -1, -1, False
        for r in range(nrel):
            k = rel[r]
            s0 = _side(xy, ci[k, 0], cs, sn, c, near, nn, mask)
            if s0 != _side(xy, ci[k, 3], cs, sn, c, near, nn, mask):
                if (edge < 0 and ci[k, 2] == 0 and _near_index(near, nn, ci[k, 0]) >= 0
                        and _near_index(near, nn, ci[k, 3]) >= 0):  # fmt: skip
                    edge, spot, below = ci[k, 0], m, s0
                lo_b[m], hi_b[m] = xa[r], xb[r]
                m += 1
        if m % 2 == 1:
            return -1  # a ring crossed an odd number of times (cannot happen)
        drop = m // 2 if margin < 0.0 else 0
        for j in range(SPLIT if edge >= 0 else 1):
            lo_s[:m], hi_s[:m] = lo_b[:m], hi_b[:m]
            c0 = oc[2]
            c1 = c0
            if edge >= 0:  # the crossing on piece j of the edge
                c1 = c0 + nn
                ct[c0:c1], cr[c0:c1] = ct[n0 : n0 + nn], cr[n0 : n0 + nn]
                cup[c0:c1] = cup[n0 : n0 + nn]
                ta, tb = np.inf, -np.inf
                for e in (j, j + 1):
                    lam = e / SPLIT
                    px = xy[edge, 0] + lam * (xy[edge, 2] - xy[edge, 0])
                    py = xy[edge, 1] + lam * (xy[edge, 3] - xy[edge, 1])
                    tp = cs * px + sn * py
                    ta, tb = min(ta, tp), max(tb, tp)
                    if 0 < e < SPLIT:  # the piece's start on the edge start's side, its end not
                        _condition(ct, cr, cup, c1, -sn * px + cs * py, tp, c, cd,
                                   below if e == j else not below, 0.0)  # fmt: skip
                        c1 += 1
                if not _feasible(ct[c0:], cr[c0:], cup[c0:], c1 - c0, su, eta):
                    continue
                lo_s[spot], hi_s[spot] = ta - eps - X_SLACK, tb + eps + X_SLACK
                oc[2] = c1
            if edge < 0:
                c0, c1 = n0, n0 + nn
            got = _emit(lo_s, hi_s, m, tiny, 0, drop, opt, olo, ohi, oc, c0, c1, first)
            if got < 0:
                return -1
            most = max(most, got)
    return most


def chain_bound(xy, ci, cf, nch, cs, sn, sdelta, eta, d, s, eps, k0, lines, nlines, lo, hi,
                n_fixed, a, b, tiny, margin):  # fmt: skip
    """The chain bound (module doc) of a box (rotation at most ``asin(sdelta)``, shift at most
    ``eta``; its ``nch`` chains ``ci, cf`` of the real edges ``xy``, :func:`_chains`) whose
    lines ``k0 + lines[:nlines]`` are uncertain and whose sure lines have the segment intervals
    ``lo/hi[:n_fixed]``; ``inf`` where it does not apply; ``margin`` as
    :func:`_line_options`'s."""
    if nlines == 0 or nlines > MAX_LINES:
        return np.inf
    cap = MAX_OPTIONS * nlines
    opt = np.zeros((cap, 4), dtype=np.int64)
    olo = np.empty(cap * (nch // 2 + 1))
    ohi = np.empty(cap * (nch // 2 + 1))
    ncap = nlines * ((1 << MAX_NEAR) * MAX_NEAR + MAX_OPTIONS * (MAX_NEAR + 2)) + MAX_NEAR + 2
    ct = np.empty(ncap)
    cr = np.empty(ncap)
    cup = np.zeros(ncap, dtype=np.bool_)
    oc = np.zeros(3, dtype=np.int64)
    lstart = np.zeros(nlines + 1, dtype=np.int64)
    width, cd = n_fixed, math.sqrt(max(1.0 - sdelta * sdelta, 0.0))
    for q in range(nlines):
        c = d + (k0 + lines[q]) * s
        most = _line_options(xy, ci, cf, nch, cs, sn, sdelta, cd, eta, c, eps, tiny, margin, opt,
                             olo, ohi, oc, ct, cr, cup)  # fmt: skip
        if most < 0:
            return np.inf
        lstart[q + 1] = oc[0]
        if oc[0] == lstart[q]:
            return -np.inf  # no motion of the box is left: it holds no layout
        width += most
    return _combine(opt, olo, ohi, ct, cr, cup, lstart, nlines, lo, hi, n_fixed, width, sdelta,
                    eta, a, b)  # fmt: skip


def _combine(opt, olo, ohi, ct, cr, cup, lstart, nlines, lo, hi, n_fixed, width, su, eta, a,
             b):  # fmt: skip
    """The largest exact maximum over the combinations of the lines' options that some motion
    of the box allows, found depth first (a partial combination no motion allows is cut);
    ``inf`` after :data:`MAX_COMBOS` feasibility checks."""
    sl = np.empty(width)
    sh = np.empty(width)
    sl[:n_fixed] = lo[:n_fixed]
    sh[:n_fixed] = hi[:n_fixed]
    w = np.ones(width)
    pos = np.empty(2 * width)
    nc = (MAX_NEAR + 2) * nlines
    kt = np.empty(nc)
    kr = np.empty(nc)
    ku = np.zeros(nc, dtype=np.bool_)
    pick = np.full(nlines, -1, dtype=np.int64)
    mstart = np.zeros(nlines + 1, dtype=np.int64)
    best, level, checks = -np.inf, 0, 0
    while level >= 0:
        pick[level] += 1
        if pick[level] >= lstart[level + 1] - lstart[level]:
            pick[level] = -1
            level -= 1
            continue
        p = lstart[level] + pick[level]
        m = mstart[level]
        for g in range(opt[p, 2], opt[p, 3]):
            kt[m], kr[m], ku[m] = ct[g], cr[g], cup[g]
            m += 1
        checks += 1
        if checks > MAX_COMBOS:
            return np.inf
        if not _feasible(kt, kr, ku, m, su, eta):
            continue
        if level + 1 < nlines:
            mstart[level + 1] = m
            level += 1
            continue
        n = n_fixed
        for q in range(nlines):
            p = lstart[q] + pick[q]
            for g in range(opt[p, 0], opt[p, 1]):
                sl[n], sh[n] = olo[g], ohi[g]
                n += 1
        if n > 0:
            for g in range(n):
                pos[2 * g] = sl[g]
                pos[2 * g + 1] = sh[g]
            order = np.argsort(pos[: 2 * n])
            best = max(best, _sup_w(sl, sh, w, n, order, a, b, pos))
    return best


def near_margin(rings: list[NDArray[np.float64]], tiny: float) -> float:
    """How near a vertex a line must pass to cut a segment of length at most ``tiny`` from the
    region of closed ``rings`` (normalised frame), or ``-1`` if that is not known small
    (:data:`MARGIN_CAP`).

    The segment's ends lie on two edges within ``tiny`` of each other. Two edges that share no
    vertex are farther apart than the region's minimum clearance (GEOS: the least distance of a
    vertex to an edge not incident to it); if that exceeds ``tiny`` the two edges meet at a
    vertex ``v``, with an angle ``phi`` between them, and both ends lie within
    ``tiny / f`` of ``v`` (``f = sin phi`` if ``phi`` is acute, else 1), so the line passes
    within ``tiny / f`` of ``v``."""
    import shapely

    poly = shapely.Polygon(rings[0], rings[1:])
    if not shapely.minimum_clearance(poly) > 2.0 * tiny:
        return -1.0
    f = 1.0
    for r in rings:
        back = np.roll(r, 1, axis=0) - r
        ahead = np.roll(r, -1, axis=0) - r
        cross = np.abs(back[:, 0] * ahead[:, 1] - back[:, 1] * ahead[:, 0])
        dot = (back * ahead).sum(axis=1)
        norm = np.hypot(back[:, 0], back[:, 1]) * np.hypot(ahead[:, 0], ahead[:, 1])
        sines = np.where(dot > 0.0, cross / np.maximum(norm, 1e-300), 1.0)
        f = min(f, float(sines.min()))
    margin = 2.0 * tiny / max(f, 1e-300)
    return margin if margin <= MARGIN_CAP else -1.0


def prepare() -> None:
    """Swap this module's helpers for their numba versions (before a caller compiles)."""
    kernel._compiled()
    helpers = ("_edge_class", "edge_lengths", "_chains", "_crossing_range", "_feasible", "_side",
               "_near_index", "_collect", "_condition", "_emit", "_line_options", "_combine",
               "_sup_w")  # fmt: skip
    jit_globals(globals(), helpers)
