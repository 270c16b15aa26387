"""The certified Eq. 1 branch and bound at scale (``method="certified-bb"``,
:mod:`boustro.optimize.smith_bb`): its box bound against layouts sampled inside the boxes, its
result against a dense grid and the event method, and its use by ``plan_area``."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest
import torch

from boustro.errors import InvalidParameterError, NonConvexPolygonError, ProblemTooLargeError
from boustro.geometry import Polygon, halfplanes
from boustro.geometry.random import random_convex_polygon
from boustro.mission import estimate_work, plan_area
from boustro.objectives import ShortestPath, SmithFitness
from boustro.optimize import evaluate_grid, evaluate_pairs
from boustro.optimize.cover.boxes import Boxes
from boustro.optimize.exact import global_optimum
from boustro.optimize.smith_bb import smith_bb
from boustro.optimize.smith_bb.kernel import _sup, eq1_at_angle, eq1_values
from boustro.optimize.smith_bb.search import _Search


def ellipse(n: int, rx: float = 150.0, ry: float = 105.0) -> np.ndarray:
    t = np.linspace(0, 2 * math.pi, n, endpoint=False)
    return np.c_[rx * np.cos(t), ry * np.sin(t)]


def _polygons(seed: int, count: int) -> list[tuple[Polygon, float]]:
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        p = random_convex_polygon(rng, int(rng.integers(3, 41)))
        out.append((p, p.diameter * float(rng.uniform(0.03, 0.2))))
    return out


def test_the_interval_maximum_is_the_maximum_over_the_box_of_lengths():
    """``_sup``: never below Eq. 1 at lengths sampled in the intervals (nor on the path
    ``clip(c)`` where the maximiser lies), and reached by it to the sampling's resolution."""
    rng = np.random.default_rng(3)
    for trial in range(60):
        n = int(rng.integers(1, 10))
        a, b = (0.0, 1.0) if trial % 10 == 0 else tuple(rng.uniform(0, 1, 2))
        lo = rng.uniform(0, 1, n)
        hi = lo + rng.uniform(0, 0.5, n) * (rng.uniform(size=n) < 0.7)
        if trial % 7 == 0:  # nearly equal lengths: the std's kink
            lo[:], hi[:] = 0.3, 0.3 + rng.uniform(0, 1e-3, n)
        sup = _sup(lo, hi, 0, n - 1, a, b, np.empty(2 * n))
        pts = np.concatenate(
            [rng.uniform(lo, hi, (500, n)), np.clip(np.linspace(-0.5, 2, 20001)[:, None], lo, hi)]
        )
        values = a * pts.mean(axis=1) + b * (1 - pts.std(axis=1))
        assert values.max() <= sup + 1e-12
        assert sup - values.max() < 1e-4


def test_chord_kernels_agree_with_the_library_model():
    for p, s in _polygons(5, 6):
        search = _Search(p, s, 0.5, 0.5)
        rng = np.random.default_rng(len(p))
        theta, d = rng.uniform(0, math.pi, 40), rng.uniform(0, search.s, 40)
        ours = eq1_values(search.xy, theta, d, search.s, 0.5, 0.5)
        ref = evaluate_pairs(
            halfplanes(p), torch.as_tensor(theta), torch.as_tensor(d), search.s,
            fitness=SmithFitness(),
        ).numpy()  # fmt: skip
        assert np.allclose(ours, ref, rtol=0, atol=1e-12)
        chains = eq1_at_angle(search.v, float(theta[0]), d, search.s, 0.5, 0.5)
        grid = evaluate_grid(
            halfplanes(p), torch.as_tensor(theta[:1]), torch.as_tensor(d), search.s,
            fitness=SmithFitness(),
        ).numpy()[0]  # fmt: skip
        assert np.allclose(chains, grid, rtol=0, atol=1e-12)


