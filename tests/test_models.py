"""Exact chords vs shapely, the paper model's fidelity, batching, gradients, conventions."""

import math

import numpy as np
import pytest
import shapely
import torch

from boustro.errors import InvalidParameterError
from boustro.fitness import smith_fitness
from boustro.geometry import Polygon, halfplanes
from boustro.models import (
    ExactModel,
    PaperModel,
    _prepare,
    _SigmoidIntegral,
    exact_chords,
    paper_lengths,
    transect_positions,
)

from .conftest import PAPER_SPACING_NORMALISED, random_polygons


def shapely_lengths(poly: Polygon, theta: float, positions: np.ndarray) -> np.ndarray:
    shape = shapely.Polygon(poly.vertices)
    u = np.array([math.cos(theta), math.sin(theta)])
    n = np.array([-math.sin(theta), math.cos(theta)])
    lines = [shapely.LineString([c * n - 3 * u, c * n + 3 * u]) for c in positions]
    return np.array([shape.intersection(line).length for line in lines])


@pytest.mark.parametrize("seed", range(40))
def test_exact_chords_match_shapely(seed):
    rng = np.random.default_rng(1000 + seed)
    poly = random_polygons(seed, 1)[0]
    hp = halfplanes(poly)
    spacing = rng.uniform(0.01, 1 / 3)
    for theta, offset in rng.uniform([0, -1], [2 * math.pi, 1], size=(3, 2)):
        ch = exact_chords(hp, theta, offset, spacing)
        ref = shapely_lengths(poly, theta, ch.positions.numpy())
        np.testing.assert_allclose(ch.lengths.numpy(), ref, rtol=0, atol=1e-12)
        # endpoints lie on the polygon boundary
        hit = ch.lengths > 0
        u = np.array([math.cos(theta), math.sin(theta)])
        n = np.array([-math.sin(theta), math.cos(theta)])
        ends = ch.positions[hit].numpy()[:, None] * n + ch.lower[hit].numpy()[:, None] * u
        boundary = shapely.Polygon(poly.vertices).exterior
        assert max(boundary.distance(shapely.Point(p)) for p in ends) < 1e-12


def test_grid_covers_polygon_for_any_offset(parallelogram):
    hp = halfplanes(parallelogram)
    s = PAPER_SPACING_NORMALISED
    for offset in (-3.7, 0.0, 0.02, 5.0):
        c = transect_positions(torch.tensor(offset, dtype=torch.float64), s, hp.radius)
        assert c.min() <= -hp.radius and c.max() >= hp.radius
        np.testing.assert_allclose(np.diff(c.numpy()), s, rtol=1e-12)
        assert abs(math.remainder(float(c[0]) - offset, s)) < 1e-12


def test_exact_lengths_batched_equal_looped():
    """Three polygons x two (angle, offset) pairs in one call equal six single calls."""
    polys = random_polygons(7, 3)
    hp = halfplanes(polys)  # (3, E, 2), padded
    theta = torch.tensor([[0.1], [2.9]], dtype=torch.float64)  # (2, 1): broadcasts over polygons
    offset = torch.tensor([[0.0], [0.03]], dtype=torch.float64)
    batched = exact_chords(hp, theta, offset, 0.07)
    assert batched.lengths.shape[:2] == (2, 3)
    for i, poly in enumerate(polys):
        for j in range(2):
            one = exact_chords(halfplanes(poly), float(theta[j, 0]), float(offset[j, 0]), 0.07)
            got = batched.lengths[j, i]
            # grids differ in extent (radius of the batch vs of one polygon): match positions
            idx = torch.round((one.positions - batched.positions[j, i, 0]) / 0.07).long()
            torch.testing.assert_close(got[idx], one.lengths, rtol=0, atol=1e-15)
            assert float(got.sum()) == pytest.approx(float(one.lengths.sum()), abs=1e-14)


