"""Coverage of a plan: sensor footprints and the covered share, computed exactly with shapely."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..geometry import Polygon
from ..scoring import as_polygon

if TYPE_CHECKING:
    from ..geometry.region import Region

from .types import Plan

__all__ = [
    "Coverage",
    "coverage",
    "footprint",
    "swath_polygons",
]


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
    rects = []
    for a, b in _sides(plan):
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
        swept_area: sum of the footprints' areas: the lanes' rectangles, and along each pass
            ``2 reach`` times its length plus one round cap (a pass counted once along its
            length, not once per edge).
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

    Plans over concave areas, cells or holes (:func:`boustro.plan.plan_region`) are
    measured the same way per lane direction (:func:`footprint`), the unions are mapped back to
    the plan frame and joined with the footprints of the passes around holes; ``region`` may
    then be a :class:`~boustro.regions.Region` (default: the plan's).

    Example:
        >>> from boustro.plan import build_plan
        >>> plan = build_plan([(0, 0), (10, 0), (10, 10), (0, 10)], 2.0, 0.0, 0.0)
        >>> c = coverage(plan)
        >>> round(c.covered_share, 4), round(c.overlap_share, 4)
        (1.0, 0.0)
    """
    if plan.transect_angles is not None or plan.region is not None or _has_holes(region):
        return _coverage_general(plan, region)
    import shapely

    ring = plan.polygon.vertices if region is None else as_polygon(region).vertices  # type: ignore[arg-type]
    u, n = _axes(plan.angle)
    origin = plan.polygon.centre
    target = shapely.Polygon(np.stack([(ring - origin) @ u, (ring - origin) @ n], axis=1))
    swept, union = _lanes_union(plan.transects, plan.angle, origin, plan, _within(ring, plan))
    return _measure(target, union, swept)


def _within(ring: ArrayLike, plan: Plan) -> float:
    """How far across a footprint can matter to the coverage of ``ring``: the diagonal ``D`` of
    the box around the ring's vertices and the plan's transects, so every point of the area lies
    within ``D`` of every point of every transect.

    Exactness: a lane's box ``[c + a, c + b]`` across (``c`` its offset) holds no point of the
    area beyond ``c +- D``, so cutting ``a`` and ``b`` to ``[-D, D]`` leaves its part of the area
    unchanged; a pass's buffer of radius ``reach >= D`` holds the whole area, as does its buffer
    of radius ``D``. Union and intersection with the area commute, so the covered area is the
    same, while the coordinates stay of the area's size: a spacing of ``1e20`` m measured with
    its full width lost the area to rounding ("covered 0.0000%"). The swept area (and so the
    overlap) is still that of the full footprints.
    """
    points = np.concatenate([np.asarray(ring, dtype=np.float64), plan.transects.reshape(-1, 2)])
    return float(np.hypot(*(points.max(axis=0) - points.min(axis=0))))


def _lanes_union(
    transects: NDArray[np.float64],
    angle: float,
    origin: NDArray[np.float64],
    plan: Plan,
    within: float,
) -> tuple[float, Any]:
    """The swept area of the lanes' footprints at ``angle`` and their union in the lanes' frame,
    the footprints cut to ``within`` across their lane (:func:`_within`)."""
    import shapely

    sides = _sides(plan)
    t_lo, lo, t_hi, hi = _aligned_boxes(transects, angle, origin, sides, plan.spacing)
    swept = float(np.sum((t_hi - t_lo) * (hi - lo)))
    cut = [(max(a, -within), min(b, within)) for a, b in sides]
    if cut != sides:  # edges that differ by rounding at the cut width's scale, not the spacing's
        scale = min(plan.spacing, within)
        t_lo, lo, t_hi, hi = _aligned_boxes(transects, angle, origin, cut, scale)
    real = (t_hi > t_lo) & (hi > lo)
    return swept, shapely.union_all(shapely.box(t_lo, lo, t_hi, hi)[real])


