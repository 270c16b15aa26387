"""Keeping the path inside the area: lanes cut to it, boundary passes, the length outside.

With ``keep_inside`` (:func:`boustro.plan.plan_region`) no part of the path leaves the area or
enters a hole. Three pieces make that possible without losing coverage:

* :func:`clip_lanes` cuts every coverage-guaranteed lane to the area (the line's chords), or to
  the area shrunk by half a spacing (:func:`inside_layout` keeps whichever needs less driving
  with its passes): a lane still covers every point of its band whose foot on the lane's line
  is reached from it inside the area, so what the lanes leave uncovered lies near the boundary;
* :func:`boundary_passes` finds what they leave (shapely: the area minus the lanes' footprints)
  and covers it with the parts of the *contour* (the boundary of the area shrunk by half a
  spacing, ``buffer(-spacing / 2)``) within reach of it, with a spur into every convex corner
  the contour does not reach (:mod:`boustro.plan.contour`), then with short *patches* (the
  middle line of each piece still uncovered, cut to the area) for sharp corners and the parts
  narrower than a spacing, which no contour reaches (a short one near a contour becomes a
  spur of it);
* connecting moves are routed inside the area (:class:`boustro.plan.routing.Router` with no
  reach outside: its visibility graph holds the shell's reflex vertices as well as the holes').

:func:`outside_length` (:mod:`boustro.plan.outside`) measures how much of a
path lies outside an area or inside one of its holes (the ``outside_length`` statistic of
every plan). Shapely is imported inside the functions (``import boustro.plan`` does not load
it).
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._memo import bytes_key, remember
from ..geometry.region import Region
from .cells import _crossings, _frame
from .contour import Contour, _contour_arcs, _corner_spurs, _lines, _pieces, contour_of
from .coverage import _aligned_boxes, _axes
from .lanes import Lanes
from .margin_floor import RingTests, kept_samples, stretch_floor, test_points
from .outside import shapely_area

__all__ = [
    "MARGINS",
    "MAX_PATCHES",
    "SCREEN_SLACK",
    "SPUR_CACHE",
    "boundary_passes",
    "clip_lanes",
    "inside_layout",
    "margin_floor",
]

#: Patches (short passes over corners and thin parts) placed at most; more means the area has
#: thousands of slivers narrower than a spacing, and what is left is reported as not covered.
MAX_PATCHES = 5000
#: Pass pieces whose bands :func:`_band` keeps (a few kilobytes each: the pieces of a contour
#: between its spurs recur in every plan of an area).
BAND_CACHE = 4096
#: Unions of bands kept (:func:`_bands`).
UNION_CACHE = 128
#: Points of the contour stretches (and of their spurs) an area's :class:`_Geometry` keeps for
#: :meth:`_Geometry.spurs` (the oldest forgotten past it: about 8 MB an area with the keys; a
#: review: 1024 whole rings of a 2000-vertex trace per area, 32 areas, would hold 2 GB).
SPUR_CACHE = 1 << 18
#: Results of :func:`inside_layout` kept (keyed by the area, the lanes' bytes, the spacing and
#: the reach): a search's screen (:func:`~boustro.plan.region_floor.plan_floor`) lays a
#: layout's lanes and passes, and the plan of a layout that passes it lays the same again.
LAYOUT_CACHE = 4
#: Areas whose shapely geometry (:func:`_geometry`) is kept: a search plans one area (or a
#: decomposition's few cells) hundreds of times.
AREA_CACHE = 32


class _Geometry:
    """What a keep-inside plan needs of its area alone, built once per area and spacing (the
    plans a search evaluates share it): the area as a prepared shapely polygon, its contour
    (:func:`~boustro.plan.contour.contour_of`) and the area shrunk by each margin."""

    def __init__(self, area: Region, spacing: float) -> None:
        import shapely

        self.target = shapely_area(area)
        shapely.prepare(self.target)
        self.spacing = spacing
        self.tol = 1e-9 * area.diameter
        self._contour: Contour | None = None
        self._shrunk: dict[float, Any] = {}
        self._spurs: dict[tuple[bytes, int, float], NDArray[np.float64]] = {}
        self._spur_points = 0  # of the kept stretches and their spurs (SPUR_CACHE)
        self._tests: dict[float, list[RingTests]] = {}

    @property
    def contour(self) -> Contour:
        if self._contour is None:
            self._contour = contour_of(self.target, self.spacing / 2, self.tol)
        return self._contour

    def spurs(self, line: NDArray[np.float64], reach: float) -> NDArray[np.float64]:
        """``line`` (a kept stretch of the contour) with its corner spurs
        (:func:`~boustro.plan.contour._corner_spurs`), cached by the stretch's points: the plans
        of a search keep the same few stretches (the whole ring where the lanes leave some of
        it all round), and the spurs depend on nothing else (the same array, read-only)."""
        key = (np.ascontiguousarray(line, dtype=np.float64).tobytes(), len(line), reach)
        out = self._spurs.get(key)
        if out is None:
            out = _corner_spurs(line, self.contour, self.spacing / 2, reach, self.tol)
            out = np.array(out, dtype=np.float64)  # its own copy, never written
            out.flags.writeable = False
            while self._spurs and self._spur_points + len(line) + len(out) > SPUR_CACHE:
                old_key, old = next(iter(self._spurs.items()))
                self._spur_points -= old_key[1] + len(old)
                del self._spurs[old_key]
            self._spurs[key] = out
            self._spur_points += len(line) + len(out)
        return out

    def stretch_floor(self, lanes: list[Lanes], reach: float) -> tuple[float, int]:
        """A floor of the length of the contour stretches the residual of the cut ``lanes``
        keeps (:func:`~boustro.plan.margin_floor.stretch_floor`; its test points built once
        per reach), and at most how many points those stretches hold (per ring: its points, and
        two ends per stretch, the stretches disjoint and at most one per two samples; plus 2)."""
        import shapely

        perimeter = float(shapely.length(self.target))
        vertices = int(shapely.get_num_coordinates(self.target))
        tests = self._tests_of(reach)
        floor = stretch_floor(tests, lanes, reach, self.spacing, perimeter, vertices)
        points = sum(len(r.v) + len(r.samples) + 2 for r in self.contour.rings)
        return floor, points

    def known(self, lanes: list[Lanes], reach: float) -> list[NDArray[np.bool_]]:
        """Per contour ring, the samples known to be within reach of the residual of ``lanes``
        (:func:`~boustro.plan.margin_floor.kept_samples`)."""
        return kept_samples(self._tests_of(reach), lanes, reach, self.spacing)

    def _tests_of(self, reach: float) -> list[RingTests]:
        """The contour's test points (:func:`~boustro.plan.margin_floor.test_points`), built
        once per reach."""
        if reach not in self._tests:
            self._tests[reach] = test_points(self.target, self.contour.rings, self.spacing, reach)
        return self._tests[reach]

    def shrunk(self, margin: float) -> Any:
        """The area shrunk by ``margin`` (``quad_segs=8``), prepared."""
        import shapely

        if margin not in self._shrunk:
            inner = self.target.buffer(-margin, quad_segs=8)
            if not inner.is_empty:
                shapely.prepare(inner)
            self._shrunk[margin] = inner
        return self._shrunk[margin]


_GEOMETRIES: dict[bytes, _Geometry] = {}


def _geometry(area: Region, spacing: float) -> _Geometry:
    """The :class:`_Geometry` of ``area`` at ``spacing``, from a cache of the last
    :data:`AREA_CACHE` areas (keyed by their coordinates and the spacing)."""
    rings = [area.shell.vertices, *(h.vertices for h in area.holes)]
    key = b"|".join(np.ascontiguousarray(v, dtype=np.float64).tobytes() for v in rings)
    key += np.float64(spacing).tobytes()
    return remember(_GEOMETRIES, key, AREA_CACHE, lambda: _Geometry(area, spacing))


def clip_lanes(
    lanes: Lanes, area: Region, tol: float, margin: float = 0.0, spacing: float | None = None
) -> Lanes:
    """The lanes cut to their parts inside ``area`` (a lane across a bay becomes two), or with
    ``margin > 0`` inside the area shrunk by ``margin`` (shapely); parts shorter than ``tol`` are
    dropped: what they covered is left to the boundary passes. ``spacing``: the plan's (the
    area's shrunk shapes are cached per area and spacing), default twice the margin."""
    u, n = _frame(lanes.angle)
    if margin > 0:
        geo = _geometry(area, 2 * margin if spacing is None else spacing)
        i, a, b = _shrunk_intervals(lanes, geo.shrunk(margin))
    else:
        i, a, b = _chords(area.edges - lanes.origin, u, n, lanes.c)
    # a lane's end cuts its chord only where strictly inside it (ties keep the chord's end,
    # -0.0 against 0.0 included: np.maximum / np.minimum would return the lane's)
    t0, t1 = lanes.t0[i], lanes.t1[i]
    lo, hi = np.where(t0 > a, t0, a), np.where(t1 < b, t1, b)
    keep = hi - lo > tol
    i = i[keep]
    return Lanes(
        lanes.angle,
        lanes.origin,
        np.asarray(lanes.k, dtype=np.int64)[i],
        np.asarray(lanes.c, dtype=np.float64)[i],
        lo[keep],
        hi[keep],
        lanes.cut,
    )


