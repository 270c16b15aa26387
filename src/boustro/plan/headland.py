"""Headlands: passes around the field's boundary and its holes, lanes in the inner field.

``passes`` headland passes at ``(k - 1/2) * spacing`` inside the boundary (``k = 1 .. passes``;
shapely's inward buffers of the field, so each pass also goes around every hole) cover the band
of width ``passes * spacing`` along the boundary, and the lanes cover the inner field, the
field buffered inwards by that width (:func:`inner_field`, a little larger so that the polygonal
arcs of the buffers leave no sliver between them). Where the pass's swath misses a piece of its
band (at a convex corner of the band's outer edge, for the outermost pass a corner of the
field), the pass drives towards the piece's farthest point until that is within reach, and
back (a *spike*, driven in reverse or turned on the spot: the vehicle's turn radius applies to
the moves between passes, not to the passes' corners; :func:`_spikes`), so that the footprints
cover the whole field; the path never leaves it. Where the
field is too narrow for pass ``k + 1`` but wider than ``2k`` spacings (a corridor between a
hole and the boundary), open passes along the contour at depth ``k * spacing`` cover the strip
that neither pass ``k`` nor the lanes reach, and shallower contours a corridor narrower than a
spacing, where no pass goes (:func:`_gap_passes`).
:func:`add_headland` appends the passes to a plan of the inner field, gap passes (the nearest
next) and then the rings innermost first, each
begun at its point nearest the vehicle, joined by moves inside the field. The passes'
waypoints have the kind ``headland`` (first ``start``, last ``end``) and their edges are
transects with the role ``"headland"``, measured like passes around holes.
"""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidParameterError, InvalidPolygonError
from ..geometry.region import Region
from .outside import with_outside_length
from .routing import Router
from .types import Plan

__all__ = ["MAX_HEADLAND", "add_headland", "check_headland", "headland_rings", "inner_field"]

#: Most headland passes (a guard against a typo: 1000 passes at 10 m is a 10 km band).
MAX_HEADLAND = 100

#: Depths (shares of a spacing) of the contours that cover a corridor narrower than a spacing
#: (a hole less than a spacing from the boundary), where no pass goes: one of them lies in it
#: whenever it is wider than twice the depth, and every point of it is within reach of that.
_NARROW = (0.4, 0.25, 0.1, 0.02)

#: The shallowest contour tried (share of a spacing): a corridor narrower than twice that (a
#: hole touching the boundary to within a hundredth of a millimetre at 10 m) gets a pass along
#: the hole's boundary (:func:`_touching`; it used to stay uncovered).
_SHALLOWEST = 1e-6

#: Segments of the pieces the rings are buffered in (a ring weaving around 40 holes took GEOS
#: 5.6 s to buffer whole, its 4-segment pieces 0.6 s with their union).
_CHUNK = 4

#: Segments per quarter circle of the buffers' arcs (at reflex corners of the field).
_QUAD_SEGS = 16

#: The inner field reaches this share of a spacing into the innermost headland band: the
#: chords of the buffers' arcs never leave a sliver uncovered between lanes and passes.
_OVERLAP = 0.02

#: Segments per quarter circle of the swaths' arcs, as :mod:`boustro.plan.coverage` measures them
#: (their chords lie up to ``1 - cos(pi / 256)``, 7.5e-5 of a reach, inside the circle).
_SWATH_SEGS = 64

#: A point of a missed piece within ``(1 - _CHORD) * reach`` of what is driven lies inside the
#: swath's chords (:data:`_SWATH_SEGS`); one farther gets a spike.
_CHORD = 1e-4

#: A spike stops this share of a reach short of the reach from its target (the target inside
#: its swath with a margin over the buffers' chords, 7.5e-5 of a reach at 64 segments per
#: quarter circle; the target is covered where the vehicle turns, as around a pass's corners).
_SHORT = 1e-2

#: Rounds of spikes per pass (each covers its targets; the rest of a piece is the next round's).
_ROUNDS = 6


