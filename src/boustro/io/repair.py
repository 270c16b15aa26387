"""Validity of an area as read, and its repair (``boustro plan --repair``), through GEOS.

:func:`area_problem` says why GEOS finds an area invalid (e.g. "Ring Self-intersection at
(2, 4)"); :func:`repair_area` makes it valid with ``shapely.make_valid`` and says what changed.
A repair that yields several polygons is refused with their areas (planning the parts as
separate fields is not done here), unless the parts besides the largest are negligible
(:data:`NEGLIGIBLE` of the area: the loops of a traced boundary), which are then dropped, as are
negligible holes the repair made; the note says so. Both work in the file's coordinates
(:func:`detach_holes` in the plan frame too), before projection. shapely is imported on use.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..errors import InvalidParameterError, InvalidPolygonError
from ..geometry import Polygon, Region
from ..geometry.region import TOUCH_TOLERANCE
from ..geometry.validity import geos_reason
from .area import LONLAT, Area, crs_name
from .crs import check_lonlat, plan_frame

__all__ = ["area_problem", "check_area", "detach_holes", "repair_area"]

#: ``--repair``: the parts besides the largest, and the holes ``make_valid`` made, are dropped
#: (filled) when together they are at most this share of the area: the loops of a GPS-traced
#: boundary (2026-11-28: 257 loops of 0.1 m^2, 0.06% of a 6 ha field); a bow-tie's halves or two
#: fields in one ring are still refused.
NEGLIGIBLE = 1e-3

#: How far :func:`detach_holes` cuts a hole back from the shell it touches, a fraction of the
#: shell's largest extent (1 cm on a 100 m field).
DETACH_GAP = 1e-4

#: How many touching holes (and pairs of holes) :func:`detach_holes`' note names; the rest counted.
NAMED = 5


def _shapely_area(area: Area):
    import shapely

    return shapely.Polygon(area.ring, list(area.holes))


def _vertices(geom) -> int:
    """Vertices of a polygon's rings, without the closing vertex of each ring."""
    return sum(len(r.coords) - 1 for r in [geom.exterior, *geom.interiors])


def area_problem(area: Area) -> str | None:
    """GEOS's reason why ``area`` (shell and holes, file coordinates) is invalid, or None.

    Example:
        >>> bow_tie = Area(np.array([[0, 0], [1, 0], [0, 1], [1, 1]]), None, "", "")
        >>> area_problem(bow_tie)
        'Self-intersection at (0.5, 0.5)'
    """
    import shapely

    with np.errstate(all="ignore"):  # coordinates near the float limit: the range check says
        reason = shapely.is_valid_reason(_shapely_area(area))
    return None if reason == "Valid Geometry" else geos_reason(reason)


def check_area(area: Area) -> None:
    """Refuse an invalid ``area`` in the file's coordinates, with boustro's reason (the rules of
    :class:`~boustro.geometry.Region`), GEOS's where it says more, and a hint to repair it when
    GEOS finds it invalid (so that ``make_valid`` would change it).

    Raises:
        InvalidPolygonError: one line, naming the file (``area.source``).
    """
    if area.crs is not None and crs_name(area.crs) == LONLAT:
        check_lonlat(area.ring, area.source)  # a pole or the antimeridian first: not a repair
    try:
        Region(area.ring, list(area.holes))
    except InvalidPolygonError as exc:
        message = f"{area.source}: {exc}"
        problem = area_problem(area)
        if problem is not None:
            if problem not in message:
                message += f" (GEOS: {problem})"
            if _repairable(area):
                message += "; try --repair (shapely.make_valid; it says what it changes)"
        raise InvalidPolygonError(message) from None


def _repairable(area: Area) -> bool:
    """Whether ``make_valid`` leaves some area (not for NaN, inf, or collinear vertices)."""
    import shapely

    return _finite(area) and shapely.make_valid(_shapely_area(area)).area > 0


def _finite(area: Area) -> bool:
    return all(np.all(np.isfinite(r)) for r in [area.ring, *area.holes])