def _chords(
    edges: NDArray[np.float64], u: NDArray[np.float64], n: NDArray[np.float64], c: Any
) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]:
    """The chords of the lines ``c`` through the area of ``edges`` (relative to the lanes'
    origin) as flat arrays ``(lane, start, end)``, lane by lane and along each line: the
    intervals of :func:`~boustro.plan.lanes._intervals_on_lines` (crossings ``2j, 2j + 1``)."""
    t, _, count = _crossings(edges, u, n, c)
    j = np.arange(0, max(t.shape[1] - 1, 0), 2)
    pick = j[None, :] < (count[:, None] - 1)
    i, col = np.nonzero(pick)
    col = j[col]
    return i.astype(np.int64), t[i, col], t[i, col + 1]


def _shrunk_intervals(
    lanes: Lanes, inner: Any
) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]:
    """The intervals (along each lane) of its line inside ``inner`` (the area shrunk by the
    margin, :meth:`_Geometry.shrunk`) as flat arrays ``(lane, start, end)``, lane by lane and
    each lane's in the order of its intersection's parts: the line parts of each lane's
    intersection, their extreme points along the lane (all parts at once: the same products
    as part by part)."""
    import shapely

    u, _ = _frame(lanes.angle)
    none = (np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0))
    if len(lanes.k) == 0 or inner.is_empty:
        return none
    parts = shapely.intersection(shapely.linestrings(lanes.segments), inner)
    lines, owner = shapely.get_parts(parts, return_index=True)
    pick = (shapely.get_type_id(lines) == 1) & ~shapely.is_empty(lines)  # LineStrings
    if not pick.any():
        return none
    xy, which = shapely.get_coordinates(lines[pick], return_index=True)
    t = (xy - lanes.origin) @ u
    starts = np.concatenate([[0], np.flatnonzero(np.diff(which)) + 1])
    lo, hi = np.minimum.reduceat(t, starts), np.maximum.reduceat(t, starts)
    order = np.argsort(owner[pick], kind="stable")  # lane by lane, parts in their order
    return owner[pick][order].astype(np.int64), lo[order], hi[order]


