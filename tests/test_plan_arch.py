"""The plan part of the restructuring: old import paths, shims and the new packages."""

from __future__ import annotations

import importlib
import subprocess
import sys

import numpy as np
import pytest

import boustro.decompose
import boustro.formats
import boustro.geo
import boustro.io
import boustro.mission
import boustro.plan
import boustro.plot
import boustro.plot_plan
import boustro.routing
from boustro.plan import PlanOptions, coverage, plan_region

OLD_NAMES = {
    "boustro.plan": [
        "KINDS",
        "Coverage",
        "Plan",
        "PlanCell",
        "PlanStats",
        "build_plan",
        "convex_hull",
        "coverage",
        "edge_offset",
        "footprint",
        "guaranteed_segments",
        "hull_depth",
        "nearly_convex",
        "swath_polygons",
    ],
    "boustro.decompose": [
        "Decomposition",
        "Lanes",
        "Trapezoids",
        "choose_sweep",
        "decompose",
        "optimize_region",
        "plan_region",
        "region_lanes",
        "trapezoids",
        "SWEEP_SEARCH",
        "ORDER_BUDGET",
    ],
    "boustro.routing": ["Route", "Router"],
    "boustro.geo": [
        "DEFAULT_HULL_TOLERANCE",
        "DEFAULT_METHOD",
        "LONLAT",
        "METHOD_OPTIONS",
        "REGION_OPTIONS",
        "MissingDependencyError",
        "Mission",
        "Projection",
        "check_lonlat",
        "parse_crs",
        "plan_area",
        "projection_for",
        "utm_crs",
        "FALLBACK_METHOD",
    ],
    "boustro.io": [
        "EMBEDDED_FIELD",
        "LONLAT",
        "PAPER_PARALLELOGRAM",
        "PAPER_SPACING",
        "Area",
        "area_from_json",
        "area_from_kml",
        "area_from_text",
        "area_from_wkt",
        "atomic_write",
        "embedded_field",
        "polygon_from_json",
        "read_area",
        "read_polygon",
    ],
    "boustro.formats": [
        "FORMATS",
        "MAV_CMD_NAV_WAYPOINT",
        "MAV_FRAME_GLOBAL_RELATIVE_ALT",
        "atomic_write",
        "format_for",
        "render",
        "write_mission",
        "to_geojson",
        "to_kml",
        "to_gpx",
        "to_csv",
        "to_qgc_plan",
        "to_wpl",
        "_xml_text",
    ],
    "boustro.plot": ["plot_layout"],
    "boustro.plot_plan": ["nice_length", "plot_plan"],
}


@pytest.mark.parametrize("module", sorted(OLD_NAMES))
def test_old_names_importable(module):
    mod = importlib.import_module(module)
    for name in OLD_NAMES[module]:
        assert hasattr(mod, name), f"{module}.{name}"


def test_alias_shims_are_the_new_modules():
    assert boustro.routing is importlib.import_module("boustro.plan.routing")
    assert boustro.formats is importlib.import_module("boustro.io.formats")
    assert boustro.plot_plan is importlib.import_module("boustro.plot.plan")


def test_geo_shim_shares_the_settings():
    # monkeypatch.setitem(geo.METHOD_OPTIONS, ...) must reach plan_area
    assert boustro.geo.METHOD_OPTIONS is boustro.mission.METHOD_OPTIONS
    assert boustro.geo.REGION_OPTIONS is boustro.mission.REGION_OPTIONS
    assert boustro.geo.plan_area is boustro.mission.plan_area
    assert boustro.decompose.plan_region is boustro.plan.plan_region


def test_every_module_has_all():
    for name in [
        "boustro.plan",
        "boustro.plan.types",
        "boustro.plan.convex",
        "boustro.plan.coverage",
        "boustro.plan.hull",
        "boustro.plan.cells",
        "boustro.plan.region_opt",
        "boustro.plan.lanes",
        "boustro.plan.tour",
        "boustro.plan.routing",
        "boustro.plan.region",
        "boustro.io",
        "boustro.io.read",
        "boustro.io.crs",
        "boustro.io.formats",
        "boustro.mission",
        "boustro.plot",
        "boustro.plot.layout",
        "boustro.plot.plan",
        "boustro.geo",
        "boustro.decompose",
    ]:
        mod = importlib.import_module(name)
        for public in mod.__all__:
            assert hasattr(mod, public), f"{name}.{public}"


def test_plan_package_loads_no_edge():
    code = (
        "import sys, boustro.plan; "
        "bad = [m for m in ('shapely', 'matplotlib', 'pyproj', 'boustro.io', 'boustro.mission') "
        "if m in sys.modules]; print(bad); sys.exit(bool(bad))"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_plan_options_are_checked_once():
    u_shape = [(0, 0), (9, 0), (9, 9), (6, 9), (6, 3), (3, 3), (3, 9), (0, 9)]
    plan = plan_region(u_shape, 1.0, turnaround=0.5, decompose_area=True)
    assert coverage(plan).covered_share == pytest.approx(1.0)
    assert set(plan.kinds) <= {"run_in", "start", "end", "run_out", "via", "loop"}
    with pytest.raises(Exception, match="reach must be"):
        plan_region(u_shape, 1.0, reach=0.1)
    opts = PlanOptions(spacing=1.0, reach=0.5)
    with pytest.raises(AttributeError):
        opts.spacing = 2.0  # type: ignore[misc]


def test_coverage_convex_and_general_paths_agree():
    # One coverage code path: a convex plan measured directly and as a region agree.
    from boustro.plan import build_plan
    from boustro.regions import Region

    square = np.array([(0, 0), (10, 0), (10, 10), (0, 10)], dtype=float)
    plan = build_plan(square, 1.5, 0.3, 0.2, nadir_gap=0.2, reach=1.0)
    a = coverage(plan)
    b = coverage(plan, Region(square, [np.array([(4, 4), (5, 4), (5, 5), (4, 5)], float)]))
    assert a.swept_area == pytest.approx(b.swept_area)
    assert a.area == pytest.approx(b.area + 1.0)
