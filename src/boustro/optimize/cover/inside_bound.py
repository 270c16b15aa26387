"""The lower bound of a ``keep_inside`` plan (:mod:`boustro.plan.inside`) over a box of layouts:
the lanes cut at the boundary, or half a spacing inside it with the boundary passes they need.

The planner lays a layout's lanes one of two ways (``MARGINS``) and keeps the one whose lanes
and passes are shorter; the tour then adds its moves. Whichever it keeps, its cost is at least
the smaller of two bounds (docs/mission_time.md, "Keep-inside: the bound"):

* **lanes cut at the boundary** (margin 0): each lane is its line's chord of the area itself,
  so :func:`~.bounds.lower_bounds` over the sandwich's inner set *not* shrunk by half a spacing
  holds (chords, no run-ins: they end at the boundary; no hole passes counted), with the
  contour stretches its lanes leave uncovered (:mod:`~.inside_cut`: by the angle, and where
  the grid is known by the lines' positions, :func:`_near_cut`);
* **lanes cut half a spacing inside** (margin 1/2): the search's keep-inside bound (chords of
  the inner set shrunk by half a spacing), with the non-lane part of the path (moves and
  passes) at least the largest of: the moves across the lines, the length ``P`` of the
  contour's stretches along edges at least :data:`MIN_ANGLE` from the lanes (every such stretch
  is a boundary pass: no lane covers the strip along its edge) and, in boxes, along edges
  nearer the lanes' direction where no grid line can reach the strip (:func:`_near_lengths`),
  and ``sqrt(A^2 + C^2)`` (``A`` those stretches' travel along the lanes, ``C`` the moves
  across them: the lengths of the segments of a path are at least the length of the sum of
  their (along, across) vectors); and one turn per contour ring holding such a stretch (each
  ring's passes are its own). A stretch counts over every sample the planner flags (within
  ``reach + step`` of the strip, :func:`_flag_reach`), whose run it keeps whole.

The contour's stretches (:class:`ContourEdges`) are computed once per area with the planner's
own construction (``area.buffer(-spacing / 2, quad_segs=8)`` without slivers): a rigid motion
of the area (a box's layouts) moves them with it, so only their angle and position relative
to the lines depend on the layout. Shapely is imported inside the functions.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from ...geometry.region import Region
from .bands import BandStats, band_stats
from .bounds import lower_bounds
from .cost import CoverCost
from .inside_cut import (
    CUT_BAND,
    NEAR_CUT_ANGLE,
    clearance,
    cut_stretches,
    relative_angle,
    rings_holding,
)
from .inside_moves import line_moves, pass_count
from .sandwich import Level

__all__ = [
    "BAND_HI",
    "BAND_LO",
    "MIN_ANGLE",
    "MIN_PART",
    "NEAR_ANGLE",
    "ContourEdges",
    "contour_edges",
    "inside_box_bounds",
    "keep_inside_bounds",
    "path_floor",
    "stretch_length",
]

#: Across the lanes, the band (half-spacings inside a strip's point) where a grid line has a
#: lane that could cover the strip's points at depth 0.005-0.0055 half-spacings
#: (:func:`_near_lengths`): lane points are at least ``cos(pi / 32) > 0.9951`` half-spacings
#: from every edge (the planner's ``quad_segs=8`` erosion), so the line lies between
#: ``0.9951 - 0.0055`` and ``1 + 0.0055``, widened a little for rounding.
BAND_LO, BAND_HI = 0.989, 1.006
#: The parts of a strip shorter than this (spacings) are not counted by :func:`_near_lengths`.
MIN_PART = 1e-4
#: Stretches up to this angle from the lanes (radians, over the box) are counted by
#: :func:`_near_lengths` where :data:`MIN_ANGLE`'s rule does not count them whole.
NEAR_ANGLE = 0.3

#: Whether the margin-1/2 bound adds the moves between lanes that no pass holding a counted
#: stretch can serve to those stretches (:mod:`~.inside_moves`), not the larger of the two.
MOVES_ON_PASSES = True

#: Where the margin-0 bound counts its lanes' passes (:mod:`~.inside_cut`): ``"off"``,
#: ``"certificate"`` (the certificate's bounds only: the search decides as before),
#: ``"bound"`` (the bounds the search keeps, retires and rules out by, not the value that ranks
#: the layouts it plans) or ``"all"``.
CUT_PASSES = "bound"

#: Whether the layouts' own bounds (not the value that ranks them) count the stretches near
#: the lanes' direction (:func:`_near_lengths`, at a box of radius 0) as the boxes' do.
NEAR_AT_LAYOUTS = True

#: Whether the boxes' bounds (radius above 0, the grid ``d`` known) count the stretches margin
#: 0's lanes leave uncovered by the lines' positions (:mod:`~.inside_cut`, "Where the lines
#: are"); ``False``: off. The layouts' own bounds never do: there it raises the lowest model and
#: with it the settling value (``branch.retire_at``), and random area 9's plan came out 7.0 s
#: longer (docs/mission_time.md, fifteenth round, measured at a97f56f).
NEAR_CUT = True

#: Edges closer than this to the lanes' direction (radians, over the whole box) are left out
#: of ``P`` by the angle rule (:data:`NEAR_ANGLE`'s rule may count them): the strip the lanes
#: leave along an edge at angle ``phi`` is ``s/2 (1 - cos phi)`` deep (less the 0.5% the
#: planner's polygonised erosion may gain at a reflex vertex), and it must stay well above the
#: planner's sliver tolerance.
MIN_ANGLE = 0.15


class ContourEdges(NamedTuple):
    """The straight stretches of the keep-inside contour (the boundary of the area shrunk by
    half a spacing) that run along an edge of the area: per stretch its direction (radians,
    mod pi) and the length of its *core*: the part the planner keeps when the strip the lanes
    leave along the edge (feet ``J``: on the stretch and at least half a spacing from the
    edge's ends) is uncovered, i.e. its samples within ``rho`` (:func:`_flag_reach`) of ``J``
    (0 when ``J`` is shorter than a sample step)."""

    angle: NDArray[np.float64]
    core: NDArray[np.float64]
    applies: bool  # the reach is half the spacing (else nothing is counted)
    ring: NDArray[np.int64]  # the contour ring each stretch lies on
    strip: NDArray[np.float64]  # (S, 2, 2): the ends of the strip's feet on the edge (J)
    inward: NDArray[np.float64]  # (S, 2): the edge's unit normal towards the stretch
    feet: NDArray[np.float64]  # (S, 4): the stretch's feet g0, g1 and the strip's j_lo, j_hi
    reach: NDArray[np.float64]  # (S, 2): the ring's sample step and flag reach (rho)
    #: the tenth round's cores (feet at least half a spacing plus a sample step from the edge's
    #: ends): the layouts' own values that rank the layouts a search plans (``ranking``)
    trimmed: NDArray[np.float64]
    #: (S, 2): the core along its contour ring (arc lengths from the ring's first point) and
    #: (S,) the ring's length: which counted stretches one pass holds (:mod:`~.inside_moves`)
    arc: NDArray[np.float64]
    total: NDArray[np.float64]
    #: (S,) the distance from the edge's part over ``J`` to the area beyond its line
    #: (:func:`~.inside_cut.clearance`: margin 0's passes)
    clear: NDArray[np.float64]


def _contour_rings(area: Region, half: float) -> list[NDArray[np.float64]]:
    """The rings of the planner's contour (:func:`boustro.plan.contour.contour_of`): the
    boundary of the area shrunk by ``half`` (``quad_segs=8``) without sliver parts."""
    import shapely

    target = shapely.Polygon(area.shell.vertices, [h.vertices for h in area.holes])
    shrunk = target.buffer(-half, quad_segs=8)
    parts = [
        g
        for g in shapely.get_parts(shrunk)
        if g.geom_type == "Polygon" and not g.is_empty and not g.buffer(-1e-7 * half).is_empty
    ]
    inner = shapely.union_all(parts)
    if inner.is_empty:
        return []
    rings = []
    for ring in shapely.get_parts(shapely.boundary(inner)):
        v = np.asarray(ring.coords, dtype=np.float64)
        if len(v) >= 4:
            rings.append(v)
    return rings


def contour_edges(area: Region, spacing: float, reach: float) -> ContourEdges:
    """The :class:`ContourEdges` of ``area`` at ``spacing`` (plan units)."""
    half = spacing / 2
    applies = abs(reach - half) <= 1e-9 * spacing
    edges = area.edges  # (N, 2, 2)
    p0, d = edges[:, 0], edges[:, 1] - edges[:, 0]
    length = np.hypot(d[:, 0], d[:, 1])
    ok = length > 0
    p0, d, length = p0[ok], d[ok], length[ok]
    u = d / length[:, None]
    angles, cores, rings, strips, inwards, feet, reaches, trims = [], [], [], [], [], [], [], []
    arcs, totals = [], []
    for index, ring in enumerate(_contour_rings(area, half) if applies else []):
        total = float(np.linalg.norm(np.diff(ring, axis=0), axis=1).sum())
        step = total / max(8, math.ceil(total / (half / 2)))  # the planner's sample step
        a, b = ring[:-1], ring[1:]
        seg = b - a
        seg_len = np.hypot(seg[:, 0], seg[:, 1])
        start = np.concatenate([[0.0], np.cumsum(seg_len)[:-1]])  # arc length at a
        keep = seg_len > step
        a, b, seg, seg_len, start = a[keep], b[keep], seg[keep], seg_len[keep], start[keep]
        if not len(a):
            continue
        # per (stretch, edge): parallel, both ends half a spacing from the edge's line, feet
        cross = np.abs(seg[:, None, 0] * u[None, :, 1] - seg[:, None, 1] * u[None, :, 0])
        parallel = cross <= 1e-9 * seg_len[:, None]

        def across(p: NDArray[np.float64]) -> NDArray[np.float64]:
            q = p[:, None, :] - p0[None]
            return np.abs(q[..., 0] * u[None, :, 1] - q[..., 1] * u[None, :, 0])

        def foot(p: NDArray[np.float64]) -> NDArray[np.float64]:
            q = p[:, None, :] - p0[None]
            return q[..., 0] * u[None, :, 0] + q[..., 1] * u[None, :, 1]

        tol = 1e-7 * spacing
        near = (np.abs(across(a) - half) <= tol) & (np.abs(across(b) - half) <= tol)
        fa, fb = foot(a), foot(b)
        g0, g1 = np.minimum(fa, fb), np.maximum(fa, fb)
        # the uncovered strip: feet in J (on the stretch and half a spacing from E's ends)
        j_lo = np.maximum(g0, half)
        j_hi = np.minimum(g1, length[None] - half)
        # the samples within reach + step of it: feet within rho of J (heights <= half + tol)
        rho = _flag_reach(half, step, tol)
        k_lo, k_hi = np.maximum(g0, j_lo - rho), np.minimum(g1, j_hi + rho)
        strip = parallel & near & (j_hi - j_lo >= step * (1 + 1e-9))
        core = np.where(strip, k_hi - k_lo, 0.0)
        best = core.max(axis=1)
        e = core.argmax(axis=1)
        lo = np.maximum(g0, half + step)
        hi = np.minimum(g1, length[None] - half - step)
        trim = np.where(parallel & near, np.maximum(hi - lo, 0.0), 0.0).max(axis=1)
        trims.append(np.where(trim > step, trim, 0.0))
        angles.append(np.arctan2(seg[:, 1], seg[:, 0]) % math.pi)
        cores.append(best)
        rings.append(np.full(len(best), index, dtype=np.int64))
        rows = np.arange(len(best))
        # the core along the ring: feet measured from a's foot, forwards or backwards
        fa_e, fwd = fa[rows, e], fb[rows, e] >= fa[rows, e]
        c0 = np.where(fwd, k_lo[rows, e] - fa_e, fa_e - k_hi[rows, e])
        arcs.append(start[:, None] + np.stack([c0, c0 + best], axis=1))
        totals.append(np.full(len(best), total))
        ends = np.stack([j_lo[rows, e], j_hi[rows, e]], axis=1)
        strips.append(p0[e][:, None, :] + ends[..., None] * u[e][:, None, :])
        feet.append(np.concatenate([np.stack([g0[rows, e], g1[rows, e]], axis=1), ends], axis=1))
        reaches.append(np.tile([step, rho], (len(best), 1)))
        normal = np.stack([-u[e][:, 1], u[e][:, 0]], axis=1)
        side = np.sign(((a - p0[e]) * normal).sum(axis=1))
        inwards.append(normal * np.where(side == 0, 1.0, side)[:, None])
    if not angles:
        z = np.zeros(0)
        return ContourEdges(
            z, z, applies, z.astype(np.int64), np.zeros((0, 2, 2)), np.zeros((0, 2)),
            np.zeros((0, 4)), np.zeros((0, 2)), z, np.zeros((0, 2)), z, z,
        )  # fmt: skip
    strip_all, inward_all = np.concatenate(strips), np.concatenate(inwards)
    return ContourEdges(
        np.concatenate(angles), np.concatenate(cores), applies, np.concatenate(rings),
        strip_all, inward_all, np.concatenate(feet),
        np.concatenate(reaches), np.concatenate(trims), np.concatenate(arcs),
        np.concatenate(totals), clearance(area, strip_all, inward_all, spacing),
    )  # fmt: skip


def _flag_reach(half: float, step: float, tol: float) -> float:
    """How far along a contour stretch (beyond the feet of the strip it lies over) its samples
    are still within ``reach + step`` of the strip's edge points: ``sqrt((r + step)^2 - h^2)``
    with the reach ``r`` at least ``half (1 - 1e-8)`` (:class:`ContourEdges`' ``applies``) and
    the stretch's height ``h`` over the edge at most ``half + tol``, less a millionth."""
    r, h = half * (1 - 1e-8), half + tol
    return math.sqrt(max((r + step) ** 2 - h**2, 0.0)) * (1 - 1e-6)


def path_floor(area: Region, reach: float) -> float:
    """A length every plan covering ``area`` flies (any layout, either margin): its path is
    connected and passes within ``reach`` of every point of the area, so its projection on the
    line of the area's diameter covers the diameter less ``reach`` at each end (less a
    millionth of the diameter for rounding)."""
    import shapely

    hull = np.asarray(shapely.MultiPoint(area.shell.vertices).convex_hull.exterior.coords)[:-1]
    diff = hull[:, None, :] - hull[None, :, :]
    diameter = float(np.sqrt((diff**2).sum(axis=2)).max())
    return max(0.0, diameter * (1 - 1e-6) - 2 * reach)


def stretch_length(contour: ContourEdges, theta: float) -> float:
    """``P`` at one layout (angle ``theta``): the boundary passes the planner's lanes cut half a
    spacing inside (margin 1/2) need at least (0 where the reach is not half the spacing)."""
    if not contour.applies:
        return 0.0
    p, _, _ = _stretches(contour, np.array([theta]), np.zeros(1))
    return float(p[0])


def _near_lengths(
    contour: ContourEdges,
    theta: NDArray[np.float64],
    d: NDArray[np.float64],
    eps: NDArray[np.float64],
    origin: NDArray[np.float64],
    spacing: float,
    parts: list[NDArray[np.int64]] | None = None,
    band: tuple[float, float] = (BAND_LO, BAND_HI),
    max_angle: float = NEAR_ANGLE,
) -> NDArray[np.float64]:
    """``(L, S)`` per layout and stretch, the length of the stretch the planner keeps for the
    parts of its strip (feet ``J`` on the edge) that no line of the grid ``(theta, d)``, moved
    across by up to ``eps``, passes between ``band`` (half-spacings inside; default
    :data:`BAND_LO` and :data:`BAND_HI`, margin 1/2: then no lane covers their points at
    depth 0.005-0.0055 half-spacings; the rule for stretches near the lanes' direction,
    docs/mission_time.md, "Keep-inside: the bound"; margin 0's is
    :data:`~.inside_cut.CUT_BAND`), computed where the stretch is within ``max_angle`` of
    the lanes at ``theta`` (the caller gates the box's angles):
    each such part (at least :data:`MIN_PART` long) flags the stretch's samples up to
    ``rho`` beyond it, and a flagged run at least a sample step long is kept whole.
    ``parts``: a list that gets ``(L, S)``, the number of separate parts of that union (each a
    run of consecutive flagged samples, :mod:`~.inside_moves`)."""
    half = spacing / 2
    n_l, n_s = len(theta), len(contour.core)
    cs, sn = np.cos(theta)[:, None, None], np.sin(theta)[:, None, None]
    rel = contour.strip - origin  # (S, 2, 2)
    h = -sn * rel[None, :, :, 0] + cs * rel[None, :, :, 1]  # (L, S, 2)
    side = -np.sin(theta)[:, None] * contour.inward[None, :, 0]
    side = side + np.cos(theta)[:, None] * contour.inward[None, :, 1]
    sigma = np.where(side >= 0, 1.0, -1.0)  # (L, S): the side of the area across the lanes
    u = sigma[..., None] * h  # across, towards the area: at j_lo and at j_hi
    e = np.broadcast_to(np.asarray(eps, dtype=np.float64), theta.shape)[:, None]
    lo, hi = band[0] * half - e, band[1] * half + e  # (L, 1)
    g0, g1, j_lo, j_hi = (contour.feet[None, :, i] for i in range(4))
    step, rho = contour.reach[None, :, 0], contour.reach[None, :, 1]
    sd = sigma * d[:, None]
    u_min, u_max = u.min(axis=2), u.max(axis=2)
    angle = relative_angle(contour.angle, theta)
    use = (angle <= max_angle) & (hi - lo < spacing) & (contour.core[None, :] > 0)
    if not use.any():
        if parts is not None:
            parts.append(np.zeros((n_l, n_s), dtype=np.int64))
        return np.zeros((n_l, n_s))
    k0 = np.ceil((u_min + lo - sd) / spacing)  # the first line whose band can meet J
    m = int(np.max(np.where(use, u_max - u_min, 0.0)) / spacing) + 3  # every line up to J's end
    k = k0[..., None] + np.arange(m)  # (L, S, m) lines
    line = sd[..., None] + k * spacing
    du = u[..., 1] - u[..., 0]
    flat = np.abs(du) <= 1e-12 * spacing
    scale = (j_hi - j_lo) / np.where(flat, 1.0, du)
    # the bad u-range [line - hi, line - lo] mapped to feet, clipped to J
    fa = j_lo[..., None] + (line - hi[..., None] - u[..., 0:1]) * scale[..., None]
    fb = j_lo[..., None] + (line - lo[..., None] - u[..., 0:1]) * scale[..., None]
    bl = np.clip(np.minimum(fa, fb), j_lo[..., None], j_hi[..., None])
    bh = np.clip(np.maximum(fa, fb), j_lo[..., None], j_hi[..., None])
    bl, bh = np.sort(bl, axis=2), np.sort(bh, axis=2)
    starts = np.concatenate([np.broadcast_to(j_lo, (n_l, n_s))[..., None], bh], axis=2)
    ends = np.concatenate([bl, np.broadcast_to(j_hi, (n_l, n_s))[..., None]], axis=2)
    good = ends - starts >= MIN_PART * spacing
    ds = np.maximum(g0[..., None], starts - rho[..., None])
    de = np.minimum(g1[..., None], ends + rho[..., None])
    good &= de - ds >= step[..., None] * (1 + 1e-9)
    de = np.where(good, de, -np.inf)
    before = np.maximum.accumulate(
        np.concatenate([np.full((n_l, n_s, 1), -np.inf), de[..., :-1]], axis=2), axis=2
    )
    length = np.where(good, np.maximum(de - np.maximum(ds, before), 0.0), 0.0).sum(axis=2)
    # a flat strip (parallel to the lines at the centre): the whole of J or nothing
    flat_free = ((sd - u_min - lo) % spacing) > (u_max - u_min) + (hi - lo) + 1e-9 * spacing
    length = np.where(flat, np.where(flat_free, contour.core[None, :], 0.0), length)
    if parts is not None:  # a part starts where no earlier flagged stretch reaches
        n = (good & (ds > before)).sum(axis=2)
        n = np.where(flat, flat_free.astype(np.int64), n)
        parts.append(np.where(use & (length > 0), n, 0))
    return np.where(use, length, 0.0)


def _stretches(
    contour: ContourEdges,
    theta: NDArray[np.float64],
    delta: NDArray[np.float64],
    near: NDArray[np.float64] | None = None,
    ranking: bool = False,
    *,
    parts: NDArray[np.int64] | None = None,
    spacing: float = 0.0,
    passes: list[NDArray[np.int64]] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64]]:
    """``(P, A, R)`` per layout: the cores of the stretches at least :data:`MIN_ANGLE` from
    every lane angle in ``theta +- delta`` and, nearer the lanes' direction, the lengths
    ``near`` (:func:`_near_lengths`, up to :data:`NEAR_ANGLE`), their least travel along the
    lanes, and the number of contour rings holding such a core (each a boundary pass of its
    own). ``ranking``: the tenth round's cores (:attr:`ContourEdges.trimmed`) and no rings.
    ``passes``: a list that gets ``(L,)``, at most how many passes hold those stretches
    (:func:`~.inside_moves.pass_count`; ``parts``: the near lengths' parts, ``spacing``)."""
    if not len(contour.core):
        z = np.zeros(len(theta))
        if passes is not None:
            passes.append(np.zeros(len(theta), dtype=np.int64))
        return z, z, np.zeros(len(theta), dtype=np.int64)
    rel = relative_angle(contour.angle, theta)
    pick = rel - delta[:, None] >= MIN_ANGLE
    core = np.where(pick, (contour.trimmed if ranking else contour.core)[None, :], 0.0)
    close = np.zeros_like(pick)
    if near is not None:
        close = ~pick & (rel + delta[:, None] <= NEAR_ANGLE)
        core = np.where(close, np.minimum(near, contour.core[None, :]), core)
    if passes is not None:
        far = pick & (core > 0)
        in_near = None if parts is None else np.where(close & (core > 0), parts, 0)
        if in_near is None and close.any():
            raise ValueError("the near lengths' parts are needed to count the passes")
        passes.append(pass_count(contour.arc, contour.total, contour.ring, far, in_near, spacing))
    along = core * np.cos(np.minimum(rel + delta[:, None], math.pi / 2))
    rings = np.zeros(len(theta), dtype=np.int64) if ranking else rings_holding(core, contour.ring)
    return core.sum(axis=1), along.sum(axis=1), rings


def _moves(st: BandStats, spacing: float) -> NDArray[np.float64]:
    """The moves across the lines of :func:`~.bounds.lower_bounds`: ``(k_max - k_min) s``."""
    used = st.count >= 1
    idx = np.arange(st.count.shape[1])
    k_max = np.where(used, idx, -1).max(axis=1)
    k_min = np.where(used, idx, st.count.shape[1]).min(axis=1)
    return np.where(used.any(axis=1), (k_max - k_min) * spacing, 0.0)


def _extra(
    p: NDArray[np.float64], a: NDArray[np.float64], c: NDArray[np.float64]
) -> NDArray[np.float64]:
    """The non-lane path beyond the moves across the lines ``c``: at least the larger of the
    passes' stretches ``p`` and ``sqrt(a^2 + c^2)`` (``a`` their travel along the lanes)."""
    return np.maximum(np.maximum(p, np.sqrt(a**2 + c**2)) - c, 0.0)


def _with_cut_passes(
    zero: NDArray[np.float64],
    st_zero: BandStats,
    cost: CoverCost,
    spacing: float,
    contour: ContourEdges,
    theta: NDArray[np.float64],
    delta: NDArray[np.float64],
    near: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """The margin-0 bound ``zero`` with the passes its lanes need (:mod:`~.inside_cut`):
    the non-lane path at least the larger of their length ``P0`` and ``sqrt(A0^2 + C0^2)``
    (``C0`` the moves across the lines ``zero`` counts), one turn per ring holding one.
    ``near``: the stretches' lengths by the lines' positions (:func:`_near_cut`), or none."""
    if not contour.applies or not len(contour.core):
        return zero
    p, a, rings = cut_stretches(contour, theta, delta, spacing, near)
    c = _moves(st_zero, spacing)
    extra = _extra(p, a, c)
    turns = np.where(st_zero.count.sum(axis=1) > 0, rings, 0)
    return zero + cost.per_length * extra + cost.per_turn * turns


def _near_cut(
    contour: ContourEdges,
    theta: NDArray[np.float64],
    d: NDArray[np.float64] | None,
    eps: float,
    origin: NDArray[np.float64] | None,
    spacing: float,
) -> NDArray[np.float64] | None:
    """``(L, S)`` margin 0's stretch lengths by the lines' positions (:mod:`~.inside_cut`,
    "Where the lines are"; :data:`~.inside_cut.CUT_BAND`), or ``None`` without the grid."""
    if d is None or origin is None or not contour.applies or not len(contour.core):
        return None
    e = np.full(len(theta), eps)
    return _near_lengths(
        contour, theta, d, e, origin, spacing, band=CUT_BAND, max_angle=NEAR_CUT_ANGLE
    )


def _no_holes(st: BandStats) -> BandStats:
    return st._replace(cut=np.zeros_like(st.cut), rigid=np.zeros_like(st.rigid))


def keep_inside_bounds(
    st_half: BandStats,
    level_half: Level,
    st_zero: BandStats,
    level_zero: Level,
    cost: CoverCost,
    spacing: float,
    contour: ContourEdges,
    theta: NDArray[np.float64],
    delta: NDArray[np.float64],
    *,
    runins: bool,
    floor: float = 0.0,
    d: NDArray[np.float64] | None = None,
    eps: float = 0.0,
    origin: NDArray[np.float64] | None = None,
    ranking: bool = False,
    tight: list[NDArray[np.float64]] | None = None,
    cut_passes: str | None = None,
) -> NDArray[np.float64]:
    """``(L,)`` a lower bound on the cost of every keep-inside plan of the layouts (module
    docstring). ``st_half``/``level_half``: the sandwich's inner set shrunk by half a spacing
    (band 0), ``st_zero``/``level_zero`` the same radius not shrunk; ``delta`` the boxes'
    angular half-widths (0 at a layout); ``floor``: :func:`path_floor` (plan units), a path no
    plan of the area is shorter than; ``d`` the boxes' centre offsets, ``eps`` a radius that
    holds every box's rigid motion and ``origin`` the grid's centre: with them the stretches
    near the lanes' direction whose strip no line can reach are counted too. ``ranking``:
    ``(2, L)``, the bound and the value that ranks the layouts a search plans, the tenth
    round's bound (trimmed stretches, no turn per pass; lower, so still a bound). ``tight``:
    a list that gets ``(L,)``, the bound with the moves on top of the passes
    (:mod:`~.inside_moves`, :data:`MOVES_ON_PASSES`), which the certificate takes where the
    search decides by the bound returned (docs/mission_time.md). ``cut_passes``: where margin
    0's passes count (:data:`CUT_PASSES`' values; default :data:`CUT_PASSES`)."""
    mode = CUT_PASSES if cut_passes is None else cut_passes
    kw: dict[str, Any] = {"boustrophedon": False, "ends": None}
    half = lower_bounds(st_half, level_half, cost, spacing, runins=runins, **kw)
    zero = lower_bounds(_no_holes(st_zero), level_zero, cost, spacing, runins=False, **kw)
    near0 = _near_cut(contour, theta, d, eps, origin, spacing) if NEAR_CUT and eps > 0 else None
    cut = _with_cut_passes(zero, st_zero, cost, spacing, contour, theta, delta, near0)
    halves = [half, half] if ranking else [half]
    moved = half
    if contour.applies and len(contour.core):
        near = None
        parts: list[NDArray[np.int64]] = []
        if d is not None and origin is not None:
            e = np.full(len(theta), eps)
            sink = parts if tight is not None and MOVES_ON_PASSES else None
            near = _near_lengths(contour, theta, d, e, origin, spacing, parts=sink)
        c = _moves(st_half, spacing)
        plain = lower_bounds(_no_holes(st_half), level_half, cost, spacing, runins=runins, **kw)
        # a turn before each boundary pass (the plan's turns: its lanes and passes less one)
        lanes = st_half.count.sum(axis=1) > 0
        for i, trimmed in enumerate([False, True][: len(halves)]):
            want = tight is not None and MOVES_ON_PASSES and not trimmed
            held: list[NDArray[np.int64]] | None = [] if want else None
            p, a, rings = _stretches(
                contour, theta, delta, None if trimmed else near, trimmed,
                parts=parts[0] if parts else None, spacing=spacing, passes=held,
            )  # fmt: skip
            extra = _extra(p, a, c)
            turns = np.where(lanes, rings, 0)
            halves[i] = np.maximum(half, plain + cost.per_length * extra + cost.per_turn * turns)
            if held:  # the moves no pass holding a counted stretch serves
                more = np.maximum(extra, p + line_moves(st_half.count, spacing, held[0]) - c)
                moved = np.maximum(half, plain + cost.per_length * more + cost.per_turn * turns)
    least = cost.per_length * floor + cost.fixed
    # margin 0's passes (inside_cut): in the bound, the ranking value and the certificate
    # as CUT_PASSES says
    zeros = [cut if mode in ("bound", "all") else zero]
    zeros += [cut if mode == "all" else zero] if ranking else []
    out = [np.maximum(np.minimum(h, z), least) for h, z in zip(halves, zeros, strict=True)]
    if tight is not None:
        z = zero if mode == "off" else cut
        tight.append(np.maximum(np.minimum(np.maximum(moved, halves[0]), z), least))
    return np.stack(out) if ranking else out[0]


def inside_box_bounds(
    search: Any,
    lv: Level,
    st: BandStats,
    radius: float,
    reach_out: float,
    theta: NDArray[np.float64],
    d: NDArray[np.float64],
    delta: NDArray[np.float64],
    ranking: bool = False,
    tight: list[NDArray[np.float64]] | None = None,
) -> NDArray[np.float64]:
    """:func:`keep_inside_bounds` for a :class:`~.search.CoverSearch` with ``keep_inside``:
    ``lv, st`` its level at ``radius`` shrunk by half a spacing, the level not shrunk bounded
    here (lines within ``reach_out``); with ``ranking``, the bound and the ranking value
    stacked ``(2, L)``; ``tight``, a list that gets the certificate's bound."""
    lv0 = search.sandwich.level(radius, 0.0)
    st0 = band_stats(
        lv0.inner, lv0.outer, theta, d, search.s, 0.0, search.origin,
        search.k_range(reach_out), search.n_holes, search.tol, inner_reach=0.0,
    )  # fmt: skip
    # the stretches near the lanes' direction in boxes, and at the layouts in their bound but
    # not in the value that ranks the layouts the search plans (with them there it planned
    # longer plans: docs), where NEAR_AT_LAYOUTS; a decomposition's cell searches
    # (moves_on_passes False: their floors screen candidates) decide as before both
    fourteenth = bool(search.moves_on_passes)
    near = d if radius > 0 or (NEAR_AT_LAYOUTS and fourteenth) else None
    args = (st, lv, st0, lv0, search.cost, search.s, search.contour, theta, delta)
    kw = {"runins": search.n_holes == 0, "floor": search.floor, "origin": search.origin}
    # with ranking, the layouts' own values that rank the layouts the search plans: the tenth
    # round's terms there (with the eleventh round's, 9 of 34 keep-inside plans of the 100-area
    # run came out longer by 0.1-9.5 s, one shorter: a review)
    cut = None if fourteenth else "off"
    return keep_inside_bounds(
        *args, d=near, eps=radius, ranking=ranking, tight=tight, cut_passes=cut, **kw
    )
