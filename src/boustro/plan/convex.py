"""Convex plans: guaranteed transects (:func:`guaranteed_segments`) and the path."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validate import as_number
from ..errors import InvalidParameterError, NoTransectError
from ..geometry import HalfPlanes, Polygon, halfplanes
from ..models import check_finite, check_spacing, exact_chords
from ..scoring import Segments, as_polygon, transect_segments

if TYPE_CHECKING:
    pass

from .outside import outside_length
from .types import Layout, Plan, PlanStats

__all__ = [
    "build_plan",
    "edge_offset",
    "guaranteed_segments",
]


#: Width (relative to the polygon's diameter) under which a band's overlap with the polygon is
#: rounding, not a sliver to cover.
_SLIVER = 1e-12


# -- segments ---------------------------------------------------------------------------------
def _check_nonnegative(name: str, value: float) -> float:
    v = as_number(name, value)
    if not math.isfinite(v) or v < 0:
        raise InvalidParameterError(f"{name} must be a finite number >= 0, got {value!r}")
    return v


def _aligned(
    values: NDArray[np.float64],
    positions: NDArray[np.float64],
    target: NDArray[np.float64],
    s: float,
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """``values`` of a grid re-indexed so that entry ``j`` belongs to position ``target[j]``.

    Both grids have spacing ``s`` and the same length; entries that fall outside the source grid
    come back with ``valid == False``.
    """
    shift = round((target[0] - positions[0]) / s)
    idx = np.arange(len(target)) + shift
    valid = (idx >= 0) & (idx < len(positions))
    out = np.zeros(len(target))
    out[valid] = values[idx[valid]]
    return out, valid


def guaranteed_segments(
    polygon: Polygon | ArrayLike,
    spacing: float,
    angle: float,
    offset: float = 0.0,
    *,
    reach: float | None = None,
) -> Segments:
    """Coverage-guaranteed transect segments of a convex polygon, in boustrophedon order.

    Transect ``k`` (line at position ``c_k``) spans the projection onto its line of
    ``polygon ∩ {c_k - reach <= n . p <= c_k + reach}`` (see the module docstring), computed in
    closed form from the polygon's vertices and the exact chords at ``c_k ± reach``.

    Args:
        polygon: convex polygon, plan units.
        spacing: distance between neighbouring transects, > 0.
        angle: transect direction, radians counter-clockwise from +x.
        offset: grid offset along the left normal from the polygon's vertex mean (periodic in
            the spacing), as in :func:`boustro.scoring.transect_segments`.
        reach: half-width of the band each transect must cover, ``>= spacing / 2`` (default
            ``spacing / 2``; a sensor with a nadir gap needs more, see
            :class:`boustro.sensors.Swath`).

    Returns:
        :class:`~boustro.scoring.Segments` in ascending position; the first segment runs along
        ``u``, the next against it, and so on. ``index`` counts transects from the lowest one.

    Raises:
        NonConvexPolygonError: the polygon is concave.
        InvalidParameterError: bad spacing, angle, offset or reach.

    Example:
        >>> seg = guaranteed_segments([(0, 0), (10, 0), (10, 10), (0, 10)], 2.0, 0.0, 0.0)
        >>> len(seg.segments), seg.segments[0].tolist()
        (5, [[0.0, 1.0], [10.0, 1.0]])
    """
    poly = as_polygon(polygon).require_convex("coverage-guaranteed transects")
    spacing = check_spacing(spacing, extent=poly.diameter)
    angle, offset = check_finite("angle", angle), check_finite("offset", offset)
    reach = spacing / 2 if reach is None else check_finite("reach", reach)
    if reach < spacing / 2 * (1 - 1e-12):
        raise InvalidParameterError(
            f"reach must be >= spacing / 2 = {spacing / 2:g} for the bands to tile the area, "
            f"got {reach:g}"
        )
    frame = poly.frame
    s, h, d = spacing / frame.scale, reach / frame.scale, offset / frame.scale
    hp = halfplanes(poly, tensors=False)  # numpy arrays: a plan imports no torch
    # Enough candidate lines for every band that can meet the polygon.
    wide = HalfPlanes(hp.normals, hp.offsets, hp.radius + h + s)
    mid, lo, hi = (exact_chords(wide, angle, d + shift, s) for shift in (0.0, -h, h))
    c = np.asarray(mid.positions)  # numpy arrays: ``tensors=False``
    u = np.array([math.cos(angle), math.sin(angle)])
    n = np.array([-math.sin(angle), math.cos(angle)])
    v = frame.to_normalised(poly.vertices)
    vc, vt = v @ n, v @ u
    pmin, pmax = float(vc.min()), float(vc.max())
    overlap = np.minimum(pmax, c + h) - np.maximum(pmin, c - h)
    keep = overlap > _SLIVER
    # Candidate along-coordinates: both band-edge chords and the vertices inside the band.
    t_lo = np.full(len(c), np.inf)
    t_hi = np.full(len(c), -np.inf)
    for ch, target in ((lo, c - h), (hi, c + h)):
        pos = np.asarray(ch.positions)
        length, valid = _aligned(np.asarray(ch.lengths), pos, target, s)
        lower, _ = _aligned(np.asarray(ch.lower), pos, target, s)
        upper, _ = _aligned(np.asarray(ch.upper), pos, target, s)
        has = valid & (length > 0)
        t_lo = np.where(has, np.minimum(t_lo, lower), t_lo)
        t_hi = np.where(has, np.maximum(t_hi, upper), t_hi)
    inside = np.abs(vc[None, :] - c[:, None]) <= h + _SLIVER  # (K, N)
    t_lo = np.minimum(t_lo, np.where(inside, vt[None, :], np.inf).min(axis=1))
    t_hi = np.maximum(t_hi, np.where(inside, vt[None, :], -np.inf).max(axis=1))
    keep &= np.isfinite(t_lo) & np.isfinite(t_hi)
    index = np.flatnonzero(keep)
    c, t_lo, t_hi = c[index], t_lo[index], t_hi[index]
    start = c[:, None] * n + t_lo[:, None] * u
    end = c[:, None] * n + t_hi[:, None] * u
    seg = np.stack([start, end], axis=1)
    seg[1::2] = seg[1::2, ::-1]
    return Segments(
        positions=c * frame.scale,
        segments=frame.to_user(seg),
        lengths=(t_hi - t_lo) * frame.scale,
        index=index - (index[0] if len(index) else 0),
    )


def edge_offset(
    polygon: Polygon | ArrayLike, spacing: float, angle: float, inset: float = 0.5
) -> float:
    """The offset of the usual practice: first transect ``inset * spacing`` inside the edge.

    The first transect lies ``inset * spacing`` (half a spacing by default) inside the polygon's
    extreme vertex on the right-hand side of ``angle`` (lowest position), the others follow at
    the spacing. Returned in ``[0, spacing)``, for :func:`boustro.scoring.transect_segments`.
    """
    poly = as_polygon(polygon)
    spacing = check_spacing(spacing, extent=poly.diameter)
    angle = check_finite("angle", angle)
    n = np.array([-math.sin(angle), math.cos(angle)])
    first = float(np.min((poly.vertices - poly.centre) @ n)) + inset * spacing
    return math.fmod(first, spacing) % spacing


def _travel_directions(segs: NDArray[np.float64]) -> NDArray[np.float64]:
    """Unit direction of travel ``(T, 2)`` of alternating segments (zero-length ones included)."""
    lengths = np.linalg.norm(segs[:, 1] - segs[:, 0], axis=1)
    k = int(np.argmax(lengths))
    d = (segs[k, 1] - segs[k, 0]) / lengths[k]
    sign = np.where((np.arange(len(segs)) - k) % 2 == 0, 1.0, -1.0)
    return sign[:, None] * d


def _orient(
    segs: NDArray[np.float64], start: NDArray[np.float64], turnaround: float
) -> NDArray[np.float64]:
    """Alternating segments re-ordered to begin at the corner (first waypoint) nearest start."""
    candidates = [segs, segs[:, ::-1], segs[::-1], segs[::-1, ::-1]]
    firsts = np.array([c[0, 0] - turnaround * _travel_directions(c)[0] for c in candidates])
    return candidates[int(np.argmin(np.linalg.norm(firsts - start, axis=1)))]


def _start_point(start: ArrayLike | None, default: NDArray[np.float64]) -> NDArray[np.float64]:
    """``start`` checked as a finite ``(x, y)`` pair, or ``default``."""
    if start is None:
        return default
    start_pt = np.asarray(start, dtype=np.float64).reshape(-1)
    if start_pt.shape != (2,) or not np.all(np.isfinite(start_pt)):
        raise InvalidParameterError(f"start must be a finite (x, y) pair, got {start!r}")
    return start_pt


def _waypoints(
    transects: NDArray[np.float64], travel: NDArray[np.float64], turnaround: float
) -> tuple[NDArray[np.float64], list[str], list[int]]:
    """Waypoints, their kinds and transect indices of oriented transects driven in order."""
    points: list[NDArray[np.float64]] = []
    kinds: list[str] = []
    lane: list[int] = []
    for i, seg in enumerate(transects):
        step = turnaround * travel[i]
        if turnaround > 0:
            points.append(seg[0] - step)
            kinds.append("run_in")
        points += [seg[0], seg[1]]
        kinds += ["start", "end"]
        if turnaround > 0:
            points.append(seg[1] + step)
            kinds.append("run_out")
        lane += [i] * (4 if turnaround > 0 else 2)
    return np.array(points), kinds, lane


def _convex_stats(
    n_t: int,
    transect_length: float,
    path_length: float,
    area: float,
    speed: float | None,
    turn_time: float,
    outside: float = 0.0,
) -> PlanStats:
    """Statistics of a single-grid plan (ground units): one turn between consecutive transects."""
    duration = None if speed is None else path_length / speed + (n_t - 1) * turn_time
    return PlanStats(
        n_transects=n_t,
        n_turns=n_t - 1,
        transect_length=transect_length,
        path_length=path_length,
        area=area,
        speed=speed,
        turn_time=turn_time,
        duration=duration,
        outside_length=outside,
    )


def _layout_segments(
    poly: Polygon, spacing: float, angle: float, offset: float, layout: str, reach: float | None
) -> tuple[Segments, float]:
    """The transect segments of ``layout`` and the reach (default ``spacing / 2``)."""
    if layout == "guaranteed":
        segs = guaranteed_segments(poly, spacing, angle, offset, reach=reach)
    elif layout == "chords":
        segs = transect_segments(poly, spacing, angle, offset)
    else:
        raise InvalidParameterError(f"layout must be 'guaranteed' or 'chords', got {layout!r}")
    reach = spacing / 2 if reach is None else float(reach)
    if len(segs.lengths) == 0:
        raise NoTransectError(
            f"no transect crosses the polygon at spacing {spacing:g}, angle "
            f"{math.degrees(angle):g} deg, offset {offset:g}"
        )
    return segs, reach


def build_plan(
    polygon: Polygon | ArrayLike,
    spacing: float,
    angle: float,
    offset: float = 0.0,
    *,
    layout: Layout = "guaranteed",
    start: ArrayLike | None = None,
    turnaround: float = 0.0,
    reach: float | None = None,
    nadir_gap: float = 0.0,
    ground_scale: float = 1.0,
    speed: float | None = None,
    turn_time: float = 0.0,
    area: float | None = None,
) -> Plan:
    """Build the waypoints and statistics of a boustrophedon plan.

    Args:
        polygon: convex polygon in the plan frame.
        spacing, angle, offset: the transect grid, e.g. from :func:`boustro.optimize.optimize`.
        layout: ``"guaranteed"`` (default, every point of the polygon lies within ``reach`` of
            a transect segment, measured across the transects) or ``"chords"`` (segments are the
            lines' chords: the fitness layout, with no such guarantee).
        start: point ``(x, y)``; the path begins at the corner nearest it (default: the first
            vertex of ``polygon`` as stored).
        turnaround: run-in / run-out distance beyond each transect end (plan units, >= 0).
        reach: half-width of each transect's band (default ``spacing / 2``), see
            :func:`guaranteed_segments`.
        nadir_gap: blind strip under the vehicle, recorded for :func:`coverage` (plan units).
        ground_scale: plan units per ground unit; statistics are reported in ground units.
        speed: ground speed in ground units per second, for the duration (optional).
        turn_time: seconds added per turn.
        area: area reported in the statistics, ground units squared (default: the polygon's
            area divided by ``ground_scale ** 2``); pass the surveyed area when the polygon
            planned is its convex hull.

    Raises:
        NonConvexPolygonError, InvalidParameterError: bad input.
        NoTransectError: no transect crosses the polygon (chords layout only).

    Example:
        >>> plan = build_plan([(0, 0), (10, 0), (10, 10), (0, 10)], 2.0, 0.0, 0.0)
        >>> plan.stats.n_transects, plan.stats.path_length, plan.kinds[:2]
        (5, 58.0, ('start', 'end'))
    """
    poly = as_polygon(polygon).require_convex("a boustrophedon plan")
    spacing = check_spacing(spacing, extent=poly.diameter)
    turnaround = _check_nonnegative("turnaround", turnaround)
    nadir_gap = _check_nonnegative("nadir_gap", nadir_gap)
    turn_time = _check_nonnegative("turn_time", turn_time)
    ground_scale = check_finite("ground_scale", ground_scale)
    if ground_scale <= 0:
        raise InvalidParameterError(f"ground_scale must be > 0, got {ground_scale!r}")
    if speed is not None:
        speed = check_finite("speed", speed)
        if speed <= 0:
            raise InvalidParameterError(f"speed must be > 0, got {speed!r}")
    segs, reach = _layout_segments(poly, spacing, angle, offset, layout, reach)
    start_pt = _start_point(start, poly.vertices[0])
    n = np.array([-math.sin(angle), math.cos(angle)])
    transects = _orient(segs.segments, start_pt, turnaround)
    travel = _travel_directions(transects)
    positions = (transects[:, 0] - poly.centre) @ n
    waypoints, kinds, lane = _waypoints(transects, travel, turnaround)
    transect_length = float(np.linalg.norm(transects[:, 1] - transects[:, 0], axis=1).sum())
    path_length = float(np.linalg.norm(np.diff(waypoints, axis=0), axis=1).sum())
    stats = _convex_stats(
        len(transects),
        transect_length / ground_scale,
        path_length / ground_scale,
        poly.area / ground_scale**2 if area is None else float(area),
        speed,
        turn_time,
        outside_length(waypoints, poly) / ground_scale,
    )
    return Plan(
        polygon=poly,
        spacing=spacing,
        angle=float(angle),
        offset=float(offset),
        layout=layout,
        reach=float(reach),
        nadir_gap=nadir_gap,
        turnaround=turnaround,
        positions=positions,
        transects=transects,
        waypoints=waypoints,
        kinds=tuple(kinds),
        lane=np.asarray(lane, dtype=np.int64),
        ground_scale=ground_scale,
        stats=stats,
    )