@pytest.mark.parametrize("case", range(5))
def test_the_box_bound_is_never_below_eq1_inside_the_box(case):
    """Random boxes of every size (down to 1e-9 of the diameter) on seeded convex polygons and
    a 300-gon (simplified sandwiches): Eq. 1 at 64 layouts sampled inside each box, and at its
    corners, never exceeds the box's bound."""
    if case < 4:
        p, s = _polygons(100 + case, 1)[0]
    else:
        p, s = Polygon(ellipse(300)), 10.0
    fit = SmithFitness(a=[0.5, 0.9, 0.1, 0.5, 0.3][case], b=[0.5, 0.1, 0.9, 0.5, 0.7][case])
    search = _Search(p, s, fit.a, fit.b)
    hp = halfplanes(p)
    rng = np.random.default_rng(case)
    m = 40
    size = 10.0 ** rng.uniform(-9, -1, m)
    boxes = Boxes(
        rng.uniform(0, math.pi, m), size / search.radius * rng.uniform(0.2, 1, m),
        rng.uniform(0, search.s, m), size * rng.uniform(0.2, 1, m),
    )  # fmt: skip
    search.top_eps = float((boxes.delta * search.radius + boxes.eta).max())
    bounds = search.bounds(boxes)
    u = rng.uniform(-1, 1, (m, 64, 2))
    u[:, :4] = [[-1, -1], [-1, 1], [1, -1], [1, 1]]
    theta = boxes.theta[:, None] + u[..., 0] * boxes.delta[:, None]
    d = boxes.d[:, None] + u[..., 1] * boxes.eta[:, None]
    values = evaluate_pairs(
        hp, torch.as_tensor(theta.ravel()), torch.as_tensor(d.ravel()), search.s, fitness=fit
    ).numpy().reshape(m, 64)  # fmt: skip
    assert np.all(values.max(axis=1) <= bounds), (values.max(axis=1) - bounds).max()
    # and the bound is not vacuous: small boxes are close to their values
    small = size < 1e-6
    assert np.all(bounds[small] - values.max(axis=1)[small] < 1e-4)


@pytest.mark.parametrize("case", range(3))
def test_the_certificate_holds_against_a_dense_grid(case):
    p, s = [*_polygons(7, 2), (Polygon(ellipse(300, 120, 70)), 9.0)][case]
    r = smith_bb(p, s, tol=1e-5)
    assert r.method == "certified-bb" and r.info["converged"] and r.gap <= 1e-5 + 1e-12
    hp = halfplanes(p)
    s_n = s / p.frame.scale
    n_angles, n_offsets = (361, 49) if case < 2 else (121, 25)
    grid = evaluate_grid(
        hp, torch.linspace(0, math.pi, n_angles, dtype=torch.float64)[:-1],
        torch.linspace(0, s_n, n_offsets, dtype=torch.float64)[:-1], s_n, fitness=SmithFitness(),
    )  # fmt: skip
    assert float(grid.max()) <= r.upper_bound + 1e-12
    assert r.fitness >= float(grid.max()) - r.gap - 1e-12
    # the reported fitness is the library's exact score of the returned layout
    d = torch.tensor([r.offset / p.frame.scale], dtype=torch.float64)
    exact = evaluate_grid(hp, torch.tensor([r.angle], dtype=torch.float64), d, s_n)
    assert float(exact[0, 0]) == pytest.approx(r.fitness, abs=1e-12)


@pytest.mark.parametrize("case", range(6))
def test_agrees_with_the_event_method_within_the_gaps(case):
    p, s = _polygons(11, 6)[case]
    g = global_optimum(p, s)
    b = smith_bb(p, s, tol=1e-6)
    assert b.info["converged"]
    assert b.fitness >= g.fitness - b.gap - 1e-12
    assert g.fitness >= b.fitness - g.gap - 1e-12
    assert b.upper_bound >= g.fitness - 1e-12 and g.upper_bound >= b.fitness - 1e-12