def test_paper_model_batched_equal_looped(parallelogram):
    hp = halfplanes(parallelogram)
    thetas = torch.tensor([0.0, 0.7, 2.0], dtype=torch.float64)
    offsets = torch.tensor([0.01, -0.02, 0.3], dtype=torch.float64)
    model = PaperModel(temperature=100.0, points_per_transect=200)
    batched = model(hp, thetas, offsets, PAPER_SPACING_NORMALISED)
    for i in range(3):
        one = model(hp, thetas[i], offsets[i], PAPER_SPACING_NORMALISED)
        torch.testing.assert_close(batched.lengths[i], one.lengths, rtol=0, atol=1e-14)
        torch.testing.assert_close(batched.weights[i], one.weights, rtol=0, atol=1e-14)


def mean_abs_error(temperature, points, polys, seed=0, clip=False):
    rng = np.random.default_rng(seed)
    errors = []
    for poly in polys:
        hp = halfplanes(poly)
        theta, offset, s = rng.uniform(0, math.pi), rng.uniform(0, 1), rng.uniform(0.03, 1 / 3)
        exact = ExactModel(clip=clip)(hp, theta, offset, s)
        soft = PaperModel(temperature, points, clip=clip)(hp, theta, offset, s)
        f_exact = smith_fitness(exact.lengths, exact.weights)
        f_soft = smith_fitness(soft.lengths, soft.weights)
        errors.append(abs(float(f_exact - f_soft)))
    return float(np.mean(errors))


def test_paper_model_converges_to_exact_as_temperature_grows():
    """The trend of the paper's Table I: the error falls as the temperature rises."""
    polys = random_polygons(11, 30)
    errors = [mean_abs_error(t, 1000, polys) for t in (10, 100, 1000, 10000)]
    assert errors[0] > errors[1] > errors[2] > errors[3]
    assert errors[3] < 1e-3


def test_paper_model_converges_as_points_grow():
    polys = random_polygons(12, 20)
    coarse, fine = mean_abs_error(10000, 30, polys), mean_abs_error(10000, 2000, polys)
    assert fine < coarse and fine < 1e-3


def test_paper_clip_window_under_measures_a_triangle(triangle):
    """A triangle centred on its vertex mean reaches 0.577 > 0.5: the paper's window cuts it."""
    hp = halfplanes(triangle)
    theta = math.pi / 2  # transects along y: the apex is at y = 0.577 in the normalised frame
    full = exact_chords(hp, theta, 0.0, 0.05).lengths.sum()
    clipped = exact_chords(hp, theta, 0.0, 0.05, clip=True).lengths.sum()
    assert clipped < full - 1e-3
    soft_full = paper_lengths(hp, theta, 0.0, 0.05, temperature=1e4, points_per_transect=2000)
    assert float(soft_full.lengths.sum()) == pytest.approx(float(full), rel=1e-3)


@pytest.mark.grad
def test_gradcheck_paper_model(parallelogram):
    hp = halfplanes(parallelogram)

    def f(theta, offset):
        tl = paper_lengths(hp, theta, offset, 0.15, temperature=8.0, points_per_transect=40)
        return smith_fitness(tl.lengths, tl.weights)

    theta = torch.tensor([0.3, 1.1], dtype=torch.float64, requires_grad=True)
    offset = torch.tensor([0.02, -0.05], dtype=torch.float64, requires_grad=True)
    assert torch.autograd.gradcheck(f, (theta, offset))


@pytest.mark.grad
def test_gradcheck_exact_lengths_away_from_breakpoints(parallelogram):
    hp = halfplanes(parallelogram)

    def f(theta, offset):
        return exact_chords(hp, theta, offset, 0.15).lengths

    theta = torch.tensor(0.3, dtype=torch.float64, requires_grad=True)
    offset = torch.tensor(0.021, dtype=torch.float64, requires_grad=True)
    assert torch.autograd.gradcheck(f, (theta, offset))


