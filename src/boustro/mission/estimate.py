"""The estimate before planning: lanes, vertices, area and time, and the refusal of the absurd.

A planar file read as longitude/latitude (a local grid in metres, 0..150, taken for degrees)
becomes an area of continental size, and planning it ran for over 11 minutes before it was
stopped. :func:`check_work` estimates the work from the projected area before any long work
starts (the lanes across the convex hull at the worst angle, the vertices, the holes) and
refuses the absurd with one line that names the numbers and the usual cause, unless forced.
The cost model and its measured error are in ``docs/concave.md`` ("The estimate before
planning"); ``benchmarks/estimate.py`` measures it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

from .._validate import MAX_TRANSECTS
from ..errors import TooMuchWorkError
from ..optimize.exact import WORK_LIMIT, global_work
from ..optimize.smith_bb import region as region_search
from .defaults import DEFAULT_METHOD, SCALE_METHOD

if TYPE_CHECKING:
    from .project import Frame

__all__ = [
    "COST_MODEL",
    "COVER_HOLES",
    "FIELD_AREA_KM2",
    "KEEP_INSIDE_FACTOR",
    "MAX_AREA_KM2",
    "MAX_LANES",
    "MAX_SECONDS",
    "REGION_EXTENDED",
    "SAY_SECONDS",
    "WorkEstimate",
    "check_work",
    "estimate_seconds",
    "frame_estimate",
    "refusals",
]

#: Refusal thresholds (without ``force``): lanes across the area at the worst angle, ground
#: area (km^2) and estimated planning time (seconds). Real fields and lakes (up to ~100 km^2 at
#: a spacing of 1 m or more) are far below the first two; the time limit is for concave areas.
MAX_LANES = 100_000
MAX_AREA_KM2 = 10_000.0
MAX_SECONDS = 600.0
#: The largest real field or lake considered: at most this area (km^2) and this many lanes at
#: the worst angle (a 10 km square at 1 m: 14,142); never refused for its estimated time. A
#: thin sliver of small area can still be thousands of kilometres long (a mistaken file).
FIELD_AREA_KM2 = 100.0
FIELD_LANES = 20_000
#: Above this estimate ``boustro plan`` says on stderr what it is about to do.
SAY_SECONDS = 3.0

#: The cost model: seconds as a function of the vertices ``n`` (with the holes'), the lanes
#: ``L`` at the worst angle and, for a convex area that the certified optimiser takes
#: (``method="global"``, the default, within its :data:`~boustro.optimize.exact.WORK_LIMIT`),
#: its work ``W`` (:func:`~boustro.optimize.exact.global_work`):
#: ``"certified"``: ``a + b W``; ``"convex"`` (the hybrid or another optimiser) and ``"concave"``
#: (a region, or with holes): ``a + c1 L^beta + c2 n^alpha``, as ``(a, c1, beta, c2, alpha)``.
#: Fitted on this machine by ``benchmarks/estimate.py --fit`` (load 4-7); docs/concave.md states
#: the fit's error (estimate / measured 0.34..2.8 on the calibration, 0.37..4.8 held out). The
#: ``"concave"`` row was fitted again after issue 21 made a plan near-linear in the vertices.
#: ``"certified-bb"`` (a convex area beyond that limit, Eq. 1 certified by
#: :func:`~boustro.optimize.smith_bb.smith_bb`) has the form of ``"convex"``; provisional, set
#: from six ``plan_area`` runs (superellipses of 200-5000 vertices, 37-216 lanes, and the
#: 1000-vertex ellipse of ``benchmarks/web.py`` at 22 and 106 lanes, load 0.4-2: 0.12-3.7 s,
#: within a factor 2), not yet fitted by ``benchmarks/estimate.py --fit``.
#: ``"region-certified"`` (a concave area or one with holes under the default method: the
#: certified optimum over segments of the area and its cells,
#: :mod:`boustro.mission.region_certified`) has the form of ``"concave"`` (its exponents);
#: ``a``, ``c1``, ``c2`` set on the nine areas of ``benchmarks/region_certified.py``
#: (2026-11-27, load 2-2.7: five searches stopped by their budget, 0.37-1.05 s, and four
#: converging, 0.14-0.17 s): estimate / measured 0.50-1.98. A budget-bound search costs about
#: the same whatever the area (its budget), so the constant dominates on small areas. Since the
#: twelfth round a search whose gap keeps shrinking doubles its budget up to 8 times
#: (:data:`~boustro.optimize.smith_bb.region.REGION_EXTEND`): :data:`REGION_EXTENDED` adds
#: what those doublings cost.
COST_MODEL: dict[str, tuple[float, ...]] = {
    "certified": (0.05, 3.18e-7),
    "certified-bb": (0.05, 0.005, 1.0, 4.2e-6, 1.6),
    "convex": (0.05, 0.329, 0.61, 8.94e-5, 1.72),
    "concave": (0.05, 2.03e-5, 2.02, 7.67e-5, 1.34),
    "region-certified": (0.26, 6e-5, 2.02, 8.9e-5, 1.34),
    "cover": (0.3, 0.00708, 1.0, 6.36e-5, 1.40),
    "cover-region": (0.5, 0.448, 0.521, 1.14e-6, 2.06),
}
#: ``"cover"`` and ``"cover-region"``: a plan-level objective (mission time, fewest transects
#: on a concave area) planned by the certified cover search over flown plans
#: (:mod:`boustro.mission.cover`; on a concave area or one with holes also the decomposed
#: alternative, :mod:`boustro.mission.decomposed`). Fitted on CPU seconds of
#: ``benchmarks/estimate.py --objective time --fit`` (2026-11-27, load 5-7, 5 m/s, 10 s a
#: turn): ``"cover-region"`` on 14 stars of 10-2000 vertices and 9-91 lanes, estimate /
#: measured 0.47-1.58; ``"cover"`` (``beta`` held at 1) on 16 convex polygons of 10-2000
#: vertices and 10-300 lanes, 0.16-6.6, median 1.12 (its measured times are irregular: a
#: 1000-vertex polygon took 0.37 s at 10 lanes and 10.2 s at 40). With ``keep_inside`` every
#: plan the search evaluates carries its boundary passes: the estimate is multiplied by
#: :data:`KEEP_INSIDE_FACTOR`, fitted on ``benchmarks/keep_inside_speed.py --random 6``
#: (2026-11-27, load 5: CPU / the row's estimate 0.75-0.99 on Fields2Cover's three concave
#: fields, where the decomposition is screened out, 2.3-4.3 on six random areas with holes,
#: 3.5 on ``test.json``, 4.6 on the 200-vertex star): 2, the middle of that range, leaves the
#: estimate within a factor 2.7 of the CPU measured (it was 10 when every cell was searched
#: with and without keep-inside: measured 4.3-21x then).
KEEP_INSIDE_FACTOR = 2.0
#: ``(c, kappa, gamma)``: the doublings of the certified region search's budget
#: (``"region-certified"``): ``(REGION_EXTEND - 1) c L^kappa n^gamma`` seconds more. A search
#: whose gap keeps shrinking at its budget doubles it, up to
#: :data:`~boustro.optimize.smith_bb.region.REGION_EXTEND` times (8; 16,
#: ``REGION_EXTEND_POOLED``, where its boxes keep the pooled split bound, as in the fit's runs
#: at 2-4 m: the fitted ``c`` holds that, the 8 is only a scale), and its boxes cost more
#: with more lines (the strips and the split choices are per line; the budget counts edges): on
#: a large noisy area at a fine spacing the search spends its whole extended budget (issue 21's
#: field, 2120 vertices, at 3 m: the row alone said 7.2 s, ``plan_area`` took 48.6 s, 33.8 s
#: since the thirteenth round). Fitted (least squares on the log, the row held) on 20
#: ``plan_area`` runs (2026-11-28, load 7-11, CPU s): the nine areas of
#: ``benchmarks/region_certified.py`` and traced fields of 500-2000 vertices with 0 or 10 holes
#: at 2-10 m: estimate / measured 0.40-3.63 (the row alone 0.21-2.43); on the traced fields with
#: holes 0.50-1.38 (the row alone 0.21-0.82), without holes 3.6 (a plan without cells);
#: docs/concave.md, "The estimate before planning".
REGION_EXTENDED = (1.14e-6, 1.26, 0.92)
#: ``(c, kappa, gamma)``: an area with ``h`` holes planned by the cover search
#: (``"cover-region"``) adds ``c h^kappa n^gamma`` seconds (the passes around the holes and the
#: moves past them in every plan the search makes, and the plans they add). The
#: ``"cover-region"`` row was fitted on stars without holes; on issue 21's traced fields it said
#: 5.3-55 s for 8.8-83 s measured (0.27-0.66x) on 2026-11-27, when ``(0.0467, 0.25, 0.75)``
#: was fitted. Since then the searches got 2-4x faster on big fields (a simplified sandwich's
#: plans ruled out by their exact bound, a partial last round, the holes wider than the
#: spacing as rigid cuts) and the row over-estimated them (38.9 s for 9.4 s at 2000 vertices,
#: 105 s for 22.1 s at 5000). Refitted (least squares on the log, ``gamma`` held at 0: the
#: time per hole no longer grows with the vertices, the big areas' searches run on
#: simplified sandwiches) on ``benchmarks/scale.py --part time`` (2026-11-28, load 8-13, 5 m/s,
#: 10 s a turn, 10 m): traced fields of 500, 1000, 2000, 5000 vertices with 10 holes (11.9,
#: 11.7, 9.4, 22.1 s) and of 500 and 2000 with 2 (6.4, 9.9 s): estimate / measured 0.72,
#: 0.87, 1.71, 2.62, 0.92, 1.29 (the 5000-vertex field's estimate is the row's ``n^2.06``,
#: fitted on stars of at most 2000 vertices: 54.7 s alone; not refitted). A small area with
#: one hole gains about 0.3 s.
COVER_HOLES = (0.315, 1.0, 0.0)

#: Above this many (hull) vertices the certified optimiser's work is over its limit whatever
#: the spacing (at least ``n^3 (n - 1)``), so :func:`global_work` is not computed.
_CERTIFIED_VERTICES = 100


class WorkEstimate(NamedTuple):
    """What planning an area will take, estimated before it starts."""

    lanes: float  #: the convex hull's width at the worst angle (its diameter) / spacing
    vertices: int  #: of the ring and the holes
    holes: int
    area_km2: float  #: ground area, km^2
    kind: str  #: the row of :data:`COST_MODEL`: "certified", "certified-bb", "convex",
    #: "concave" (the grid), "region-certified", "cover", "cover-region"
    work: float  #: the certified optimiser's work (0 unless ``kind == "certified"``)
    seconds: float  #: estimated planning time on a machine like the calibration's

    @property
    def concave(self) -> bool:
        return self.kind in ("concave", "region-certified", "cover-region")

    def describe(self) -> str:
        """``"planning ~N lanes over V vertices, estimated T s"``."""
        return (
            f"planning ~{self.lanes:.0f} lanes over {self.vertices} vertices"
            f"{f' ({self.holes} holes)' if self.holes else ''}, estimated {self.seconds:.3g} s"
        )


def estimate_seconds(
    kind: str, vertices: int, lanes: float, work: float = 0.0, holes: int = 0
) -> float:
    """The cost model :data:`COST_MODEL` (row ``kind``) at ``vertices``, ``lanes``, ``work``;
    with ``holes`` the cover search's time per hole (:data:`COVER_HOLES`); the certified region
    search's with the doublings of its budget (:data:`REGION_EXTENDED`)."""
    if kind == "certified":
        a, b = COST_MODEL["certified"]
        return a + b * work
    a, c1, beta, c2, alpha = COST_MODEL[kind]
    n = max(vertices, 3)
    out = a + c1 * max(lanes, 1.0) ** beta + c2 * n**alpha
    if kind == "cover-region" and holes > 0:
        c3, kappa, gamma = COVER_HOLES
        out += c3 * holes**kappa * n**gamma
    if kind == "region-certified":  # the doublings of the search's budget
        c3, kappa, gamma = REGION_EXTENDED
        out += (region_search.REGION_EXTEND - 1.0) * c3 * max(lanes, 1.0) ** kappa * n**gamma
    return out