def _lane_footprint(
    segments: NDArray[np.float64],
    angles: NDArray[np.float64],
    origin: NDArray[np.float64],
    reach: float,
    spacing: float,
) -> Any:
    """The union of the lanes' footprints (rectangles ``reach`` either side), built per lane
    direction in that direction's frame as :func:`boustro.plan.coverage.footprint` does."""
    import shapely

    parts = []
    for angle in np.unique(angles):
        pick = angles == angle
        t_lo, lo, t_hi, hi = _aligned_boxes(
            segments[pick], float(angle), origin, [(-reach, reach)], spacing
        )
        real = (t_hi > t_lo) & (hi > lo)
        union = shapely.union_all(shapely.box(t_lo, lo, t_hi, hi)[real])
        u, n = _axes(float(angle))
        parts.append(
            shapely.transform(union, lambda p, u=u, n=n: origin + p[:, :1] * u + p[:, 1:] * n)
        )
    return shapely.union_all(parts) if parts else shapely.Polygon()


def _patch(piece: Any, target: Any, reach: float, tol: float) -> list[NDArray[np.float64]]:
    """Short passes over one uncovered ``piece``: the middle line of its narrowest enclosing
    rectangle when that is at most two reaches wide (cut to the area), else a short segment
    through a point inside it (every patch removes some of the piece)."""
    import shapely

    env = shapely.oriented_envelope(piece)
    if env.geom_type == "Polygon":
        c = np.asarray(env.exterior.coords)[:4]
        sides = np.linalg.norm(c[[1, 2]] - c[[0, 1]], axis=1)
        long_first = sides[0] >= sides[1]
        width = float(sides[1] if long_first else sides[0])
        if width <= 2 * reach * (1 + 1e-9):  # its middle line covers it
            if long_first:  # c0 -> c1 is a long side: the middle line joins mid(c0 c3), mid(c1 c2)
                line = np.stack([(c[0] + c[3]) / 2, (c[1] + c[2]) / 2])
            else:
                line = np.stack([(c[0] + c[1]) / 2, (c[3] + c[2]) / 2])
            lines = _lines(shapely.intersection(shapely.LineString(line), target), tol)
            if lines:
                return lines
    p = np.asarray(piece.representative_point().coords[0])
    # 30 halvings of reach / 4 x 8 directions, the longest first: the first covered one
    a = np.linspace(0, math.pi, 8, endpoint=False)
    d = (reach / 4 * 0.5 ** np.arange(30))[:, None, None] * np.stack([np.cos(a), np.sin(a)], 1)
    segs = np.stack([p - d, p + d], axis=2).reshape(-1, 2, 2)
    for lo, hi in ((0, 8), (8, len(segs))):  # most pieces take the first 8 tries
        ok = np.flatnonzero(shapely.covers(target, shapely.linestrings(segs[lo:hi])))
        if len(ok):
            return [segs[lo + ok[0]]]
    return []