def detach_holes(area: Area) -> tuple[Area, str | None]:
    """``area`` with every hole that touches the shell or an earlier hole (GEOS allows one point
    in common; the planner needs disjoint holes strictly inside, :class:`~boustro.geometry.Region`:
    farther than :data:`~boustro.geometry.region.TOUCH_TOLERANCE` times the shell's diameter, the
    rule applied here too, in the file's coordinates and in the plan frame as the Region is
    checked in both, so that a hole the Region accepts is left as it is) cut back from what it
    touches by :data:`DETACH_GAP` of the shell's extent, and a line saying so (None when no hole
    touches anything, or the area is invalid for GEOS: :func:`check_area` says why).

    The cut only shrinks holes, so the area planned contains the file's area: lanes that cover
    it cover the file's area too. A hole is cut back from the rings of the file (the shell, an
    earlier hole as read), and every hole only shrinks, so two cut holes are at least the gap
    apart. The path may run through the cut-off part of a hole: at most the gap deep, but as
    long as the gap divided by the sine of the angle between the two edges (2026-11-28, 100 m
    square, ``--keep-inside``: 4 mm of path for a hole edge at 63 degrees, 4 m at 0.14 degrees).
    The returned area keeps the holes as read (``Area.cut_holes``), against which the plan's
    ``outside_length_m`` is measured, so that length is counted.
    """
    import shapely

    if not area.holes or area_problem(area) is not None:
        return area, None
    try:  # the Region's own rules: a hole touching the shell, two holes touching
        frames = _frames(area)
        tols = [TOUCH_TOLERANCE * Polygon(shell).diameter for shell, _ in frames]
    except (InvalidPolygonError, InvalidParameterError):  # check_area or the plan says why
        return area, None
    rings = [shapely.linearrings(area.ring)] + [shapely.linearrings(h) for h in area.holes]
    gap = DETACH_GAP * float(np.max(np.ptp(area.ring, axis=0)))
    holes: list[np.ndarray] = []
    on_shell: list[str] = []  # "hole i at [x, y]"
    on_holes: list[str] = []  # "hole i touches hole j at [x, y]"
    for i, h in enumerate(area.holes):
        # what hole i touches in any frame: the shell (0) or an earlier hole (j + 1)
        near = [
            k
            for k in range(i + 1)
            if any(_within(f, k, i, tol) for f, tol in zip(frames, tols, strict=True))
        ]
        if not near:
            holes.append(h)
            continue
        for k in near:
            at = shapely.get_coordinates(shapely.shortest_line(rings[i + 1], rings[k]))[0]
            if k == 0:
                on_shell.append(f"hole {i + 1} at {at.tolist()}")
            else:
                on_holes.append(f"hole {i + 1} touches hole {k} at {at.tolist()}")
        cut = shapely.Polygon(h).difference(shapely.union_all([rings[k] for k in near]).buffer(gap))
        holes += [
            np.asarray(p.exterior.coords, dtype=np.float64)[:-1]
            for p in shapely.get_parts(cut)
            if p.geom_type == "Polygon" and not p.is_empty
        ]
    if not on_shell and not on_holes:
        return area, None
    before = _shapely_area(area).area
    after = replace(area, holes=tuple(holes), cut_holes=area.holes)
    said = on_holes[:NAMED] + (
        [f"{len(on_holes) - NAMED} more pairs"] if len(on_holes) > NAMED else []
    )
    if on_shell:
        many = len(on_shell) > 1
        named = on_shell[:NAMED] + (
            [f"{len(on_shell) - NAMED} more holes"] if len(on_shell) > NAMED else []
        )
        which = ", ".join(named[:-1]) + " and " + named[-1] if many else named[0]
        said.insert(0, f"{which} {'touch' if many else 'touches'} the shell")
    cuts = len(set(t.split()[1] for t in on_shell + on_holes))
    note = (
        f"{area.source or 'the area'}: {'; '.join(said)}; planned with "
        f"{'each' if cuts > 1 else 'the'} hole cut back {gap:.3g} (file units) from "
        f"{'what it touches' if on_holes else 'the shell'}, area {before:.6g} -> "
        f"{_shapely_area(after).area:.6g} (coverage of the file's area is kept: it lies "
        "inside the area planned; the path's length outside is measured on the file's holes)"
    )
    return after, note


def _frames(area: Area) -> list[tuple[np.ndarray, tuple[np.ndarray, ...]]]:
    """The shell and holes in the file's coordinates and, projected, in the plan frame: the
    Region checks both (:mod:`boustro.mission.project`), and a lon/lat edge that is straight in
    the file bends in the UTM frame (a hole 2 mm inside a 300 m edge at 52 N crosses it)."""
    files = (area.ring, area.holes)
    if area.crs is None:
        return [files]
    proj, ring = plan_frame(area.ring, area.crs, area.source)
    return [files, (ring, tuple(proj.to_plan(h) for h in area.holes))]


