"""The smooth closed form (boustro.smooth): limit, bounds, gradients, degenerate places."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
import torch

import boustro.smooth as smooth_module
from boustro.errors import InvalidParameterError
from boustro.fitness import smith_fitness
from boustro.geometry import HalfPlanes, Polygon, halfplanes
from boustro.models import (
    ExactModel,
    TransectModel,
    _prepare,
    exact_chords,
    transect_positions,
)
from boustro.optimize import evaluate_grid
from boustro.smooth import (
    DEFAULT_SMOOTHING,
    SmoothModel,
    length_error_bound,
    smooth_lengths,
    smoothing_from_temperature,
    temperature_from_smoothing,
)

F64 = torch.float64
LEVELS = (1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6)
MARGIN = 32.0  # boustro.smooth._MARGIN: the smooth grid covers the disc grown by 32 h


def random_convex_polygon(rng: np.random.Generator, n: int) -> Polygon:
    """Vertices at sorted random angles on a random ellipse: convex by construction."""
    while True:
        angles = np.sort(rng.uniform(0, 2 * math.pi, n))
        gaps = np.diff(np.concatenate([angles, angles[:1] + 2 * math.pi]))
        if gaps.min() > 0.05:
            break
    ax, ay = 1.0, rng.uniform(0.2, 1.0)
    rot = rng.uniform(0, math.pi)
    pts = np.stack([ax * np.cos(angles), ay * np.sin(angles)], axis=1)
    c, s = math.cos(rot), math.sin(rot)
    pts = pts @ np.array([[c, -s], [s, c]]).T + rng.normal(size=2)
    return Polygon(pts)


def random_polygons(seed: int, count: int) -> list[Polygon]:
    rng = np.random.default_rng(seed)
    return [random_convex_polygon(rng, int(rng.integers(3, 10))) for _ in range(count)]


def grown(hp: HalfPlanes, smoothing: float) -> HalfPlanes:
    """The same half-planes with the radius the smooth model's grid covers, for exact_chords."""
    return HalfPlanes(hp.normals, hp.offsets, hp.radius + MARGIN * smoothing)


def batch(seed: int, polygons: int = 16, pairs: int = 8, spacing: float = 0.07):
    """Padded half-planes (P, E) and angles, offsets (A, P), offsets inside (0.1 s, 0.9 s)."""
    hp = halfplanes(random_polygons(seed, polygons))
    gen = torch.Generator().manual_seed(seed)
    theta = torch.rand(pairs, polygons, generator=gen, dtype=F64) * 2 * math.pi
    offset = (0.1 + 0.8 * torch.rand(pairs, polygons, generator=gen, dtype=F64)) * spacing
    return hp, theta, offset, spacing


# -- the zero-smoothing limit ----------------------------------------------------------------------
@pytest.mark.parametrize("clip", [False, True])
def test_lengths_within_the_error_bound_at_every_level(clip):
    hp, theta, offset, s = batch(0)
    n_edges = hp.normals.shape[-2]
    worst = []
    for h in LEVELS:
        tl = smooth_lengths(hp, theta, offset, s, smoothing=h, clip=clip)
        ex = exact_chords(grown(hp, h) if not clip else hp, theta, offset, s, clip=clip)
        assert torch.equal(tl.positions, ex.positions)
        err = (tl.lengths - ex.lengths).abs().max().item()
        assert err <= length_error_bound(h, n_edges) + 1e-12, (h, err)
        worst.append(err)
    assert all(b < a for a, b in itertools.pairwise(worst)), worst
    assert worst[-1] < 1e-5


def test_weights_tend_to_the_step():
    hp, theta, offset, s = batch(1)
    h = 1e-4
    tl = smooth_lengths(hp, theta, offset, s, smoothing=h)
    ex = exact_chords(grown(hp, h), theta, offset, s)
    d = ex.upper - ex.lower  # signed chord; -inf-free for the candidates here
    far = d.abs() > 50 * h
    step = (d > 0).to(F64)
    assert far.float().mean() > 0.9
    assert torch.allclose(tl.weights[far], step[far], atol=1e-20, rtol=0)
    assert torch.all((tl.weights >= 0) & (tl.weights <= 1))


