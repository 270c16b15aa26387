"""Coordinate systems: projections, geographic checks, ground spacing, plan_area, area reading."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pyproj
import pytest

from boustro.errors import (
    InvalidParameterError,
    InvalidPolygonError,
    NonConvexPolygonError,
    PolygonFileError,
)
from boustro.geo import check_lonlat, parse_crs, plan_area, projection_for, utm_crs
from boustro.geometry import Polygon
from boustro.io import Area, area_from_text, embedded_field, read_area
from boustro.sensors import Camera

_DATA = Path(__file__).resolve().parent / "data"

FAST: dict = {}  # the default (certified global) optimiser is fast enough for tests
GEOD = pyproj.Geod(ellps="WGS84")


def _rectangle(lon: float, lat: float, width_m: float, height_m: float, tilt: float = 20.0):
    """A tilted rectangle of the given size around (lon, lat), as a lon/lat ring."""
    corners = []
    for az, dist in [(-1, -1), (1, -1), (1, 1), (-1, 1)]:
        x, y = az * width_m / 2, dist * height_m / 2
        r = math.radians(tilt)
        x, y = x * math.cos(r) - y * math.sin(r), x * math.sin(r) + y * math.cos(r)
        azimuth = math.degrees(math.atan2(x, y))
        lon2, lat2, _ = GEOD.fwd(lon, lat, azimuth, math.hypot(x, y))
        corners.append((lon2, lat2))
    return np.array(corners)


def test_utm_zones():
    assert utm_crs(6.06, 51.5) == "EPSG:32632"
    assert utm_crs(5.99, 51.5) == "EPSG:32631"
    assert utm_crs(-0.1, 51.5) == "EPSG:32630"
    assert utm_crs(151.2, -33.9) == "EPSG:32756"
    assert utm_crs(-180.0, 0.0) == "EPSG:32601"
    assert utm_crs(180.0, 0.0) == "EPSG:32660"
    assert utm_crs(10.0, 85.0) == "EPSG:32661"
    assert utm_crs(10.0, -85.0) == "EPSG:32761"


@pytest.mark.parametrize(
    ("lon", "lat"),
    [(6.06, 51.51), (151.2, -33.9), (-70.6, -33.4), (-2.99, 0.01), (17.9, 78.2), (30.0, -84.5)],
)
def test_lonlat_round_trip(lon, lat):
    ring = _rectangle(lon, lat, 900.0, 500.0)
    proj = projection_for(ring, "EPSG:4326")
    rng = np.random.default_rng(0)
    pts = ring[0] + rng.uniform(-0.01, 0.01, size=(200, 2))
    metric = proj.to_plan(pts)
    assert np.ptp(metric[:, 0]) > 100  # really metres, not degrees
    back = proj.to_source(metric)
    assert np.max(np.abs(back - pts)) < 1e-9
    np.testing.assert_allclose(proj.to_lonlat(metric), pts, atol=1e-9, rtol=0)


def test_field_round_trip_and_scale():
    area = embedded_field()
    proj = projection_for(area.ring, area.crs)
    assert proj.plan_crs == "EPSG:32632"
    assert np.max(np.abs(proj.to_source(proj.to_plan(area.ring)) - area.ring)) < 1e-9
    # UTM zone 32 at 6.06 E: about 2.9 degrees west of the central meridian, k ~ 1.00011.
    assert 1.0001 < proj.scale_min <= proj.scale <= proj.scale_max < 1.00012
    assert proj.scale_max / proj.scale_min - 1 < 1e-5


@pytest.mark.parametrize(
    ("ring", "match"),
    [
        ([(0, 0), (1, 0), (1, 91)], "latitude 91 at vertex 3 is outside"),
        ([(0, 0), (181, 0), (1, 1)], "longitude 181 at vertex 2 is outside"),
        ([(179.9, 0), (-179.9, 0), (-179.9, 0.1), (179.9, 0.1)], "crosses the antimeridian"),
        ([(0, 85), (90, 85), (180, 85), (-90, 85)], "encloses the North Pole"),
        ([(0, -89), (120, -89), (-120, -89)], "encloses the South Pole"),
        ([(0, 89), (10, 90), (20, 89)], "on a pole"),
        ([(0, 0), (float("nan"), 0), (1, 1)], "finite"),
    ],
)
def test_bad_lonlat(ring, match):
    with pytest.raises(InvalidPolygonError, match=match):
        check_lonlat(ring)
    with pytest.raises(InvalidPolygonError, match=match):
        plan_area(Area(np.array(ring, float), "EPSG:4326", "", "<test>"), 10.0)


def test_parse_crs():
    assert parse_crs(None) is None
    assert parse_crs("planar") is None
    assert parse_crs(28992) == "EPSG:28992"
    assert parse_crs("EPSG:4326") == "EPSG:4326"
    with pytest.raises(InvalidParameterError, match="unknown coordinate reference system"):
        parse_crs("EPSG:999999")
    with pytest.raises(InvalidParameterError, match="neither geographic"):
        parse_crs("EPSG:4978")  # geocentric


def _ground_spacings(mission) -> np.ndarray:
    """Geodesic distance between neighbouring transects, measured on the ellipsoid."""
    plan, proj = mission.plan, mission.projection
    n = np.array([-math.sin(plan.angle), math.cos(plan.angle)])
    out = []
    for a, b in zip(plan.transects[:-1], plan.transects[1:], strict=True):
        mid = a.mean(axis=0)
        foot = mid + float((b[0] - mid) @ n) * n  # on b's line, perpendicular from a's middle
        out.append(float(proj.ground_distance(mid, foot)))
    return np.array(out)


@pytest.mark.parametrize(("lon", "lat"), [(6.06, 51.51), (-68.9, -54.8), (2.99, 10.0)])
def test_transects_have_the_spacing_on_the_ground(lon, lat):
    ring = _rectangle(lon, lat, 600.0, 350.0, tilt=33.0)
    mission = plan_area(ring, 12.5, options=FAST, check_coverage=False)
    measured = _ground_spacings(mission)
    assert len(measured) >= 20
    # Never wider than asked (coverage), and narrower only by the scale's variation.
    assert np.all(measured <= 12.5 * (1 + 1e-9))
    assert np.all(measured >= 12.5 * (1 - 1e-5))


def test_embedded_field_spacing_coverage_and_statistics():
    mission = plan_area(embedded_field(), 10.0, options=FAST)
    assert mission.coverage is not None and mission.coverage.covered_share >= 1 - 1e-9
    measured = _ground_spacings(mission)
    assert measured == pytest.approx(np.full(len(measured), 10.0), rel=1e-5)
    assert np.all(measured <= 10.0 * (1 + 1e-9))
    # Area on the ellipsoid (the Fields2Cover README calls it 3.6 ha).
    assert mission.stats.area == pytest.approx(35955, abs=5)
    assert 0 < mission.hull_depth < 0.5
    # Statistics in metres on the ground: path length equals geodesic sum of the legs.
    legs = [
        GEOD.inv(a[0], a[1], b[0], b[1])[2]
        for a, b in zip(mission.waypoints_lonlat[:-1], mission.waypoints_lonlat[1:], strict=True)
    ]
    assert mission.stats.path_length == pytest.approx(sum(legs), rel=1e-6)
    # Results in the input's coordinates: lon/lat near the field.
    assert np.all(np.abs(mission.waypoints - (6.0637, 51.512)) < 0.01)
    np.testing.assert_allclose(mission.waypoints, mission.waypoints_lonlat, atol=1e-12)
    assert 0 <= mission.bearing < 180


def test_projected_crs_in_and_out():
    field = embedded_field()
    rd = pyproj.Transformer.from_crs("EPSG:4326", "EPSG:28992", always_xy=True)
    x, y = rd.transform(field.ring[:, 0], field.ring[:, 1])
    area = Area(np.stack([x, y], axis=1), "EPSG:28992", "rd", "<test>")
    mission = plan_area(area, 10.0, options=FAST)
    assert mission.projection.plan_crs == "EPSG:28992"
    assert mission.coverage.covered_share >= 1 - 1e-9
    # Waypoints come back in RD New metres, and agree with their lon/lat.
    assert np.all((mission.waypoints[:, 0] > 1e5) & (mission.waypoints[:, 1] > 3e5))
    lon, lat = pyproj.Transformer.from_crs("EPSG:28992", "EPSG:4326", always_xy=True).transform(
        mission.waypoints[:, 0], mission.waypoints[:, 1]
    )
    np.testing.assert_allclose(np.stack([lon, lat], 1), mission.waypoints_lonlat, atol=1e-9)
    measured = _ground_spacings(mission)
    assert np.all(measured <= 10.0 * (1 + 1e-9)) and np.all(measured >= 10.0 * (1 - 1e-4))


def test_planar_area():
    ring = np.array([(0, 0), (120, 0), (130, 70), (10, 80)], dtype=float)
    mission = plan_area(ring, 7.0, crs=None, options=FAST)
    assert mission.projection.planar and mission.waypoints_lonlat is None
    np.testing.assert_array_equal(mission.waypoints, mission.plan.waypoints)
    assert np.diff(np.sort(mission.plan.positions)) == pytest.approx(7.0)
    assert mission.stats.area == pytest.approx(9050.0)


def test_start_point_in_input_coordinates():
    field = embedded_field()
    corner = field.ring[np.argmax(field.ring[:, 0])]  # the easternmost vertex
    mission = plan_area(field, 10.0, start=corner, options=FAST, check_coverage=False)
    first = mission.waypoints_lonlat[0]
    dist_first = GEOD.inv(first[0], first[1], corner[0], corner[1])[2]
    for other in (mission.transects_lonlat[0, 1], mission.transects_lonlat[-1, 0]):
        assert dist_first <= GEOD.inv(other[0], other[1], corner[0], corner[1])[2] + 1e-6
    np.testing.assert_allclose(mission.home_lonlat, corner, atol=1e-9)


def test_hull_tolerance_and_concave_areas():
    # Issue 7 changed this: a concave area beyond the hull tolerance is planned as a concave
    # area (decomposed where that pays) instead of being refused.
    hulled = plan_area(embedded_field(), 10.0, options=FAST, check_coverage=False)
    assert hulled.hull_depth > 0 and hulled.plan.region is None
    exact = plan_area(embedded_field(), 10.0, hull_tolerance=0.1, options=FAST)
    assert exact.hull_depth == 0 and exact.plan.region is not None
    assert exact.coverage.covered_share >= 1 - 1e-9
    ell = np.array([(0, 0), (200, 0), (200, 100), (100, 100), (100, 200), (0, 200)], float)
    single = plan_area(ell, 10.0, crs=None, decompose=False)
    assert single.plan.stats.n_cells == 1 and single.coverage.covered_share >= 1 - 1e-9
    mission = plan_area(ell, 10.0, crs=None, decompose=True, sweep=135.0)
    assert mission.plan.stats.n_cells == 2 and mission.coverage.covered_share >= 1 - 1e-9
    assert mission.summary()["n_cells"] == 2 and mission.optimum.method == "decomposed"
    with pytest.raises(NonConvexPolygonError, match=r"hull tolerance 0\.1"):
        from boustro.plan import nearly_convex

        nearly_convex(Polygon(ell), 0.1)


def test_camera_sets_spacing_and_altitude():
    cam = Camera(13.2, 8.8, 5472, gsd=1.0, side_overlap=0.75)
    mission = plan_area(embedded_field(), cam, options=FAST, check_coverage=False)
    spacing = cam.spacing()
    assert mission.spacing == pytest.approx(spacing.spacing)
    assert mission.altitude == pytest.approx(spacing.altitude)
    assert "GSD 1.00 cm/px" in mission.sensor


def test_read_area_formats(tmp_path):
    field = embedded_field()
    ring = field.ring.tolist()
    wkt = "POLYGON ((" + ", ".join(f"{x!r} {y!r}" for x, y in ring) + "))"
    kml = (
        '<?xml version="1.0"?><kml xmlns="http://www.opengis.net/kml/2.2"><Placemark>'
        "<name>parcel</name><Polygon><outerBoundaryIs><LinearRing><coordinates>"
        + " ".join(f"{x!r},{y!r},0" for x, y in ring)
        + "</coordinates></LinearRing></outerBoundaryIs></Polygon></Placemark></kml>"
    )
    pairs = "[" + ", ".join(f"[{x!r}, {y!r}]" for x, y in ring) + "]"
    for name, text in [("a.wkt", wkt), ("a.kml", kml), ("a.json", pairs), ("a.txt", wkt)]:
        path = tmp_path / name
        path.write_text(text)
        area = read_area(path)
        np.testing.assert_array_equal(area.ring, field.ring)
        assert area.crs == "EPSG:4326"
    assert read_area(tmp_path / "a.kml").name == "parcel"
    assert read_area(tmp_path / "a.wkt").name == "a"
    ewkt = area_from_text("SRID=28992;POLYGON Z ((0 0 1, 10 0 1, 10 10 1, 0 0 1))")
    assert ewkt.crs == "EPSG:28992" and ewkt.ring.shape == (3, 2)
    assert area_from_text(wkt, crs="EPSG:4258").crs == "EPSG:4258"
    gml = read_area(_DATA / "Envelope.xml")
    assert gml.crs == "EPSG:4258" and len(gml.ring) == 12


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ('{"type": "FeatureCollection", "features": []}', "holds no Polygon"),
        ('{"type": "Point", "coordinates": [0, 0]}', "expected a Polygon"),
        ("<kml><Document/></kml>", "no Polygon"),
        ("POINT (1 2)", "expected a WKT POLYGON"),
        ("POLYGON EMPTY", "EMPTY"),
        ("just some words", "not a polygon file"),
        ("", "empty"),
        ("[[0, 0], [1, 1]]", "at least 3 vertices"),
    ],
)
def test_area_without_polygon(text, match):
    with pytest.raises(PolygonFileError, match=match):
        area_from_text(text)