def boundary_passes(
    area: Region,
    lanes: list[Lanes],
    spacing: float,
    reach: float,
) -> tuple[list[NDArray[np.float64]], float]:
    """Passes that cover what lanes cut to ``area`` leave uncovered (module docstring).

    Returns:
        ``(passes, uncovered)``: each pass an ``(P, 2)`` polyline inside the area (closed when
        its first and last points agree), contour parts first, then patches; ``uncovered`` the
        area still uncovered after them (0 unless :data:`MAX_PATCHES` ran out).
    """
    geo, residual = _residual(area, lanes, spacing, reach)
    if residual is None:
        return [], 0.0
    known = geo.known(lanes, reach)
    arcs = _contour_arcs(residual, reach, geo.tol, geo.contour, spacing / 2, known)
    return _completed(geo, residual, arcs, reach)


def _residual(
    area: Region, lanes: list[Lanes], spacing: float, reach: float
) -> tuple[_Geometry, Any]:
    """The area's :class:`_Geometry` and what the lanes' footprints leave of it (shapely),
    ``None`` when that is only rounding slivers."""
    import shapely

    geo = _geometry(area, spacing)
    segments = [ls.segments for ls in lanes if len(ls.k)]
    if segments:
        angles = np.concatenate([np.full(len(ls.k), ls.angle) for ls in lanes if len(ls.k)])
        covered = _lane_footprint(np.concatenate(segments), angles, area.centre, reach, spacing)
        residual = shapely.difference(geo.target, covered)
    else:
        residual = geo.target
    return geo, (residual if _pieces(residual, 1e-7 * spacing) else None)


