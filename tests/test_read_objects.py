"""Geometry objects through the API: shapely, ``__geo_interface__``, GeoJSON mappings."""

from __future__ import annotations

import subprocess
import sys
from typing import ClassVar

import numpy as np
import pytest
import shapely

from boustro.errors import InvalidParameterError, PolygonFileError
from boustro.io import area_from_object, areas_from_object
from boustro.mission import plan_area

SHELL = [(0.0, 0.0), (100.0, 0.0), (100.0, 60.0), (0.0, 60.0)]
HOLE = [(40.0, 20.0), (60.0, 20.0), (60.0, 40.0), (40.0, 40.0)]
POLY = shapely.Polygon(SHELL, [HOLE])


class Parcel:
    """A foreign object that only speaks ``__geo_interface__`` (as geopandas, fiona, ...)."""

    __geo_interface__: ClassVar[dict] = {
        "type": "Feature",
        "properties": {"name": "parcel 7"},
        "geometry": {"type": "Polygon", "coordinates": [[*SHELL, SHELL[0]]]},
    }


def test_a_shapely_polygon_is_planar_with_its_holes():
    area = area_from_object(POLY)
    assert area.crs is None
    assert area.ring.tolist() == [list(p) for p in SHELL]
    assert len(area.holes) == 1 and area.holes[0].tolist() == [list(p) for p in HOLE]


def test_an_object_and_its_mapping_plan_the_same():
    a = plan_area(POLY, 10.0)
    b = plan_area(POLY.__geo_interface__, 10.0)
    c = plan_area({"type": "Feature", "properties": {}, "geometry": POLY.__geo_interface__}, 10.0)
    assert a.plan.stats.n_transects == b.plan.stats.n_transects == c.plan.stats.n_transects > 0
    assert np.allclose(a.waypoints, b.waypoints) and np.allclose(a.waypoints, c.waypoints)


def test_a_geo_interface_object_keeps_its_name_and_crs_is_taken_from_the_caller():
    assert area_from_object(Parcel()).name == "parcel 7"
    lonlat = shapely.box(5.0, 52.0, 5.003, 52.002)
    assert area_from_object(lonlat, crs="EPSG:4326").crs == "EPSG:4326"
    mission = plan_area(lonlat, 20.0, crs="EPSG:4326")
    assert mission.area.crs == "EPSG:4326" and mission.area_lonlat is not None
    planar = plan_area(shapely.box(0, 0, 300, 200), 20.0)
    assert planar.area.crs is None and planar.area_lonlat is None


def test_a_mapping_crs_member_is_used_and_checked():
    mapping = {
        "type": "Polygon",
        "coordinates": [[[155000, 463000], [155300, 463000], [155300, 463200], [155000, 463000]]],
        "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::28992"}},
    }
    assert area_from_object(mapping).crs == "EPSG:28992"
    mapping["crs"]["properties"]["name"] = "+proj=longlat +nadgrids=/nonexistent/grid"
    with pytest.raises(PolygonFileError, match="is refused"):
        area_from_object(mapping)


def test_several_polygons_are_refused_pointing_to_the_several_field_reader():
    multi = shapely.MultiPolygon([shapely.box(0, 0, 10, 10), shapely.box(20, 0, 30, 10)])
    with pytest.raises(PolygonFileError, match=r"2 polygons .*areas_from_object"):
        plan_area(multi, 1.0)
    collection = {
        "type": "FeatureCollection",
        "features": [
            {"type": "Feature", "properties": {"name": "a"}, "geometry": g.__geo_interface__}
            for g in multi.geoms
        ],
    }
    with pytest.raises(PolygonFileError, match="several fields"):
        plan_area(collection, 1.0)
    assert [a.name for a in areas_from_object(collection)] == ["a", "a"]
    assert [a.name for a in areas_from_object(multi)] == ["field 1", "field 2"]
    (one,) = areas_from_object(shapely.MultiPolygon([shapely.box(0, 0, 10, 10)]))
    assert one.name == "" and plan_area(one, 1.0).plan.stats.n_transects >= 10  # 10 m / 1 m


def test_not_a_geometry_is_one_clear_error():
    with pytest.raises(PolygonFileError, match="no Polygon"):
        plan_area(shapely.LineString([(0, 0), (1, 1)]), 1.0)
    with pytest.raises(PolygonFileError, match="expected a GeoJSON geometry"):
        plan_area({"coordinates": []}, 1.0)
    with pytest.raises(InvalidParameterError, match="area must be an Area"):
        plan_area(object(), 1.0)
    with pytest.raises(InvalidParameterError, match="carries its own holes"):
        plan_area(POLY, 1.0, holes=[HOLE])


def test_vertices_stay_lonlat_by_default():
    ring = [(5.0, 52.0), (5.003, 52.0), (5.003, 52.002), (5.0, 52.002)]
    mission = plan_area(ring, 20.0)
    assert mission.area.crs == "EPSG:4326" and mission.area_lonlat is not None


def test_import_boustro_still_loads_no_shapely():
    code = "import sys, boustro; assert 'shapely' not in sys.modules, 'shapely loaded'"
    subprocess.run([sys.executable, "-c", code], check=True)


def test_a_crs_object_as_a_geodataframe_has_is_taken_as_its_name():
    # A GeoPandas user passes ``gdf.crs`` (a pyproj.CRS): boustro.plan_area raised
    # AttributeError ('CRS' object has no attribute 'strip') in its lon/lat check.
    import boustro

    pyproj = pytest.importorskip("pyproj")
    utm = shapely.box(500000.0, 5700000.0, 500300.0, 5700200.0)
    assert area_from_object(utm, crs=pyproj.CRS("EPSG:32632")).crs == "EPSG:32632"
    # a CRS made from a WKT (as read from a file) is still named by its code, not its WKT
    from_wkt = pyproj.CRS.from_wkt(pyproj.CRS("EPSG:32632").to_wkt())
    assert area_from_object(utm, crs=from_wkt).crs == "EPSG:32632"
    lonlat = shapely.box(5.0, 52.0, 5.003, 52.002)
    plan = boustro.plan_area(lonlat, 20.0, crs=pyproj.CRS("EPSG:4326"))
    assert plan.mission.area.crs == "EPSG:4326" and plan.mission.area_lonlat is not None
    assert plan.lanes.bounds[0] >= 4.99 and plan.lanes.bounds[3] <= 52.01  # lon/lat out
    custom = pyproj.CRS.from_proj4("+proj=tmerc +lon_0=10 +k=0.9996 +x_0=500000 +ellps=WGS84")
    assert custom.to_authority() is None
    name = area_from_object(utm, crs=custom).crs
    assert pyproj.CRS.from_user_input(name).equals(custom)
    assert boustro.plan_area(utm, 20.0, crs=custom).mission.area.crs is not None


def test_a_geo_plan_names_its_crs_for_a_geodataframe():
    # from_features(plan) has no CRS (GeoJSON carries none): plan.crs is the input's.
    import boustro

    geopandas = pytest.importorskip("geopandas")
    lonlat = shapely.box(5.0, 52.0, 5.003, 52.002)
    plan = boustro.plan_area(lonlat, 20.0, crs="EPSG:4326")
    frame = geopandas.GeoDataFrame.from_features(plan, crs=plan.crs)
    assert plan.crs == "EPSG:4326" and frame.crs.to_epsg() == 4326
    assert frame.total_bounds[0] > 4.99 and frame.total_bounds[3] < 52.01
    assert boustro.plan_area(shapely.box(0, 0, 300, 200), 20.0).crs is None
