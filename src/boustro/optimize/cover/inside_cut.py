"""The boundary passes of a ``keep_inside`` plan whose lanes are cut at the boundary (margin 0,
:mod:`boustro.plan.inside`): the contour stretches the triangles its lanes leave along an
oblique edge make the planner keep (issue 16; docs/mission_time.md, "Keep-inside: margin 0's
passes").

**The argument.** Take a straight stretch of the contour (:class:`~.inside_bound.ContourEdges`:
half a spacing ``s/2`` from an edge ``E``, parallel to it, over the feet ``[g0, g1]`` on ``E``;
``J = [j_lo, j_hi]`` its feet at least ``s/2`` from ``E``'s ends, where the strip along ``E``
up to ``s/2`` deep is in the area) and a layout whose lanes make an angle ``phi`` with ``E``.
The reach is ``s/2`` (else nothing is counted), so the lanes' swaths (flat, ``s/2`` either
side, :func:`~boustro.plan.inside._lane_footprint`) on neighbouring lines meet exactly and a
point at across-distance ``0 < c < s/2`` from line ``k`` is covered only by a lane on line
``k``. At margin 0 each lane is a piece of its line's chord of the area (a coverage-guaranteed
lane spans the chord; the cut keeps exactly its pieces), so a line ``k`` crossing ``E`` at a
point ``X`` with feet in ``J`` has a lane ending at ``X``. On one side of the line (across
``c`` in ``(0, s/2)``) ``E`` runs on beyond the lane's flat end: the triangle between the end,
``E`` and the line ``c = s/2`` (legs ``s/2`` and ``s/2 cot phi``, its side on ``E`` of length
``h = s/2 / sin phi``) lies in the area (in the strip, when its side's feet are in ``J``) and
is covered by no other lane, unless line ``k`` comes back into the area beyond ``X`` within
``s/2 cot phi`` (a lane there could reach over it). It does not when every point of the area
beyond ``E``'s line (deeper than ``1e-7 s``) is farther than that from ``E``'s part over ``J``
(``clear``, once per area: :func:`clearance`); a lane piece that comes back shallower covers
only a sliver of the triangle ``(1e-7 s / cos phi)`` deep along ``E`` (counted below as
``TOUCH_SLACK``). So along ``E`` the lanes leave uncovered triangles touching ``E`` over
every other interval of length ``h`` (lines cross ``E`` every ``2h``): between the first and
the last of them the gaps are at most ``h`` long. A contour sample at foot ``f`` is ``s/2``
(to ``1e-7 s``) from ``E``'s line, so it is within ``reach + step`` of a point of ``E`` at
foot within ``rho`` (:func:`~.inside_bound._flag_reach`) of ``f``: when ``h/2`` (plus the
slack) is at most ``rho`` every sample from ``rho`` before the first triangle to ``rho`` after
the last is flagged (the planner's residual is the area less the lanes' footprints, tested raw
by ``dwithin``; the triangles are far above its sliver rule, ``cot phi >= COT_MIN``). The
first triangle touches ``E`` at most ``2h`` past ``j_lo`` (a crossing lies in every ``2h``; its
side runs ``h`` one way or the other, and must stay in ``J``), the last at least ``2h`` before
``j_hi``; so every sample of the stretch with feet in ``[max(g0, j_lo + 2h - rho), min(g1,
j_hi - 2h + rho)]`` is flagged and, when that holds a sample (at least a step long), the
planner keeps the whole of it (its runs reach from an unflagged sample to the next, as for
:mod:`~.inside_bound`'s ``P``). Over a box of layouts the area moves rigidly, so ``J`` and
``clear`` are the same and only ``phi`` varies (``rel +- delta``): the smallest ``phi`` bounds
``h`` and ``cot phi``, the largest the sliver rule. Each ring holding a counted stretch has a
pass of its own (a turn), as at margin 1/2.

**Where the lines are** (:func:`near_cut_use`; the fifteenth round). Where ``h/2 > rho``
(``phi`` under about 27 degrees) the triangles are too far apart for the whole stretch, but a
layout's grid (``theta``, ``d``: the box's centre, the area moved rigidly by at most ``eps``
across the lines) says where they are. Take a point ``p`` of the strip at depth ``0 < delta <=
CUT_DEPTH s/2`` over a foot ``f`` in ``J`` (in the area, as above), ``p_E`` its foot on ``E``,
``u`` the coordinate across the lanes, oriented so that the area side of ``E`` is ``+``
(``u(p) = u(p_E) + delta cos phi``). A lane covering ``p`` passes through ``q = p - c n`` with
``|c| <= s/2`` (flat swaths, ``n`` the lanes' normal), and ``q`` lies on a chord of the area (a
margin-0 lane is a piece of one). ``q`` is within ``s/2 + delta`` of ``E``'s part over ``J``,
so where ``clear`` exceeds that no point of the area beyond ``E``'s line deeper than ``D =
DEPTH s`` is there: ``q`` is at least ``-D`` inside ``E``'s line, i.e. ``delta - c' cos phi
>= -D`` (``c'`` the signed ``c`` along ``+u``). Its line's ``u`` is ``u(p) - c'``, so it lies
between ``delta cos phi - (delta + D) / cos phi >= -(CUT_DEPTH s/2 + D) / cos(NEAR_CUT_ANGLE)``
and ``delta cos phi + s/2 <= (1 + CUT_DEPTH) s/2`` across from ``p_E``: inside ``CUT_BAND``
(-0.005 to 1.005 half-spacings, with room for rounding). So wherever no grid line lies in that
band (widened by ``eps`` each side in a box) the strip's points up to ``CUT_DEPTH s/2`` (1.5e-3
``s``) deep are uncovered by every lane: a residual far above the planner's sliver rule
(``1e-7 s``) once at least ``MIN_PART`` (1e-4 spacings) long. From there the count is
:func:`~.inside_bound._near_lengths`' (the margin-1/2 rule near the lanes' direction, with this
band): each such part of ``J`` flags the contour samples within ``rho`` of it, and each union
of flagged stretches a step long or more is kept whole. The stretch's count is the larger of
this and :func:`cut_cores` (each is a part of the plan's passes); this rule needs the grid, so
it applies where the bound has it, in the boxes' bounds only (:data:`~.inside_bound.NEAR_CUT`),
not in the layouts' own bounds nor the value that ranks the layouts. It counts a
stretch parallel to the lanes whole when the nearest line inside is more than ``1.005 s/2``
from it (no lane reaches its edge), and about half of a stretch at a small angle (the
triangles' sides and ``rho`` either side).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...geometry.region import Region

__all__ = [
    "COT_MIN",
    "CUT_BAND",
    "CUT_DEPTH",
    "DEPTH",
    "NEAR_CUT_ANGLE",
    "TOUCH_SLACK",
    "clearance",
    "cut_cores",
    "cut_lengths",
    "cut_stretches",
    "near_cut_use",
    "relative_angle",
    "rings_holding",
]

#: The largest angle's cotangent a stretch is counted at (its triangles are at least
#: ``s^2 COT_MIN / 8`` in area, far above the planner's sliver rule at ``1e-7 s``).
COT_MIN = 0.01
#: Points of the area beyond an edge's line shallower than this (spacings) are not searched by
#: :func:`clearance` (rounding on the edge itself).
DEPTH = 1e-7
#: Spacings by which the triangles' sides on the edge may be shorter at each end than the
#: argument's (a lane piece coming back shallower than :data:`DEPTH`: at most ``DEPTH /
#: (sin phi cos phi)``, under ``2.3e-5`` at ``sin phi >= 0.44`` and ``cot phi >= COT_MIN``).
TOUCH_SLACK = 1e-4
#: Margin 0's rule by the lines' positions (module docstring, "Where the lines are"): stretches
#: up to this angle from the lanes (radians, over the box) ...
NEAR_CUT_ANGLE = 0.6
#: ... whose strip's points up to this deep (half-spacings) are uncovered wherever no grid
#: line lies between ``CUT_BAND`` half-spacings inside the strip's point on the edge:
#: ``-(CUT_DEPTH + 2 DEPTH) / cos(NEAR_CUT_ANGLE) = -0.00364`` and ``1 + CUT_DEPTH``, widened
#: for rounding.
CUT_DEPTH = 0.003
CUT_BAND = (-0.005, 1.005)


def relative_angle(angle: NDArray[np.float64], theta: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(L, S)`` the angle (radians, in ``[0, pi/2]``) between the lanes at each ``theta`` and
    each stretch's direction ``angle`` (mod pi)."""
    return np.abs((angle[None, :] - theta[:, None] + math.pi / 2) % math.pi - math.pi / 2)


