"""The paper's model on lines at given positions (``paper_line_lengths``): one implementation
serves the library's grid (``paper_lengths``) and the experiments' batched Table I."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from boustro.errors import InvalidParameterError
from boustro.geometry import Polygon, halfplanes
from boustro.models import paper_lengths, paper_line_lengths, trapezoid_scale
from boustro.models.base import _components, _prepare, transect_positions

from .conftest import random_polygons

METHODS = ("full", "band", "subsets", "auto")


def _parts(polys, angles):
    """``(across, along, b)`` ``(S, E)`` of polygons with the same vertex count."""
    hp = halfplanes(polys)
    theta = torch.tensor(angles, dtype=torch.float64)
    return _components(torch.cos(theta), torch.sin(theta), hp.normals, hp.offsets)


def plain_lengths(across, along, b, positions, sample, half, temperature, points, step=None):
    """Eq. 3-6 by a plain trapezoid sum, one line and one point at a time."""
    out = []
    for m, c in enumerate(positions.tolist()):
        s = int(sample[m])
        h, temp = float(half[s]), float(temperature[s])
        dx = 2 * h / (points - 1) if step is None else step(h)
        total = 0.0
        for p in range(points):
            t = -h + 2 * h * p / (points - 1)
            prod = 1.0
            for j in range(across.shape[-1]):
                v = float(across[s, j]) * c + float(along[s, j]) * t + float(b[s, j])
                prod *= 1.0 / (1.0 + math.exp(-temp * v))
            q = 1.0 / (1.0 + math.exp(-temp * (prod - 0.5)))
            total += (0.5 if p in (0, points - 1) else 1.0) * dx * q
        out.append(total)
    return np.array(out)


@pytest.fixture
def ragged():
    """Three pentagons at their own angles, windows and temperatures; 4, 1 and 3 lines."""
    polys = random_polygons(3, 3, 5, 6)
    across, along, b = _parts(polys, [0.3, 1.2, 2.5])
    positions = torch.tensor([-0.3, -0.1, 0.05, 0.2, 0.0, -0.2, 0.1, 0.33], dtype=torch.float64)
    sample = torch.tensor([0, 0, 0, 0, 1, 2, 2, 2])
    half = torch.tensor([0.5, 0.7, 0.6], dtype=torch.float64)
    temperature = torch.tensor([30.0, 100.0, 8.0], dtype=torch.float64)
    return across, along, b, positions, sample, half, temperature


@pytest.mark.parametrize("method", METHODS)
def test_line_lengths_equal_a_plain_trapezoid_sum(ragged, method):
    across, along, b, positions, sample, half, temperature = ragged
    got = paper_line_lengths(
        across,
        along,
        b,
        positions,
        sample,
        half=half,
        temperature=temperature,
        points_per_transect=60,
        method=method,
    )
    want = plain_lengths(across, along, b, positions, sample, half, temperature, 60)
    np.testing.assert_allclose(got.numpy(), want, rtol=1e-12, atol=1e-14)


def test_authors_step_equals_a_plain_sum_with_step_over_points(ragged):
    """``trapezoid="points"``: the step ``2 half / points`` (the authors' ``1 / points`` for
    their window of half-width 0.5) at the same points."""
    across, along, b, positions, sample, half, temperature = ragged
    got = paper_line_lengths(
        across,
        along,
        b,
        positions,
        sample,
        half=half,
        temperature=temperature,
        points_per_transect=40,
        trapezoid="points",
    )
    want = plain_lengths(
        across, along, b, positions, sample, half, temperature, 40, step=lambda h: 2 * h / 40
    )
    np.testing.assert_allclose(got.numpy(), want, rtol=1e-12, atol=1e-14)
    with pytest.raises(InvalidParameterError):
        trapezoid_scale(40, "authors")  # type: ignore[arg-type]


@pytest.mark.parametrize("method", METHODS)
def test_batched_lines_equal_one_polygon_at_a_time(ragged, method):
    across, along, b, positions, sample, half, temperature = ragged
    shuffled = torch.tensor([5, 0, 7, 2, 4, 1, 6, 3])  # lines in any order
    got = paper_line_lengths(
        across,
        along,
        b,
        positions[shuffled],
        sample[shuffled],
        half=half,
        temperature=temperature,
        points_per_transect=300,
        method=method,
    )
    for s in range(3):
        mine = torch.nonzero(sample[shuffled] == s)[:, 0]
        one = paper_line_lengths(
            across[s : s + 1],
            along[s : s + 1],
            b[s : s + 1],
            positions[shuffled][mine],
            torch.zeros(len(mine), dtype=torch.long),
            half=float(half[s]),
            temperature=float(temperature[s]),
            points_per_transect=300,
            method="full",
        )
        torch.testing.assert_close(got[mine], one, rtol=1e-12, atol=1e-14)


def test_line_lengths_at_the_grid_equal_paper_lengths():
    """The lines of the library's grid give :func:`paper_lengths`' values (band and full)."""
    polys = random_polygons(8, 4, 4, 5)
    hp = halfplanes(polys)
    theta = torch.tensor([0.1, 0.7, 1.9, 2.8], dtype=torch.float64)
    offset = torch.tensor([0.01, -0.02, 0.03, 0.0], dtype=torch.float64)
    for temperature in (5.0, 2000.0):
        tl = paper_lengths(
            hp, theta, offset, 0.1, temperature=temperature, points_per_transect=2000
        )
        _, _, across, along, b = _prepare(hp, theta, offset)
        c = transect_positions(offset, 0.1, hp.radius)
        k = c.shape[-1]
        for method in ("full", "band", "auto"):
            got = paper_line_lengths(
                across,
                along,
                b,
                c.reshape(-1),
                torch.arange(4).repeat_interleave(k),
                half=hp.radius,
                temperature=temperature,
                points_per_transect=2000,
                method=method,
            )
            torch.testing.assert_close(got.view(4, k), tl.lengths, rtol=1e-12, atol=1e-13)


def test_paper_lengths_authors_step_scales_lengths_and_eq7_follows():
    hp = halfplanes(Polygon([(0, 0), (4, 0), (4, 3), (0, 3)]))
    args = (hp, torch.tensor(0.2), torch.tensor(0.05), 0.2)
    span = paper_lengths(*args, temperature=50.0, points_per_transect=100)
    points = paper_lengths(*args, temperature=50.0, points_per_transect=100, trapezoid="points")
    torch.testing.assert_close(points.lengths, span.lengths * 0.99, rtol=1e-15, atol=0)
    torch.testing.assert_close(points.weights, 2 * torch.sigmoid(50.0 * points.lengths) - 1)


@pytest.mark.grad
@pytest.mark.parametrize("method", ["full", "band", "auto"])
def test_line_lengths_gradcheck(ragged, method):
    across, along, b, positions, sample, half, _ = ragged
    temperature = torch.tensor([3.0, 5.0, 2.0], dtype=torch.float64)
    inputs = tuple(x.clone().requires_grad_(True) for x in (across, along, b, positions))

    def f(across, along, b, positions):
        return paper_line_lengths(
            across,
            along,
            b,
            positions,
            sample,
            half=half,
            temperature=temperature,
            points_per_transect=25,
            method=method,
        )

    assert torch.autograd.gradcheck(f, inputs, eps=1e-6, atol=1e-7)


def test_subsets_has_no_gradient(ragged):
    across, along, b, positions, sample, half, temperature = ragged
    with pytest.raises(InvalidParameterError, match="no gradient"):
        paper_line_lengths(
            across.clone().requires_grad_(True),
            along,
            b,
            positions,
            sample,
            half=half,
            temperature=temperature,
            points_per_transect=20,
            method="subsets",
        )
