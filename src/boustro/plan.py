"""From an optimum (angle, offset) to a plan: coverage-guaranteed transects, waypoints, statistics.

Layer 5 of the core (numpy and torch only; shapely is imported lazily inside :func:`coverage`).
Everything here works in one planar, metric-like frame, the *plan frame* (the edges of the system,
:mod:`boustro.geo`, bring geographic areas into it and take the results back out).

Coverage guarantee
------------------
Transect ``k`` is the line at signed position ``c_k = offset + k * spacing`` along the left normal
``n = (-sin angle, cos angle)`` of the transect direction ``u = (cos angle, sin angle)``, measured
from the polygon's vertex mean (the convention of :func:`boustro.scoring.transect_segments`). It
is made responsible for the *band* ``c_k - reach <= n . p <= c_k + reach`` (``reach = spacing / 2``
by default: the bands tile the plane) and its segment spans the projection onto the line of
``polygon ∩ band``. A sensor that sees ``reach`` to each side of the vehicle therefore sees every
point of the polygon: no part is left outside every swath.

For a convex polygon ``polygon ∩ band`` is a convex polygon whose vertices are the polygon's
vertices inside the band and the end points of the chords of the two band edges, so its extent
along ``u`` has a closed form: the chords come from :func:`boustro.models.exact_chords` at offsets
shifted by ``± reach``, the vertices from one vectorised comparison. Transects whose band meets the
polygon although their line misses it (the band covers a sliver at the polygon's extreme) get a
segment too, so a guaranteed plan can have one or two more transects than the fitness layout of
the same (angle, offset), and its segments are longer than the chords (they reach the band's
widest point). :func:`build_plan` with ``layout="chords"`` gives the fitness layout (segments =
chords of the lines), which is what most planners fly and which leaves strips uncovered.

Waypoints
---------
Transects are driven back and forth in order of position (boustrophedon). Of the four corners
where such a path can begin (first or last transect, either end) the one nearest ``start`` is
chosen. An optional ``turnaround`` (run-in / run-out) distance extends every transect beyond both
ends for vehicles that cannot turn on the spot; the connecting moves are straight lines from the
end of one transect (or its run-out) to the start of the next (or its run-in).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import torch
from numpy.typing import ArrayLike, NDArray

from .errors import (
    InvalidParameterError,
    NonConvexPolygonError,
    NoTransectError,
    as_number,
)
from .geometry import HalfPlanes, Polygon, halfplanes
from .models import check_finite, check_spacing, exact_chords
from .scoring import Segments, as_polygon, transect_segments

if TYPE_CHECKING:
    from .regions import Region

__all__ = [
    "KINDS",
    "Coverage",
    "Plan",
    "PlanCell",
    "PlanStats",
    "build_plan",
    "convex_hull",
    "coverage",
    "edge_offset",
    "footprint",
    "guaranteed_segments",
    "hull_depth",
    "nearly_convex",
    "swath_polygons",
]

#: What each waypoint is: run-in point before a transect, its start, its end, the run-out point;
#: for areas with holes or cells also ``via`` (a corner of a connecting move that goes around an
#: obstacle) and ``loop`` (a corner of a pass around a hole).
KINDS = ("run_in", "start", "end", "run_out", "via", "loop")

#: Width (relative to the polygon's diameter) under which a band's overlap with the polygon is
#: rounding, not a sliver to cover.
_SLIVER = 1e-12

Layout = Literal["guaranteed", "chords"]


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
    hp = halfplanes(poly)
    # Enough candidate lines for every band that can meet the polygon.
    wide = HalfPlanes(hp.normals, hp.offsets, hp.radius + h + s)
    with torch.no_grad():
        mid, lo, hi = (exact_chords(wide, angle, d + shift, s) for shift in (0.0, -h, h))
    c = mid.positions.numpy()
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
        pos = ch.positions.numpy()
        length, valid = _aligned(ch.lengths.numpy(), pos, target, s)
        lower, _ = _aligned(ch.lower.numpy(), pos, target, s)
        upper, _ = _aligned(ch.upper.numpy(), pos, target, s)
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


# -- plans ------------------------------------------------------------------------------------
@dataclass(frozen=True)
class PlanStats:
    """Statistics of a plan, in ground units (plan units divided by ``ground_scale``).

    Attributes:
        n_transects: transects driven.
        n_turns: turns between transects (``n_transects - 1``).
        transect_length: total length of the transects (survey segments, without run-ins).
        path_length: total length of the path through all waypoints (transects, run-ins and
            run-outs, connecting moves).
        area: area of the polygon planned (units squared).
        speed: speed used for the duration, or ``None``.
        turn_time: time added per turn (seconds).
        duration: ``path_length / speed + n_turns * turn_time`` (seconds), ``None`` without speed.
        n_cells: cells of a decomposed plan (1 otherwise).
        hole_pass_length: length of the passes around holes (included in ``path_length``).
        outside_length: length of the connecting moves outside the area (ends of lanes that
            reach beyond the boundary, and moves between them; included in ``path_length``).

    For a plan over an area with holes or a decomposed plan, ``n_transects`` counts the lane
    segments driven and ``n_turns`` the connecting moves between consecutive passes (a lane
    segment, or a pass around a hole): ``passes - 1``.
    """

    n_transects: int
    n_turns: int
    transect_length: float
    path_length: float
    area: float
    speed: float | None = None
    turn_time: float = 0.0
    duration: float | None = None
    n_cells: int = 1
    hole_pass_length: float = 0.0
    outside_length: float = 0.0


@dataclass(frozen=True)
class PlanCell:
    """One cell of a decomposed plan (or the whole area of a single-angle plan).

    Attributes:
        region: the cell (plan units), a :class:`~boustro.regions.Region` (it has holes where
            it surrounds one of the area's).
        angle, offset: its lanes (radians; plan units from the cell's shell's vertex mean).
        fitness: the optimiser's value for the cell (Eq. 1 over segments by default), or NaN.
        n_transects: lane segments planned in the cell.
        optimum: the optimiser's result for the cell, if it was optimised.
    """

    region: Region
    angle: float
    offset: float
    fitness: float
    n_transects: int
    optimum: Any = None

    @property
    def polygon(self) -> Polygon:
        """The cell's outer boundary."""
        return self.region.shell


@dataclass(frozen=True)
class Plan:
    """An ordered boustrophedon path over a convex polygon, in the plan frame.

    Attributes:
        polygon: the convex polygon planned (plan units).
        spacing, angle, offset: the transect grid (plan units, radians; see the module
            docstring).
        layout: ``"guaranteed"`` (segments cover the projection of polygon ∩ band) or
            ``"chords"`` (segments are the chords of the lines).
        reach: half-width of the band each transect covers (``spacing / 2`` by default).
        nadir_gap: width of a blind strip centred under the vehicle (0 for most sensors).
        turnaround: run-in / run-out distance beyond each transect end (plan units).
        positions: ``(T,)`` position of each transect, in driving order.
        transects: ``(T, 2, 2)`` survey segments ``[start, end]`` in driving order and direction.
        waypoints: ``(W, 2)`` the path, in order.
        kinds: ``(W,)`` what each waypoint is, one of :data:`KINDS`.
        lane: ``(W,)`` index (into ``transects``) of the transect each waypoint belongs to.
        ground_scale: plan units per ground unit (1 for a planar frame; a projection's scale
            factor for a map projection); statistics are divided by it.
        stats: :class:`PlanStats`.
        region: for an area with a concave boundary or holes
            (:func:`boustro.decompose.plan_region`), the area planned; ``polygon`` is its shell.
        cells: the cells of a decomposed plan (:class:`PlanCell`), or the whole area as one cell.
        transect_angles: ``(T,)`` lane direction of each transect where they differ (cells,
            passes around holes), else ``None`` (all at ``angle``).
        roles: ``"lane"`` or ``"hole"`` per transect (empty: all lanes).
        transect_cells: ``(T,)`` the cell of each transect (-1 for passes around holes).
        notes: what the plan could not do as asked (e.g. moves that leave the area).
    """

    polygon: Polygon
    spacing: float
    angle: float
    offset: float
    layout: str
    reach: float
    nadir_gap: float
    turnaround: float
    positions: NDArray[np.float64]
    transects: NDArray[np.float64]
    waypoints: NDArray[np.float64]
    kinds: tuple[str, ...]
    lane: NDArray[np.int64]
    ground_scale: float
    stats: PlanStats
    region: Region | None = None
    cells: tuple[PlanCell, ...] = ()
    transect_angles: NDArray[np.float64] | None = None
    roles: tuple[str, ...] = ()
    transect_cells: NDArray[np.int64] | None = None
    notes: tuple[str, ...] = ()

    @property
    def n_transects(self) -> int:
        return len(self.transects)

    def transect_angle(self) -> NDArray[np.float64]:
        """``(T,)`` the lane direction of every transect (the plan's angle unless it has many)."""
        if self.transect_angles is None:
            return np.full(len(self.transects), self.angle)
        return self.transect_angles

    def role(self) -> tuple[str, ...]:
        """What each transect is: ``"lane"`` (a survey lane) or ``"hole"`` (an edge of a pass
        around a hole)."""
        return self.roles or ("lane",) * len(self.transects)

    @property
    def start(self) -> NDArray[np.float64]:
        """The first waypoint."""
        return self.waypoints[0]


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
    if layout == "guaranteed":
        segs = guaranteed_segments(poly, spacing, angle, offset, reach=reach)
        reach = spacing / 2 if reach is None else float(reach)
    elif layout == "chords":
        segs = transect_segments(poly, spacing, angle, offset)
        reach = spacing / 2 if reach is None else float(reach)
    else:
        raise InvalidParameterError(f"layout must be 'guaranteed' or 'chords', got {layout!r}")
    if len(segs.lengths) == 0:
        raise NoTransectError(
            f"no transect crosses the polygon at spacing {spacing:g}, angle "
            f"{math.degrees(angle):g} deg, offset {offset:g}"
        )
    if start is None:
        start_pt = poly.vertices[0]
    else:
        start_pt = np.asarray(start, dtype=np.float64).reshape(-1)
        if start_pt.shape != (2,) or not np.all(np.isfinite(start_pt)):
            raise InvalidParameterError(f"start must be a finite (x, y) pair, got {start!r}")
    n = np.array([-math.sin(angle), math.cos(angle)])
    transects = _orient(segs.segments, start_pt, turnaround)
    travel = _travel_directions(transects)
    positions = (transects[:, 0] - poly.centre) @ n
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
    waypoints = np.array(points)
    transect_length = float(np.linalg.norm(transects[:, 1] - transects[:, 0], axis=1).sum())
    path_length = float(np.linalg.norm(np.diff(waypoints, axis=0), axis=1).sum())
    n_t = len(transects)
    transect_length /= ground_scale
    path_length /= ground_scale
    duration = None if speed is None else path_length / speed + (n_t - 1) * turn_time
    stats = PlanStats(
        n_transects=n_t,
        n_turns=n_t - 1,
        transect_length=transect_length,
        path_length=path_length,
        area=poly.area / ground_scale**2 if area is None else float(area),
        speed=speed,
        turn_time=turn_time,
        duration=duration,
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


# -- coverage ---------------------------------------------------------------------------------
def swath_polygons(plan: Plan) -> NDArray[np.float64]:
    """The sensor footprint of every transect as rectangles ``(T, P, 4, 2)``, plan frame.

    ``P`` is 1 (the band ``[-reach, reach]`` across the transect over the segment's length) or,
    with a nadir gap, 2 (``[-reach, -gap/2]`` and ``[gap/2, reach]``). Every rectangle is
    counter-clockwise. Each transect's rectangle is aligned with its own lane direction
    (:meth:`Plan.transect_angle`); for the edges of a pass around a hole it is the band along
    the edge (the pass's corners are swept as the vehicle turns, see :func:`coverage`).
    """
    angles = plan.transect_angle()
    u = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    n = np.stack([-np.sin(angles), np.cos(angles)], axis=1)
    seg = plan.transects.copy()
    backwards = np.einsum("ij,ij->i", seg[:, 1] - seg[:, 0], u) < 0
    seg[backwards] = seg[backwards, ::-1]  # along +u, so that every rectangle is CCW
    if plan.nadir_gap > 0:
        sides = [(-plan.reach, -plan.nadir_gap / 2), (plan.nadir_gap / 2, plan.reach)]
    else:
        sides = [(-plan.reach, plan.reach)]
    rects = []
    for a, b in sides:
        rects.append(
            np.stack(
                [seg[:, 0] + a * n, seg[:, 1] + a * n, seg[:, 1] + b * n, seg[:, 0] + b * n],
                axis=1,
            )
        )
    return np.stack(rects, axis=1)


@dataclass(frozen=True)
class Coverage:
    """How much of an area a plan's footprints cover, computed exactly (shapely), plan units.

    Attributes:
        area: area of the region checked.
        covered_area: area of (region ∩ union of footprints).
        covered_share: ``covered_area / area`` (1.0 for a guaranteed plan, to rounding; capped
            at 1 where rounding would exceed it).
        swept_area: sum of the footprints' areas.
        overlap_share: ``(swept_area - covered_area) / area``: footprint area spent outside the
            region or on parts already covered, as a share of the region's area.
    """

    area: float
    covered_area: float
    covered_share: float
    swept_area: float
    overlap_share: float


def coverage(plan: Plan, region: Polygon | Region | ArrayLike | None = None) -> Coverage:
    """The share of ``region`` (default: the planned polygon or region) that the plan's
    footprints cover.

    Computed exactly with shapely (imported here, not at module import): the area of region ∩
    union of the footprints of :func:`swath_polygons`. The computation runs in the transects'
    frame (``t`` along, ``c`` across, a rotation, which preserves areas), where every footprint
    is an axis-aligned box and neighbouring boxes share their edge coordinate exactly (edges that
    differ by rounding only, < 1e-9 spacing, are merged): GEOS's union of many rotated rectangles
    with nearly coincident edges was seen to lose whole rectangles (GEOS 3.14).

    Plans over concave areas, cells or holes (:func:`boustro.decompose.plan_region`) are
    measured the same way per lane direction (:func:`footprint`), the unions are mapped back to
    the plan frame and joined with the footprints of the passes around holes; ``region`` may
    then be a :class:`~boustro.regions.Region` (default: the plan's).
    """
    if plan.transect_angles is not None or plan.region is not None or _has_holes(region):
        return _coverage_general(plan, region)
    import shapely

    ring = plan.polygon.vertices if region is None else as_polygon(region).vertices  # type: ignore[arg-type]
    u = np.array([math.cos(plan.angle), math.sin(plan.angle)])
    n = np.array([-math.sin(plan.angle), math.cos(plan.angle)])
    origin = plan.polygon.centre
    target = shapely.Polygon(np.stack([(ring - origin) @ u, (ring - origin) @ n], axis=1))
    t = (plan.transects - origin) @ u  # (T, 2)
    c = ((plan.transects - origin) @ n).mean(axis=1)
    if plan.nadir_gap > 0:
        sides = [(-plan.reach, -plan.nadir_gap / 2), (plan.nadir_gap / 2, plan.reach)]
    else:
        sides = [(-plan.reach, plan.reach)]
    lo = np.concatenate([c + a for a, _ in sides])
    hi = np.concatenate([c + b for _, b in sides])
    t_lo = np.tile(t.min(axis=1), len(sides))
    t_hi = np.tile(t.max(axis=1), len(sides))
    # One float per shared edge: merge edge coordinates that differ by rounding only.
    edges = np.unique(np.concatenate([lo, hi]))
    merged = edges.copy()
    for i in range(1, len(edges)):
        if edges[i] - merged[i - 1] <= 1e-9 * plan.spacing:
            merged[i] = merged[i - 1]
    lo = merged[np.searchsorted(edges, lo)]
    hi = merged[np.searchsorted(edges, hi)]
    boxes = shapely.box(t_lo, lo, t_hi, hi)
    swept = float(np.sum((t_hi - t_lo) * (hi - lo)))
    real = (t_hi > t_lo) & (hi > lo)
    union = shapely.union_all(boxes[real])
    covered = float(shapely.area(shapely.intersection(target, union)))
    area = float(target.area)
    return Coverage(
        area=area,
        covered_area=covered,
        covered_share=min(1.0, covered / area),
        swept_area=swept,
        overlap_share=(swept - covered) / area,
    )


def _has_holes(region: object) -> bool:
    return getattr(region, "n_holes", 0) > 0 or (
        region is not None and not isinstance(region, Polygon) and hasattr(region, "shell")
    )


def _aligned_boxes(
    transects: NDArray[np.float64],
    angle: float,
    origin: NDArray[np.float64],
    sides: list[tuple[float, float]],
    spacing: float,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """``(t_lo, c_lo, t_hi, c_hi)`` of every footprint box in the lanes' frame, with box edges
    that differ by rounding only merged (see :func:`coverage`)."""
    u = np.array([math.cos(angle), math.sin(angle)])
    n = np.array([-math.sin(angle), math.cos(angle)])
    t = (transects - origin) @ u
    c = ((transects - origin) @ n).mean(axis=1)
    lo = np.concatenate([c + a for a, _ in sides])
    hi = np.concatenate([c + b for _, b in sides])
    t_lo = np.tile(t.min(axis=1), len(sides))
    t_hi = np.tile(t.max(axis=1), len(sides))
    edges = np.unique(np.concatenate([lo, hi]))
    merged = edges.copy()
    for i in range(1, len(edges)):
        if edges[i] - merged[i - 1] <= 1e-9 * spacing:
            merged[i] = merged[i - 1]
    lo = merged[np.searchsorted(edges, lo)]
    hi = merged[np.searchsorted(edges, hi)]
    return t_lo, lo, t_hi, hi


def footprint(plan: Plan) -> tuple[Any, float]:
    """The union of a plan's sensor footprints as a shapely geometry (plan frame), and the sum
    of their areas. Lanes: rectangles (one union per lane direction, built in that direction's
    frame, see :func:`coverage`); passes around holes: every point within ``reach`` of the pass
    (the vehicle turns on the spot at the hole's corners with its sensor on)."""
    import shapely

    origin = plan.polygon.centre
    angles = plan.transect_angle()
    lane = np.array(plan.role()) == "lane"
    if plan.nadir_gap > 0:
        sides = [(-plan.reach, -plan.nadir_gap / 2), (plan.nadir_gap / 2, plan.reach)]
    else:
        sides = [(-plan.reach, plan.reach)]
    parts = []
    swept = 0.0
    for angle in np.unique(angles[lane]):
        pick = lane & (angles == angle)
        t_lo, lo, t_hi, hi = _aligned_boxes(
            plan.transects[pick], float(angle), origin, sides, plan.spacing
        )
        swept += float(np.sum((t_hi - t_lo) * (hi - lo)))
        real = (t_hi > t_lo) & (hi > lo)
        union = shapely.union_all(shapely.box(t_lo, lo, t_hi, hi)[real])
        u = np.array([math.cos(angle), math.sin(angle)])
        n = np.array([-math.sin(angle), math.cos(angle)])
        parts.append(
            shapely.transform(union, lambda p, u=u, n=n: origin + p[:, :1] * u + p[:, 1:] * n)
        )
    holes = ~lane
    if holes.any():
        lines = shapely.linestrings(plan.transects[holes])
        buffers = shapely.buffer(lines, plan.reach, quad_segs=64)  # round ends, not octagons
        swept += float(np.sum(shapely.area(buffers)))
        parts.append(shapely.union_all(buffers))
    return shapely.union_all(parts), swept


def _coverage_general(plan: Plan, region: Any) -> Coverage:
    """:func:`coverage` for plans with several lane directions, passes around holes, or a
    region with holes."""
    import shapely

    if region is None:
        region = plan.region if plan.region is not None else plan.polygon
    if hasattr(region, "shell"):
        target = shapely.Polygon(region.shell.vertices, [h.vertices for h in region.holes])
    else:
        target = shapely.Polygon(as_polygon(region).vertices)
    union, swept = footprint(plan)
    covered = float(shapely.area(shapely.intersection(target, union)))
    area = float(target.area)
    return Coverage(
        area=area,
        covered_area=covered,
        covered_share=min(1.0, covered / area),
        swept_area=swept,
        overlap_share=(swept - covered) / area,
    )


# -- nearly convex areas ----------------------------------------------------------------------
def convex_hull(points: ArrayLike) -> NDArray[np.float64]:
    """Counter-clockwise convex hull ``(H, 2)`` of points ``(N, 2)`` (monotone chain)."""
    pts = np.unique(np.asarray(points, dtype=np.float64).reshape(-1, 2), axis=0)  # sorted

    def half(seq: NDArray[np.float64]) -> list[NDArray[np.float64]]:
        out: list[NDArray[np.float64]] = []
        for p in seq:
            while len(out) >= 2:
                a, b = out[-2], out[-1]
                if (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]) > 0:
                    break
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(pts[::-1])
    return np.array(lower[:-1] + upper[:-1])


def hull_depth(polygon: Polygon | ArrayLike) -> float:
    """How far the convex hull reaches beyond the polygon: the depth of its deepest pocket.

    For each hull edge that is not an edge of the polygon (the lid of a pocket), the largest
    distance from the lid's line of the polygon vertices it skips. Every point of the hull lies
    within this distance of the polygon, so transects planned on the hull leave the polygon by
    at most this much. 0 for a convex polygon.
    """
    poly = as_polygon(polygon)
    if poly.is_convex:
        return 0.0
    v = poly.vertices
    hull = convex_hull(v)
    where = {tuple(p): i for i, p in enumerate(v)}
    idx = [where[tuple(p)] for p in hull]
    depth = 0.0
    n = len(v)
    for a, b in zip(idx, idx[1:] + idx[:1], strict=True):
        skipped = [(a + k) % n for k in range(1, (b - a) % n)]
        if not skipped:
            continue
        p, q = v[a], v[b]
        lid = q - p
        dist = np.abs(lid[0] * (v[skipped, 1] - p[1]) - lid[1] * (v[skipped, 0] - p[0]))
        depth = max(depth, float(dist.max() / np.linalg.norm(lid)))
    return depth


def nearly_convex(polygon: Polygon | ArrayLike, tolerance: float) -> tuple[Polygon, float]:
    """The polygon itself if convex, else its convex hull if no pocket is deeper than tolerance.

    Real parcels are often convex but for digitising noise (the shipped field is 0.999 of its
    hull, with pockets 0.3 m deep). Planning the hull covers the polygon (it contains it), and
    the transects leave the polygon by at most the returned depth.

    Returns:
        ``(polygon to plan, depth)``.

    Raises:
        NonConvexPolygonError: a pocket is deeper than ``tolerance`` (units of the polygon).
    """
    poly = as_polygon(polygon)
    tolerance = _check_nonnegative("hull tolerance", tolerance)
    if poly.is_convex:
        return poly, 0.0
    depth = hull_depth(poly)
    if depth <= tolerance:
        return Polygon(convex_hull(poly.vertices)), depth
    try:
        poly.require_convex("a boustrophedon plan")
    except NonConvexPolygonError as exc:
        raise NonConvexPolygonError(
            f"{exc}; its convex hull reaches {depth:.3g} beyond it, more than the hull "
            f"tolerance {tolerance:g} (plan it as a concave area: boustro.decompose.plan_region)"
        ) from None
    raise AssertionError("unreachable")  # pragma: no cover