def _completed(
    geo: _Geometry, residual: Any, arcs: list[NDArray[np.float64]], reach: float
) -> tuple[list[NDArray[np.float64]], float]:
    """:func:`boundary_passes` from the residual and the contour's kept stretches ``arcs``
    (:func:`~boustro.plan.contour._contour_arcs`): their corner spurs, the patches."""
    import shapely

    target, spacing, tol = geo.target, geo.spacing, geo.tol
    eps = 1e-7 * spacing  # slivers thinner than this are rounding
    passes = [geo.spurs(line, reach) for line in arcs]
    inner = reach  # as boustro.plan.coverage measures the passes (quad_segs=64)

    def cover(lines: list[NDArray[np.float64]], rest: Any) -> Any:
        keys = [np.ascontiguousarray(k, dtype=np.float64) for k in _near(lines, rest, 2 * inner)]
        if not keys:
            return rest
        band = _bands(tuple((k.tobytes(), len(k)) for k in keys), inner)
        return shapely.difference(rest, band)

    residual = cover(passes, residual)
    patches: list[NDArray[np.float64]] = []
    pieces = _pieces(residual, eps)
    while pieces and len(patches) < MAX_PATCHES:
        new: list[NDArray[np.float64]] = []
        for piece in pieces:
            new += _patch(piece, target, reach, tol)
        if not new:
            break
        patches += new
        residual = cover(new, shapely.union_all(pieces))
        pieces = _pieces(residual, eps)
    rest = _attach(passes, patches, target, spacing)
    return [_dedupe(p, tol) for p in passes + rest], float(sum(p.area for p in pieces))


def _near(lines: list[NDArray[np.float64]], rest: Any, far: float) -> list[NDArray[np.float64]]:
    """The runs of segments of ``lines`` within ``far`` of ``rest``, each split where it turns
    back on itself (a spur's tip): buffered by ``reach <= far / 2`` they cover the same part of
    ``rest`` as the whole lines (a point of ``rest`` within ``reach`` of a pass is within
    ``reach`` of a kept segment; the caps at a run's cut ends lie more than ``reach`` from
    ``rest``; at a spur's tip the join of the whole line is the caps of its two halves) at a
    fraction of the cost (a line with spurs is GEOS's worst case: most of a plan's time on a
    traced boundary)."""
    import shapely

    if not lines or rest.is_empty:
        return []
    segs = np.concatenate([np.stack([line[:-1], line[1:]], axis=1) for line in lines])
    counts = np.array([len(line) - 1 for line in lines])
    first = np.concatenate([[0], np.cumsum(counts)[:-1]])  # each line's first segment
    keep = shapely.dwithin(shapely.linestrings(segs), rest, far)
    # segment m runs on into m + 1: both kept, the same line, not turning back (a spur's tip)
    d = segs[:, 1] - segs[:, 0]
    norm = np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-300)
    back = np.einsum("ij,ij->i", d[:-1], d[1:]) / (norm[:-1] * norm[1:]) < -1 + 1e-9
    on = keep[:-1] & keep[1:] & ~back
    ends_at = first[1:][first[1:] > 0] - 1  # each line's last segment (before the next)
    on[ends_at[ends_at < len(on)]] = False  # never runs on into the next line's first
    on = np.concatenate([on, [False]])
    starts = np.flatnonzero(keep & ~np.concatenate([[False], on[:-1]]))
    ends = np.flatnonzero(keep & ~on)
    owner = np.repeat(np.arange(len(lines)), counts)
    out = []
    for j, k in zip(starts.tolist(), ends.tolist(), strict=True):
        i = int(owner[j])
        out.append(lines[i][j - first[i] : k - first[i] + 2])
    return out