def degenerate_cases(poly: Polygon):
    """(theta, offset, spacing) with a transect through a vertex, parallel to an edge, tangent."""
    p = poly.normalised()
    v = p.vertices
    edge = v[1] - v[0]
    along_edge = math.atan2(edge[1], edge[0])
    s = 0.1
    cases = []
    theta = 0.4
    n = np.array([-math.sin(theta), math.cos(theta)])
    cases.append((theta, float(v[2] @ n), s))  # a grid line through vertex 2
    cases.append((along_edge, float(v[0] @ np.array([-edge[1], edge[0]]) / np.hypot(*edge)), s))
    proj = v @ n
    cases.append((theta, float(proj.max()), s))  # tangent at the extreme vertex
    cases.append((theta, float(proj.min()), s))
    return cases


@pytest.mark.grad
@pytest.mark.parametrize("temperature", [1.0, 1e3, 1e5])
def test_finite_gradients_at_degenerate_places(parallelogram, triangle, temperature):
    for poly in (parallelogram, triangle, Polygon([(0, 0), (1, 0), (1, 1), (0, 1)])):
        hp = halfplanes(poly)
        for theta0, offset0, s in degenerate_cases(poly):
            for model in (PaperModel(temperature, 300), ExactModel()):
                theta = torch.tensor(theta0, dtype=torch.float64, requires_grad=True)
                offset = torch.tensor(offset0, dtype=torch.float64, requires_grad=True)
                tl = model(hp, theta, offset, s)
                f = smith_fitness(tl.lengths, tl.weights)
                f.backward()
                assert torch.isfinite(f)
                assert torch.isfinite(theta.grad) and torch.isfinite(offset.grad)


def test_length_gradients_approach_the_exact_ones(parallelogram):
    """Where the sigmoid transition is resolved by the points, d(length)/d(angle, offset) of the
    paper model approaches the exact chord's derivative. Eq. 5 applies the temperature twice, so
    the transition is ~1/T^2 wide: resolving it needs dt << 1/T^2 (here T = 100, dt = 5e-5).
    Transects near a vertex see the sigmoid-rounded corner, so only those crossing the two long
    edges are compared."""
    hp = halfplanes(parallelogram)
    s = 0.1
    exact_lengths = exact_chords(hp, 0.35, 0.013, s).lengths
    inner = exact_lengths > exact_lengths.max() - 1e-9
    assert int(inner.sum()) >= 4

    def grads(fn):
        theta = torch.tensor(0.35, dtype=torch.float64, requires_grad=True)
        offset = torch.tensor(0.013, dtype=torch.float64, requires_grad=True)
        fn(theta, offset)[inner].sum().backward()
        return float(theta.grad), float(offset.grad)

    exact = grads(lambda t, d: exact_chords(hp, t, d, s).lengths)
    soft = grads(
        lambda t, d: paper_lengths(hp, t, d, s, temperature=100, points_per_transect=20000).lengths
    )
    assert soft == pytest.approx(exact, rel=0.02, abs=0.02)


def test_high_temperature_needs_dense_points_for_gradients(parallelogram):
    """The paper model's documented pitfall: when the sigmoid's width 1/T is below the point
    spacing, the trapezoid integral is a step function of the edges and its gradient vanishes."""
    hp = halfplanes(parallelogram)
    theta = torch.tensor(0.35, dtype=torch.float64, requires_grad=True)
    tl = paper_lengths(hp, theta, 0.013, 0.1, temperature=1e5, points_per_transect=1000)
    tl.lengths.sum().backward()
    assert abs(float(theta.grad)) < 1e-6


def test_float32_follows_input_dtype(parallelogram):
    hp = halfplanes(parallelogram, dtype=torch.float32)
    tl = PaperModel(100.0, 50)(hp, torch.tensor(0.3), torch.tensor(0.0), 0.1)
    assert tl.lengths.dtype == torch.float32
    assert exact_chords(hp, 0.3, 0.0, 0.1).lengths.dtype == torch.float32


