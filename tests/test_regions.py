"""Regions (concave shells, holes): validation, exact segments vs shapely, the soft model."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
import shapely
import torch

from boustro.errors import InvalidParameterError, InvalidPolygonError
from boustro.fitness import SmithFitness, smith_fitness, transect_count
from boustro.geometry import Polygon, halfplanes
from boustro.models import ExactModel
from boustro.regions import (
    Region,
    RegionExactModel,
    RegionSoftModel,
    evaluate_region_grid,
    random_region,
    region_edges,
    region_segments,
    segment_moments,
    soft_indicator,
    soft_region_lengths,
)

from .conftest import random_regions, shapely_region

SQUARE = [(0, 0), (4, 0), (4, 4), (0, 4)]
INNER = [(1, 1), (2, 1), (2, 2), (1, 2)]


# -- validation -------------------------------------------------------------------------------
def test_region_basics():
    r = Region(SQUARE, holes=[INNER[::-1]])  # a clockwise hole is fine
    assert r.area == pytest.approx(15.0) and r.n_holes == 1 and not r.is_convex
    assert Region(SQUARE).is_convex
    assert r.edges.shape == (8, 2, 2)
    # Every ring has the region on its left: the signed areas add up to the region's area.
    e = r.edges
    signed = 0.5 * np.sum(e[:, 0, 0] * e[:, 1, 1] - e[:, 1, 0] * e[:, 0, 1])
    assert signed == pytest.approx(15.0)
    inside = r.contains([(0.5, 0.5), (1.5, 1.5), (5, 5), (3, 3)])
    assert inside.tolist() == [True, False, False, True]
    np.testing.assert_allclose(r.normalised().shell.diameter, 1.0)
    assert shapely_region(r).area == pytest.approx(r.area)


@pytest.mark.parametrize(
    ("holes", "match"),
    [
        ([[(5, 5), (6, 5), (6, 6)]], "hole 1 lies outside the shell"),
        ([[(3, 1), (4.5, 1), (4.5, 2)]], "hole 1 touches or crosses the shell"),
        ([[(0, 1), (1, 1), (1, 2)]], "hole 1 touches or crosses the shell"),
        ([INNER, [(1.5, 1.5), (3, 1.5), (3, 3)]], "holes 1 and 2 touch or overlap"),
        ([INNER, [(2, 2), (3, 2), (3, 3)]], "holes 1 and 2 touch or overlap"),
        ([[(0.5, 0.5), (3.5, 0.5), (3.5, 3.5), (0.5, 3.5)], INNER], "hole 2 lies inside hole 1"),
        ([[(1, 1), (2, 2), (2, 1), (1, 2)]], "hole 1: the polygon is self-intersecting"),
        ([[(1, 1), (2, 2), (3, 3)]], "hole 1: the polygon has zero area"),
    ],
)
def test_invalid_holes_are_refused(holes, match):
    with pytest.raises(InvalidPolygonError, match=match):
        Region(SQUARE, holes)


def test_invalid_shell_and_hole_argument():
    with pytest.raises(InvalidPolygonError, match="the shell: the polygon is self-intersecting"):
        Region([(0, 0), (1, 1), (1, 0), (0, 1)])
    with pytest.raises(InvalidPolygonError, match="sequence of rings"):
        Region(SQUARE, np.array(INNER, dtype=float))


def test_random_regions_are_valid():
    for r in random_regions(seed=1, count=10, n_holes=(1, 3)):
        assert r.n_holes >= 1
        assert shapely_region(r).is_valid
        assert shapely_region(r).area == pytest.approx(r.area, rel=1e-12)


# -- exact segments ---------------------------------------------------------------------------
def _shapely_lengths(region: Region, angle: float, position: float) -> list[float]:
    u = np.array([math.cos(angle), math.sin(angle)])
    n = np.array([-math.sin(angle), math.cos(angle)])
    line = shapely.LineString([position * n - 10 * u, position * n + 10 * u])
    piece = shapely_region(region).intersection(line)
    parts = getattr(piece, "geoms", [piece])
    return sorted(g.length for g in parts if g.length > 0)


def test_exact_segments_match_shapely_on_random_concave_regions_with_holes():
    rng = np.random.default_rng(7)
    checked = 0
    for region in random_regions(seed=2, count=12, n_holes=(1, 3)):
        r = region.normalised()
        edges = region_edges(r, normalise=False)
        for _ in range(4):
            angle, spacing = float(rng.uniform(0, math.pi)), float(rng.uniform(0.02, 0.15))
            offset = float(rng.uniform(0, spacing))
            seg = region_segments(edges, angle, offset, spacing)
            for k, c in enumerate(seg.positions.numpy()):
                ours = sorted(x for x in seg.lengths[k].numpy() if x > 1e-12)
                ref = _shapely_lengths(r, angle, float(c))
                assert len(ours) == len(ref)
                np.testing.assert_allclose(ours, ref, atol=1e-12, rtol=0)
                checked += 1
    assert checked > 500


def test_segments_through_vertices_and_along_edges():
    r = Region(SQUARE, [INNER]).map(lambda v: v - 2.0)  # centred: vertices on the grid lines
    edges = region_edges(r, normalise=False)
    seg = region_segments(edges, 0.0, 0.0, 1.0)  # lines y = -2, -1, 0, 1, 2: along edges
    lengths = {round(float(c), 9): sorted(x for x in row if x > 0) for c, row in
               zip(seg.positions.numpy(), seg.lengths.numpy(), strict=True)}  # fmt: skip
    assert lengths[0.0] == [4.0]
    assert lengths[-0.0 + -1.0] == [1.0, 2.0]  # the hole's lower edge: the half-open rule
    assert lengths[-2.0] == [4.0] and lengths[2.0] == []
    n, s1, s2 = segment_moments(r.edges, [0.0], [0.0], 1.0, tiny=1e-12)
    total = [x for row in seg.lengths.numpy() for x in row if x > 1e-12]
    assert (n[0], s1[0], s2[0]) == pytest.approx(
        (len(total), sum(total), sum(x * x for x in total))
    )


def test_segment_moments_match_the_dense_model():
    rng = np.random.default_rng(3)
    for region in random_regions(seed=4, count=6):
        edges = region_edges(region)
        e = region.frame.to_normalised(region.edges)
        angles = rng.uniform(0, math.pi, 50)
        offsets = rng.uniform(-1, 1, 50)
        n, s1, s2 = segment_moments(e, angles, offsets, 0.07, tiny=1e-12 * edges.radius)
        tl = RegionExactModel()(edges, torch.as_tensor(angles), torch.as_tensor(offsets), 0.07)
        L = tl.lengths * tl.weights
        np.testing.assert_array_equal(n, transect_count(tl.weights).numpy())
        np.testing.assert_allclose(s1, L.sum(-1).numpy(), rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(s2, (L * L).sum(-1).numpy(), rtol=1e-12, atol=1e-12)


def test_region_model_on_a_convex_polygon_is_the_papers_model():
    poly = Polygon([(0, 0), (3, 0.5), (4, 3), (1, 4)])
    theta = torch.linspace(0, math.pi, 13, dtype=torch.float64)[:, None]
    offset = torch.linspace(0, 0.05, 5, dtype=torch.float64)[None, :]
    ours = RegionExactModel()(region_edges(poly), theta, offset, 0.05)
    ref = ExactModel()(halfplanes(poly), theta, offset, 0.05)
    f_ours = smith_fitness(ours.lengths, ours.weights)
    f_ref = smith_fitness(ref.lengths, ref.weights)
    torch.testing.assert_close(f_ours, f_ref, rtol=0, atol=1e-12)
    line = RegionExactModel(per="line")(region_edges(poly), theta, offset, 0.05)
    torch.testing.assert_close(line.lengths.sum(-1), ref.lengths.sum(-1), rtol=0, atol=1e-12)


def test_evaluate_region_grid_fast_path_equals_the_model():
    region = random_regions(seed=5, count=1, n_holes=(2, 2))[0]
    edges = region_edges(region)
    angles = np.linspace(0, math.pi, 7, endpoint=False)
    offsets = np.linspace(0, 0.05, 4, endpoint=False)
    fast = evaluate_region_grid(edges, angles, offsets, 0.05)
    with torch.no_grad():
        tl = RegionExactModel()(
            edges, torch.as_tensor(angles)[:, None], torch.as_tensor(offsets)[None], 0.05
        )
        dense = smith_fitness(tl.lengths, tl.weights).numpy()
    np.testing.assert_allclose(fast, dense, atol=1e-12)
    paper_stats = evaluate_region_grid(
        edges, angles, offsets, 0.05, fitness=SmithFitness(statistics="paper")
    )
    np.testing.assert_allclose(paper_stats, dense, atol=1e-12)  # equal for 0/1 weights
    pairs = evaluate_region_grid(edges, angles[:4], offsets, 0.05, pairs=True)
    np.testing.assert_allclose(pairs, fast[np.arange(4), np.arange(4)], atol=1e-15)
    far = evaluate_region_grid(edges, [0.0], [0.0], 5.0)  # one line through the middle
    assert np.isfinite(far).all()
    with pytest.raises(InvalidParameterError, match="pairs"):
        evaluate_region_grid(edges, angles, offsets, 0.05, pairs=True)


# -- the soft model ---------------------------------------------------------------------------
@pytest.fixture(scope="module")
def holed():
    rng = np.random.default_rng(11)
    return random_region(rng, 12, 2, hole_size=(0.25, 0.35), roughness=0.3)


def test_soft_model_converges_to_the_exact_segments(holed):
    edges = region_edges(holed)
    theta = torch.tensor([0.3, 1.2, 2.5], dtype=torch.float64)
    offset = torch.tensor([0.013, 0.021, 0.004], dtype=torch.float64)
    ex = RegionExactModel()(edges, theta, offset, 0.05)
    f_exact = smith_fitness(ex.lengths, ex.weights)
    total_exact = region_segments(edges, theta, offset, 0.05).lengths.sum((-1, -2))
    errors = []
    for h in (1e-2, 1e-3, 1e-4, 1e-5, 1e-7):
        soft = soft_region_lengths(edges, theta, offset, 0.05, smoothing=h)
        f_soft = smith_fitness(soft.lengths, soft.weights)
        total_soft = (soft.lengths * soft.weights).sum(-1)
        count_soft = soft.weights.sum(-1)
        errors.append(float((f_soft - f_exact).abs().max()))
        assert torch.all((total_soft - total_exact).abs() <= 40 * h)
        assert torch.all((count_soft - ex.weights.sum(-1)).abs() <= 2.0)
    assert errors[-1] < 1e-9 and errors[-2] < 1e-6
    assert errors[-1] <= errors[0]
    soft = soft_region_lengths(edges, theta, offset, 0.05, smoothing=1e-7)
    np.testing.assert_allclose(soft.weights.sum(-1).numpy(), ex.weights.sum(-1).numpy(), atol=1e-6)


def test_soft_total_is_the_line_integral_of_the_soft_indicator(holed):
    edges = region_edges(holed)
    h, theta, spacing = 0.02, 0.7, 0.05
    soft = soft_region_lengths(edges, theta, 0.01, spacing, smoothing=h)
    u = torch.tensor([math.cos(theta), math.sin(theta)], dtype=torch.float64)
    n = torch.tensor([-math.sin(theta), math.cos(theta)], dtype=torch.float64)
    t = torch.linspace(-1.2, 1.2, 12001, dtype=torch.float64)
    positions = soft.positions.reshape(-1)
    unique = torch.unique(positions)
    for c in unique[len(unique) // 2 - 2 : len(unique) // 2 + 2]:
        indicator = soft_indicator(edges, c * n + t[:, None] * u, theta, smoothing=h)
        quadrature = torch.trapezoid(indicator, t)
        closed = (soft.lengths * soft.weights)[positions == c].sum()
        assert float((quadrature - closed).abs()) < 1e-5


def test_soft_indicator_is_one_inside_and_zero_outside_and_in_holes(holed):
    r = holed.normalised()
    edges = region_edges(r, normalise=False)
    rng = np.random.default_rng(0)
    pts = rng.uniform(-0.8, 0.8, size=(4000, 2))
    far = r.boundary_distance(pts) > 0.02
    value = soft_indicator(edges, torch.as_tensor(pts[far]), 0.4, smoothing=1e-3).numpy()
    inside = r.contains(pts[far])
    assert np.all(value[inside] > 1 - 1e-6) and np.all(value[~inside] < 1e-6)
    in_holes = np.zeros(len(pts), dtype=bool)
    from boustro.regions import points_in_ring

    for hole in r.holes:
        in_holes |= points_in_ring(pts, hole.vertices)
    assert (in_holes & far).sum() > 10  # the holes were sampled


@pytest.mark.grad
def test_soft_model_gradcheck_and_finite_gradients(holed):
    edges = region_edges(holed)
    theta = torch.tensor([0.3, 1.9], dtype=torch.float64, requires_grad=True)
    offset = torch.tensor([0.011, 0.027], dtype=torch.float64, requires_grad=True)

    def f(a, b):
        tl = soft_region_lengths(edges, a, b, 0.06, smoothing=2e-2)
        return smith_fitness(tl.lengths, tl.weights)

    assert torch.autograd.gradcheck(f, (theta, offset))
    # Nasty places: a line through a vertex, lines parallel to edges, tiny smoothing.
    square = Region(SQUARE, [INNER]).map(lambda v: v - 2.0)
    sq_edges = region_edges(square)
    for h in (1e-2, 1e-5):
        for a, d in ((0.0, 0.0), (math.pi / 2, 0.0), (0.0, 0.125), (1e-13, 0.0)):
            a_t = torch.tensor(a, dtype=torch.float64, requires_grad=True)
            d_t = torch.tensor(d, dtype=torch.float64, requires_grad=True)
            tl = soft_region_lengths(sq_edges, a_t, d_t, 0.125, smoothing=h)
            smith_fitness(tl.lengths, tl.weights).backward()
            assert torch.isfinite(a_t.grad) and torch.isfinite(d_t.grad)
        for model in (RegionSoftModel(h), RegionExactModel()):
            a_t = torch.tensor(0.0, dtype=torch.float64, requires_grad=True)
            d_t = torch.tensor(0.0, dtype=torch.float64, requires_grad=True)
            tl = model(sq_edges, a_t, d_t, 0.125)
            smith_fitness(tl.lengths, tl.weights).backward()
            assert torch.isfinite(a_t.grad) and torch.isfinite(d_t.grad)


def test_soft_model_batched_equals_single_calls(holed):
    edges = region_edges(holed)
    theta = torch.tensor([[0.2, 0.9], [1.7, 2.8]], dtype=torch.float64)
    offset = torch.tensor([[0.0, 0.01], [0.02, 0.03]], dtype=torch.float64)
    batch = soft_region_lengths(edges, theta, offset, 0.05, smoothing=1e-3)
    f_batch = smith_fitness(batch.lengths, batch.weights)
    for i in range(2):
        for j in range(2):
            one = soft_region_lengths(edges, theta[i, j], offset[i, j], 0.05, smoothing=1e-3)
            torch.testing.assert_close(smith_fitness(one.lengths, one.weights), f_batch[i, j])


def test_soft_model_settings():
    assert RegionSoftModel.from_temperature(100).smoothing == pytest.approx(0.01)
    assert RegionSoftModel(0.5).temperature == 2.0
    for bad in (0, -1, float("nan"), "x"):
        with pytest.raises(InvalidParameterError, match="smoothing"):
            RegionSoftModel(bad)  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match="per"):
        RegionExactModel(per="edge")  # type: ignore[arg-type]


def test_region_modules_are_core():
    code = (
        "import sys, boustro.regions, boustro.routing, boustro.decompose; "
        "bad = [m for m in ('matplotlib', 'shapely', 'pyproj', 'boustro.cli', 'boustro.io') "
        "if m in sys.modules]; print(','.join(bad))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""