def check_headland(passes: object) -> int:
    """``passes`` as an int in ``[0, MAX_HEADLAND]``, or :class:`InvalidParameterError`."""
    if isinstance(passes, bool):
        raise InvalidParameterError(f"headland must be a whole number of passes, got {passes!r}")
    if not isinstance(passes, (int, np.integer)):
        try:
            value = float(passes)  # type: ignore[arg-type]
        except (TypeError, ValueError):
            raise InvalidParameterError(
                f"headland must be a whole number of passes, got {passes!r}"
            ) from None
        if not value.is_integer():
            raise InvalidParameterError(
                f"headland must be a whole number of passes, got {passes!r}"
            )
        passes = int(value)
    n = int(passes)
    if not 0 <= n <= MAX_HEADLAND:
        raise InvalidParameterError(f"headland must be between 0 and {MAX_HEADLAND}, got {n}")
    return n


def _shapely_region(field: Region):
    import shapely

    return shapely.Polygon(field.shell.vertices, [h.vertices for h in field.holes])


def _as_region(geom, what: str) -> Region:
    """One shapely polygon (the largest part is refused if there are several) as a Region."""
    import shapely

    geom = shapely.make_valid(geom)
    parts = [g for g in getattr(geom, "geoms", [geom]) if g.geom_type == "Polygon" and g.area > 0]
    if not parts:
        raise InvalidParameterError(f"the headland leaves no {what}: use fewer passes")
    if len(parts) > 1:
        areas = ", ".join(f"{p.area:.4g}" for p in sorted(parts, key=lambda p: -p.area))
        raise InvalidParameterError(
            f"the headland splits the {what} into {len(parts)} parts (areas {areas}): boustro "
            "plans one inner field; use fewer passes"
        )
    poly = parts[0]
    try:
        return Region(
            np.asarray(poly.exterior.coords)[:-1],
            [np.asarray(r.coords)[:-1] for r in poly.interiors],
        )
    except InvalidPolygonError as exc:
        raise InvalidParameterError(f"the headland's {what} is not a valid area ({exc})") from None


def inner_field(field: Region, spacing: float, passes: int) -> Region:
    """The field buffered inwards by ``passes * spacing`` (less :data:`_OVERLAP` spacing): where
    the lanes go. Refused if nothing is left or it falls apart."""
    return _as_region(_offset(field, (passes - _OVERLAP) * spacing), "inner field")


def headland_rings(field: Region, spacing: float, passes: int) -> list[list[NDArray[np.float64]]]:
    """The passes' rings: for ``k = 1 .. passes``, the boundary of the field buffered inwards by
    ``(k - 1/2) * spacing``: its shell, then the rings around holes (each closed: last point =
    first point)."""
    out = []
    for k in range(1, passes + 1):
        geom = _offset(field, (k - 0.5) * spacing)
        rings = []
        for poly in getattr(geom, "geoms", [geom]):
            if poly.geom_type != "Polygon" or poly.is_empty:
                continue
            rings.append(np.asarray(poly.exterior.coords))
            rings += [np.asarray(r.coords) for r in poly.interiors]
        if not rings:
            raise InvalidParameterError(f"the field is too narrow for {passes} headland passes")
        out.append(rings)
    return out


def _offset(field: Region, depth: float):
    """The field buffered inwards by ``depth`` (shapely; the field itself at depth 0)."""
    import shapely

    region = _shapely_region(field)
    return region if depth == 0 else shapely.buffer(region, -depth, quad_segs=_QUAD_SEGS)


def _segment_distance(
    points: NDArray[np.float64], a: NDArray[np.float64], b: NDArray[np.float64]
) -> NDArray[np.float64]:
    """The distance of each of ``points`` (``(n, 2)``) to its nearest segment ``a[j] -> b[j]``."""
    d = b - a
    dd = np.maximum(np.einsum("ij,ij->i", d, d), 1e-300)
    rel = points[:, None, :] - a[None, :, :]
    t = np.clip(np.einsum("nij,ij->ni", rel, d) / dd, 0.0, 1.0)
    return np.linalg.norm(rel - t[:, :, None] * d[None, :, :], axis=2).min(axis=1)