def _within(frame: tuple[np.ndarray, tuple[np.ndarray, ...]], k: int, i: int, tol: float) -> bool:
    """Whether hole ``i`` of ``frame`` comes within ``tol`` of its shell (``k = 0``) or of its
    hole ``k - 1``."""
    import shapely

    shell, holes = frame
    other = shell if k == 0 else holes[k - 1]
    return bool(shapely.dwithin(shapely.linearrings(other), shapely.linearrings(holes[i]), tol))


def repair_area(area: Area) -> tuple[Area, str | None]:
    """``area`` made valid by ``shapely.make_valid``, and a line saying what changed (None
    when the area was valid and is returned unchanged).

    Only the polygonal result is kept (lines and points that collapsed out of the area are
    dropped; parts and holes the repair made, together at most :data:`NEGLIGIBLE` of the area,
    too). Raises :class:`InvalidPolygonError` when the repair yields no polygon or several
    that are not negligible (naming their areas).
    """
    import shapely

    problem = area_problem(area)
    if problem is None:
        return area, None
    if not _finite(area):  # GEOS's make_valid raises on NaN or inf
        raise InvalidPolygonError(
            f"{area.source or 'the area'}: {problem}: a coordinate is not a finite number "
            "(NaN or inf), which --repair cannot mend; fix the file"
        )
    before = _shapely_area(area)
    fixed = shapely.make_valid(before)
    parts = [g for g in shapely.get_parts(fixed) if g.geom_type in ("Polygon", "MultiPolygon")]
    polygons = [p for g in parts for p in shapely.get_parts(g) if not p.is_empty]
    where = area.source or "the area"
    if not polygons:
        raise InvalidPolygonError(f"{where}: {problem}; --repair leaves no polygon (zero area)")
    polygons.sort(key=lambda p: -p.area)
    total = sum(p.area for p in polygons)
    if total - polygons[0].area > NEGLIGIBLE * total:
        sizes = ", ".join(f"{p.area:.6g}" for p in polygons[:5])
        raise InvalidPolygonError(
            f"{where}: {problem}; --repair splits the area into {len(polygons)} polygons of "
            f"areas {sizes}{', ...' if len(polygons) > 5 else ''} (file units squared): plan "
            "each part as its own area"
        )
    poly, crumbs = polygons[0], polygons[1:]
    poly, filled = _fill_new_holes(poly, area)
    ring = np.asarray(poly.exterior.coords, dtype=np.float64)[:-1]
    holes = tuple(np.asarray(h.coords, dtype=np.float64)[:-1] for h in poly.interiors)
    dropped = (
        f"; dropped {len(crumbs)} {'part' if len(crumbs) == 1 else 'parts'} of "
        f"{sum(p.area for p in crumbs):.3g} in all (the loops of a traced boundary)"
        if crumbs
        else ""
    )
    dropped += (
        f"; filled {len(filled)} {'hole' if len(filled) == 1 else 'holes'} the repair made, "
        f"{sum(filled):.3g} in all"
        if filled
        else ""
    )
    note = (
        f"--repair: {where} was invalid ({problem}); shapely.make_valid changed it: vertices "
        f"{_vertices(before)} -> {_vertices(poly)}, holes {len(area.holes)} -> {len(holes)}, "
        f"area {before.area:.6g} -> {poly.area:.6g} (file units squared){dropped}"
    )
    return replace(area, ring=ring, holes=holes), note


def _fill_new_holes(poly, area: Area):
    """``poly`` without the holes ``make_valid`` made (none of ``area``'s holes meets them: the
    loops of a traced boundary that winds back on itself), when together they are at most
    :data:`NEGLIGIBLE` of its area; and the areas of those filled. Filling only adds area to
    plan, so the repaired area stays covered; the file's holes (obstacles) are kept."""
    import shapely

    known = shapely.union_all([shapely.Polygon(h) for h in area.holes])
    new = [k for k, h in enumerate(poly.interiors) if not shapely.Polygon(h).intersects(known)]
    sizes = [shapely.Polygon(poly.interiors[k]).area for k in new]
    if not new or sum(sizes) > NEGLIGIBLE * poly.area:
        return poly, []
    kept = [h for k, h in enumerate(poly.interiors) if k not in set(new)]
    return shapely.Polygon(poly.exterior, kept), sizes