def test_fitness_error_shrinks_with_smoothing():
    hp, theta, offset, s = batch(2, polygons=24, pairs=8)
    exact = ExactModel()(hp, theta, offset, s)
    f_exact = smith_fitness(exact.lengths, exact.weights)
    means = []
    for h in LEVELS:
        tl = smooth_lengths(hp, theta, offset, s, smoothing=h)
        means.append((smith_fitness(tl.lengths, tl.weights) - f_exact).abs().mean().item())
    assert all(b < a for a, b in itertools.pairwise(means)), means
    # Below the paper's best Table I cell (0.00016) from h = 1e-4 on (benchmarks: from 1e-3).
    assert means[3] < 1.6e-4 and means[5] < 1e-9, means


def test_zero_smoothing_is_the_exact_model():
    hp, theta, offset, s = batch(3)
    for clip in (False, True):
        a = smooth_lengths(hp, theta, offset, s, smoothing=0.0, clip=clip)
        b = ExactModel(clip=clip)(hp, theta, offset, s)
        for x, y in zip(a, b, strict=True):
            assert torch.equal(x, y)
    assert SmoothModel(smoothing=0).temperature == math.inf


@pytest.fixture(params=["compiled", "whole", "sparse"])
def kernel_path(request, monkeypatch):
    """Every evaluation of the model: the compiled CPU kernels (``boustro._compiled``), and the
    tensor code's whole-tensor (small calls) and sparse-tail (large calls) paths, chosen by
    ``boustro.smooth._SPARSE_MIN``."""
    monkeypatch.setattr(smooth_module, "COMPILED", request.param == "compiled")
    monkeypatch.setattr(smooth_module, "COMPILED_MIN", 0)  # small test calls included
    monkeypatch.setattr(smooth_module, "_SPARSE_MIN", 0 if request.param == "sparse" else 1 << 62)
    return request.param


# -- gradients -------------------------------------------------------------------------------------
@pytest.mark.grad
@pytest.mark.parametrize("h", [0.05, 0.01])
@pytest.mark.parametrize("clip", [False, True])
def test_gradcheck(h, clip, kernel_path):
    hp = halfplanes(random_polygons(4, 3))
    theta = torch.tensor([0.3, 1.9, 4.0], dtype=F64, requires_grad=True)
    offset = torch.tensor([0.03, 0.05, 0.07], dtype=F64, requires_grad=True)
    smoothing = torch.tensor([h, 2 * h, h / 2], dtype=F64, requires_grad=True)
    s = 0.1  # positions 0.03 + 0.1 k etc. stay >= 0.03 from the clip window's edges

    def lengths_and_weights(theta, offset, smoothing):
        tl = smooth_lengths(hp, theta, offset, s, smoothing=smoothing, clip=clip)
        return tl.lengths, tl.weights, smith_fitness(tl.lengths, tl.weights)

    assert torch.autograd.gradcheck(lengths_and_weights, (theta, offset, smoothing))


def _breakpoint_distance(hp: HalfPlanes, theta, offset, s, smoothing):
    """Per pair: the smallest distance of any transect to a breakpoint of the exact model
    (two lower or two upper bounds equal, or the chord length zero)."""
    _, _, across, along, b = _prepare(hp, theta, offset)
    c = exact_chords(grown(hp, smoothing), theta, offset, s).positions
    a = across[..., None, :] * c[..., :, None] + b[..., None, :]
    al = along[..., None, :]
    bound = -a / torch.where(al == 0, 1.0, al)
    lo = torch.where(al > 0, bound, -math.inf).sort(dim=-1, descending=True).values
    up = torch.where(al < 0, bound, math.inf).sort(dim=-1).values
    gaps = torch.stack(
        [lo[..., 0] - lo[..., 1], up[..., 1] - up[..., 0], (up[..., 0] - lo[..., 0]).abs()], -1
    )
    return gaps.nan_to_num(math.inf).amin(dim=(-1, -2))