@lru_cache(maxsize=UNION_CACHE)
def _bands(keys: tuple[tuple[bytes, int], ...], reach: float) -> Any:
    """The union of the passes' bands (:func:`_band`). Cached as well: the plans of a search
    share most of their sets of contour passes, and the union is then most of a plan's cost."""
    import shapely

    return shapely.union_all([_band(line, n, reach) for line, n in keys])


@lru_cache(maxsize=BAND_CACHE)
def _band(line: bytes, n: int, reach: float) -> Any:
    """The band of a pass (a polyline of ``n`` points, as bytes) ``reach`` either side, as
    :mod:`boustro.plan.coverage` measures it (``quad_segs=64``). Cached: the plans a search
    evaluates share most of their contour passes, and buffering them is most of a plan's
    cost."""
    import shapely

    pts = np.frombuffer(line, dtype=np.float64).reshape(n, 2)
    return shapely.buffer(shapely.LineString(pts), reach, quad_segs=64)


def _dedupe(line: NDArray[np.float64], tol: float) -> NDArray[np.float64]:
    """``line`` without points within ``tol`` of the one before (no zero-length edges)."""
    keep = np.concatenate([[True], np.linalg.norm(np.diff(line, axis=0), axis=1) > tol])
    return line[keep]


def _attach(
    contours: list[NDArray[np.float64]],
    patches: list[NDArray[np.float64]],
    target: Any,
    spacing: float,
) -> list[NDArray[np.float64]]:
    """Each short patch near a contour pass (the patch and the way to it and back at most two
    spacings) becomes a spur of it (in place): from the contour's nearest point out along the
    patch and back, when both legs stay in ``target``;
    returns the patches left as passes of their own. A spur into a corner costs a few
    centimetres where a pass of its own would cost a move there and back."""
    import shapely

    if not contours:
        return patches
    rest = []
    for patch in patches:
        seg = shapely.LineString(patch)
        lines = [shapely.LineString(c) for c in contours]
        d = shapely.distance(lines, seg)
        ci = int(np.argmin(d))
        if 2 * d[ci] + seg.length > 2 * spacing:  # a long spur would drive its patch twice
            rest.append(patch)
            continue
        line = contours[ci]
        at = lines[ci].project(shapely.Point(patch[len(patch) // 2]))
        q = np.asarray(lines[ci].interpolate(at).coords[0])
        a = patch[::-1] if np.linalg.norm(patch[-1] - q) < np.linalg.norm(patch[0] - q) else patch
        if not (
            target.covers(shapely.LineString([q, a[0]]))
            and target.covers(shapely.LineString([a[-1], q]))
        ):
            rest.append(patch)
            continue
        cum = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(line, axis=0), axis=1))])
        i = int(np.clip(np.searchsorted(cum, at, side="right") - 1, 0, len(line) - 2))
        spur = [q[None], a, q[None]]
        contours[ci] = np.concatenate([line[: i + 1], *spur, line[i + 1 :]])
    return rest


#: The margins (in spacings) inside the boundary at which :func:`inside_layout` tries cutting
#: the lanes: at the boundary, and half a spacing inside (where the contour runs).
MARGINS = (0.0, 0.5)
#: Relative room of :func:`inside_layout`'s margin screen: margin 0 is completed unless margin
#: 1/2 is shorter by this share of margin 0's floor (far above the sums' rounding, 1e-15, and
#: the points dropped within 1e-9 of the area's diameter; the lengths differ by percents).
SCREEN_SLACK = 1e-6


def _length(cut: list[Lanes], passes: list[NDArray[np.float64]]) -> float:
    """The lanes' and the passes' length together."""
    length = sum(float(np.sum(ls.t1 - ls.t0)) for ls in cut)
    return length + sum(float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum()) for p in passes)