def _spikes(
    outer, inner, rings: list[NDArray[np.float64]], reach: float, spacing: float, router: Router
) -> list[NDArray[np.float64]]:
    """The rings of a pass with the spikes that cover what their swath misses of its band.

    ``outer``: the band's outer side (the field, or the field buffered inwards by ``(k - 1)``
    spacings), ``inner``: the area inside the pass (``rings`` are its boundary, half a spacing
    inside ``outer``). Every point of the band deeper than the pass is within reach of it (its
    nearest point on the pass lies on the way to its nearest boundary point), so the swath
    misses only pieces between the pass and the band's outer edge, at its convex corners:
    ``outer`` less ``inner`` buffered by ``reach``. Each round takes every such piece's vertex
    farthest from what is driven (the rings and the spikes so far), deepest first (skipping one
    a spike of this round already reaches), and drives a spike from its nearest point on the
    rings towards it, stopping :data:`_SHORT` of a reach before it (the vertex inside the
    spike's swath with a margin, the swath's corner at it), and back; the rest of the pieces
    goes to the next round (at most :data:`_ROUNDS`), and what is left after that to
    :func:`_gap_passes`, the guarantee. On a noisy traced boundary the pieces are the noise's
    convex corners, a few decimetres deep, and so are the spikes (spikes all the way into every
    corner of the band made a 33 km headland around a 2.2 km boundary, 3000 vertices)."""
    import shapely

    tiny = 1e-12 * spacing**2
    lines = [shapely.LineString(r) for r in rings]
    driven: list = list(lines)
    inserts: list[list[tuple[float, NDArray[np.float64], NDArray[np.float64]]]] = [
        [] for _ in rings
    ]
    cover = shapely.buffer(inner, reach, quad_segs=_SWATH_SEGS)
    left = _pieces(shapely.difference(outer, cover), tiny)
    for _ in range(_ROUNDS):
        everything = shapely.multilinestrings(driven)
        targets = []
        for piece in left:
            xy = shapely.get_coordinates(piece.exterior)
            depth = shapely.distance(everything, shapely.points(xy))
            j = int(np.argmax(depth))
            if depth[j] > reach * (1 - _CHORD):  # beyond reach, or outside the swath's chords
                targets.append((float(depth[j]), xy[j]))
        a: list[NDArray[np.float64]] = []
        b: list[NDArray[np.float64]] = []
        for _, f in sorted(targets, key=lambda x: -x[0]):
            if a and _segment_distance(f[None], np.asarray(a), np.asarray(b))[0] < reach:
                continue  # a spike of this round reaches it
            pt = shapely.Point(f)
            i = int(np.argmin([line.distance(pt) for line in lines]))
            along = lines[i].project(pt)
            p = np.asarray(lines[i].interpolate(along).coords[0])
            q = f + (p - f) * (reach * (1 - _SHORT) / np.linalg.norm(p - f))
            if router.inside(p, q):
                inserts[i].append((along, p, q))
                a.append(p)
                b.append(q)
        if not a:
            break
        spikes = shapely.linestrings(np.stack([np.asarray(a), np.asarray(b)], axis=1))
        driven += list(spikes)
        swaths = shapely.union_all(shapely.buffer(spikes, reach, quad_segs=_SWATH_SEGS))
        left = _pieces(shapely.difference(shapely.union_all(left), swaths), tiny)
    out = []
    for ring, line, ins in zip(rings, lines, inserts, strict=True):
        if not ins:
            out.append(ring)
            continue
        cum = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(ring, axis=0), axis=1))])
        pts: list[NDArray[np.float64]] = []
        ins.sort(key=lambda x: x[0])
        j = 0
        for a_ in range(len(ring)):
            pts.append(ring[a_])
            nxt = cum[a_ + 1] if a_ + 2 < len(ring) else math.inf  # the last edge: to its end
            while j < len(ins) and ins[j][0] < nxt - 1e-12 and a_ + 1 < len(ring):
                _, p, q = ins[j]
                pts += [p, q, p]
                j += 1
        out.append(_dedupe(np.asarray(pts), 1e-9 * line.length))
    return out