@pytest.mark.grad
def test_gradients_match_finite_differences_of_the_exact_model():
    hp, theta, offset, s = batch(5, polygons=24, pairs=6)
    h = 1e-7
    away = _breakpoint_distance(hp, theta, offset, s, h) > 1e-3
    assert away.sum() >= 40

    def exact_f(th, off):
        tl = exact_chords(grown(hp, h), th, off, s)
        return smith_fitness(tl.lengths), tl.lengths.sum(-1)

    th = theta.clone().requires_grad_(True)
    off = offset.clone().requires_grad_(True)
    tl = smooth_lengths(hp, th, off, s, smoothing=h)
    f = smith_fitness(tl.lengths, tl.weights)
    total = tl.lengths.sum(-1)
    for value, index in ((f, 0), (total, 1)):
        g_th, g_off = torch.autograd.grad(value.sum(), (th, off), retain_graph=True)
        eps = 1e-6
        fd_th = (exact_f(theta + eps, offset)[index] - exact_f(theta - eps, offset)[index]) / (
            2 * eps
        )
        fd_off = (exact_f(theta, offset + eps)[index] - exact_f(theta, offset - eps)[index]) / (
            2 * eps
        )
        torch.testing.assert_close(g_th[away], fd_th[away], atol=1e-6, rtol=1e-5)
        torch.testing.assert_close(g_off[away], fd_off[away], atol=1e-6, rtol=1e-5)


def _square() -> HalfPlanes:
    """The square [-1/4, 1/4]^2 as exact binary half-planes (edges exactly parallel at 0, pi/2)."""
    normals = torch.tensor([[0.0, 1.0], [-1.0, 0.0], [0.0, -1.0], [1.0, 0.0]], dtype=F64)
    return HalfPlanes(normals, torch.full((4,), 0.25, dtype=F64), 0.25 * math.sqrt(2))


@pytest.mark.grad
@pytest.mark.parametrize("h", [1e-1, 1e-4, 1e-8])
@pytest.mark.parametrize("dtype", [torch.float64, torch.float32])
def test_finite_gradients_at_degenerate_places(h, dtype, kernel_path):
    square = _square()
    diamond = halfplanes(Polygon([(0.5, 0), (0, 0.5), (-0.5, 0), (0, -0.5)]))
    hexagon = [(math.cos(k * math.pi / 3), math.sin(k * math.pi / 3)) for k in range(6)]
    mixed = halfplanes([Polygon([(0, 0), (1, 0), (0, 1)]), Polygon(hexagon)])
    cases = [
        # transects exactly on the square's edges, edges exactly parallel (along == 0)
        (square, [0.0, math.pi / 2, math.pi], [0.0, 0.0, 0.0], 0.125),
        # transects through the diamond's four vertices (c = 0: side vertices; c = +-1/2:
        # the extreme ones, chord length exactly 0), and grazing them
        (diamond, [0.0, math.pi / 2, math.pi / 4], [0.0, 1e-15, 0.0], 0.25),
        # padding half-planes (normal 0), empty transects outside, a huge offset
        (mixed, [[0.7, 2.0]], [[0.0, 1e3]], 0.05),
    ]
    for hp, theta, offset, s in cases:
        hp = HalfPlanes(hp.normals.to(dtype), hp.offsets.to(dtype), hp.radius)
        th = torch.tensor(theta, dtype=dtype, requires_grad=True)
        off = torch.tensor(offset, dtype=dtype, requires_grad=True)
        hh = torch.tensor(h, dtype=dtype, requires_grad=True)
        tl = smooth_lengths(hp, th, off, s, smoothing=hh)
        assert torch.isfinite(tl.lengths).all() and torch.isfinite(tl.weights).all()
        value = smith_fitness(tl.lengths, tl.weights).sum() + tl.lengths.sum() + tl.weights.sum()
        grads = torch.autograd.grad(value, (th, off, hh))
        for g in grads:
            assert torch.isfinite(g).all(), (theta, offset, h, grads)


