"""The chain bound of the region search (``smith_bb/region_chains.py``): sound in boxes of
every size on rectilinear, random and traced areas (layouts that put a vertex within
``DEGENERATE / 2`` of a line excepted, as documented), and the areas whose lines run along
edges beside holes and reflex corners certified against an independent dense search."""

from __future__ import annotations

import math

import numpy as np
import pytest

from boustro.geometry import Polygon
from boustro.geometry.region import Region, random_region
from boustro.geometry.traced import traced_field
from boustro.optimize.cover.boxes import Boxes, box_radius, level_radius
from boustro.optimize.region_grid import evaluate_region_grid
from boustro.optimize.smith_bb.region import _RegionSearch, smith_bb_region
from boustro.optimize.smith_bb.region_chains import DEGENERATE
from boustro.optimize.smith_bb.region_kernel import region_bounds

L_SHAPE = [(0, 0), (7, 0), (7, 2.3), (2.9, 2.3), (2.9, 6.1), (0, 6.1)]
U_SHAPE = [(0, 0), (90, 0), (90, 60), (65, 60), (65, 20), (25, 20), (25, 60), (0, 60)]
SQUARE = [(0, 0), (40, 0), (40, 40), (0, 40)]


def _comb() -> list[tuple[float, float]]:
    pts = [(0.0, 0.0), (90.0, 0.0)]
    for i in range(5):
        right = 2 * (4 - i) + 1
        pts += [(right * 10.0, 40.0), (right * 10.0 - 10.0, 40.0)]
        if right > 1:
            pts += [(right * 10.0 - 10.0, 10.0), (right * 10.0 - 20.0, 10.0)]
    return pts


AREAS = {
    "L": (Region(Polygon(L_SHAPE)), 0.7),
    "U": (Region(Polygon(U_SHAPE)), 10.0),
    "ring": (Region(Polygon(SQUARE), [Polygon([(10, 10), (30, 10), (30, 30), (10, 30)])]), 7.0),
    "comb": (Region(Polygon(_comb())), 5.0),
    "L+pond": (
        Region(
            Polygon([(0, 0), (60, 0), (60, 20), (25, 20), (25, 50), (0, 50)]),
            [Polygon([(5, 5), (15, 5), (15, 15), (5, 15)])],
        ),
        4.0,
    ),
}


def _near_a_line(search: _RegionSearch, theta: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Layouts with a vertex within DEGENERATE / 2 (and rounding) of one of their lines."""
    x, y = search.v[None, :, 0], search.v[None, :, 1]
    h = -np.sin(theta)[:, None] * x + np.cos(theta)[:, None] * y
    r = np.mod(h - d[:, None], search.s)
    return np.minimum(r, search.s - r).min(axis=1) <= 0.5 * DEGENERATE + 1e-13


def _check_boxes(region: Region, spacing: float, seed: int, m: int = 60) -> int:
    """Sample layouts in boxes (half at whole degrees and offsets through a vertex, where lines
    run along edges) and assert none above its box's bound; returns the samples checked."""
    rng = np.random.default_rng(seed)
    search = _RegionSearch(region, spacing, 0.5, 0.5)
    search.top_eps = 0.2
    checked, applied = 0, 0
    for delta, eta in ((0.02, 0.2), (1e-3, 1e-2), (1e-5, 1e-4), (1e-8, 1e-7), (1e-11, 1e-10)):
        theta = rng.uniform(0, math.pi, m)
        theta[: m // 2] = np.radians(rng.integers(0, 180, m // 2))
        d = rng.uniform(0, search.s, m)
        for i in range(m // 2):
            h = -math.sin(theta[i]) * search.v[:, 0] + math.cos(theta[i]) * search.v[:, 1]
            d[i] = h[rng.integers(len(h))] % search.s
        boxes = Boxes(theta, np.full(m, delta), d, np.full(m, eta * search.s))
        search.top_eps = max(search.top_eps, float(box_radius(boxes, search.radius).max()))
        bounds = search.bounds(boxes)
        inner, outer = search.level(float(level_radius(box_radius(boxes, search.radius),
                                                       search.top_eps).max()))  # fmt: skip
        chain = region_bounds(inner, outer, search.real, theta, boxes.delta, d,
                              box_radius(boxes, search.radius) * (1 + 1e-9) + 1e-12, search.s,
                              0.5, 0.5, search.tiny, boxes.eta * (1 + 1e-9) + 1e-12,
                              search.margin, cut=math.inf)  # fmt: skip
        applied += int(np.isfinite(chain).sum())
        for _ in range(8):
            t = theta + rng.uniform(-delta, delta, m)
            o = d + rng.uniform(-eta, eta, m) * search.s
            values = search.values(t, o)
            near = _near_a_line(search, t, o)
            ok = near | (values <= np.minimum(bounds, chain) + 1e-12)
            assert ok.all(), (t[~ok], o[~ok], values[~ok], bounds[~ok], chain[~ok])
            checked += int((~near).sum())
    assert applied > 0  # the chain bound applied in some boxes
    return checked


@pytest.mark.parametrize("name", sorted(AREAS))
def test_bound_is_sound_on_rectilinear_areas(name: str) -> None:
    region, spacing = AREAS[name]
    assert _check_boxes(region, spacing, seed=len(name)) > 2000


def test_bound_is_sound_on_random_and_traced_areas() -> None:
    rng = np.random.default_rng(21)
    for _ in range(3):
        region = random_region(rng, int(rng.integers(10, 50)), int(rng.integers(1, 3)))
        _check_boxes(region, 0.1 * region.diameter, seed=int(rng.integers(1000)), m=40)
    _check_boxes(traced_field(300, 2), 10.0, seed=3, m=40)


def _dense(region: Region, spacing: float, n_angles: int = 720, n_offsets: int = 80) -> float:
    f = region.frame
    angles = np.linspace(0.0, math.pi, n_angles, endpoint=False)
    # whole degrees and their neighbours too: where lines run along the edges
    angles = np.concatenate([angles, np.radians(np.arange(180.0)) + 1e-7])
    offsets = np.linspace(0.0, spacing / f.scale, n_offsets, endpoint=False)
    edges = f.to_normalised(region.edges)
    return float(evaluate_region_grid(edges, angles, offsets, spacing / f.scale).max())


@pytest.mark.parametrize("name", ["L", "U", "L+pond"])
def test_lines_along_edges_are_certified(name: str) -> None:
    region, spacing = AREAS[name]
    res = smith_bb_region(region, spacing)
    assert res.info["converged"] and res.gap <= 1e-4
    dense = _dense(region, spacing)
    assert res.upper_bound >= dense - 1e-12
    assert res.fitness >= dense - res.gap - 1e-12


def test_square_ring_is_certified_with_a_larger_budget() -> None:
    region, spacing = AREAS["ring"]
    res = smith_bb_region(region, spacing, max_work=3e7)
    assert res.info["converged"]
    assert res.upper_bound >= _dense(region, spacing) - 1e-12
