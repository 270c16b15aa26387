"""The certified optimiser's spot check, screened (kernel_check, issue 21): the screen scores
the check's grid as the exact model does (to rounding), hands the grid to the exact model
where a value comes near the search's, and leaves every result as it was."""

from __future__ import annotations

import math

import numpy as np
import pytest

from boustro.geometry import random_convex_polygon
from boustro.models import grid_size
from boustro.optimize.exact import global_optimum, kernel_check, kernel_exact
from boustro.optimize.exact.kernel import compiled
from boustro.optimize.exact.smith import _check_grid, _Scorer, _spot_check

SPACINGS = (1 / 3, 1 / 10, 1 / 30, 1 / 100)


def cases(seed: int, count: int):
    """Seeded random convex polygons of 3-24 vertices, spacings 1/3 .. 1/100 of the diameter."""
    rng = np.random.default_rng(seed)
    for k in range(count):
        polygon = random_convex_polygon(rng, int(rng.integers(3, 25)))
        yield polygon, SPACINGS[k % len(SPACINGS)] * polygon.diameter


def problem(v, s, angles=None, offsets=None):
    """The arguments of the check kernels for vertices ``v`` (normalised) at spacing ``s``."""
    assert compiled() is not None
    n = len(v)
    normals, boffs = np.empty((n, 2)), np.empty(n)
    radius = kernel_exact._halfplanes_into(v, normals, boffs)
    k_count, m = grid_size(s, radius)
    grid = _check_grid(v, s)
    angles = grid[0] if angles is None else angles
    offsets = grid[1] if offsets is None else offsets
    lanes = np.empty((3, max(k_count, n)))
    return (v, normals, boffs, radius, s, k_count, m, 0.5, 0.5, angles, offsets, lanes)


def exact_grid(args):
    """Every layout of the grid by the exact model (kernel_exact._layout_value)."""
    v, normals, boffs, radius, s, k_count, m, a, b, angles, offsets, lanes = args
    out = np.empty((len(angles), len(offsets)))
    for i, theta in enumerate(angles):
        h_lo, h_hi = kernel_exact._angle_setup(normals, v, theta, lanes[0], lanes[1])
        for j, d in enumerate(offsets):
            out[i, j] = kernel_exact._layout_value(
                lanes[0], lanes[1], boffs, h_lo, h_hi, radius, s, k_count, m, d, a, b, lanes[2]
            )
    return out


def screened_grid(args):
    """Every layout of the grid by the screen (NaN where it declines)."""
    v, normals, _, radius, s, _, _, a, b, angles, offsets, lanes = args
    n = len(v)
    ch, counts = np.empty((2, n, 4)), np.empty(2, dtype=np.int64)
    sums, vals = np.empty((4, len(offsets))), np.empty(len(offsets))
    out = np.empty((len(angles), len(offsets)))
    for i, theta in enumerate(angles):
        h_lo, h_hi = kernel_exact._angle_setup(normals, v, theta, lanes[0], lanes[1])
        kernel_check._chains_at(v, theta, ch, counts)
        kernel_check._screen_angle(ch, counts, h_lo, h_hi, radius, s, offsets, a, b, sums, vals)
        out[i] = vals
    return out


def test_the_screen_scores_as_the_exact_model():
    """On seeded random polygons (3-24 vertices, spacings 1/3 .. 1/100 of the diameter), at
    the check's angles and at random ones, every layout the screen scores has the exact
    model's value to 1e-13 (the same transects counted), and it declines few."""
    rng = np.random.default_rng(5)
    scored = declined = 0
    for polygon, spacing in cases(12, 24):
        v = polygon.frame.to_normalised(polygon.vertices)
        s = spacing / polygon.diameter
        for angles in (None, rng.uniform(0, math.pi, 20)):
            args = problem(v, s, angles)
            exact, screen = exact_grid(args), screened_grid(args)
            done = ~np.isnan(screen)
            finite = np.isfinite(exact)
            assert np.array_equal(finite[done], np.isfinite(screen[done]))
            np.testing.assert_allclose(screen[done & finite], exact[done & finite], atol=1e-13)
            scored += int(done.sum())
            declined += int((~done).sum())
    assert scored > 20_000 and declined < scored / 100


def test_the_screen_declines_lines_through_vertices():
    """A square at angle 0 with offsets whose lines pass through its corners (the exact
    model's knife edge): those layouts go to the exact model, the others are screened."""
    v = np.array([(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)]) / math.sqrt(2)
    s = 0.1
    h = 0.5 / math.sqrt(2)  # the corners' height across the transects at angle 0
    corner = math.fmod(h, s)
    args = problem(v, s, np.array([0.0, 0.3]), np.array([0.01, corner, 0.07]))
    screen = screened_grid(args)
    assert np.isnan(screen[0, 1]) and not np.isnan(screen[0, 0]) and not np.isnan(screen[1, 1])
    out = np.empty(7)
    kernel_check._screened_check(*args, -math.inf, out)
    best = exact_grid(args)
    i, j = np.unravel_index(int(np.argmax(best)), best.shape)
    assert (out[3], out[4]) == (args[9][i], args[10][j])
    assert out[5] == pytest.approx(best[i, j], abs=1e-13)


def test_a_close_check_goes_to_the_exact_model_bit_for_bit():
    """Where the screen's best comes within SCREEN_MARGIN of the search's value, the grid is
    scored by the exact model: the check's answer is _check_into's, bit for bit."""
    for polygon, spacing in cases(13, 8):
        v = polygon.frame.to_normalised(polygon.vertices)
        args = problem(v, spacing / polygon.diameter)
        screened, exact = np.empty(7), np.empty(7)
        kernel_exact._check_into(*args, exact)
        top = exact[5]
        # far below: no hand-over; within the margin or above: hand-over
        assert not kernel_check._screened_check(*args, top + 1e-6, screened)
        assert kernel_check._screened_check(*args, top + 1e-12 - 0.5e-9, screened)
        assert kernel_check._screened_check(*args, top - 1e-3, screened)


def test_the_screen_misses_no_firing_check():
    """On random polygons the exact model's spot check (smith._spot_check) never beats the
    returned layout by more than 1e-12 where the screened one says it does not (the search
    and the candidates are untouched: the result is as before the screen)."""
    for polygon, spacing in cases(14, 12):
        r = global_optimum(polygon, spacing)
        assert r.info["converged"] and "note" not in r.info and r.gap <= 1e-6
        v = polygon.frame.to_normalised(polygon.vertices)
        s = spacing / polygon.diameter
        score = _Scorer(polygon, v, s, 0.5, 0.5, True)
        assert _spot_check(score, v, s)[2] <= r.fitness + 1e-12
