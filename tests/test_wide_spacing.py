"""A spacing far wider than the area (QA round 19): its one lane's coverage measured exactly,
and spacings whose geometry would overflow float64 refused by one rule (:func:`plan_area`)."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

from boustro.errors import InvalidParameterError
from boustro.mission import plan_area
from boustro.mission.pipeline import MAX_SPACING
from boustro.plan import build_plan, coverage

from .conftest import run_cli

RING = np.array([[4.0, 52.0], [4.0015, 52.0], [4.0015, 52.001], [4.0, 52.001]])


@pytest.mark.parametrize("spacing", [1e9, 1e20, 1e50, MAX_SPACING])
def test_one_lane_far_wider_than_the_area_covers_it_all(spacing):
    """Measured with its full width, a 1e20 m lane lost the area to rounding ("covered
    0.0000%"). The overlap stays the whole footprint's: (swept - covered) / area."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mission = plan_area(RING, spacing)
    c = mission.coverage
    assert mission.plan.stats.n_transects == 1
    assert c.covered_share == 1.0 and c.covered_area == pytest.approx(c.area, rel=1e-12)
    length = float(np.linalg.norm(np.diff(mission.plan.transects[0], axis=0)))
    assert c.swept_area == pytest.approx(spacing * length, rel=1e-3)  # the whole footprint
    assert c.overlap_share == pytest.approx((c.swept_area - c.area) / c.area, rel=1e-12)


def test_a_square_measured_with_wide_lanes_and_a_nadir_gap():
    """The cut width keeps a lane's two strips and its blind strip where they are: a nadir gap
    wider than the area leaves it uncovered, one narrower covers all but the gap."""
    square = [(0, 0), (10, 0), (10, 10), (0, 10)]
    for gap, share in ((4.0, 0.6), (1e21, 0.0)):
        plan = build_plan(square, 4e21, 0.0, 0.0, reach=2e21, nadir_gap=gap)
        assert coverage(plan).covered_share == pytest.approx(share, abs=1e-12), gap


@pytest.mark.parametrize("spacing", ["1e300", "1.5e100"])
def test_plan_refuses_a_spacing_whose_figures_overflow(capsys, tmp_path, spacing):
    area = tmp_path / "field.geojson"
    ring = [*RING.tolist(), RING[0].tolist()]
    area.write_text(json.dumps({"type": "Polygon", "coordinates": [ring]}))
    code, _, err = run_cli(capsys, "plan", area, "--spacing", spacing)
    assert code == 2
    assert err.strip().startswith(f"boustro: error: spacing {float(spacing):g} is too wide")
    assert "overflow" not in err


def test_plan_area_refuses_a_turn_time_without_a_speed():
    """QA round 19: plan, batch and the page's API refused it, the library ignored it."""
    with pytest.raises(InvalidParameterError, match=r"^turn_time needs speed"):
        plan_area(RING, 20.0, turn_time=5.0)
    assert plan_area(RING, 20.0, turn_time=5.0, speed=3.0).plan.stats.turn_time == 5.0