def test_transect_on_a_parallel_edge_counts_like_the_exact_model():
    square = _square()
    s = 0.125
    ex = exact_chords(grown(square, 1e-9), 0.0, 0.0, s)
    tl = smooth_lengths(square, 0.0, 0.0, s, smoothing=1e-9)
    on_edge = ex.positions.abs() == 0.25
    assert on_edge.sum() == 2
    torch.testing.assert_close(ex.lengths[on_edge], torch.full((2,), 0.5, dtype=F64))
    torch.testing.assert_close(tl.lengths, ex.lengths, atol=1e-8, rtol=0)
    outside = ex.positions.abs() > 0.25
    assert torch.all(tl.weights[outside] < 1e-12)


# -- the evaluation against the plain formula -----------------------------------------------------
def plain_formula(hp, theta, offset, spacing, h, clip):
    """The module docstring's formula, term by term, with autograd: the reference for the
    slot-sorted kernel with its analytic backward and its shortcuts."""
    theta, offset, across, along, b = _prepare(hp, theta, offset)
    window = 0.5 if clip else hp.radius + MARGIN * h
    c = transect_positions(offset, spacing, window)
    real = torch.broadcast_to(hp.normals.abs().sum(-1) > 0, along.shape)  # not padding
    safe = torch.where(real, along, torch.ones_like(along))
    bound = -(b[..., None, :] + across[..., None, :] * c[..., :, None]) / safe[..., None, :]
    lower = torch.where((real & (along > 0))[..., None, :], bound / h, -math.inf)
    minus_upper = torch.where((real & (along < 0))[..., None, :], -bound / h, -math.inf)
    if clip:
        w = torch.full((*lower.shape[:-1], 1), -0.5 / h, dtype=lower.dtype)
        lower, minus_upper = torch.cat([lower, w], -1), torch.cat([minus_upper, w], -1)
    z = -torch.logsumexp(lower, -1) - torch.logsumexp(minus_upper, -1)
    length, weight = h * torch.nn.functional.softplus(z), torch.sigmoid(z)
    if clip:
        inside = (c >= -0.5) & (c < 0.5)
        length, weight = length * inside, weight * inside
    return length, weight


@pytest.mark.grad
@pytest.mark.parametrize("clip", [False, True])
@pytest.mark.parametrize("h", [3e-2, 1e-3, 1e-4])
def test_kernel_equals_the_plain_formula(h, clip, kernel_path):
    # batched polygons of 3-9 edges (padded), two angle/offset pairs each; values and the
    # gradients of Eq. 1 w.r.t. angle and offset, on both evaluation paths
    hp, theta, offset, s = batch(11, polygons=12, pairs=2, spacing=0.05)
    results = []
    for f in (smooth_lengths, plain_formula):
        th, off = theta.clone().requires_grad_(True), offset.clone().requires_grad_(True)
        if f is smooth_lengths:
            length, weight, _ = f(hp, th, off, s, smoothing=h, clip=clip)
        else:
            length, weight = f(hp, th, off, s, h, clip)
        fit = smith_fitness(length, weight)
        results.append((length, weight, fit, *torch.autograd.grad(fit.sum(), (th, off))))
    names = ("lengths", "weights", "fitness", "d/dangle", "d/doffset")
    for name, x, y in zip(names, *results, strict=True):
        scale = float(y.detach().abs().max())
        torch.testing.assert_close(x, y, atol=1e-9 * max(scale, 1.0), rtol=1e-9, msg=name)