def frame_estimate(
    frame: Frame, method: str | None = None, *, cover: bool = False, keep_inside: bool = False
) -> WorkEstimate:
    """The estimate for a projected area (step 1 of :func:`plan_area`) and ``method``; with
    ``cover``, for a plan-level objective (the cover search: mission time, fewest transects
    on a concave area), with ``keep_inside`` as :func:`plan_area`'s."""
    s_plan = frame.sensor.spacing * frame.proj.scale_min
    lanes = frame.surveyed.diameter / s_plan  # the hull's diameter: its widest extent
    vertices = len(frame.ring) + sum(len(h) for h in frame.holes)
    kind, work = ("concave" if frame.region is not None else "convex"), 0.0
    if cover:
        kind = "cover-region" if kind == "concave" else "cover"
    elif kind == "concave" and method in (None, DEFAULT_METHOD, SCALE_METHOD):
        kind = "region-certified"  # mission.region_certified (Eq. 1; the grid otherwise)
    elif kind == "convex" and method == SCALE_METHOD:
        kind = "certified-bb"
    elif kind == "convex" and (method or DEFAULT_METHOD) == "global":
        kind = "certified-bb"  # beyond the event method's limit (mission.steps)
        if len(frame.poly) <= _CERTIFIED_VERTICES:
            w = global_work(frame.poly.vertices, s_plan)
            if w <= WORK_LIMIT:
                kind, work = "certified", w
    return WorkEstimate(
        lanes=float(lanes),
        vertices=int(vertices),
        holes=len(frame.holes),
        area_km2=float(frame.ground_area) / 1e6,
        kind=kind,
        work=float(work),
        seconds=estimate_seconds(kind, vertices, lanes, work, holes=len(frame.holes))
        * (KEEP_INSIDE_FACTOR if keep_inside and cover else 1.0),
    )