@pytest.mark.parametrize(
    "kwargs",
    [
        {"temperature": 0.0},
        {"temperature": -1.0},
        {"temperature": float("nan")},
        {"points_per_transect": 1},
        {"points_per_transect": 2.5},
    ],
)
def test_paper_model_rejects_bad_settings(parallelogram, kwargs):
    with pytest.raises(InvalidParameterError):
        paper_lengths(halfplanes(parallelogram), 0.0, 0.0, 0.1, **kwargs)


@pytest.mark.parametrize("spacing", [0.0, -0.1, float("nan"), float("inf"), "x"])
def test_bad_spacing(parallelogram, spacing):
    with pytest.raises(InvalidParameterError):
        exact_chords(halfplanes(parallelogram), 0.0, 0.0, spacing)


def test_temperature_as_batched_tensor(parallelogram):
    hp = halfplanes(parallelogram)
    temps = torch.tensor([10.0, 1000.0], dtype=torch.float64)
    batched = paper_lengths(
        hp, torch.zeros(2), torch.zeros(2), 0.1, temperature=temps, points_per_transect=100
    )
    for i in range(2):
        one = paper_lengths(hp, 0.0, 0.0, 0.1, temperature=float(temps[i]), points_per_transect=100)
        torch.testing.assert_close(batched.lengths[i], one.lengths)


@pytest.mark.grad
def test_fused_integral_equals_log_space_autograd(parallelogram, triangle):
    """The chunked kernel with analytic backward and plain autograd through
    exp(sum(logsigmoid)) (taken when the temperature requires grad) agree, values and grads."""
    for poly in (parallelogram, triangle):
        hp = halfplanes(poly)
        for temp in (3.0, 1e3, 1e5):
            out = []
            for needs_grad in (False, True):
                theta = torch.tensor([0.3, 1.7, 2.9], dtype=torch.float64, requires_grad=True)
                offset = torch.tensor([0.01, -0.2, 0.05], dtype=torch.float64, requires_grad=True)
                t = torch.tensor(temp, dtype=torch.float64, requires_grad=needs_grad)
                tl = paper_lengths(hp, theta, offset, 0.07, temperature=t, points_per_transect=300)
                f = smith_fitness(tl.lengths, tl.weights).sum()
                f.backward()
                out.append((tl.lengths.detach(), theta.grad, offset.grad))
            for a, b in zip(*out, strict=True):
                torch.testing.assert_close(a, b, rtol=1e-9, atol=1e-9)
                assert torch.all(torch.isfinite(a))


def kernel_inputs(hp, theta, offset, spacing, temperature, points):
    """The fused kernel's inputs, built as :func:`paper_lengths` builds them."""
    theta, offset, across, along, b = _prepare(hp, theta, offset)
    temp = torch.broadcast_to(torch.as_tensor(temperature, dtype=across.dtype), theta.shape)
    c = transect_positions(offset, spacing, hp.radius)
    t = torch.linspace(-hp.radius, hp.radius, points, dtype=c.dtype)
    lhs = (temp[:, None] * across)[:, None, :] * c[:, :, None] + (temp[:, None] * b)[:, None, :]
    slope = temp[:, None] * along
    return lhs, slope, t, temp.contiguous(), 2 * hp.radius / (points - 1)


def kernel_run(poly, dtype, rows, spacing, temps, upstream, band):
    """Lengths and the gradients of ``sum(upstream * lengths)`` from the fused kernel."""
    hp = halfplanes(poly, dtype=dtype)
    theta = torch.tensor([th for th, _ in rows], dtype=dtype)
    offset = torch.tensor([off for _, off in rows], dtype=dtype)
    lhs, slope, t, temp, dx = kernel_inputs(hp, theta, offset, spacing, temps.to(dtype), 700)
    lhs.requires_grad_(True)
    slope.requires_grad_(True)
    length = _SigmoidIntegral.apply(lhs, slope, t, temp, dx, band)
    upstream = upstream.to(dtype)
    g_lhs, g_slope = torch.autograd.grad((length * upstream).sum(), (lhs, slope))
    return length.detach(), g_lhs, g_slope