def _axes(angle: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Unit vectors along (``u``) and across (``n``, to the left) lanes at ``angle``."""
    u = np.array([math.cos(angle), math.sin(angle)])
    n = np.array([-math.sin(angle), math.cos(angle)])
    return u, n


def _sides(plan: Plan) -> list[tuple[float, float]]:
    """The footprint across a transect: ``[-reach, reach]``, or two strips beside a nadir gap."""
    if plan.nadir_gap > 0:
        return [(-plan.reach, -plan.nadir_gap / 2), (plan.nadir_gap / 2, plan.reach)]
    return [(-plan.reach, plan.reach)]


def _measure(target: Any, union: Any, swept: float) -> Coverage:
    """The :class:`Coverage` of ``target`` by the footprints ``union`` (``swept``: their areas)."""
    import shapely

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
    u, n = _axes(angle)
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


def footprint(plan: Plan, within: float = math.inf) -> tuple[Any, float]:
    """The union of a plan's sensor footprints as a shapely geometry (plan frame), and the sum
    of their areas. Lanes: rectangles (one union per lane direction, built in that direction's
    frame, see :func:`coverage`); passes around holes and boundary passes: every point within
    ``reach`` of the pass (the vehicle turns on the spot at the corners with its sensor on),
    whose swept area is :func:`_passes_swept`. ``within``: the union is of the footprints cut
    to ``within`` across their transect (exact for an area within ``within`` of every transect
    point, see :func:`_within`); the sum is of the whole footprints."""
    import shapely

    origin = plan.polygon.centre
    angles = plan.transect_angle()
    lane = np.array(plan.role()) == "lane"
    parts = []
    swept = 0.0
    for angle in np.unique(angles[lane]):
        pick = lane & (angles == angle)
        area, union = _lanes_union(plan.transects[pick], float(angle), origin, plan, within)
        swept += area
        u, n = _axes(float(angle))
        parts.append(
            shapely.transform(union, lambda p, u=u, n=n: origin + p[:, :1] * u + p[:, 1:] * n)
        )
    holes = ~lane
    if holes.any():
        lines = shapely.linestrings(plan.transects[holes])
        # round ends, not octagons
        buffers = shapely.buffer(lines, min(plan.reach, within), quad_segs=64)
        swept += _passes_swept(plan.transects[holes], plan.reach, plan.spacing)
        parts.append(shapely.union_all(buffers))
    return shapely.union_all(parts), swept


def _passes_swept(edges: NDArray[np.float64], reach: float, spacing: float) -> float:
    """The area the passes' ``(E, 2, 2)`` edges sweep: ``2 reach`` times their length, plus a
    round cap of ``pi reach^2`` for each pass (an edge that does not start where the previous one
    ends, within ``1e-9 * spacing``, starts a new pass). A pass's footprint is counted once along
    its length, not once per edge: buffering every edge of a traced ring alone counts the round
    ends that overlap at every joint (a 2000-vertex field's overlap share read 1.56 where its
    lanes and passes overlap by 0.08). For a closed convex ring, ``2 reach L`` is exactly its
    band's area (Steiner's formula)."""
    length = float(np.linalg.norm(edges[:, 1] - edges[:, 0], axis=1).sum())
    breaks = np.abs(edges[1:, 0] - edges[:-1, 1]).max(axis=1) > 1e-9 * spacing
    return 2.0 * reach * length + math.pi * reach**2 * (1 + int(breaks.sum()))


def _coverage_general(plan: Plan, region: Any) -> Coverage:
    """:func:`coverage` for plans with several lane directions, passes around holes, or a
    region with holes."""
    import shapely

    if region is None:
        region = plan.region if plan.region is not None else plan.polygon
    if hasattr(region, "shell"):
        ring = region.shell.vertices
        target = shapely.Polygon(ring, [h.vertices for h in region.holes])
    else:
        ring = as_polygon(region).vertices
        target = shapely.Polygon(ring)
    union, swept = footprint(plan, _within(ring, plan))
    return _measure(target, union, swept)