def _cause(frame: Frame, est: WorkEstimate) -> str:
    """The usual cause of an absurd area, as a hint (empty when nothing points to one)."""
    if not frame.proj.geographic:
        return ""
    ring = frame.area.ring
    span = float(max(ring[:, 0].max() - ring[:, 0].min(), ring[:, 1].max() - ring[:, 1].min()))
    if est.area_km2 > MAX_AREA_KM2 or span > 1.0:
        return (
            f"; the coordinates span {span:.3g} degrees: a planar file read as longitude/"
            "latitude? (give its CRS with --crs, e.g. an EPSG code or 'planar'; or are "
            "longitude and latitude swapped?)"
        )
    return ""


def refusals(est: WorkEstimate) -> list[str]:
    """Why ``est`` is absurd (empty when it is not): more than :data:`MAX_LANES` lanes, an area
    over :data:`MAX_AREA_KM2` km^2, or an estimated time over :data:`MAX_SECONDS` s for an
    area larger than a real field (:data:`FIELD_AREA_KM2`, :data:`FIELD_LANES`; a real field
    is never refused for its time: it is told the estimate and shown progress). Each number is
    named once: the time's reason (the area and lanes) leaves out what a first reason named."""
    why = []
    many_lanes, large = est.lanes > MAX_LANES, est.area_km2 > MAX_AREA_KM2
    if many_lanes:
        why.append(f"~{est.lanes:.3g} lanes (more than {MAX_LANES})")
    if large:
        why.append(f"an area of {est.area_km2:.3g} km^2 (more than {MAX_AREA_KM2:.0f})")
    if est.seconds > MAX_SECONDS and (est.area_km2 > FIELD_AREA_KM2 or est.lanes > FIELD_LANES):
        size = [f"{est.area_km2:.3g} km^2"] * (not large) + [f"~{est.lanes:.3g} lanes"] * (
            not many_lanes
        )
        why.append(
            f"an estimated {est.seconds:.3g} s (more than {MAX_SECONDS:.0f})"
            + (f" for {' and '.join(size)}" if size else "")
        )
    return why