def rings_holding(core: NDArray[np.float64], ring: NDArray[np.int64]) -> NDArray[np.int64]:
    """``(L,)`` the number of contour rings holding a stretch with ``core > 0`` (``(L, S)``;
    ``ring``: each stretch's ring)."""
    held = np.zeros((core.shape[0], int(ring.max()) + 1), dtype=bool)
    rows, cols = np.nonzero(core > 0)
    held[rows, ring[cols]] = True
    return held.sum(axis=1)


def clearance(
    area: Region, strip: NDArray[np.float64], inward: NDArray[np.float64], spacing: float
) -> NDArray[np.float64]:
    """``(S,)`` per stretch, the distance from its edge's part over ``J`` (``strip``: its
    ends, ``(S, 2, 2)``) to the area's points beyond the edge's line (the side away from
    ``inward``) deeper than :data:`DEPTH` spacings (``inf`` where there are none)."""
    import shapely

    if not len(strip):
        return np.zeros(0)
    target = shapely.Polygon(area.shell.vertices, [h.vertices for h in area.holes])
    big = 4.0 * float(area.diameter) + spacing
    a, b = strip[:, 0], strip[:, 1]
    u = b - a
    u = u / np.maximum(np.linalg.norm(u, axis=1), 1e-300)[:, None]
    out_n = -inward
    near = DEPTH * spacing * out_n
    corners = np.stack(
        [
            a - big * u + near,
            b + big * u + near,
            b + big * u + big * out_n,
            a - big * u + big * out_n,
        ],
        axis=1,
    )
    beyond = shapely.intersection(target, shapely.polygons(corners))
    d = shapely.distance(shapely.linestrings(strip), beyond)
    return np.where(shapely.is_empty(beyond) | np.isnan(d), np.inf, d)


