"""Crosshatch: two passes 90 degrees apart, each covering 100%, the angle chosen for the pair."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from boustro.cli import main
from boustro.errors import InvalidParameterError
from boustro.geometry import Polygon
from boustro.io import embedded_field
from boustro.mission import plan_area
from boustro.mission.crosshatch import crosshatch_angle, plan_crosshatch
from boustro.objectives import FewestTransects
from boustro.optimize.fixed_angle import optimize_offset

FIELD = [(0, 0), (400, 0), (450, 300), (0, 250)]
KITE = [(0, 0), (500, 80), (420, 300), (60, 260)]  # its pair's optimum: a knife edge
L_SHAPE = [(0, 0), (300, 0), (300, 200), (150, 200), (150, 100), (0, 100)]


def _pair(target, spacing, a, fitness=None):
    return sum(
        optimize_offset(target, spacing, a + k * math.pi / 2, fitness=fitness).fitness
        for k in (0, 1)
    )


@pytest.mark.parametrize("area", [FIELD, L_SHAPE])
def test_two_passes_90_degrees_apart_each_covering_everything(area):
    m = plan_crosshatch(area, 20.0, crs=None)
    first, second = m.passes
    turn = (second.plan.angle - first.plan.angle) % math.pi
    assert turn == pytest.approx(math.pi / 2, abs=1e-12)
    assert first.coverage.covered_share == pytest.approx(1.0, abs=1e-9)
    assert second.coverage.covered_share == pytest.approx(1.0, abs=1e-9)
    # the mission flies both: every lane of each pass once, the first pass first
    np.testing.assert_array_equal(m.transects, np.concatenate([first.transects, second.transects]))
    assert m.stats.n_transects == first.stats.n_transects + second.stats.n_transects
    move = float(np.hypot(*(second.waypoints[0] - first.waypoints[-1])))
    assert m.stats.path_length == pytest.approx(
        first.stats.path_length + move + second.stats.path_length
    )
    if area is FIELD:  # convex: the second pass starts at its corner nearest the first's end
        corners = second.transects[[0, -1]].reshape(-1, 2)
        assert move <= float(np.hypot(*(corners - first.waypoints[-1]).T).min()) + 1e-9
    assert [p["angle_deg"] for p in m.summary()["crosshatch"]] == pytest.approx(
        [math.degrees(first.plan.angle), math.degrees(second.plan.angle)]
    )


@pytest.mark.parametrize("area", [FIELD, KITE])
def test_the_angle_is_the_best_pair(area):
    poly = Polygon(area)
    single = plan_area(area, 10.0, crs=None).plan.angle  # the one-pass optimum
    angle, value = crosshatch_angle(poly, 10.0, candidates=[single])
    assert 0 <= angle < math.pi / 2
    assert value == pytest.approx(_pair(poly, 10.0, angle), abs=1e-12)
    grid = [_pair(poly, 10.0, a) for a in np.radians(np.arange(0.0, 90.0, 1.0))]
    assert value >= max(grid) - 1e-9  # at least as good as a 1-degree scan of the pairs
    assert value >= _pair(poly, 10.0, single) - 1e-12  # and the one-pass optimum plus 90
    m = plan_crosshatch(area, 10.0, crs=None)  # what plan_crosshatch finds by itself
    assert m.passes[0].plan.angle == pytest.approx(angle, abs=1e-12)


def test_a_minimised_objective_is_minimised_for_the_pair():
    poly, fewest = Polygon(FIELD), FewestTransects()
    _, value = crosshatch_angle(poly, 20.0, fewest)
    grid = [_pair(poly, 20.0, a, fewest) for a in np.radians(np.arange(0.0, 90.0, 1.0))]
    assert value <= min(grid) + 1e-9


def test_options_it_refuses():
    with pytest.raises(InvalidParameterError, match="crosshatch"):
        plan_crosshatch(FIELD, 20.0, crs=None, method="grid")
    fixed = plan_crosshatch(FIELD, 20.0, crs=None, angle=math.radians(10))
    assert math.degrees(fixed.passes[0].plan.angle) == pytest.approx(10.0)


def test_command_line_crosshatch(tmp_path, capsys):
    out = tmp_path / "m.plan"
    args = ["-q", "plan", "--crosshatch", "--altitude", "30", "--out", str(out), "--json"]
    assert main(args) == 0
    summary = json.loads(capsys.readouterr().out)
    a, b = summary["crosshatch"]
    assert (b["angle_deg"] - a["angle_deg"]) % 180 == pytest.approx(90.0)
    assert a["covered_share"] == b["covered_share"] == 1.0
    items = json.loads(out.read_text())["mission"]["items"]
    single = plan_area(embedded_field(), 10.0)
    assert len(items) == 2 * summary["n_transects"] > 2 * single.stats.n_transects
    assert main(["plan", "--crosshatch", "--decompose"]) == 2
