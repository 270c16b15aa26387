"""The certified optimiser's work after its search in one compiled call (kernel_check._finish)
against the Python code it replaces, and the option checks' kept signatures (issue 21)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from boustro import optimize as opt
from boustro.errors import InvalidParameterError
from boustro.geometry import Polygon, random_convex_polygon
from boustro.optimize.exact import global_optimum
from boustro.optimize.exact.kernel import finish_smith_compiled
from boustro.optimize.exact.smith import (
    _attained,
    _candidate_pieces,
    _check_grid,
    _Scorer,
    _spot_check,
)
from boustro.optimize.methods import _check_options

SPACINGS = (1 / 3, 1 / 10, 1 / 30, 1 / 100)


def cases(seed: int, count: int):
    """Seeded random convex polygons of 3-24 vertices, spacings 1/3 .. 1/100 of the diameter."""
    rng = np.random.default_rng(seed)
    for k in range(count):
        polygon = random_convex_polygon(rng, int(rng.integers(3, 25)))
        yield polygon, SPACINGS[k % len(SPACINGS)] * polygon.diameter


def finish(v, s, angles, a, b):
    """The compiled finish as global_optimum calls it (numpy orders tied pieces)."""
    grid = _check_grid(v, s)
    done = finish_smith_compiled(v, s, angles, a, b, *grid)
    if done[6] == 2.0:
        done = finish_smith_compiled(
            v, s, angles, a, b, *grid, _candidate_pieces(v, s, angles, a, b)
        )
    assert done[6] == 0.0
    return done


@pytest.mark.parametrize("weights", [(0.5, 0.5), (0.9, 0.1), (0.0, 1.0)])
def test_finish_is_the_python_scoring_bit_for_bit(weights):
    """The candidates' best layout against _attained with the same compiled pieces and
    scores: the same numbers, not only to rounding; the spot check's best layout against
    _spot_check's, screened (kernel_check): its value to rounding, and the exact model's
    value of the layout it names the same (tests/test_exact_check.py: bit for bit where the
    screen hands the grid to the exact model)."""
    a, b = weights
    rng = np.random.default_rng(4)
    for polygon, spacing in cases(8, 24):
        v = polygon.frame.to_normalised(polygon.vertices)
        s = spacing / polygon.diameter
        theta = rng.uniform(0, math.pi)
        width = rng.choice([1e-9, 1e-4, 1e-2])
        angles = np.array([theta, theta - width, theta + width])
        with np.errstate(all="ignore"):
            done = finish(v, s, angles, a, b)
            score = _Scorer(polygon, v, s, a, b, True)
            assert tuple(done[:3]) == _attained(score, v, s, angles, a, b)
            check = _spot_check(score, v, s)
            assert done[5] == pytest.approx(check[2], abs=1e-14)
            named = score.grid(np.array([done[3]]), np.array([done[4]]))[0, 0]
            assert named == pytest.approx(check[2], abs=1e-14)


def test_finish_agrees_with_the_torch_model():
    """The same against the numpy pieces and the torch model (BOUSTRO_COMPILED=0's path): the
    values to rounding."""
    for polygon, spacing in cases(9, 16):
        v = polygon.frame.to_normalised(polygon.vertices)
        s = spacing / polygon.diameter
        angles = np.array([0.3, 0.3 - 1e-3, 0.3 + 1e-3])
        with np.errstate(all="ignore"):
            done = finish(v, s, angles, 0.5, 0.5)
            score = _Scorer(polygon, v, s, 0.5, 0.5, False)
            value, _, _ = _attained(score, v, s, angles, 0.5, 0.5)
            check = _spot_check(score, v, s)
        assert done[0] == pytest.approx(value, abs=1e-12)
        assert done[5] == pytest.approx(check[2], abs=1e-12)


def test_tied_pieces_are_ordered_by_numpy():
    """A rectangle at angle 0: pieces tie, the kernel asks for numpy's order (flag 2), and
    with it gives what _attained gives."""
    square = Polygon([(0, 0), (2, 0), (2, 1), (0, 1)])
    v = square.frame.to_normalised(square.vertices)
    s = 0.25 / square.diameter
    angles = np.array([0.0, 0.0, math.pi / 2])
    grid = _check_grid(v, s)
    assert finish_smith_compiled(v, s, angles, 0.5, 0.5, *grid)[6] == 2.0
    done = finish(v, s, angles, 0.5, 0.5)
    with np.errstate(all="ignore"):
        assert tuple(done[:3]) == _attained(
            _Scorer(square, v, s, 0.5, 0.5, True), v, s, angles, 0.5, 0.5
        )
    r = global_optimum(square, 0.25)
    assert r.info["converged"] and r.fitness == pytest.approx(0.9505, abs=1e-4)


def test_option_checks_are_kept_and_still_refuse():
    """The signatures are kept per function: a refused option is refused every time, with the
    same message, and an unhashable callable is still checked."""
    square = [(0, 0), (2, 0), (2, 1), (0, 1)]
    for _ in range(2):
        with pytest.raises(InvalidParameterError, match="takes no option 'bogus'"):
            opt.optimize(square, 0.25, method="global", bogus=1)
        assert opt.optimize(square, 0.25, method="global", tol=1e-5).gap <= 1e-5

    class Unhashable:
        __hash__ = None  # type: ignore[assignment]

        def __call__(self, polygon, spacing, *, fitness=None, n=3):
            return None

    with pytest.raises(InvalidParameterError, match="takes no option 'm'"):
        _check_options("mine", Unhashable(), {"m": 1})
    _check_options("mine", Unhashable(), {"n": 1})
