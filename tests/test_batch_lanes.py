"""The ``lanes`` layer of ``boustro batch``: ground lengths in metres whatever the CRS (a
lon/lat input wrote degrees), and each row's ``pass`` (lanes told from the passes around holes,
which coverage needs with round ends), as the GeoJSON export says them; an output of the
layer's older schema is refused, not appended to."""

from __future__ import annotations

import sqlite3

import numpy as np
import pyogrio
import pyogrio.raw
import pytest
import shapely

import boustro
from boustro.errors import InvalidParameterError
from boustro.io import areas_from_object
from boustro.io.formats import render
from boustro.mission import plan_area

# a 300 m x 220 m field in the Netherlands with a 60 m pond, longitude/latitude
_LON, _LAT = 6.06, 51.51
_DLON, _DLAT = 300 / 69_400, 220 / 111_250  # about 300 m and 220 m


def _field() -> shapely.Polygon:
    shell = shapely.box(_LON, _LAT, _LON + _DLON, _LAT + _DLAT)
    pond = shapely.box(_LON + 0.4 * _DLON, _LAT + 0.35 * _DLAT,
                       _LON + 0.6 * _DLON, _LAT + 0.62 * _DLAT)  # fmt: skip
    return shell.difference(pond)


@pytest.fixture(scope="module")
def planned(tmp_path_factory):
    folder = tmp_path_factory.mktemp("lanes")
    fields = folder / "fields.gpkg"
    pyogrio.raw.write(str(fields), np.array([shapely.to_wkb(_field())], dtype=object),
                      [np.array(["pond field"], dtype=object)], ["name"], crs="EPSG:4326",
                      geometry_type="Polygon", driver="GPKG")  # fmt: skip
    out = folder / "plans.gpkg"
    result = boustro.batch(str(fields), str(out), spacing=12.0, workers=1)
    assert result.planned == 1 and result.failed == 0
    (area,) = areas_from_object(_field(), "EPSG:4326")
    return out, plan_area(area, 12.0)


def test_lane_lengths_are_metres_on_the_ground_for_lonlat_input(planned):
    import json

    out, mission = planned
    lanes = pyogrio.read_dataframe(str(out), layer="lanes")
    exported = json.loads(render(mission, "geojson"))
    want = [f["properties"]["length_m"] for f in exported["features"]
            if f["properties"].get("role") == "transect"]  # fmt: skip
    assert len(lanes) == len(want) == len(mission.transects)
    np.testing.assert_allclose(lanes["length_m"], want, rtol=1e-12)
    assert lanes["length_m"].min() > 1.0  # metres (degrees would be below 0.01)
    fields = pyogrio.read_dataframe(str(out), layer="fields", read_geometry=False)
    lane_rows = lanes[lanes["pass"] == "lane"]
    assert lane_rows["length_m"].sum() == pytest.approx(fields["transect_length_m"][0], rel=1e-9)


def test_each_row_says_its_pass_and_lanes_and_passes_cover_the_field(planned):
    out, mission = planned
    lanes = pyogrio.read_dataframe(str(out), layer="lanes")
    fields = pyogrio.read_dataframe(str(out), layer="fields", read_geometry=False)
    assert lanes["pass"].tolist() == list(mission.plan.role())
    assert (lanes["pass"] == "lane").sum() == fields["lanes"][0] < len(lanes)  # hole passes too
    assert set(lanes["pass"]) == {"lane", "hole"}
    # coverage from the layer alone, in metres: lanes flat-ended, passes round-ended
    import pyproj

    tm = f"+proj=tmerc +lon_0={_LON + _DLON / 2} +lat_0={_LAT} +k=1 +ellps=WGS84"  # ground m
    utm = pyproj.Transformer.from_crs("EPSG:4326", tm, always_xy=True)
    field = shapely.transform(_field(), lambda xy: np.c_[utm.transform(*xy.T)])
    half = fields["spacing_m"][0] / 2
    swaths = []
    for line, kind in zip(lanes.geometry, lanes["pass"], strict=True):
        line = shapely.transform(line, lambda xy: np.c_[utm.transform(*xy.T)])
        swaths.append(line.buffer(half, cap_style="flat" if kind == "lane" else "round"))
    assert field.difference(shapely.union_all(swaths)).area < 1e-6 * field.area
    lanes_only = [w for w, kind in zip(swaths, lanes["pass"], strict=True) if kind == "lane"]
    assert field.difference(shapely.union_all(lanes_only)).area > 1e-6 * field.area


def test_geo_interface_says_each_transects_pass():
    plan = boustro.plan_area(_field(), 12.0, crs="EPSG:4326")
    kinds = [f["properties"]["pass"] for f in plan.__geo_interface__["features"]
             if f["properties"]["kind"] == "lane"]  # fmt: skip
    assert kinds == list(plan.mission.plan.role()) and "hole" in kinds


def test_an_output_of_the_older_lanes_schema_is_refused(planned, tmp_path):
    import shutil

    out, _ = planned
    old = tmp_path / "old.gpkg"
    shutil.copy(out, old)
    db = sqlite3.connect(old)
    db.execute('ALTER TABLE lanes DROP COLUMN "pass"')
    db.commit()
    db.close()
    fields = out.parent / "fields.gpkg"
    with pytest.raises(InvalidParameterError, match=r"another version of boustro.*pass"):
        boustro.batch(str(fields), str(old), spacing=12.0, workers=1)
