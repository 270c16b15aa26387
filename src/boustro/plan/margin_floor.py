"""A floor of the contour stretches that lanes cut at the boundary need, without their residual.

:func:`~boustro.plan.inside.inside_layout` lays the lanes half a spacing inside the area
(margin 1/2) in full, then decides whether the lanes cut at the boundary (margin 0) could be
shorter with their passes: their residual (the area less their footprints, a shapely union
and difference) and the contour's stretches within reach of it (the samples' ``dwithin``)
were computed on every layout, although margin 1/2 wins on nearly all (docs/keep_inside.md,
"Margin screen"). :func:`stretch_floor` bounds the length of those stretches from below from
the lanes' arrays alone, so that margin 0 is dropped before its residual where the floor
already says it loses; the stretches are computed as before where it does not.

*Test points* (:func:`test_points`, once per area, spacing and reach): for each sample ``q``
of a contour ring (:func:`~boustro.plan.contour.contour_of`, ``n`` samples ``step = total / n``
apart, a sample kept when ``dwithin(q, residual, reach + step)``), points ``p`` near the
boundary within ``(reach + step) (1 - 1e-9)`` of ``q``, inside the area at least ``DEPTH``
spacings from its boundary (``r = DEPTH * spacing``).

*The floor* (per layout): a test point outside every lane's footprint box (``reach`` either
side of the lane, from its start to its end: :func:`~boustro.plan.inside._lane_footprint`)
grown by ``r`` has its disk of radius ``r`` inside the residual: in the area (its depth) and in
no box. That disk lies in one polygon of the residual, whose area is then at least ``pi r^2``
and whose perimeter ``P`` is at most the area's perimeter plus the boxes' (its boundary lies on
theirs), with at most ``n = (V + 4 B)^2`` vertices (``V`` the area's, ``B`` boxes: the
boundaries' points and crossings); where ``pi r^2 > 2 eps (P + pi n eps)`` (``eps = 1e-7``
spacings, :func:`~boustro.plan.contour._pieces`' area rule) that polygon is kept, so the
residual is not only slivers and the sample ``q`` within reach of ``p`` is kept. The stretches
of a ring hold every kept sample: a run of kept samples ``i..j`` is the stretch between its
unkept neighbours, ``(j - i + 2) step`` long, stretches closer than the merge gap are joined
(longer), the whole ring is ``n step`` long, and a stretch's polyline along the ring is as
long as its arc. So the stretches are at least ``step`` times the samples a test point keeps,
per ring, less rounding (a ``1e-9`` share). Where the area rule does not hold (lanes far more
than the area's size in spacings) the floor is 0: margin 0 is laid as before.

*Known samples* (:func:`kept_samples`): where a residual is computed anyway (margin 1/2's, and
margin 0's where the floor does not screen it), a sample with an uncovered test point is within
``reach + step`` of it (the point's disk lies in it; no area rule needed), so
:func:`~boustro.plan.contour._contour_arcs` tests only the other samples' ``dwithin``: the
same samples kept, most of margin 1/2's known (its lanes end half a spacing short of the
boundary).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from .cells import _frame
from .lanes import Lanes

__all__ = ["ALONG", "DEPTH", "RingTests", "kept_samples", "stretch_floor", "test_points"]

#: Depth of the test points inside the area, and the radius of their disks, in spacings.
DEPTH = 0.02
#: Offsets (in spacings) along the boundary from a sample's nearest boundary point at which
#: the test points lie (those farther than the sample's reach, or too shallow, are dropped).
ALONG = (-0.5, -0.25, 0.0, 0.25, 0.5)


class RingTests(NamedTuple):
    """The test points of one contour ring: ``points (T, 2)``, the sample each belongs to
    (``sample (T,)``), the ring's samples ``n`` and their step."""

    points: NDArray[np.float64]
    sample: NDArray[np.int64]
    n: int
    step: float


