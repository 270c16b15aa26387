"""A fixed transect angle (``plan_area(angle=...)``, ``boustro plan --angle``): the angle is
kept and the offset is the best one at it, checked against dense offset scans."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import torch

from boustro.cli import main
from boustro.errors import InvalidParameterError
from boustro.geometry import Polygon, halfplanes
from boustro.geometry.region import Region
from boustro.io import embedded_field
from boustro.mission import plan_area
from boustro.objectives import FewestTransects, SmithFitness
from boustro.optimize import evaluate_grid
from boustro.optimize.fixed_angle import optimize_offset
from boustro.optimize.region_grid import evaluate_region_grid
from boustro.plan import build_plan

CONVEX = [(0, 0), (120, 0), (130, 70), (10, 80)]
L_SHAPE = [(0, 0), (60, 0), (60, 20), (20, 20), (20, 50), (0, 50)]
RING_HOLE = [(30, 30), (40, 30), (40, 40), (30, 40)]
DENSE = 4096


def _convex_scan(ring, spacing, angle, fitness):
    """Eq. 1 (or another objective) at ``DENSE`` offsets over one spacing, exact chords."""
    poly = Polygon(ring)
    frame = poly.frame
    s_n = spacing / frame.scale
    offsets = torch.arange(DENSE, dtype=torch.float64) * (s_n / DENSE)
    theta = torch.tensor([angle % math.pi], dtype=torch.float64)
    return evaluate_grid(halfplanes(poly), theta, offsets, s_n, fitness=fitness)[0].numpy()


def _region_scan(region, spacing, angle, fitness):
    frame = region.frame
    s_n = spacing / frame.scale
    offsets = np.arange(DENSE) * (s_n / DENSE)
    edges = frame.to_normalised(region.edges)
    return evaluate_region_grid(edges, [angle % math.pi], offsets, s_n, fitness=fitness)[0]


@pytest.mark.parametrize("degrees", [0.0, 17.5, 90.0, 143.0])
def test_convex_eq1_offset_is_the_best_at_the_angle(degrees):
    mission = plan_area(CONVEX, 7.0, crs=None, angle=math.radians(degrees))
    out = mission.summary()
    assert out["angle_deg"] == pytest.approx(degrees, abs=1e-9)
    assert out["method"] == "exact-offset"
    scan = _convex_scan(CONVEX, 7.0, math.radians(degrees), SmithFitness())
    assert mission.optimum.fitness >= scan.max() - 1e-12  # never beaten by the dense scan
    assert mission.optimum.fitness <= scan.max() + 1e-3  # and attained (the scan comes close)


@pytest.mark.parametrize("degrees", [0.0, 33.0, 120.0])
def test_convex_fewest_transects_at_the_angle_is_the_fewest_flown_lanes(degrees):
    angle = math.radians(degrees)
    mission = plan_area(CONVEX, 7.0, crs=None, angle=angle, fitness=FewestTransects())
    assert mission.optimum.method == "width-offset"
    assert mission.summary()["angle_deg"] == pytest.approx(degrees, abs=1e-9)
    assert mission.coverage.covered_share == pytest.approx(1.0, abs=1e-9)
    # the lanes flown (coverage-guaranteed) at every offset of a scan: none fewer than ours
    poly = Polygon(CONVEX)
    counts = []
    for offset in np.linspace(0.0, 7.0, 64, endpoint=False):
        counts.append(build_plan(poly, 7.0, angle, float(offset)).stats.n_transects)
    assert mission.stats.n_transects == min(counts)
    assert mission.stats.n_transects == int(mission.optimum.fitness)


@pytest.mark.parametrize("degrees", [0.0, 30.0, 120.0])
@pytest.mark.parametrize("holes", [(), (RING_HOLE,)])
def test_concave_offset_is_the_best_of_a_dense_scan(degrees, holes):
    ring = L_SHAPE if not holes else [(0, 0), (70, 0), (70, 70), (0, 70)]
    angle = math.radians(degrees)
    mission = plan_area(ring, 4.0, crs=None, holes=holes, angle=angle)
    out = mission.summary()
    assert out["method"] == "region-offset-grid"
    assert out["n_cells"] == 1 and out["cells"][0]["angle_deg"] == pytest.approx(degrees)
    assert out["angle_deg"] == pytest.approx(degrees, abs=1e-9)
    scan = _region_scan(Region(ring, list(holes)), 4.0, angle, SmithFitness())
    assert mission.optimum.fitness >= scan.max() - 1e-6 * abs(scan.max())
    assert mission.coverage.covered_share == pytest.approx(1.0, abs=1e-6)


def test_optimize_offset_refuses_bad_angles():
    for bad in (math.nan, math.inf, -math.inf, "north"):
        with pytest.raises(InvalidParameterError, match="angle"):
            optimize_offset(CONVEX, 7.0, bad)
        with pytest.raises(InvalidParameterError, match="angle"):
            plan_area(CONVEX, 7.0, crs=None, angle=bad)


@pytest.mark.parametrize(
    "extra", [{"method": "grid"}, {"decompose": True}, {"sweep": 10.0}], ids=str
)
def test_a_fixed_angle_refuses_what_it_excludes(extra):
    with pytest.raises(InvalidParameterError, match="fixed angle"):
        plan_area(L_SHAPE, 4.0, crs=None, angle=0.5, **extra)


def test_angle_is_taken_modulo_180_degrees():
    a = optimize_offset(CONVEX, 7.0, math.radians(200.0))
    b = optimize_offset(CONVEX, 7.0, math.radians(20.0))
    assert math.degrees(a.angle) == pytest.approx(20.0)
    assert a.fitness == pytest.approx(b.fitness)


def test_cli_angle_is_honoured_and_bad_values_refused(tmp_path, capsys):
    assert main(["-q", "plan", "--angle", "30", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["angle_deg"] == pytest.approx(30.0) and out["method"] == "exact-offset"
    area = tmp_path / "l.wkt"
    area.write_text("POLYGON ((0 0, 60 0, 60 20, 20 20, 20 50, 0 50, 0 0))")
    args = ["-q", "plan", str(area), "--crs", "planar", "--spacing", "4", "--json"]
    assert main([*args, "--angle", "120"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["angle_deg"] == pytest.approx(120.0) and out["method"] == "region-offset-grid"
    for bad in ("nan", "inf", "-inf"):
        with pytest.raises(SystemExit) as exc:
            main([*args, "--angle", bad])
        assert exc.value.code == 2
    assert main([*args, "--angle", "10", "--decompose"]) == 2
    assert "fixed angle" in capsys.readouterr().err


@pytest.mark.parametrize("bearing", [0.0, 30.0, 95.5, 179.0])
def test_bearing_is_the_reported_bearing(bearing):
    lonlat = plan_area(embedded_field(), 10.0, bearing=bearing)
    assert (lonlat.bearing - bearing + 90) % 180 - 90 == pytest.approx(0.0, abs=1e-6)
    assert lonlat.optimum.method == "exact-offset"
    planar = plan_area(L_SHAPE, 4.0, crs=None, bearing=bearing)
    assert (planar.bearing - bearing + 90) % 180 - 90 == pytest.approx(0.0, abs=1e-9)
    assert planar.summary()["angle_deg"] == pytest.approx((90.0 - bearing) % 180.0)
    with pytest.raises(InvalidParameterError, match="not both"):
        plan_area(L_SHAPE, 4.0, crs=None, bearing=bearing, angle=0.1)
    with pytest.raises(InvalidParameterError, match="finite"):
        plan_area(L_SHAPE, 4.0, crs=None, bearing=math.nan)


def test_cli_bearing(capsys):
    assert main(["-q", "plan", "--bearing", "120", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["bearing_deg"] == pytest.approx(120.0, abs=1e-6)
    with pytest.raises(SystemExit) as exc:
        main(["plan", "--bearing", "10", "--angle", "10"])
    assert exc.value.code == 2