def _gap_passes(
    field: Region, spacing: float, reach: float, passes: int, rings: list[list[NDArray[np.float64]]]
) -> list[NDArray[np.float64]]:
    """Open passes over what the rings (with their spikes) and the inner field leave uncovered.

    Pass ``k + 1`` exists only where the field is deeper than ``(k + 1/2) * spacing``: in a
    corridor (between a hole and the boundary, or a narrow part of the field) between ``2k`` and
    ``2k + 1`` spacings wide, neither it nor the inner field reaches the strip of depth
    ``k * spacing .. (k + 1/2) * spacing`` between the two sides' pass ``k`` (a 25 m corridor at
    10 m with 2 passes: a 5 m strip). Every point of such a strip lies within
    ``depth - k * spacing < reach`` of the contour at depth ``k * spacing`` (walk towards its
    nearest boundary point), so pieces of that contour near the strip cover it: chosen greedily
    (most uncovered area first) until nothing is left (components under ``1e-12 spacing^2``,
    the buffers' rounding, ignored: at ``1e-6 spacing^2`` a whole corridor of 100 um by 0.9 m
    between two holes at 10 m was dropped, a review). A corridor narrower than a spacing (a hole
    closer to the boundary) gets no pass at all: every point of it is within reach of a contour
    at a depth under half its width (:data:`_NARROW`, then a fifth of the last depth at a time,
    down to :data:`_SHALLOWEST`; then the field's boundary itself, which lies in the field), and
    one narrower than twice that a pass along the hole (:func:`_touching`)."""
    region = _shapely_region(field)
    tiny = 1e-12 * spacing**2
    out = _touching(field, 2 * _SHALLOWEST * spacing)
    left = _uncovered(region, spacing, reach, passes, [*rings, out], tiny)
    # the corridors between 2k and 2k + 1 spacings wide, and those narrower than a spacing;
    # then ever shallower contours while something is left (a corridor narrower than 2 depths),
    # and last the boundary (depth 0: a corridor of a few micrometres)
    depths = [k * spacing for k in range(1, passes)] + [f * spacing for f in _NARROW]
    while depths and left:
        left = _greedy(region, left, depths, reach, tiny, out)
        last = depths[-1]
        depths = [last / 5] if last > _SHALLOWEST * spacing else [0.0] if last > 0 else []
    return out


def _touching(field: Region, width: float) -> list[NDArray[np.float64]]:
    """Passes along a hole's boundary where it lies closer than ``width`` (twice the shallowest
    contour's depth) to the shell or another hole: every point of such a corridor is within its
    width of them: one pass along the hole covers such a corridor directly, where the contours
    would need depths down to 0 (1 um by 70 m: 7e-5 m2 missed when pieces under
    ``1e-6 spacing^2`` were still taken for rounding)."""
    import shapely

    rings = [shapely.LinearRing(r) for r in field.rings]
    out: list[NDArray[np.float64]] = []
    for i in range(1, len(rings)):
        others = rings[:i]  # the shell and the holes before: each close pair gets one pass
        if min(shapely.distance(rings[i], others)) >= width:
            continue
        near = shapely.buffer(shapely.union_all(others), width)
        piece = shapely.line_merge(shapely.intersection(rings[i], near))
        out += [
            np.asarray(g.coords)
            for g in getattr(piece, "geoms", [piece])
            if g.geom_type == "LineString" and g.length > 0
        ]
    return out


def _uncovered(region, spacing: float, reach: float, passes: int, rings, tiny: float) -> list:
    """The parts (over ``tiny``) of the field that neither the rings' swaths nor the inner field
    cover, as a list of polygons. The rings are buffered in pieces of :data:`_CHUNK` segments
    (the same swaths): a whole ring weaving around many holes took GEOS seconds to buffer."""
    import shapely

    inner = shapely.buffer(region, -(passes - _OVERLAP) * spacing, quad_segs=_QUAD_SEGS)
    chunks = [
        shapely.LineString(r[a : a + _CHUNK + 1])
        for rs in rings
        for r in rs
        for a in range(0, len(r) - 1, _CHUNK)
    ]
    covered = shapely.union_all([*shapely.buffer(chunks, reach, quad_segs=_SWATH_SEGS), inner])
    return _pieces(shapely.difference(region, covered), tiny)