def test_points(target: Any, rings: list[Any], spacing: float, reach: float) -> list[RingTests]:
    """The test points (module docstring) of each ring of the contour of the shapely area
    ``target`` (prepared), ``rings`` as :class:`~boustro.plan.contour.Contour` holds them."""
    import shapely

    depth = DEPTH * spacing
    boundary = shapely.boundary(target)
    out = []
    for ring in rings:
        n = len(ring.samples)
        step = ring.total / n
        q = shapely.get_coordinates(ring.samples)
        foot = shapely.get_coordinates(shapely.shortest_line(ring.samples, boundary))[1::2]
        d = np.linalg.norm(q - foot, axis=1)
        inward = (q - foot) / np.maximum(d, 1e-300)[:, None]
        along = np.stack([-inward[:, 1], inward[:, 0]], axis=1)
        pts = np.concatenate([foot + a * spacing * along + 2 * depth * inward for a in ALONG])
        sample = np.tile(np.arange(n), len(ALONG))
        ok = np.linalg.norm(pts - q[sample], axis=1) <= (reach + step) * (1 - 1e-9)
        ok &= shapely.contains_xy(target, pts[:, 0], pts[:, 1])
        ok[ok] = shapely.distance(shapely.points(pts[ok]), boundary) >= depth * (1 + 1e-6)
        out.append(RingTests(pts[ok], sample[ok], n, float(step)))
    return out


def stretch_floor(
    tests: list[RingTests],
    lanes: list[Lanes],
    reach: float,
    spacing: float,
    perimeter: float,
    vertices: int,
) -> float:
    """A lower bound of the length of the contour stretches
    (:func:`~boustro.plan.contour._contour_arcs`) that the residual of the cut ``lanes`` keeps
    (module docstring), given the area's ``perimeter`` and ``vertices``; 0 where the area rule
    does not hold."""
    depth = DEPTH * spacing
    eps = 1e-7 * spacing
    boxes = sum(len(ls.k) for ls in lanes)
    box_perimeter = sum(float(np.sum(2 * (ls.t1 - ls.t0) + 4 * reach)) for ls in lanes)
    n_max = float(vertices + 4 * boxes) ** 2
    rim = 2 * eps * (1.01 * (perimeter + box_perimeter) + math.pi * n_max * eps)
    if not math.pi * depth * depth * (1 - 1e-5) > rim:
        return 0.0
    kept = kept_samples(tests, lanes, reach, spacing)
    return sum(int(k.sum()) * ring.step for k, ring in zip(kept, tests, strict=True)) * (1 - 1e-9)


def kept_samples(
    tests: list[RingTests], lanes: list[Lanes], reach: float, spacing: float
) -> list[NDArray[np.bool_]]:
    """Per ring, the samples a test point outside every lane's box (grown by ``DEPTH``
    spacings) shows within ``reach + step`` of the residual of ``lanes``: that point's disk lies
    in the residual (module docstring), so ``dwithin(q, residual, reach + step)`` holds there
    whatever else the residual is (:func:`~boustro.plan.contour._contour_arcs` tests only the
    others)."""
    depth = DEPTH * spacing
    out = []
    for ring in tests:
        kept = np.zeros(ring.n, dtype=bool)
        if len(ring.points):
            kept[ring.sample[_uncovered(ring.points, lanes, reach + depth, depth)]] = True
        out.append(kept)
    return out


def _uncovered(
    points: NDArray[np.float64], lanes: list[Lanes], across: float, grow: float
) -> NDArray[np.bool_]:
    """Whether each point lies outside every lane's box grown to ``across`` either side of the
    lane and ``grow`` past its ends (in the lane's own frame). Each point is tested against the
    lanes whose lines lie within ``across`` of it only (found by sorting the lines: a few per
    point), not against all: memory and time grow with points plus lanes, not their product
    (a 6 km field at 5 m spacing: 2 GB per layout tested against all)."""
    free = np.ones(len(points), dtype=bool)
    for ls in lanes:
        idx = np.flatnonzero(free)
        if not len(ls.k) or not len(idx):
            continue
        u, n = _frame(ls.angle)
        rel = points[idx] - ls.origin
        t, c = rel @ u, rel @ n
        order = np.argsort(ls.c, kind="stable")
        lines = ls.c[order]
        # every lane within across of a point, and perhaps a few more (the window is widened
        # past rounding): the exact test below decides
        room = across * (1 + 1e-6) + 1e-9 * np.abs(c)
        lo = np.searchsorted(lines, c - room, side="left")
        hi = np.searchsorted(lines, c + room, side="right")
        counts = hi - lo
        which = np.repeat(np.arange(len(idx)), counts)
        first = np.repeat(np.cumsum(counts) - counts, counts)
        lane = order[np.repeat(lo, counts) + np.arange(len(which)) - first]
        hit = (
            (np.abs(c[which] - ls.c[lane]) <= across)
            & (t[which] >= ls.t0[lane] - grow)
            & (t[which] <= ls.t1[lane] + grow)
        )
        free[idx[which[hit]]] = False
    return free
