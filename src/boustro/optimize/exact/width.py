"""The fewest-transects layout in closed form: the minimum-width direction."""

from __future__ import annotations

import math
import time

import numpy as np
from numpy.typing import ArrayLike

from ...geometry import Polygon
from ...models import (
    check_spacing,
)
from ...objectives import coverage_count
from ...scoring import as_polygon
from ..result import OptimizeResult, canonical
from .structure import Array

__all__ = ["fewest_transects_optimum"]


def _width_pieces(v: Array) -> tuple[Array, Array, Array]:
    """The width ``w(theta) = max h - min h`` on ``[0, pi]`` as ``|n(theta) . (v_i - v_j)|`` for
    a fixed pair between consecutive angles where an edge is parallel to the transects.

    Returns the breakpoints ``(B + 1,)`` and for each of the ``B`` arcs the pair's difference
    vector ``(B, 2)``.
    """
    e = np.roll(v, -1, axis=0) - v
    cuts = np.mod(np.arctan2(e[:, 1], e[:, 0]), math.pi)
    cuts = np.unique(np.concatenate([[0.0, math.pi], cuts]))
    mids = 0.5 * (cuts[:-1] + cuts[1:])
    h = v[:, 1] * np.cos(mids)[:, None] - v[:, 0] * np.sin(mids)[:, None]
    top, bottom = np.argmax(h, axis=1), np.argmin(h, axis=1)
    return cuts, v[top] - v[bottom], mids


def _width(v: Array, theta: Array) -> Array:
    h = v[:, 1] * np.cos(theta)[:, None] - v[:, 0] * np.sin(theta)[:, None]
    return h.max(axis=1) - h.min(axis=1)


def fewest_transects_optimum(
    polygon: Polygon | ArrayLike, spacing: float, *, progress: bool | None = None
) -> OptimizeResult:
    """The layout with the fewest transects that covers the polygon, in closed form.

    At angle ``theta`` full coverage (every point within half a spacing of a transect) needs
    ``ceil(width(theta) / spacing)`` transects and that many suffice with a free offset, so the
    optimum is the minimum-width direction, which for a convex polygon is parallel to one of its
    edges (the width is ``|n . (v_i - v_j)|`` for a fixed antipodal pair between edge
    directions, a concave arc, so its minimum is at an arc's end). The offset centres the
    transects: equal margins ``(width - (N - 1) s) / 2 <= s / 2`` on both sides.

    Every angle with ``width(theta) <= N s`` ties; ``info["optimal_angles"]`` lists them as
    closed intervals (radians, in ``[0, pi]``), computed in closed form per arc. ``progress``
    is accepted for the common optimiser interface.

    Returns:
        :class:`~boustro.optimize.OptimizeResult` with ``method="fewest_transects"``,
        ``fitness`` = the number of transects (minimised: ``upper_bound`` is None; it is exact,
        ``info["gap"] = 0``), ``info["width"]`` (polygon units), ``info["optimal_angles"]``.

    >>> r = fewest_transects_optimum([(0, 0), (4, 0), (4, 1), (0, 1)], 0.25)
    >>> r.fitness, round(r.angle, 4)
    (4.0, 0.0)
    """
    t0 = time.perf_counter()
    del progress
    poly = as_polygon(polygon).require_convex("the fewest-transects optimiser")
    spacing = check_spacing(spacing, extent=poly.diameter)
    v = poly.vertices - poly.centre  # user units, centred: offsets relative to the vertex mean
    e = np.roll(v, -1, axis=0) - v
    edge_angle = np.mod(np.arctan2(e[:, 1], e[:, 0]), math.pi)
    widths = _width(v, edge_angle)
    k = int(np.argmin(widths))
    theta, width = float(edge_angle[k]), float(widths[k])
    count = coverage_count(width, spacing)
    h = v[:, 1] * math.cos(theta) - v[:, 0] * math.sin(theta)
    margin = 0.5 * (width - (count - 1) * spacing)
    first = float(h.min()) + margin
    angle, offset = canonical(theta, first, spacing)
    # the tie set {theta : width(theta) <= count * spacing}, arc by arc
    cuts, diff, _ = _width_pieces(v)
    limit = count * spacing
    intervals: list[list[float]] = []
    for lo, hi, dv in zip(cuts[:-1], cuts[1:], diff, strict=True):
        amp = float(np.hypot(dv[0], dv[1]))
        alpha = math.atan2(-dv[0], dv[1])  # width = amp * |cos(theta - alpha)| on the arc
        if amp <= limit:
            pieces = [(lo, hi)]
        else:
            gap = math.acos(
                limit / amp
            )  # |cos| <= limit / amp  <=>  theta - alpha in [gap, pi - gap] mod pi
            pieces = []
            for base in (
                alpha + gap - 2 * math.pi,
                alpha + gap - math.pi,
                alpha + gap,
                alpha + gap + math.pi,
            ):
                a0, a1 = max(lo, base), min(hi, base + math.pi - 2 * gap)
                if a0 <= a1:
                    pieces.append((a0, a1))
        for a0, a1 in pieces:
            if intervals and a0 <= intervals[-1][1] + 1e-15:
                intervals[-1][1] = max(intervals[-1][1], a1)
            else:
                intervals.append([float(a0), float(a1)])
    return OptimizeResult(
        angle=angle,
        offset=offset,
        fitness=float(count),
        spacing=spacing,
        method="fewest_transects",
        evaluations=len(edge_angle),
        seconds=time.perf_counter() - t0,
        upper_bound=None,
        info={
            "objective": "fewest_transects",
            "maximise": False,
            "lower_bound": float(count),
            "gap": 0.0,
            "width": width,
            "margin": margin,
            "optimal_angles": intervals,
        },
    )