@pytest.mark.grad
@pytest.mark.parametrize("dtype", [torch.float64, torch.float32])
@pytest.mark.parametrize("temperature", [1.0, 10.0, 1e3, 1e5, "mixed"])
def test_band_kernel_equals_full_kernel(parallelogram, triangle, square, dtype, temperature):
    """The band evaluation (saturated points summed in closed form) equals the evaluation at
    every point: values to rounding, gradients to rounding plus the documented bound on the
    dropped terms (4e-19 T per unit span in float64). Cases: random angles, transects through
    a vertex, tangent, exactly and nearly parallel to an edge; a batch mixing temperatures
    mixes band rows with rows left to the full kernel. In float32 both differ from the float64
    values by float32 rounding (sums of ~1000 terms of either sign, 1e-3 of the largest
    gradient); the band may differ from the full kernel by no more than the full kernel's own
    float32 error (twice it, as both round independently)."""
    gen = torch.Generator().manual_seed(5)
    for poly in (parallelogram, triangle, square):
        cases = degenerate_cases(poly)
        edge_angle, edge_offset = cases[1][0], cases[1][1]
        cases += [(edge_angle + d, edge_offset, 0.1) for d in (1e-9, 1e-6, 1e-3, 0.05)]
        cases += [(0.3, 0.02, 0.07), (1.9, -0.01, 0.07)]
        for spacing in sorted({s for _, _, s in cases}):
            rows = [(th, off) for th, off, s in cases if s == spacing]
            if temperature == "mixed":
                temps = torch.tensor([1.0, 1e3, 1e5, 30.0] * len(rows))[: len(rows)]
            else:
                temps = torch.full((len(rows),), temperature)
            temps = temps.to(torch.float64)
            k = len(transect_positions(torch.tensor(0.0), spacing, halfplanes(poly).radius))
            upstream = torch.randn(len(rows), k, generator=gen, dtype=torch.float64)
            args = (poly, dtype, rows, spacing, temps, upstream)
            full, banded = kernel_run(*args, band=False), kernel_run(*args, band=True)
            assert all(torch.all(torch.isfinite(x)) for x in banded)
            if dtype == torch.float64:
                torch.testing.assert_close(banded[0], full[0], rtol=1e-12, atol=0)
                # dropped terms: <= 4e-19 T * span * |upstream| per transect; the slope's gradient
                # sums K transects (times |t| <= radius <= 1). Rounding: both are sums of up to
                # K * P terms of either sign, in different orders.
                bound = 4e-19 * float(temps.max()) * 2 * halfplanes(poly).radius * k
                bound *= float(upstream.abs().max())
                for got, ref in zip(banded[1:], full[1:], strict=True):
                    rounding = 1e-12 * float(ref.abs().max())
                    torch.testing.assert_close(got, ref, rtol=1e-12, atol=bound + rounding)
            else:
                exact = kernel_run(poly, torch.float64, rows, spacing, temps, upstream, False)
                for got, ref, ref64 in zip(banded, full, exact, strict=True):
                    own_error = float((ref.double() - ref64).abs().max())
                    diff = float((got.double() - ref.double()).abs().max())
                    assert diff <= 2 * own_error + 1e-6 * float(ref64.abs().max()) + 1e-30


def test_public_band_switch_matches_every_point_evaluation(parallelogram):
    """Through the public API: a call large and hot enough to take the band evaluation equals
    PaperModel(band=False) in values and gradients."""
    hp = halfplanes(parallelogram)
    out = []
    for band in (True, False):
        theta = torch.linspace(0.0, 3.0, 40, dtype=torch.float64).requires_grad_()
        offset = torch.full((40,), 0.013, dtype=torch.float64, requires_grad=True)
        tl = PaperModel(temperature=2000.0, points_per_transect=1000, band=band)(
            hp, theta, offset, 0.0559
        )
        smith_fitness(tl.lengths, tl.weights).sum().backward()
        out.append((tl.lengths.detach(), theta.grad, offset.grad))
    for a, b in zip(*out, strict=True):
        torch.testing.assert_close(a, b, rtol=1e-10, atol=1e-12)