def cut_cores(
    contour: Any,
    theta: NDArray[np.float64],
    delta: NDArray[np.float64],
    spacing: float,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(L, S)`` per layout (angles ``theta +- delta``) and stretch, the length of the part
    every margin-0 plan keeps (module docstring; 0 where none) and the foot on its edge where
    it starts. ``contour``: a :class:`~.inside_bound.ContourEdges` (its ``feet``, ``reach``,
    ``clear``, ``angle``, ``core``)."""
    half = spacing / 2
    rel = relative_angle(contour.angle, theta)
    lo = np.maximum(rel - delta[:, None], 0.0)
    hi = np.minimum(rel + delta[:, None], math.pi / 2)
    sin_lo = np.sin(lo)
    ok = (contour.core[None, :] > 0) & (sin_lo > 0) & (np.cos(hi) >= COT_MIN * np.sin(hi))
    sin_safe = np.where(ok, sin_lo, 1.0)
    h = half / sin_safe  # the triangles' sides on the edge, at most
    cot = np.cos(lo) / sin_safe
    g0, g1, j_lo, j_hi = (contour.feet[None, :, i] for i in range(4))
    step, rho = contour.reach[None, :, 0], contour.reach[None, :, 1]
    rho = rho - TOUCH_SLACK * spacing
    ok &= h / 2 <= rho
    ok &= contour.clear[None, :] >= half * cot * (1 + 1e-6) + DEPTH * spacing
    k_lo = np.maximum(g0, j_lo + 2 * h - rho)
    k_hi = np.minimum(g1, j_hi - 2 * h + rho)
    length = k_hi - k_lo
    ok &= length >= step * (1 + 1e-9)
    return np.where(ok, length, 0.0), k_lo


def near_cut_use(
    contour: Any, theta: NDArray[np.float64], delta: NDArray[np.float64], spacing: float
) -> NDArray[np.bool_]:
    """``(L, S)`` where margin 0's rule by the lines' positions applies (module docstring):
    the stretch within :data:`NEAR_CUT_ANGLE` of every lane angle ``theta +- delta`` and no
    point of the area beyond its edge's line (deeper than :data:`DEPTH`) within half a
    spacing and :data:`CUT_DEPTH` of its strip."""
    half = spacing / 2
    rel = relative_angle(contour.angle, theta)
    clear = contour.clear >= half * (1 + CUT_DEPTH) * (1 + 1e-6) + DEPTH * spacing
    return (rel + delta[:, None] <= NEAR_CUT_ANGLE) & clear[None, :] & (contour.core > 0)


def cut_lengths(
    contour: Any,
    theta: NDArray[np.float64],
    delta: NDArray[np.float64],
    spacing: float,
    near: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """``(L, S)`` per layout and stretch, the length every margin-0 plan keeps: the larger of
    :func:`cut_cores`' and, where :func:`near_cut_use`, ``near``'s (``(L, S)``, the lengths of
    :func:`~.inside_bound._near_lengths` in :data:`CUT_BAND`; ``None``: not counted)."""
    core, _ = cut_cores(contour, theta, delta, spacing)
    if near is None:
        return core
    use = near_cut_use(contour, theta, delta, spacing)
    return np.where(use, np.maximum(core, np.minimum(near, contour.core[None, :])), core)


def cut_stretches(
    contour: Any,
    theta: NDArray[np.float64],
    delta: NDArray[np.float64],
    spacing: float,
    near: NDArray[np.float64] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64]]:
    """``(P0, A0, R0)`` per layout (angles ``theta +- delta``): the length of the contour
    stretches every margin-0 plan keeps (:func:`cut_cores`; with ``near``, ``(L, S)`` the
    lengths of :func:`~.inside_bound._near_lengths` in :data:`CUT_BAND`, the larger of the
    two where :func:`near_cut_use`), their least travel along the lanes and the number of
    contour rings holding one."""
    n_l = len(theta)
    if not contour.applies or not len(contour.core):
        z = np.zeros(n_l)
        return z, z, np.zeros(n_l, dtype=np.int64)
    core = cut_lengths(contour, theta, delta, spacing, near)
    rel = relative_angle(contour.angle, theta)
    along = core * np.cos(np.minimum(rel + delta[:, None], math.pi / 2))
    return core.sum(axis=1), along.sum(axis=1), rings_holding(core, contour.ring)