_LAYOUTS: dict[bytes, tuple[list[Lanes], list[NDArray[np.float64]], float]] = {}


def inside_layout(
    area: Region, lanes: list[Lanes], spacing: float, reach: float
) -> tuple[list[Lanes], list[NDArray[np.float64]], float]:
    """:func:`_inside_layout`, from a cache of the last :data:`LAYOUT_CACHE` calls (keyed by
    every number it reads: the area's rings, the lanes' arrays, the spacing and the reach), the
    lists copied (the arrays are the same, never written)."""
    key = _layout_key(area, lanes, spacing, reach)
    make = lambda: _inside_layout(area, lanes, spacing, reach, key)  # noqa: E731
    hit = remember(_LAYOUTS, key, LAYOUT_CACHE, make)
    return list(hit[0]), list(hit[1]), hit[2]


def _layout_key(area: Region, lanes: list[Lanes], spacing: float, reach: float) -> bytes:
    """The bytes of every number :func:`_inside_layout` reads: the area's rings, the lanes'
    arrays, the spacing and the reach."""
    rings = [area.shell.vertices, *(h.vertices for h in area.holes)]
    parts = [np.ascontiguousarray(v, dtype=np.float64).tobytes() for v in rings]
    for ls in lanes:
        head = np.array([ls.angle, *np.asarray(ls.origin, dtype=np.float64).ravel()])
        cut = np.array(sorted(ls.cut), dtype=np.int64)
        cols = [np.asarray(x, dtype=np.float64) for x in (ls.c, ls.t0, ls.t1)]
        k = np.asarray(ls.k, dtype=np.int64)
        parts += [head.tobytes(), k.tobytes(), *(x.tobytes() for x in cols), cut.tobytes()]
    parts.append(np.array([spacing, reach], dtype=np.float64).tobytes())
    return bytes_key(parts)


#: Cut lanes (:func:`_cut`) and their passes' floors (:func:`margin_floor`) kept, per layout
#: and margin: the search's cheap screen cuts a layout's lanes
#: (:func:`~boustro.plan.region_floor.lanes_floor`) and, where that does not screen it out,
#: :func:`inside_layout` cuts the same lanes again.
CUT_CACHE = 8
_CUTS: dict[bytes, list[Lanes]] = {}
_PASS_FLOORS: dict[bytes, tuple[float, int]] = {}


def margin_floor(
    area: Region, lanes: list[Lanes], spacing: float, reach: float, margin: float
) -> tuple[list[Lanes], float]:
    """The lanes cut at ``margin`` (one of :data:`MARGINS`) as :func:`inside_layout` cuts them
    (the same calls; kept, :data:`CUT_CACHE`) and a floor of the length of the passes
    :func:`boundary_passes` adds to them, from the lanes' arrays alone: the contour stretches
    their residual keeps (:meth:`_Geometry.stretch_floor`; each pass holds one whole, spurs
    and patches only add) less what :func:`_dedupe` may drop (``2 tol`` a point), never below
    0. Whichever margin :func:`inside_layout` keeps, its lanes and passes are at least that
    margin's lanes and floor (the search's cheap screen,
    :func:`~boustro.plan.region_floor.lanes_floor`)."""
    key = _layout_key(area, lanes, spacing, reach)
    cut = _cut(area, lanes, spacing, margin, key)
    stretches, points = _pass_floor(area, cut, spacing, reach, margin, key)
    return cut, max(stretches - 2 * 1e-9 * area.diameter * points, 0.0)


def _cut(
    area: Region, lanes: list[Lanes], spacing: float, margin: float, key: bytes
) -> list[Lanes]:
    """:func:`clip_lanes` of each of ``lanes`` at ``margin`` spacings inside ``area``, kept by
    the layout's ``key`` (:func:`_layout_key`; the list and its lanes never written)."""
    tol = 1e-9 * area.diameter
    make = lambda: [clip_lanes(ls, area, tol, margin * spacing, spacing) for ls in lanes]  # noqa: E731
    return remember(_CUTS, key + np.float64(margin).tobytes(), CUT_CACHE, make)


