import math

import numpy as np
import pytest
import torch

from boustro.errors import InvalidParameterError, NoTransectError
from boustro.fitness import SmithFitness, safe_sqrt, smith_fitness
from boustro.geometry import Polygon, halfplanes
from boustro.models import PaperModel
from boustro.scoring import score

from .conftest import random_polygons


def discrete_fitness(lengths, a=0.5, b=0.5):
    shown = lengths[lengths > 0]
    return a * shown.mean() + b * (1 - shown.std())  # numpy std is the population std


@pytest.mark.parametrize("statistics", ["weighted", "paper"])
def test_matches_discrete_definition(statistics):
    rng = np.random.default_rng(0)
    for _ in range(20):
        lengths = rng.random(15) * (rng.random(15) > 0.3)
        got = smith_fitness(torch.as_tensor(lengths), a=0.3, b=0.7, statistics=statistics)
        assert float(got) == pytest.approx(discrete_fitness(lengths, 0.3, 0.7), abs=1e-14)


def test_batched_equals_looped():
    lengths = torch.rand(4, 3, 10, dtype=torch.float64)
    weights = torch.rand(4, 3, 10, dtype=torch.float64)
    batched = smith_fitness(lengths, weights)
    for idx in np.ndindex(4, 3):
        single = smith_fitness(lengths[idx], weights[idx])
        assert float(batched[idx]) == pytest.approx(float(single))


def test_empty_is_finite_with_finite_gradient():
    lengths = torch.zeros(6, dtype=torch.float64, requires_grad=True)
    weights = torch.zeros(6, dtype=torch.float64, requires_grad=True)
    for statistics in ("weighted", "paper"):
        f = smith_fitness(lengths, weights, statistics=statistics)
        (g_l, g_w) = torch.autograd.grad(f, (lengths, weights))
        assert float(f.detach()) == 0.5  # mean 0, std 0: f = b
        assert torch.all(torch.isfinite(g_l)) and torch.all(torch.isfinite(g_w))


def test_equal_lengths_have_zero_std_and_finite_gradient():
    lengths = torch.full((5,), 0.4, dtype=torch.float64, requires_grad=True)
    f = smith_fitness(lengths, torch.ones(5, dtype=torch.float64))
    (g,) = torch.autograd.grad(f, lengths)
    assert float(f.detach()) == pytest.approx(0.5 * 0.4 + 0.5)
    assert torch.all(torch.isfinite(g))
    x = torch.tensor([0.0, 1e-40, 4.0], dtype=torch.float64, requires_grad=True)
    (gx,) = torch.autograd.grad(safe_sqrt(x).sum(), x)
    assert torch.all(torch.isfinite(gx)) and float(gx[2]) == pytest.approx(0.25)


def test_paper_statistics_inflate_the_mean_at_low_temperature(parallelogram):
    """The authors' code divides sum(L) by sum(S): at T = 1 every S is ~0.245, so the 'mean'
    is ~4x a length; this is the source of the paper's 0.5 error in Table I's first row."""
    hp = halfplanes(parallelogram)
    tl = PaperModel(temperature=1.0, points_per_transect=100, clip=True)(hp, 0.3, 0.0, 0.0559)
    paper = smith_fitness(tl.lengths, tl.weights, statistics="paper")
    weighted = smith_fitness(tl.lengths, tl.weights)
    assert float(paper) > 1.0 > float(weighted)


def test_invalid_settings():
    with pytest.raises(InvalidParameterError):
        SmithFitness(a=-1)
    with pytest.raises(InvalidParameterError):
        smith_fitness(torch.ones(3), statistics="median")  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError):
        smith_fitness(torch.ones(3), torch.ones(4))


def test_exact_score_without_transects_is_an_error():
    tiny = Polygon([(0, 0), (1, 0), (1, 1), (0, 1)])
    with pytest.raises(NoTransectError, match="no transect crosses"):
        score(tiny, spacing=10.0, angle=0.0, offset=5.0)


@pytest.mark.parametrize("seed", range(6))
def test_invariance_to_rotation_translation_scale(seed):
    rng = np.random.default_rng(seed)
    poly = Polygon(random_polygons(seed, 1)[0].vertices * 40 + [100, -7])
    spacing, angle, offset = rng.uniform(1, 8), rng.uniform(0, math.pi), rng.uniform(-3, 3)
    base = score(poly, spacing, angle, offset).fitness
    phi = rng.uniform(-3, 3)
    rotated = poly.rotated(phi, origin=rng.uniform(-50, 50, size=2))
    assert score(rotated, spacing, angle + phi, offset).fitness == pytest.approx(base, abs=1e-12)
    moved = poly.translated(*rng.uniform(-1e3, 1e3, size=2))
    assert score(moved, spacing, angle, offset).fitness == pytest.approx(base, abs=1e-12)
    k = rng.uniform(0.01, 100)
    scaled = poly.scaled(k, origin=(0, 0))
    assert score(scaled, spacing * k, angle, offset * k).fitness == pytest.approx(base, abs=1e-12)


@pytest.mark.parametrize("seed", range(6))
def test_periodicity_and_orientation(seed):
    rng = np.random.default_rng(seed)
    poly = random_polygons(100 + seed, 1)[0]
    spacing, angle, offset = rng.uniform(0.02, 0.3), rng.uniform(0, math.pi), rng.uniform(-1, 1)
    base = score(poly, spacing, angle, offset).fitness
    assert score(poly, spacing, angle, offset + spacing).fitness == pytest.approx(base, abs=1e-12)
    assert score(poly, spacing, angle, offset - 3 * spacing).fitness == pytest.approx(
        base, abs=1e-12
    )
    assert score(poly, spacing, angle + math.pi, -offset).fitness == pytest.approx(base, abs=1e-12)
    clockwise = poly.vertices[::-1]
    assert score(clockwise, spacing, angle, offset).fitness == pytest.approx(base, abs=1e-15)
    soft = score(poly, spacing, angle, offset, model=PaperModel(300.0, 200)).fitness
    soft_flipped = score(poly, spacing, angle + math.pi, -offset, model=PaperModel(300.0, 200))
    assert soft_flipped.fitness == pytest.approx(soft, abs=1e-12)