# -- batching, interface, errors -------------------------------------------------------------------
@pytest.mark.parametrize("clip", [False, True])
def test_batched_equals_looped(clip, kernel_path):
    hp, theta, offset, s = batch(6, polygons=5, pairs=3)
    tl = smooth_lengths(hp, theta, offset, s, smoothing=1e-3, clip=clip)
    for i in range(theta.shape[0]):
        for p in range(theta.shape[1]):
            one = HalfPlanes(hp.normals[p], hp.offsets[p], hp.radius)
            single = smooth_lengths(one, theta[i, p], offset[i, p], s, smoothing=1e-3, clip=clip)
            for x, y in zip(single, tl, strict=True):
                torch.testing.assert_close(x, y[i, p], atol=1e-13, rtol=1e-13)


def test_per_element_smoothing_equals_looped_fitness():
    hp, theta, offset, s = batch(7, polygons=4, pairs=2)
    h = torch.tensor([[1e-2, 1e-3, 1e-4, 1e-5], [3e-3, 3e-4, 3e-5, 3e-6]], dtype=F64)
    tl = smooth_lengths(hp, theta, offset, s, smoothing=h)
    f = smith_fitness(tl.lengths, tl.weights)
    for i in range(2):
        for p in range(4):
            one = HalfPlanes(hp.normals[p], hp.offsets[p], hp.radius)
            single = smooth_lengths(one, theta[i, p], offset[i, p], s, smoothing=float(h[i, p]))
            expect = smith_fitness(single.lengths, single.weights)
            torch.testing.assert_close(f[i, p], expect, atol=1e-12, rtol=0)


def test_model_interface_and_optimiser_use():
    model = SmoothModel()
    assert isinstance(model, TransectModel)
    assert model.name == "soft" and model.smoothing == DEFAULT_SMOOTHING
    assert SmoothModel.from_temperature(1000.0).smoothing == pytest.approx(1e-3)
    assert SmoothModel(smoothing=1e-4).temperature == pytest.approx(1e4)
    hot = SmoothModel(clip=True).with_temperature(200.0)
    assert hot == SmoothModel(smoothing=1 / 200.0, clip=True)
    assert temperature_from_smoothing(smoothing_from_temperature(250.0)) == pytest.approx(250.0)
    poly = random_polygons(8, 1)[0]
    hp = halfplanes(poly)
    angles = torch.linspace(0, math.pi, 7, dtype=F64)[:-1]
    offsets = torch.linspace(0, 0.1, 5, dtype=F64)[:-1]
    soft = evaluate_grid(hp, angles, offsets, 0.1, model=SmoothModel(smoothing=1e-6))
    exact = evaluate_grid(hp, angles, offsets, 0.1)
    torch.testing.assert_close(soft, exact, atol=1e-5, rtol=0)
    # float32 on the way in gives float32 out
    hp32 = HalfPlanes(hp.normals.float(), hp.offsets.float(), hp.radius)
    tl = model(hp32, torch.tensor(0.3), torch.tensor(0.01), 0.1)
    assert tl.lengths.dtype == torch.float32


@pytest.mark.parametrize(
    "kwargs",
    [
        {"smoothing": -1e-3},
        {"smoothing": math.nan},
        {"smoothing": math.inf},
        {"smoothing": torch.tensor([1e-3, 0.0])},
    ],
)
def test_bad_smoothing_raises(kwargs):
    hp = _square()
    with pytest.raises(InvalidParameterError, match="smoothing"):
        smooth_lengths(hp, torch.zeros(2), torch.zeros(2), 0.1, **kwargs)


def test_bad_settings_raise():
    with pytest.raises(InvalidParameterError, match="spacing"):
        smooth_lengths(_square(), 0.0, 0.0, 0.0)
    with pytest.raises(InvalidParameterError, match="smoothing"):
        SmoothModel(smoothing=-1.0)
    with pytest.raises(InvalidParameterError, match="temperature"):
        SmoothModel.from_temperature(0.0)
