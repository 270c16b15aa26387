"""Optimisers: one result type, exact answers, wrap-around, reproducibility, bad input."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest
import torch

from boustro.errors import InvalidParameterError, NonConvexPolygonError, NoTransectError
from boustro.geometry import HalfPlanes, Polygon, halfplanes
from boustro.models import ExactModel, PaperModel, TransectLengths
from boustro.optimize import (
    GRID_200,
    METHODS,
    OptimizeResult,
    TemperatureSchedule,
    _grid_peaks,
    _problem,
    _wrap_,
    canonical,
    evaluate_grid,
    evaluate_pairs,
    exact_fitness,
    gradient_descent,
    grid_search,
    hybrid,
    optimize,
    register_method,
)

from .conftest import random_polygons

# Seeded random convex polygons (normalised frame) with spacings drawn as in the benchmark.
CASES_SEED = 20240521


def cases(count: int) -> list[tuple[Polygon, float]]:
    rng = np.random.default_rng(CASES_SEED)
    polys = random_polygons(CASES_SEED, count)
    return [(p, float(rng.uniform(0.01, 1 / 3)) * p.diameter) for p in polys]


CASES = cases(5)


def random_best(polygon: Polygon, spacing: float, seed: int, count: int = 100) -> float:
    """The best exact fitness of ``count`` uniform random (angle, offset) layouts."""
    rng = np.random.default_rng(seed)
    s_n = spacing / polygon.diameter
    angles = torch.tensor(rng.uniform(0.0, math.pi, count))
    offsets = torch.tensor(rng.uniform(0.0, s_n, count))
    return float(evaluate_pairs(halfplanes(polygon), angles, offsets, s_n).max())


# -- the result contract -------------------------------------------------------------------

# Contract tests run over every registered method (optax's pattern: a new method is tested by
# the existing contract tests); options that keep a method fast, where it has them.
FAST = {"gradient": {"steps": 30}, "hybrid": {"steps": 30}, "learned": {"refine": True}}


@pytest.mark.parametrize("method", list(METHODS))
def test_result_contract(parallelogram, method):
    result = optimize(parallelogram, 0.5, method=method, **FAST.get(method, {}))
    assert isinstance(result, OptimizeResult)
    assert result.method == method and result.spacing == 0.5
    assert 0.0 <= result.angle < math.pi and 0.0 <= result.offset < 0.5
    assert result.evaluations > 0 and result.seconds > 0
    # The reported fitness is the EXACT model's, whatever guided the search.
    exact = exact_fitness(parallelogram, 0.5, result.angle, result.offset)
    assert result.fitness == pytest.approx(exact, abs=1e-12)
    if result.history is not None:
        assert result.history.shape[1] == 3
        assert np.all(np.diff(result.history[:, 2]) >= 0)  # best so far never falls
        assert result.history[-1, 2] == pytest.approx(result.fitness)


@pytest.mark.parametrize("index", range(len(CASES)))
@pytest.mark.parametrize("method", list(METHODS))
def test_no_worse_than_random_candidates(method, index):
    polygon, spacing = CASES[index]
    options = {"refine": True} if method == "learned" else {}  # the network alone: no promise
    result = optimize(polygon, spacing, method=method, **options)
    assert result.fitness >= random_best(polygon, spacing, seed=index) - 1e-12


@pytest.mark.parametrize("index", range(len(CASES)))
def test_hybrid_never_worse_than_grid(index):
    polygon, spacing = CASES[index]
    result = hybrid(polygon, spacing)
    # Its own grid, and the paper's 14 x 14 grid (contained in the default 42 x 28).
    assert result.fitness >= grid_search(polygon, spacing, n_angles=42, n_offsets=28).fitness
    assert result.fitness >= grid_search(polygon, spacing, **GRID_200).fitness
    assert result.info["grid_fitness"] <= result.fitness


def test_hybrid_on_paper_grid_never_worse_than_paper_grid():
    for polygon, spacing in CASES[:3]:
        result = hybrid(polygon, spacing, **GRID_200, steps=15, zoom_levels=0)
        assert result.fitness >= grid_search(polygon, spacing, **GRID_200).fitness


def test_gradient_improves_on_its_starts(parallelogram):
    result = gradient_descent(parallelogram, 0.5, starts=4, screen=0, zoom_levels=0, steps=60)
    start = result.history[0, 2]
    assert result.fitness >= start
    assert result.info["trajectory"].shape[1:] == (4, 2)


def test_start_that_no_transect_crosses_is_moved():
    # Transects along a thin strip, offset half a spacing from its centre line: none crosses.
    strip = Polygon([(0, 0), (4, 0), (4, 0.1), (0, 0.1)])
    result = gradient_descent(strip, 1.0, init=([0.0], [0.5]), steps=5, zoom_levels=0)
    assert math.isfinite(result.fitness)
    assert result.info["trajectory"][0, 0, 1] == 0.0


# -- grid search ---------------------------------------------------------------------------


def test_grid_search_is_one_batched_evaluation_equal_to_a_loop(parallelogram):
    hp = halfplanes(parallelogram)
    s_n = 0.5 / parallelogram.diameter
    angles = torch.linspace(0, 3, 7, dtype=torch.float64)
    offsets = torch.linspace(0, s_n, 5, dtype=torch.float64)
    grid = evaluate_grid(hp, angles, offsets, s_n)
    loop = torch.tensor(
        [[float(evaluate_pairs(hp, a[None], o[None], s_n)[0]) for o in offsets] for a in angles],
        dtype=torch.float64,
    )
    torch.testing.assert_close(grid, loop)


def test_grid_200_preset(parallelogram):
    result = grid_search(parallelogram, 0.5, **GRID_200)
    assert result.evaluations == 196
    assert result.info == {"n_angles": 14, "n_offsets": 14}
    assert math.degrees(result.angle) * 14 / 180 == pytest.approx(
        round(math.degrees(result.angle) * 14 / 180)
    )


def test_grid_peaks_wrap_like_layouts():
    # Angle pi is angle 0 with the offset negated: grid point (last row, j) neighbours
    # (row 0, -j). Background values are distinct so that only real maxima are peaks.
    values = -torch.arange(24, dtype=torch.float64).reshape(4, 6) * 1e-3
    values[0, 5] = 2.5
    values[3, 1] = 2.0  # second best, but next to (0, 5) across the wrap: not a peak
    values[1, 3] = 1.0  # an isolated local maximum
    ranked = _grid_peaks(values, 3, 1.0).tolist()
    assert ranked[:2] == [0 * 6 + 5, 1 * 6 + 3]
    assert ranked[2] == 3 * 6 + 1  # the best of the rest fills in after the peaks
    # Minimising ranks the smallest values first.
    assert _grid_peaks(-values, 1, -1.0).tolist() == [5]


def test_minimised_objective():
    @dataclass(frozen=True)
    class FewestTransects:
        name: str = "count"
        maximise: bool = False

        def __call__(self, tl: TransectLengths) -> torch.Tensor:
            return tl.weights.sum(dim=-1)

    rectangle = Polygon([(0, 0), (4, 0), (4, 1), (0, 1)])
    result = grid_search(rectangle, 0.3, fitness=FewestTransects(), n_angles=36, n_offsets=10)
    # Fewest transects: along the long side (angle 0), 3 lines 0.3 apart inside a width of 1.
    assert result.fitness == 3
    assert min(result.angle, math.pi - result.angle) < 0.05


# -- wrap-around keeps the optimiser moving ------------------------------------------------


@dataclass(frozen=True)
class Ramp:
    """One transect whose length grows with the offset (mod spacing) and the angle (mod pi).

    With Eq. 1, ``f = 0.5 L + 0.5``, so gradient ascent pushes the offset (``along="offset"``)
    or the angle (``along="angle"``) up at a constant rate, through its wrap-around.
    """

    along: str = "offset"
    name: str = "ramp"

    def __call__(
        self, hp: HalfPlanes, theta: torch.Tensor, offset: torch.Tensor, spacing: float
    ) -> TransectLengths:
        theta, offset = torch.broadcast_tensors(theta, offset)
        if self.along == "offset":
            length = torch.remainder(offset, spacing) / spacing
        else:
            length = torch.remainder(theta, math.pi) / math.pi
        length = 0.1 + 0.5 * length[..., None]
        return TransectLengths(length, torch.ones_like(length), offset[..., None])


@pytest.mark.parametrize("optimizer", ["sgd", "adam"])
def test_offset_keeps_moving_after_wrap(square, optimizer):
    s = 0.2
    result = gradient_descent(
        square,
        s,
        model=Ramp("offset"),
        temperature=None,
        optimizer=optimizer,
        init=([0.3], [0.0]),
        steps=40,
        lr_angle=1e-3,
        lr_offset=0.002 if optimizer == "sgd" else 0.01,
        patience=None,
        tol=0.0,
        zoom_levels=0,
    )
    offsets = result.info["trajectory"][:, 0, 1]
    assert np.all((offsets >= 0) & (offsets < s))
    steps = np.diff(offsets)
    wraps = np.flatnonzero(steps < 0)
    assert len(wraps) >= 1, "the offset never wrapped"
    after = steps[wraps[0] + 1 :]
    after = after[after > 0]
    assert len(after) >= 3 and np.all(after > 1e-4), "the offset froze after wrapping"
    if optimizer == "sgd":
        # The momentum buffer survived: under a constant gradient SGD with momentum keeps
        # accelerating, so the step after the wrap is longer than the one before (a reset
        # optimizer state would start again from its first, shortest step).
        assert wraps[0] >= 5
        assert steps[wraps[0] + 1] > steps[wraps[0] - 1] > 2 * steps[0]


def test_angle_wrap_flips_offset_and_keeps_moving(square):
    s = 0.2
    result = gradient_descent(
        square,
        s,
        model=Ramp("angle"),
        temperature=None,
        optimizer="sgd",
        init=([math.pi - 0.05], [0.3 * s]),
        steps=30,
        lr_angle=0.02,
        lr_offset=1e-9,
        patience=None,
        tol=0.0,
        zoom_levels=0,
    )
    angles = result.info["trajectory"][:, 0, 0]
    offsets = result.info["trajectory"][:, 0, 1]
    assert np.all((angles >= 0) & (angles < math.pi))
    wrap = int(np.flatnonzero(np.diff(angles) < 0)[0])
    # (theta + pi, d) is the layout (theta, -d): the offset flips to s - 0.3 s.
    assert offsets[wrap] == pytest.approx(0.3 * s, abs=1e-6)
    assert offsets[wrap + 1] == pytest.approx(0.7 * s, abs=1e-6)
    assert np.all(np.diff(angles[wrap + 1 :]) > 1e-4), "the angle froze after wrapping"


def test_wrap_in_place_keeps_tensors_and_flips_velocity():
    s_n = 0.1
    theta = torch.tensor([math.pi + 0.1, 0.5, -0.2], dtype=torch.float64, requires_grad=True)
    offset = torch.tensor([0.03, 0.03, 0.25], dtype=torch.float64, requires_grad=True)
    opt = torch.optim.Adam([theta, offset], lr=0.01)
    (theta.sum() + offset.sum()).backward()
    opt.step()
    before_avg = opt.state[offset]["exp_avg"].clone()
    before_sq = opt.state[offset]["exp_avg_sq"].clone()
    params = [id(p) for g in opt.param_groups for p in g["params"]]
    with torch.no_grad():
        theta.copy_(torch.tensor([math.pi + 0.1, 0.5, -0.2]))
        offset.copy_(torch.tensor([0.03, 0.03, 0.25]))
    flips = _wrap_(theta, offset, s_n, opt)
    assert [id(p) for g in opt.param_groups for p in g["params"]] == params
    assert flips.tolist() == [True, False, True]
    torch.testing.assert_close(theta.detach(), torch.tensor([0.1, 0.5, math.pi - 0.2]).double())
    torch.testing.assert_close(offset.detach(), torch.tensor([0.07, 0.03, 0.05]).double())
    sign = torch.tensor([-1.0, 1.0, -1.0], dtype=torch.float64)
    torch.testing.assert_close(opt.state[offset]["exp_avg"], before_avg * sign)
    torch.testing.assert_close(opt.state[offset]["exp_avg_sq"], before_sq)


@pytest.mark.parametrize(
    ("angle", "offset", "expected"),
    [
        (0.3, 0.05, (0.3, 0.05)),
        (0.3 + math.pi, 0.05, (0.3, 0.15)),
        (0.3 - 2 * math.pi, -0.05, (0.3, 0.15)),
        (math.pi, 0.05, (0.0, 0.15)),
        (-1e-18, 0.05, (0.0, 0.05)),
    ],
)
def test_canonical(angle, offset, expected):
    a, o = canonical(angle, offset, 0.2)
    assert 0 <= a < math.pi and 0 <= o < 0.2
    assert (a, o) == pytest.approx(expected, abs=1e-12)


# -- reproducibility -----------------------------------------------------------------------


def test_reproducible_under_a_seed(parallelogram):
    kwargs = {"steps": 15, "starts": 3, "screen": 64}
    first = gradient_descent(parallelogram, 0.5, seed=7, **kwargs)
    again = gradient_descent(parallelogram, 0.5, seed=7, **kwargs)
    other = gradient_descent(parallelogram, 0.5, seed=8, **kwargs)
    assert (first.angle, first.offset, first.fitness) == (again.angle, again.offset, again.fitness)
    np.testing.assert_array_equal(first.info["trajectory"], again.info["trajectory"])
    assert not np.array_equal(first.info["trajectory"][0], other.info["trajectory"][0])
    h1, h2 = hybrid(parallelogram, 0.5, steps=10), hybrid(parallelogram, 0.5, steps=10)
    assert (h1.angle, h1.offset, h1.fitness) == (h2.angle, h2.offset, h2.fitness)


# -- schedules and guiding models ----------------------------------------------------------


def test_temperature_schedule():
    constant = TemperatureSchedule.constant(100)
    assert constant(0, 50) == constant(49, 50) == 100
    anneal = TemperatureSchedule.anneal(10, 1000)
    assert anneal(0, 5) == pytest.approx(10) and anneal(4, 5) == pytest.approx(1000)
    assert anneal(2, 5) == pytest.approx(100)  # geometric
    assert str(anneal) == "10:1000" and str(constant) == "100"
    with pytest.raises(InvalidParameterError):
        TemperatureSchedule(-1.0)


def test_annealing_reaches_the_final_temperature(parallelogram):
    result = gradient_descent(
        parallelogram, 0.5, temperature=(20, 400), steps=12, patience=None, tol=0.0, starts=2
    )
    assert result.info["final_temperature"] == pytest.approx(400)
    assert result.info["temperature"] == "20:400"


def test_model_without_temperature_needs_no_schedule(parallelogram):
    with pytest.raises(InvalidParameterError, match="no temperature"):
        gradient_descent(parallelogram, 0.5, model=ExactModel(), steps=5)
    result = gradient_descent(
        parallelogram, 0.5, model=ExactModel(), temperature=None, steps=5, starts=2
    )
    assert result.info["model"] == "exact"


def test_scheduled_model_asked_for_each_temperature(parallelogram):
    seen: list[float] = []

    class Tracking:
        name = "tracking"

        def __init__(self, temperature: float = 100.0):
            self.inner = PaperModel(temperature=temperature, points_per_transect=32)

        def with_temperature(self, temperature: float) -> Tracking:
            seen.append(temperature)
            return Tracking(temperature)

        def __call__(self, hp, theta, offset, spacing):
            return self.inner(hp, theta, offset, spacing)

    gradient_descent(
        parallelogram,
        0.5,
        model=Tracking(),
        temperature=(50, 200),
        steps=4,
        patience=None,
        tol=0.0,
        starts=2,
    )
    assert seen[0] == 50 and seen[-1] == pytest.approx(200) and len(seen) >= 4


def test_progress_bar_on_stderr(parallelogram, capsys):
    gradient_descent(parallelogram, 0.5, steps=3, starts=2, progress=True, patience=None)
    out, err = capsys.readouterr()
    assert out == "" and "gradient" in err


# -- dispatcher and bad input ---------------------------------------------------------------


def test_dispatcher_is_extensible(parallelogram):
    def constant(polygon, spacing, *, fitness=None, angle=0.25):
        return OptimizeResult(angle, 0.0, 0.5, spacing, "constant", 1, 0.0)

    register_method("constant-test", constant)
    try:
        assert optimize(parallelogram, 0.5, method="constant-test", angle=0.5).angle == 0.5
        with pytest.raises(InvalidParameterError, match="already registered"):
            register_method("constant-test", constant)
    finally:
        METHODS.pop("constant-test")
    with pytest.raises(InvalidParameterError, match="unknown method"):
        optimize(parallelogram, 0.5, method="nope")


@pytest.mark.parametrize("method", list(METHODS))
def test_spacing_larger_than_the_polygon(parallelogram, method):
    with pytest.raises(NoTransectError, match="not smaller than the polygon's diameter"):
        optimize(parallelogram, 1.01 * parallelogram.diameter, method=method)


@pytest.mark.parametrize("method", list(METHODS))
def test_bad_polygon_and_spacing(method):
    concave = [(0, 0), (4, 0), (4, 4), (2, 1), (0, 4)]
    with pytest.raises(NonConvexPolygonError):
        optimize(concave, 0.5, method=method)
    for spacing in (0, -1, float("nan"), "x"):
        with pytest.raises(InvalidParameterError):
            optimize([(0, 0), (1, 0), (0, 1)], spacing, method=method)


@pytest.mark.parametrize(
    "options",
    [
        {"optimizer": "lbfgs"},
        {"steps": -1},
        {"starts": 0},
        {"lr_angle": -0.1},
        {"lr_offset": float("inf")},
        {"momentum": 1.0},
        {"temperature": -5.0},
        {"temperature": (1.0, 2.0, 3.0)},
        {"patience": 0},
        {"init": ([0.1, 0.2], [float("nan")])},
    ],
)
def test_bad_gradient_options(parallelogram, options):
    with pytest.raises(InvalidParameterError):
        gradient_descent(parallelogram, 0.5, **options)


@pytest.mark.parametrize("options", [{"n_angles": 0}, {"n_offsets": 2.5}, {"n_angles": True}])
def test_bad_grid_options(parallelogram, options):
    with pytest.raises(InvalidParameterError):
        grid_search(parallelogram, 0.5, **options)
    with pytest.raises(InvalidParameterError):
        hybrid(parallelogram, 0.5, **options)


def test_problem_frame(parallelogram):
    p = _problem(parallelogram, 0.5, None, "test")
    assert p.s_n == pytest.approx(0.5 / parallelogram.diameter) and p.sign == 1.0


def test_global_method_dispatches_on_the_objective():
    from boustro.objectives import FewestTransects, ShortestPath

    poly = [(8, 4), (8, 10), (4, 8), (4, 2)]
    assert optimize(poly, 0.5, method="global").method == "global"
    fewest = optimize(poly, 0.5, method="global", fitness=FewestTransects())
    assert fewest.method == "fewest_transects" and fewest.fitness == 8  # width 4 / 0.5
    assert optimize(poly, 0.5, method="global", fitness=ShortestPath()).method == "shortest_path"


class _CountUS:
    """Transect count with the US spelling of the direction flag (issue 15, defect 1)."""

    maximize = False

    def __call__(self, tl):
        return tl.weights.sum(dim=-1)


def test_us_spelt_minimise_flag_is_honoured(parallelogram):
    from boustro.objectives import FewestTransects
    from boustro.optimize import grid_search

    us = grid_search(parallelogram, 0.5, fitness=_CountUS(), n_angles=90, n_offsets=8)
    uk = grid_search(parallelogram, 0.5, fitness=FewestTransects(), n_angles=90, n_offsets=8)
    assert us.fitness == uk.fitness  # the fewest transects, not the most
    assert us.fitness <= 9


@pytest.mark.parametrize(
    "flags",
    [{"maximise": True, "minimize": True}, {"sense": "down"}, {"maximise": "no"}],
)
def test_contradictory_or_malformed_direction_is_refused(parallelogram, flags):
    from boustro.optimize import grid_search

    objective = type("Odd", (), {"__call__": lambda self, tl: tl.weights.sum(-1), **flags})()
    with pytest.raises(InvalidParameterError, match="objective"):
        grid_search(parallelogram, 0.5, fitness=objective, n_angles=8, n_offsets=4)
