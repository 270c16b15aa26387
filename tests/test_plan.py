"""Core plans (layer 5): coverage-guaranteed segments, waypoints, statistics, coverage."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
import shapely

from boustro.errors import InvalidParameterError, NonConvexPolygonError, NoTransectError
from boustro.geometry import Polygon
from boustro.plan import (
    KINDS,
    build_plan,
    convex_hull,
    coverage,
    edge_offset,
    guaranteed_segments,
    hull_depth,
    nearly_convex,
    swath_polygons,
)
from boustro.scoring import transect_segments
from boustro.sensors import Camera, Swath

from .conftest import random_polygons


def _random_layout(rng: np.random.Generator, poly: Polygon) -> tuple[float, float, float]:
    spacing = float(rng.uniform(0.02, 0.6)) * poly.diameter
    return spacing, float(rng.uniform(0, math.pi)), float(rng.uniform(-2, 2) * spacing)


def _band_extent(poly: Polygon, angle: float, position: float, reach: float):
    """Along-transect extent of polygon ∩ band, by shapely (the reference)."""
    u = np.array([math.cos(angle), math.sin(angle)])
    n = np.array([-math.sin(angle), math.cos(angle)])
    c, far = poly.centre, 10 * poly.diameter
    band = shapely.Polygon(
        [
            c + (position - reach) * n - far * u,
            c + (position - reach) * n + far * u,
            c + (position + reach) * n + far * u,
            c + (position + reach) * n - far * u,
        ]
    )
    piece = shapely.Polygon(poly.vertices).intersection(band)
    if piece.is_empty or piece.area == 0:
        return None
    t = (np.asarray(piece.exterior.coords) - c) @ u
    return float(t.min()), float(t.max())


def test_guaranteed_segments_match_shapely_band_projection():
    rng = np.random.default_rng(1)
    for poly in random_polygons(seed=2, count=40, low=3, high=12):
        poly = poly.scaled(100.0)
        spacing, angle, offset = _random_layout(rng, poly)
        reach = spacing / 2 * float(rng.choice([1.0, 1.0, 1.7]))
        segs = guaranteed_segments(poly, spacing, angle, offset, reach=reach)
        u = np.array([math.cos(angle), math.sin(angle)])
        for pos, seg in zip(segs.positions, segs.segments, strict=True):
            ref = _band_extent(poly, angle, pos, reach)
            assert ref is not None, "a segment for a band that misses the polygon"
            t = np.sort((seg - poly.centre) @ u)
            assert t == pytest.approx(ref, abs=1e-9 * poly.diameter)
        # No band that meets the polygon is missing.
        n = np.array([-math.sin(angle), math.cos(angle)])
        across = (poly.vertices - poly.centre) @ n
        k = np.arange(-200, 201)
        lines = offset + k * spacing
        meets = (lines - reach < across.max() - 1e-9) & (lines + reach > across.min() + 1e-9)
        assert len(segs.positions) == int(meets.sum())


def test_segments_ascend_and_alternate():
    poly = Polygon([(0, 0), (10, 0), (10, 10), (0, 10)])
    segs = guaranteed_segments(poly, 3.0, 0.0, 0.0)
    assert np.all(np.diff(segs.positions) == pytest.approx(3.0))
    directions = np.sign(segs.segments[:, 1, 0] - segs.segments[:, 0, 0])
    assert list(directions) == [1, -1, 1, -1, 1]
    # The outer lanes (line at y = -1 and y = 11) miss the square but their strips do not.
    assert segs.positions.tolist() == pytest.approx([-6, -3, 0, 3, 6])
    assert len(transect_segments(poly, 3.0, 0.0, 0.0).lengths) == 3


@pytest.mark.parametrize("turnaround", [0.0, 0.07])
def test_coverage_is_complete_on_seeded_random_polygons(turnaround):
    rng = np.random.default_rng(7)
    for poly in random_polygons(seed=11, count=60, low=3, high=12):
        spacing, angle, offset = _random_layout(rng, poly)
        plan = build_plan(
            poly, spacing, angle, offset, turnaround=turnaround, start=rng.normal(size=2)
        )
        cov = coverage(plan)
        assert cov.covered_share >= 1 - 1e-9
        assert cov.covered_area == pytest.approx(poly.area, rel=1e-9)
        assert cov.overlap_share >= -1e-9
        # The transects keep the spacing asked for.
        gaps = np.diff(np.sort(plan.positions))
        assert gaps == pytest.approx(np.full(len(gaps), spacing), rel=1e-9)


def test_chords_layout_leaves_strips_and_guaranteed_adds_at_most_two_lanes():
    rng = np.random.default_rng(3)
    worst = 1.0
    for poly in random_polygons(seed=5, count=40, low=3, high=10):
        spacing, angle, offset = _random_layout(rng, poly)
        guaranteed = build_plan(poly, spacing, angle, offset)
        try:
            chords = build_plan(poly, spacing, angle, offset, layout="chords")
        except NoTransectError:
            continue
        worst = min(worst, coverage(chords).covered_share)
        assert chords.n_transects <= guaranteed.n_transects <= chords.n_transects + 2
        assert guaranteed.stats.transect_length >= chords.stats.transect_length - 1e-9
    assert worst < 0.95  # the usual chords do leave strips uncovered


def test_coverage_survives_nearly_coincident_rectangle_edges():
    # A polygon and layout on which a plain GEOS union of the rotated footprints lost area.
    poly = Polygon(
        [
            (-116.5875452087479, 78.9890927200766),
            (-107.15012075654221, -3.9255714719251773),
            (-76.73293485238231, -75.42733660710047),
            (5.934499885531979, -147.98733131786324),
            (139.59323940794917, 3.6685776482275196),
            (154.9428615241913, 144.68256902858477),
        ]
    )
    plan = build_plan(poly, 10.0, 1.5446163880149817, 8.75)
    cov = coverage(plan)
    assert cov.covered_share == pytest.approx(1.0, abs=1e-12)
    assert cov.swept_area == pytest.approx(
        sum(shapely.Polygon(r).area for r in swath_polygons(plan).reshape(-1, 4, 2)), rel=1e-12
    )


def test_start_picks_the_nearest_corner():
    poly = Polygon([(0, 0), (100, 0), (100, 40), (0, 40)])
    for corner in [(0, 0), (100, 0), (100, 40), (0, 40)]:
        plan = build_plan(poly, 10.0, 0.0, 5.0, start=corner)
        assert np.linalg.norm(plan.waypoints[0] - corner) <= 5.0 + 1e-9
    # Default: the polygon's first (stored) vertex.
    plan = build_plan(poly, 10.0, 0.0, 5.0)
    assert np.linalg.norm(plan.waypoints[0] - poly.vertices[0]) <= 5.0 + 1e-9


def test_waypoints_turnaround_and_kinds():
    poly = Polygon([(0, 0), (100, 0), (100, 40), (0, 40)])
    plan = build_plan(poly, 10.0, 0.0, 5.0, turnaround=7.0, start=(0, 0))
    assert set(plan.kinds) <= set(KINDS)
    assert plan.kinds[:4] == ("run_in", "start", "end", "run_out")
    wp = plan.waypoints.reshape(-1, 4, 2)
    assert len(wp) == plan.n_transects == 4
    for lane, seg in zip(wp, plan.transects, strict=True):
        np.testing.assert_allclose(lane[1:3], seg)
        direction = (seg[1] - seg[0]) / np.linalg.norm(seg[1] - seg[0])
        np.testing.assert_allclose(lane[0], seg[0] - 7.0 * direction, atol=1e-12)
        np.testing.assert_allclose(lane[3], seg[1] + 7.0 * direction, atol=1e-12)
    # Boustrophedon: consecutive lanes are driven in opposite directions.
    d = plan.transects[:, 1, 0] - plan.transects[:, 0, 0]
    assert np.all(np.sign(d[1:]) == -np.sign(d[:-1]))
    assert plan.lane.tolist() == [i for i in range(4) for _ in range(4)]


def test_statistics():
    poly = Polygon([(0, 0), (100, 0), (100, 40), (0, 40)])
    plan = build_plan(poly, 10.0, 0.0, 5.0, start=(0, 0), speed=2.0, turn_time=5.0)
    s = plan.stats
    assert (s.n_transects, s.n_turns) == (4, 3)
    assert s.transect_length == pytest.approx(400.0)
    assert s.path_length == pytest.approx(400.0 + 3 * 10.0)
    assert s.area == pytest.approx(4000.0)
    assert s.duration == pytest.approx(430.0 / 2.0 + 3 * 5.0)
    scaled = build_plan(poly, 10.0, 0.0, 5.0, start=(0, 0), ground_scale=2.0, area=123.0)
    assert scaled.stats.path_length == pytest.approx(215.0)
    assert scaled.stats.area == 123.0
    assert build_plan(poly, 10.0, 0.0, 5.0).stats.duration is None


def test_edge_offset_puts_the_first_lane_half_a_spacing_inside():
    rng = np.random.default_rng(4)
    for poly in random_polygons(seed=9, count=20):
        spacing, angle, _ = _random_layout(rng, poly)
        offset = edge_offset(poly, spacing, angle)
        assert 0 <= offset < spacing
        n = np.array([-math.sin(angle), math.cos(angle)])
        low = float(np.min((poly.vertices - poly.centre) @ n))
        first = low + spacing / 2
        assert math.remainder(first - offset, spacing) == pytest.approx(0.0, abs=1e-12)


def test_nadir_gap_swath_is_covered():
    rng = np.random.default_rng(8)
    sensor = Swath(width=0.3, overlap=0.1, nadir_gap=0.04).spacing()
    for poly in random_polygons(seed=13, count=25, low=3, high=10):
        angle, offset = float(rng.uniform(0, math.pi)), float(rng.uniform(0, 1))
        plan = build_plan(
            poly,
            sensor.spacing,
            angle,
            offset,
            reach=sensor.reach,
            nadir_gap=sensor.nadir_gap,
        )
        assert coverage(plan).covered_share >= 1 - 1e-9
        # The same lanes with the gap but only spacing/2 of reach leave the gap's strips.
    thin = build_plan(
        Polygon([(0, 0), (1, 0), (1, 1), (0, 1)]), sensor.spacing, 0.0, 0.0, nadir_gap=0.04
    )
    assert coverage(thin).covered_share < 1 - 1e-3


def test_hull_of_a_nearly_convex_polygon():
    notch = Polygon([(0, 0), (10, 0), (10, 10), (5, 9.7), (0, 10)])
    assert not notch.is_convex
    assert hull_depth(notch) == pytest.approx(0.3)
    hull, depth = nearly_convex(notch, 0.5)
    assert hull.is_convex and depth == pytest.approx(0.3)
    assert hull.area == pytest.approx(100.0)
    with pytest.raises(NonConvexPolygonError, match=r"concave.*0\.3.*hull tolerance 0\.1"):
        nearly_convex(notch, 0.1)
    square = Polygon([(0, 0), (1, 0), (1, 1), (0, 1)])
    assert nearly_convex(square, 0.0) == (square, 0.0)
    np.testing.assert_allclose(
        convex_hull([(0, 0), (2, 0), (1, 0.5), (2, 2), (0, 2)]), [(0, 0), (2, 0), (2, 2), (0, 2)]
    )
    # Planning the hull covers the notched polygon completely.
    plan = build_plan(hull, 1.5, 0.3, 0.1)
    assert coverage(plan, notch).covered_share >= 1 - 1e-12


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"reach": 0.1}, "reach must be >= spacing / 2"),
        ({"turnaround": -1}, "turnaround"),
        ({"start": (0, float("nan"))}, "start"),
        ({"speed": 0}, "speed"),
        ({"layout": "zigzag"}, "layout"),
        ({"ground_scale": 0}, "ground_scale"),
    ],
)
def test_bad_parameters(kwargs, match):
    poly = Polygon([(0, 0), (1, 0), (1, 1), (0, 1)])
    with pytest.raises(InvalidParameterError, match=match):
        build_plan(poly, 0.3, 0.0, 0.0, **kwargs)


def test_concave_polygon_is_refused():
    ell = Polygon([(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)])
    with pytest.raises(NonConvexPolygonError, match="concave"):
        build_plan(ell, 0.3, 0.0, 0.0)


def test_sensor_spacings():
    cam = Camera(13.2, 8.8, 5472, altitude=80, side_overlap=0.7).spacing()
    assert cam.footprint == pytest.approx(120.0)
    assert cam.spacing == pytest.approx(36.0)
    assert cam.altitude == 80
    assert "GSD 2.19 cm/px" in cam.description
    by_gsd = Camera(13.2, 8.8, 5472, gsd=120.0 / 5472 * 100, side_overlap=0.7).spacing()
    assert by_gsd.altitude == pytest.approx(80.0)
    swath = Swath(60.0, overlap=0.1).spacing()
    assert (swath.spacing, swath.reach) == pytest.approx((54.0, 27.0))
    gap = Swath(60.0, overlap=0.0, nadir_gap=4.0).spacing()
    assert (gap.spacing, gap.reach, gap.nadir_gap) == pytest.approx((28.0, 30.0, 4.0))
    with pytest.raises(InvalidParameterError, match="exactly one of altitude"):
        Camera(13.2, 8.8, 5472).spacing()
    with pytest.raises(InvalidParameterError, match="side overlap"):
        Camera(13.2, 8.8, 5472, altitude=50, side_overlap=1.0).spacing()
    with pytest.raises(InvalidParameterError, match="nadir gap"):
        Swath(10.0, nadir_gap=10.0).spacing()


def test_plan_module_is_core():
    code = (
        "import sys, boustro.plan; "
        "bad = [m for m in ('matplotlib', 'shapely', 'pyproj', 'boustro.cli', 'boustro.io') "
        "if m in sys.modules]; print(','.join(bad))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""


def test_overlap_share_counts_a_boundary_pass_once_along_its_length():
    # A disc of radius 100 m planned with --keep-inside, its boundary traced with 40 and with 400
    # vertices: the boundary passes sweep nearly the same band, so the overlap share must not grow
    # with the vertices (buffering each short edge alone counted the round ends overlapping at
    # every joint: 0.40 and 3.10 where both are 0.10).
    from boustro.plan import plan_region
    from boustro.regions import Region

    shares = []
    for n in (40, 400):
        a = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
        plan = plan_region(Region(np.c_[100 * np.cos(a), 100 * np.sin(a)]), 10.0, keep_inside=True)
        assert "boundary" in plan.role()
        cov = coverage(plan)
        assert cov.covered_share == pytest.approx(1.0, abs=1e-9)
        shares.append(cov.overlap_share)
    assert 0.0 < shares[0] < 0.2
    assert shares[1] == pytest.approx(shares[0], abs=0.01)