def _listed(items: list[str]) -> str:
    """``"a"``, ``"a and b"``, ``"a, b and c"``."""
    return " and ".join([", ".join(items[:-1]), items[-1]] if len(items) > 1 else items)


def check_work(
    frame: Frame,
    method: str | None = None,
    force: bool = False,
    *,
    cover: bool = False,
    keep_inside: bool = False,
) -> WorkEstimate:
    """The estimate for ``frame``; unless ``force``, :class:`TooMuchWorkError` when it is
    absurd (:func:`refusals`), in one line that names the numbers and the usual cause. Beyond
    the hard limit (:data:`~boustro._validate.MAX_TRANSECTS` lanes) it is refused even with
    ``force``, in the words of that limit, with the cause."""
    est = frame_estimate(frame, method, cover=cover, keep_inside=keep_inside)
    where = frame.area.source or "area"
    spacing = frame.sensor.spacing
    if est.lanes > MAX_TRANSECTS:
        raise TooMuchWorkError(
            f"{where}: spacing {spacing:g} is too small for an area {est.lanes * spacing:.6g} "
            f"across: about {est.lanes:.3g} transects, more than the {MAX_TRANSECTS} boustro "
            f"handles{_cause(frame, est)}"
        )
    why = [] if force else refusals(est)
    if why:
        raise TooMuchWorkError(
            f"{where}: refusing to plan {est.vertices} vertices at spacing {spacing:g}: "
            f"{_listed(why)}{_cause(frame, est)}; give --force to plan anyway"
        )
    return est