def _greedy(region, left: list, depths: list[float], reach: float, tiny: float, out: list) -> list:
    """Pieces of the contours at ``depths`` within reach of ``left`` (polygons), chosen greedily
    (most uncovered area first) and appended to ``out``; returns what is still left. A choice
    changes the gains of the candidates whose swaths meet its swath only: those are recomputed,
    on the parts of ``left`` they meet (an STRtree)."""
    import shapely

    near = shapely.buffer(shapely.union_all(left), reach * (1 + 1e-6))
    candidates = []
    for depth in depths:
        contour = shapely.boundary(shapely.buffer(region, -depth, quad_segs=_SWATH_SEGS))
        piece = shapely.line_merge(shapely.intersection(contour, near))
        candidates += [g for g in getattr(piece, "geoms", [piece]) if g.geom_type == "LineString"]
    if not candidates:
        return left
    swaths = shapely.buffer(np.asarray(candidates, dtype=object), reach, quad_segs=_SWATH_SEGS)
    by_swath = shapely.STRtree(swaths)
    parts = list(left)
    gains = np.zeros(len(candidates))
    todo = np.arange(len(candidates))
    while sum(p.area for p in parts) > tiny:
        tree = shapely.STRtree(parts)
        for i in todo:
            hit = tree.query(swaths[i])
            gains[i] = sum(shapely.intersection(parts[j], swaths[i]).area for j in hit)
        best = int(np.argmax(gains))
        if gains[best] <= tiny:
            break
        out.append(np.asarray(candidates[best].coords))
        hit = set(tree.query(swaths[best]).tolist())
        parts = [
            q
            for j, p in enumerate(parts)
            for q in (_pieces(shapely.difference(p, swaths[best]), tiny) if j in hit else [p])
        ]
        todo = by_swath.query(swaths[best])
        gains[best] = -math.inf
        todo = todo[gains[todo] > -math.inf]
    return parts


def _pieces(geom, tiny: float) -> list:
    """The polygon parts of ``geom`` of area over ``tiny``."""
    return [g for g in getattr(geom, "geoms", [geom]) if g.geom_type == "Polygon" and g.area > tiny]


def _inside_the_field(
    inner: Plan, router: Router
) -> tuple[list[NDArray[np.float64]], list[str], list[int]]:
    """The inner plan's waypoints, kinds and lanes with its run-ins and run-outs cut where they
    would leave the field (dropped where cut to nothing), and every move that would leave it
    routed inside (a run-in longer than the headland band used to end outside the field)."""
    w, k = inner.waypoints, inner.kinds
    keep: list[tuple[NDArray[np.float64], str, int]] = []
    for i, (p, kind, ti) in enumerate(zip(w, k, inner.lane, strict=True)):
        anchor = (
            i + 1 if kind == "run_in" and i + 1 < len(w) and k[i + 1] == "start"
            else i - 1 if kind == "run_out" and i > 0 and k[i - 1] == "end"
            else None
        )  # fmt: skip
        if anchor is not None:
            p = _cut(router, w[anchor], p)
            if np.linalg.norm(p - w[anchor]) <= router.tol:
                continue
        keep.append((p, kind, int(ti)))
    points, kinds, lane = [keep[0][0]], [keep[0][1]], [keep[0][2]]
    pts = np.asarray([p for p, _, _ in keep])
    routes = router.paths(pts[:-1], pts[1:]) if len(pts) > 1 else []
    for (p, kind, ti), route in zip(keep[1:], routes, strict=True):
        for q in route.points[1:-1]:  # a move that would leave the field, routed inside
            points.append(q)
            kinds.append("via")
            lane.append(ti)
        points.append(p)
        kinds.append(kind)
        lane.append(ti)
    return points, kinds, lane