def _pass_floor(
    area: Region, cut: list[Lanes], spacing: float, reach: float, margin: float, key: bytes
) -> tuple[float, int]:
    """:meth:`_Geometry.stretch_floor` of the lanes ``cut`` at ``margin`` (:func:`_cut` of
    the layout ``key``), kept."""
    make = lambda: _geometry(area, spacing).stretch_floor(cut, reach)  # noqa: E731
    return remember(_PASS_FLOORS, key + np.float64(margin).tobytes(), CUT_CACHE, make)


def _inside_layout(
    area: Region, lanes: list[Lanes], spacing: float, reach: float, key: bytes
) -> tuple[list[Lanes], list[NDArray[np.float64]], float]:
    """The lanes cut inside ``area`` and the boundary passes that complete their coverage
    (:func:`boundary_passes`), for the margin of :data:`MARGINS` whose lanes and passes are the
    shortest together (the moves between them are not counted; a tie keeps the margin 0).

    Margin 1/2 is laid first; margin 0's passes are completed (their bands and patches: most of
    their cost) only when its lanes and the contour stretches it keeps (each pass holds one,
    whole: the spurs and patches only add length) are not already longer than margin 1/2's
    lanes and passes: the same choice as laying both in full, for a third of the work where
    margin 1/2 wins (docs/keep_inside.md, "Margin screen"). Before margin 0's residual, a floor
    of the stretches it keeps, from its lanes' arrays alone
    (:mod:`~boustro.plan.margin_floor`), screens it the same way (thirteenth round).

    The cut lanes and margin 0's floor are kept by the layout's ``key`` (:func:`_cut`,
    :func:`_pass_floor`: the search's cheap screen made them for most layouts).

    Returns:
        ``(lanes, passes, uncovered)``, as :func:`clip_lanes` and :func:`boundary_passes`.
    """
    tol = 1e-9 * area.diameter
    half = list(_cut(area, lanes, spacing, MARGINS[1], key))
    passes_h, uncovered_h = boundary_passes(area, half, spacing, reach)
    length_h = _length(half, passes_h)
    cut = list(_cut(area, lanes, spacing, MARGINS[0], key))

    def loses(floor: float) -> bool:
        """Whether margin 1/2 wins against a margin 0 whose length is at least ``floor``, with
        room (:data:`SCREEN_SLACK`) for the sums' rounding and the points :func:`_dedupe` drops
        (each within ``tol`` of the one before: at most ``2 tol`` shorter each)."""
        return uncovered_h == 0 and length_h < floor - tol - SCREEN_SLACK * floor

    if loses(_length(cut, [])):
        return half, passes_h, uncovered_h
    # the stretches margin 0's residual keeps, bounded from below without it (margin_floor)
    stretches, points = _pass_floor(area, cut, spacing, reach, MARGINS[0], key)
    if stretches > 0 and loses(_length(cut, []) + stretches - 2 * tol * points):
        return half, passes_h, uncovered_h
    geo, residual = _residual(area, cut, spacing, reach)
    passes: list[NDArray[np.float64]] = []
    uncovered = 0.0
    if residual is not None:
        known = geo.known(cut, reach)
        arcs = _contour_arcs(residual, reach, geo.tol, geo.contour, spacing / 2, known)
        if loses(_length(cut, arcs) - 2 * tol * sum(len(a) for a in arcs)):
            return half, passes_h, uncovered_h
        passes, uncovered = _completed(geo, residual, arcs, reach)
    if (uncovered_h, length_h) < (uncovered, _length(cut, passes) - tol):
        return half, passes_h, uncovered_h
    return cut, passes, uncovered
