"""Property tests (hypothesis): coverage, the certificate, symmetries, read-write-read.

Profiles: ``ci`` (the default run: 30 examples per property, no deadline, derandomised so that
every run tries the same examples) and ``slow`` (300 examples). The ``*_slow`` copies of every
property are marked ``@pytest.mark.slow`` and run under the ``slow`` profile with ``-m slow``;
``BOUSTRO_HYPOTHESIS_PROFILE=slow`` also runs the default copies with the ``slow`` profile.

Strategies: convex polygons (hulls of points on a circle at random angles and radii, at a random
centre and scale), concave regions with holes (:func:`boustro.geometry.region.random_region`
around a drawn seed and sizes), spacings relative to the diameter, objectives ``smith`` and
``fewest_transects``.
"""

from __future__ import annotations

import math
import os

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from boustro.geometry import Polygon
from boustro.geometry.region import Region, random_region
from boustro.io import Area, read_area
from boustro.io.formats import write_mission
from boustro.mission import plan_area
from boustro.objectives import get_objective
from boustro.objectives.turns import coverage_count
from boustro.optimize import grid_search, optimize
from boustro.optimize.fixed_angle import optimize_offset
from boustro.plan import build_plan, plan_region, swath_polygons

_COMMON = {
    "deadline": None,
    "derandomize": True,
    "database": None,
    "suppress_health_check": [HealthCheck.too_slow, HealthCheck.filter_too_much],
}
settings.register_profile("ci", max_examples=25, **_COMMON)
settings.register_profile("slow", max_examples=300, **_COMMON)
CI = settings.get_profile(os.environ.get("BOUSTRO_HYPOTHESIS_PROFILE", "ci"))
SLOW = settings.get_profile("slow")


def _twice(check, *strategies):
    """The property ``check`` under the default profile and, marked slow, under ``slow``."""
    ci = settings(CI)(given(*strategies)(check))
    slow = pytest.mark.slow(settings(SLOW)(given(*strategies)(check)))
    return ci, slow


# --- strategies -------------------------------------------------------------------------------


@st.composite
def convex_polygons(draw) -> Polygon:
    """The hull of 3..10 points on a circle (random angles and radii), any size, centred within
    1000 sizes of the origin."""
    n = draw(st.integers(3, 10))
    angles = draw(st.lists(st.floats(0, 2 * math.pi), min_size=n, max_size=n))
    radii = draw(st.lists(st.floats(0.3, 1.0), min_size=n, max_size=n))
    scale = draw(st.floats(0.01, 1e4))
    # At most 1000 sizes from the origin: farther, the rounding of absolute coordinates alone
    # exceeds the 1e-9 relative area of the coverage check (a 0.3-wide triangle at y = 65536
    # left 1.1e-9 of its area between swaths that meet up to one ulp).
    centre = np.array(draw(st.tuples(st.floats(-1e3, 1e3), st.floats(-1e3, 1e3)))) * scale
    pts = np.stack([np.cos(angles) * radii, np.sin(angles) * radii], axis=1)
    hull = shapely.MultiPoint(pts).convex_hull
    assume(hull.geom_type == "Polygon" and hull.area > 0.05)
    ring = np.asarray(hull.exterior.coords)[:-1]
    # Drop nearly collinear vertices (the hull keeps none exactly, but keep them well apart).
    assume(len(ring) >= 3 and np.min(np.linalg.norm(np.diff(ring, axis=0), axis=1)) > 1e-3)
    return Polygon(ring * scale + centre)


@st.composite
def regions(draw) -> Region:
    """A concave region with 0..3 holes from the project's generator (seed and sizes drawn)."""
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    return random_region(
        rng,
        draw(st.integers(5, 16)),
        draw(st.integers(0, 3)),
        roughness=draw(st.floats(0.2, 0.7)),
    )


spacings = st.floats(0.02, 0.3)  # relative to the diameter
objectives = st.sampled_from(["smith", "fewest_transects"])
angles = st.floats(0, math.pi, exclude_max=True)
offsets = st.floats(0, 1, exclude_max=True)  # relative to the spacing


def _uncovered(shape: shapely.Polygon, plan) -> float:
    """The area of ``shape`` that no footprint covers, relative to its area (shapely): a lane's
    footprint is its rectangle (:func:`swath_polygons`); on a pass around a hole the vehicle
    turns on the spot at the corners, so there it is every point within ``reach`` of the pass
    (a polygon inscribed in that disc-swept band: never more than it). Each footprint is cut
    from the shape in turn: GEOS's ``union_all`` of many rotated rectangles loses whole
    rectangles (GEOS 3.14; e.g. 1.70 of 2.18 units squared on a five-lane plan), the
    differences do not."""
    lane = np.asarray(plan.role()) == "lane"
    rects = swath_polygons(plan)[lane].reshape(-1, 4, 2)
    parts = [shapely.Polygon(r) for r in rects]
    parts += list(
        shapely.buffer(shapely.linestrings(plan.transects[~lane]), plan.reach, quad_segs=64)
    )
    left = shape
    for part in parts:
        left = left.difference(part)
    return left.area / shape.area


# --- coverage guarantee -----------------------------------------------------------------------


def _convex_coverage(poly: Polygon, rel: float, angle: float, offset: float) -> None:
    spacing = rel * poly.diameter
    plan = build_plan(poly, spacing, angle, offset * spacing)
    assert _uncovered(shapely.Polygon(poly.vertices), plan) <= 1e-9


test_convex_plan_covers, test_convex_plan_covers_slow = _twice(
    _convex_coverage, convex_polygons(), spacings, angles, offsets
)