def _cut(router: Router, a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """``b``, or the point where ``a -> b`` first leaves the field (or enters a hole)."""
    br, cls = router._pieces(a, b)
    bad = np.flatnonzero(cls != 0)
    return b if len(bad) == 0 else a + br[bad[0]] * (b - a)


def _nearer_first(line: NDArray[np.float64], near: NDArray[np.float64]) -> NDArray[np.float64]:
    """An open pass driven from its end nearer ``near``."""
    return line if np.linalg.norm(line[0] - near) <= np.linalg.norm(line[-1] - near) else line[::-1]


def _nearest_first(
    lines: list[NDArray[np.float64]], start: NDArray[np.float64]
) -> list[NDArray[np.float64]]:
    """Open passes in the order a vehicle at ``start`` drives them going to the nearest end of
    those left each time (the greedy's order is by area: with many holes it crossed the field
    back and forth: 40 holes 25 m from the boundary, 108.6 km of path, now 81.8 km), each from
    that end."""
    left = list(lines)
    out = []
    at = start
    while left:
        d = [min(np.linalg.norm(g[0] - at), np.linalg.norm(g[-1] - at)) for g in left]
        g = _nearer_first(left.pop(int(np.argmin(d))), at)
        out.append(g)
        at = g[-1]
    return out


def _dedupe(points: NDArray[np.float64], tol: float) -> NDArray[np.float64]:
    keep = np.concatenate([[True], np.linalg.norm(np.diff(points, axis=0), axis=1) > tol])
    return points[keep]


def _rotate(ring: NDArray[np.float64], near: NDArray[np.float64]) -> NDArray[np.float64]:
    """A closed ring re-begun at its vertex nearest ``near`` (still closed)."""
    body = ring[:-1]
    i = int(np.argmin(np.linalg.norm(body - near, axis=1)))
    body = np.roll(body, -i, axis=0)
    return np.concatenate([body, body[:1]])


def _passes_near_origin(
    field: Region, passes: int, spacing: float, reach: float
) -> tuple[list[list[NDArray[np.float64]]], list[NDArray[np.float64]]]:
    """The rings (with their spikes) and the gap passes, computed on the field moved to near the
    origin (by its shell's first vertex) and moved back: at UTM coordinates (5e6 m) GEOS's
    rounding left slivers of 3e-8..7e-8 m2 between the swaths, over the pieces ignored
    (``1e-12 spacing^2``), and a star field at 10 m got 6 gap passes, 648 m (a review)."""
    o = field.shell.vertices[0].copy()
    local = Region(field.shell.vertices - o, [h.vertices - o for h in field.holes])
    router = Router(local, reach=0.0)
    rings = [
        _spikes(
            _offset(local, k * spacing),
            _offset(local, (k + 0.5) * spacing),
            r,
            reach,
            spacing,
            router,
        )
        for k, r in enumerate(headland_rings(local, spacing, passes))
    ]
    gaps = _gap_passes(local, spacing, reach, passes, rings)
    return [[r + o for r in rs] for rs in rings], [g + o for g in gaps]


def add_headland(inner: Plan, field: Region, passes: int, *, spacing: float, reach: float) -> Plan:
    """``inner`` (a plan of :func:`inner_field`) followed by the headland passes, innermost
    first, in one path inside ``field``; plan units. Statistics recomputed (ground units), the
    length outside measured on the whole path against ``field``."""
    router = Router(field, reach=0.0)
    rings, gaps = _passes_near_origin(field, passes, spacing, reach)
    points, kinds, lane = _inside_the_field(inner, router)
    transects = list(inner.transects)
    angles = list(inner.transect_angle())
    roles = list(inner.role())
    cells = list(inner.transect_cells) if inner.transect_cells is not None else [0] * len(angles)
    positions = list(inner.positions)
    headland_length = 0.0
    n_rings = 0
    for pts, closed in [
        *((g, False) for g in _nearest_first(gaps, points[-1])),
        *((r, True) for rs in rings[::-1] for r in rs),
    ]:
        pts = _rotate(pts, points[-1]) if closed else _nearer_first(pts, points[-1])
        ti = len(transects)
        route = router.path(points[-1], pts[0])
        for p in route.points[1:-1]:
            points.append(p)
            kinds.append("via")
            lane.append(ti)
        for j, p in enumerate(pts):
            points.append(p)
            kinds.append("start" if j == 0 else "end" if j == len(pts) - 1 else "headland")
            lane.append(ti + max(0, min(j - 1, len(pts) - 2)))
        for a, b in itertools.pairwise(pts):
            d = b - a
            transects.append(np.stack([a, b]))
            angles.append(math.atan2(d[1], d[0]))
            roles.append("headland")
            cells.append(-1)
            positions.append(math.nan)
            headland_length += float(np.linalg.norm(d))
        n_rings += 1
    w = np.asarray(points)
    s, scale = inner.stats, inner.ground_scale
    path_length = float(np.linalg.norm(np.diff(w, axis=0), axis=1).sum()) / scale
    n_turns = s.n_turns + n_rings
    duration = None if s.speed is None else path_length / s.speed + n_turns * s.turn_time
    stats = dataclasses.replace(
        s,
        n_turns=n_turns,
        path_length=path_length,
        duration=duration,
        headland_length=headland_length / scale,
    )
    plan = dataclasses.replace(
        inner,
        polygon=field.shell,
        waypoints=w,
        kinds=tuple(kinds),
        lane=np.asarray(lane, dtype=np.int64),
        transects=np.asarray(transects),
        transect_angles=np.asarray(angles),
        roles=tuple(roles),
        transect_cells=np.asarray(cells, dtype=np.int64),
        positions=np.asarray(positions),
        stats=stats,
        region=field,
        headland=passes,
    )
    return with_outside_length(plan, field)  # the whole path against the whole field
