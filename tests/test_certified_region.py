"""The certified Eq. 1 optimum over the segments of concave areas and areas with holes
(``smith_bb_region``) against independent dense searches, the convex certified-bb, the
region grid, and in ``plan_area``."""

from __future__ import annotations

import math

import numpy as np
import pytest

from boustro.geometry import Polygon
from boustro.geometry.region import Region, random_region
from boustro.mission import plan_area
from boustro.optimize.cover.boxes import Boxes, box_radius
from boustro.optimize.region_grid import evaluate_region_grid
from boustro.optimize.smith_bb import smith_bb
from boustro.optimize.smith_bb.region import _RegionSearch, smith_bb_region
from boustro.plan.region_opt import optimize_region


def _dense(region: Region, spacing: float, n_angles: int = 540, n_offsets: int = 60) -> float:
    """The best exact per-segment value on a dense grid (normalised frame, as the search)."""
    f = region.frame
    edges = f.to_normalised(region.edges)
    s = spacing / f.scale
    angles = np.linspace(0.0, math.pi, n_angles, endpoint=False)
    offsets = np.linspace(0.0, s, n_offsets, endpoint=False)
    return float(evaluate_region_grid(edges, angles, offsets, s).max())


@pytest.mark.parametrize("seed", range(6))
def test_certificate_holds_against_dense_search(seed: int) -> None:
    rng = np.random.default_rng(100 + seed)
    n = int(rng.integers(10, 61))
    region = random_region(rng, n, int(rng.integers(1, 3)))
    spacing = float(rng.uniform(0.06, 0.15)) * region.diameter
    res = smith_bb_region(region, spacing)
    dense = _dense(region, spacing)
    assert res.upper_bound >= dense - 1e-12  # no layout above the certified bound
    assert res.fitness >= dense - res.gap - 1e-12
    assert res.info["converged"] and res.gap <= 1e-4
    # the returned layout's value, recomputed independently (user units -> normalised frame)
    f = region.frame
    again = evaluate_region_grid(
        f.to_normalised(region.edges), [res.angle], [res.offset / f.scale], spacing / f.scale
    )
    assert again[0, 0] == pytest.approx(res.fitness, abs=1e-12)


def test_bound_is_sound_in_random_boxes() -> None:
    """Every layout sampled inside a box scores at most the box's bound."""
    rng = np.random.default_rng(7)
    region = random_region(rng, 24, 2)
    search = _RegionSearch(region, 0.1 * region.diameter, 0.5, 0.5)
    search.top_eps = 0.2
    m = 60
    theta = rng.uniform(0, math.pi, m)
    d = rng.uniform(0, search.s, m)
    for delta, eta in ((0.05, 0.3 * search.s), (0.005, 0.03 * search.s), (1e-4, 1e-3 * search.s)):
        boxes = Boxes(theta, np.full(m, delta), d, np.full(m, eta))
        search.top_eps = max(search.top_eps, float(box_radius(boxes, search.radius).max()))
        bounds = search.bounds(boxes)
        for _ in range(20):
            t = theta + rng.uniform(-delta, delta, m)
            o = d + rng.uniform(-eta, eta, m)
            assert np.all(search.values(t, o) <= bounds + 1e-12)


def test_region_grid_never_beats_the_certificate() -> None:
    rng = np.random.default_rng(3)
    for _ in range(3):
        region = random_region(rng, int(rng.integers(12, 40)), 1)
        spacing = 0.1 * region.diameter
        res = smith_bb_region(region, spacing)
        grid = optimize_region(region, spacing)
        assert res.upper_bound >= grid.fitness - 1e-12
        assert res.fitness >= grid.fitness - res.gap - 1e-12


def test_convex_polygon_gives_the_convex_certified_value() -> None:
    hexagon = [(0, 0), (4, -1), (7, 1), (6, 4), (2, 5), (-1, 3)]
    convex = smith_bb(hexagon, 0.7)
    region = smith_bb_region(Region(Polygon(hexagon)), 0.7)
    assert region.fitness == pytest.approx(convex.fitness, abs=convex.gap + region.gap + 1e-9)
    assert region.upper_bound >= convex.fitness - 1e-12
    assert convex.upper_bound >= region.fitness - 1e-12


def test_spent_budget_says_so_and_its_bound_holds() -> None:
    rng = np.random.default_rng(11)
    region = random_region(rng, 40, 2)
    spacing = 0.08 * region.diameter
    res = smith_bb_region(region, spacing, max_work=2e5)
    assert not res.info["converged"]
    assert "budget" in res.info["stopped"]
    assert res.upper_bound >= _dense(region, spacing, 360, 40) - 1e-12


def test_plan_reports_the_certificate_for_the_plan_and_its_cells() -> None:
    rng = np.random.default_rng(5)
    region = random_region(rng, 20, 1)
    ring = region.shell.vertices * 100.0
    holes = [h.vertices * 100.0 for h in region.holes]
    mission = plan_area(ring, 12.0, crs=None, holes=holes, decompose=False)
    out = mission.summary()
    assert out["method"] == "certified-bb"
    assert out["certified"] is True and 0 <= out["gap"] <= 1e-4
    assert [c["certified"] for c in out["cells"]] == [True]
    grid = plan_area(ring, 12.0, crs=None, holes=holes, decompose=False, method="grid")
    assert grid.summary()["certified"] is False
    assert out["fitness"] >= grid.optimum.fitness - out["gap"]