def _region_coverage(region: Region, rel: float, angle: float, offset: float) -> None:
    spacing = rel * region.diameter
    plan = plan_region(region, spacing, angle=angle, offset=offset * spacing)
    shape = shapely.Polygon(region.shell.vertices, [h.vertices for h in region.holes])
    assert _uncovered(shape, plan) <= 1e-9


test_region_plan_covers, test_region_plan_covers_slow = _twice(
    _region_coverage, regions(), spacings, angles, offsets
)


# --- the certificate --------------------------------------------------------------------------


def _certificate(poly: Polygon, rel: float, name: str) -> None:
    spacing = max(rel, 0.05) * poly.diameter
    fitness = get_objective(name)
    best = optimize(poly, spacing, method="global", fitness=fitness)
    if name == "smith":  # maximised, certified by an upper bound
        dense = grid_search(poly, spacing, n_angles=90, n_offsets=16, fitness=fitness)
        assert dense.fitness <= best.fitness + best.gap + 1e-9
    else:  # minimised, exact (gap 0): the count that covers, ceil(width / s), at 720 angles
        theta = np.linspace(0, math.pi, 720, endpoint=False)
        across = poly.vertices @ np.stack([-np.sin(theta), np.cos(theta)])
        counts = [coverage_count(w, spacing) for w in np.ptp(across, axis=0)]
        assert best.info["gap"] == 0.0
        assert min(counts) >= best.fitness


test_certificate_never_beaten, test_certificate_never_beaten_slow = _twice(
    _certificate, convex_polygons(), spacings, objectives
)


# --- symmetries of the optimum ----------------------------------------------------------------


def _optimum(vertices, spacing: float, name: str):
    return optimize(vertices, spacing, method="global", fitness=get_objective(name))


def _close(a: float, b: float) -> bool:
    return math.isclose(a, b, rel_tol=1e-6, abs_tol=1e-6)


def _symmetries(poly: Polygon, rel: float, name: str, turn: float, shift, factor: float) -> None:
    spacing = max(rel, 0.05) * poly.diameter
    v = poly.vertices
    base = _optimum(v, spacing, name)
    # Clockwise input is the same polygon.
    assert _close(_optimum(v[::-1], spacing, name).fitness, base.fitness)
    # Translation and scale (the spacing scaled with the polygon).
    assert _close(_optimum(v + np.asarray(shift), spacing, name).fitness, base.fitness)
    assert _close(_optimum(v * factor, spacing * factor, name).fitness, base.fitness)
    # Rotation: the same optimum, and the optimal angle turned by the rotation (mod pi) is still
    # optimal (another angle may tie with it, so the angle itself is not compared). Eq. 1 jumps
    # where a transect starts or stops grazing a vertex and the optimum may sit on such a jump,
    # attained on one side only: the rounding of the rotation (~1e-13 rad) can move the turned
    # angle off it, so angles within 1e-9 rad of it are tried.
    c, s = math.cos(turn), math.sin(turn)
    turned = v @ np.array([[c, s], [-s, c]])
    rotated = _optimum(turned, spacing, name)
    assert _close(rotated.fitness, base.fitness)
    near = (base.angle + turn + np.linspace(-1e-9, 1e-9, 21)) % math.pi
    at_turned = [
        optimize_offset(turned, spacing, a, fitness=get_objective(name)).fitness for a in near
    ]
    assert _close(max(at_turned) if name == "smith" else min(at_turned), base.fitness)


test_optimum_symmetries, test_optimum_symmetries_slow = _twice(
    _symmetries,
    convex_polygons(),
    spacings,
    objectives,
    st.floats(-math.pi, math.pi),
    st.tuples(st.floats(-1e4, 1e4), st.floats(-1e4, 1e4)),
    st.floats(0.01, 100),
)


# --- read-write-read --------------------------------------------------------------------------


@st.composite
def lonlat_areas(draw) -> tuple[Area, float]:
    """A convex field of about 100 m to 2 km, somewhere between 70 S and 70 N, and a spacing
    (metres) of 1-20 % of its size."""
    lon = draw(st.floats(-179, 179))
    lat = draw(st.floats(-70, 70))
    poly = draw(convex_polygons())
    v = poly.vertices - poly.centre
    size = draw(st.floats(1e-3, 2e-2))  # degrees
    spacing = draw(st.floats(0.01, 0.2)) * size * 111e3 * math.cos(math.radians(lat))
    return Area(v / poly.diameter * size + (lon, lat), "EPSG:4326", "field", "<t>"), spacing


def _read_write_read(tmp_path_factory, area: Area, spacing: float) -> None:
    mission = plan_area(area, spacing)
    folder = tmp_path_factory.mktemp("rwr")
    for ext in ("geojson", "kml"):
        path = folder / f"plan.{ext}"
        write_mission(mission, path)
        back = read_area(path)
        assert back.crs == "EPSG:4326"
        ring = np.asarray(back.ring)
        if np.allclose(ring[0], ring[-1], atol=0) and len(ring) == len(area.ring) + 1:
            ring = ring[:-1]
        np.testing.assert_allclose(ring, area.ring, atol=1e-9, rtol=0)
        again = folder / f"again.{ext}"
        write_mission(plan_area(back, spacing), again)
        np.testing.assert_allclose(read_area(again).ring, back.ring, atol=1e-9, rtol=0)


@pytest.mark.parametrize(
    "profile", [pytest.param("ci"), pytest.param("slow", marks=pytest.mark.slow)]
)
def test_read_write_read(tmp_path_factory, profile):
    chosen = CI if profile == "ci" else SLOW
    small = settings(chosen, max_examples=max(10, chosen.max_examples // 3))

    @small
    @given(lonlat_areas())
    def check(case):
        _read_write_read(tmp_path_factory, *case)

    check()