def test_a_spent_budget_reports_its_gap():
    """A regular 100-gon (nearly a circle: Eq. 1 nearly the same at every angle) with a small
    budget: the search stops, says why, and its bound still holds over a dense grid."""
    t = np.linspace(0, 2 * math.pi, 100, endpoint=False)
    p = Polygon(np.c_[500 * np.cos(t), 500 * np.sin(t)])
    r = smith_bb(p, 10.0, max_work=2e6)
    assert not r.info["converged"] and "work budget" in r.info["stopped"]
    assert r.gap > 1e-4 and r.upper_bound == pytest.approx(r.fitness + r.gap)
    hp, s_n = halfplanes(p), 10.0 / p.frame.scale
    grid = evaluate_grid(
        hp, torch.linspace(0, math.pi, 181, dtype=torch.float64)[:-1],
        torch.linspace(0, s_n, 33, dtype=torch.float64)[:-1], s_n, fitness=SmithFitness(),
    )  # fmt: skip
    assert float(grid.max()) <= r.upper_bound + 1e-12


@pytest.mark.parametrize("lonlat", [False, True])
def test_a_thousand_vertex_field_is_planned_certified(lonlat):
    """The 1000-vertex field of benchmarks/web.py, planar and as longitude/latitude (planned in
    UTM, coordinates of millions of metres: the final scoring must not lose digits there)."""
    ring = ellipse(1000)
    if lonlat:
        lon = 5.66 + ring[:, 0] / (111_320 * math.cos(math.radians(51.99)))
        ring = np.column_stack([lon, 51.99 + ring[:, 1] / 111_320])
    mission = plan_area(ring, 10.0) if lonlat else plan_area(ring, 10.0, crs=None)
    opt = mission.optimum
    assert opt.method == "certified-bb"
    assert opt.info["converged"] and opt.gap <= 1e-4
    assert mission.coverage is not None and mission.coverage.covered_share > 1 - 1e-9
    assert mission.summary()["certified"] is True
    if not lonlat:  # the estimate before planning knows this path
        est = estimate_work(ring, 10.0, crs=None)
        assert est.kind == "certified-bb" and est.seconds < 3


def test_command_line_and_bad_input(capsys, tmp_path):
    from boustro.cli import main

    area = tmp_path / "field.json"
    area.write_text(json.dumps(ellipse(300).tolist()))
    assert main(["optimize", str(area), "--spacing", "10", "--method", "certified-bb",
                 "--json"]) == 0  # fmt: skip
    out = json.loads(capsys.readouterr().out)
    assert out["method"] == "certified-bb" and out["certified"] is True and out["gap"] <= 1e-4
    with pytest.raises(InvalidParameterError, match="tol"):
        smith_bb(ellipse(50), 10.0, tol=1e-12)
    with pytest.raises(InvalidParameterError, match="SmithFitness"):
        smith_bb(ellipse(50), 10.0, fitness=ShortestPath())
    with pytest.raises(NonConvexPolygonError):
        smith_bb([(0, 0), (4, 0), (4, 4), (2, 1), (0, 4)], 0.5)


def test_the_first_use_from_several_threads_at_once():
    """A fresh process whose first certified-bb optima run in four threads at once (the
    kernels compile or load once, under a lock): four equal answers."""
    code = (
        "from concurrent.futures import ThreadPoolExecutor\n"
        "from boustro.optimize import optimize\n"
        "sq = [(0, 0), (1, 0), (1, 1), (0, 1)]\n"
        "run = lambda _: optimize(sq, 0.25, method='certified-bb').fitness\n"
        "with ThreadPoolExecutor(4) as pool:\n"
        "    print(sorted(set(round(f, 12) for f in pool.map(run, range(4)))))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=300
    )
    alone = smith_bb([(0, 0), (1, 0), (1, 1), (0, 1)], 0.25).fitness
    assert out.stdout.strip() == f"[{round(alone, 12)}]", out.stderr


def test_the_estimate_of_certified_bb_by_name_is_its_own():
    ring = ellipse(1000)
    named = estimate_work(ring, 10.0, crs=None, method="certified-bb")
    assert named.kind == "certified-bb" and named.seconds < 3


def test_shortest_path_beyond_the_event_method_is_refused_clearly():
    with pytest.raises(ProblemTooLargeError, match="shortest-path objective"):
        plan_area(ellipse(1000), 10.0, crs=None, fitness=ShortestPath())
