"""The decomposition chosen by mission time (issue 16 item 3): candidate decompositions, every
cell certified, the order of the passes solved exactly (Held-Karp, checked here against a brute
force over all orders and options), by OR-Tools beyond, and the decomposed plan kept only when
it beats one grid; thin shapes planned as a person would (the ring: 4 lanes)."""

from __future__ import annotations

import itertools
import json
import math

import numpy as np
import pytest
import shapely

from boustro.geometry import Polygon
from boustro.geometry.region import Region
from boustro.mission import _as_area, _project, _Sensor, _sensor_spacing, plan_area
from boustro.mission.cover import _planner
from boustro.mission.steps import _path_options
from boustro.optimize.cover import centred_offsets
from boustro.plan import cell_order
from boustro.plan.cell_order import EXACT_PASSES, solve_order, tour_cost
from boustro.plan.region import plan_region
from boustro.plan.routing import router_for
from boustro.plan.tour import _Pass
from boustro.vehicle import Vehicle

from .conftest import run_cli

RING = [(0, 0), (10, 0), (10, 10), (0, 10)]
RING_HOLE = [(1, 1), (1, 9), (9, 9), (9, 1)]
L_SHAPE = [(0, 0), (100, 0), (100, 30), (30, 30), (30, 100), (0, 100)]
SPEED, TURN = 5.0, 10.0


def _passes(plan) -> int:
    """The passes the plan flies, from its transects: every lane, and every chain of boundary
    or hole edges (an edge that starts where the previous one of its role ends continues its
    pass; a connecting move begins a new one)."""
    roles, t = plan.role(), plan.transects
    return sum(
        1
        for k in range(len(t))
        if roles[k] == "lane"
        or k == 0
        or roles[k - 1] != roles[k]
        or not np.allclose(t[k][0], t[k - 1][1], rtol=0, atol=1e-9)
    )


def _recomputed_time(mission) -> float:
    """Path length of the waypoints / speed + (passes - 1) x turn time (:func:`_passes`)."""
    w = mission.plan.waypoints
    length = float(np.linalg.norm(np.diff(w, axis=0), axis=1).sum())
    return length / SPEED + (_passes(mission.plan) - 1) * TURN


def _contour_runs(plan) -> int:
    """Starts of lanes and runs of contour waypoints (the count this file used before)."""
    kinds = list(plan.kinds)
    return kinds.count("start") + sum(
        1 for a, b in itertools.pairwise(["", *kinds]) if b == "contour" and a != "contour"
    )


def _covered(mission, area: shapely.Polygon) -> float:
    """The share of ``area`` (the original boundary) within the lanes' flat bands of ``reach``
    and the passes' round ones (shapely, not boustro's coverage code)."""
    plan = mission.plan
    roles = np.array(plan.role())
    lanes = shapely.linestrings(plan.transects[roles == "lane"])
    other = shapely.linestrings(plan.transects[roles != "lane"])
    left = area
    for swath in [
        *shapely.buffer(lanes, plan.reach * (1 + 1e-9), cap_style="flat"),
        *shapely.buffer(other, plan.reach * (1 + 1e-9), quad_segs=64),
    ]:
        left = left.difference(swath)
    return 1 - left.area / area.area


def _ring(**kw):
    return plan_area(RING, 1.0, crs=None, holes=[RING_HOLE], speed=SPEED, turn_time=TURN, **kw)


def test_ring_is_four_lanes_along_the_sides():
    m = _ring()
    s = m.summary()
    assert m.stats.n_transects == 4 and m.stats.duration < 60
    assert s["method"] == "decomposed-cover" and s["cell_order"] == "exact"
    assert s["compared"]["decomposed"] < s["compared"]["one_grid"]
    assert all(c["certified"] and c["n_transects"] == 1 for c in s["cells"])
    assert m.stats.duration == pytest.approx(_recomputed_time(m), rel=1e-9)
    area = shapely.Polygon(RING, [RING_HOLE])
    assert _covered(m, area) >= 1 - 1e-9
    assert m.stats.outside_length == 0.0


def test_ring_keep_inside_stays_inside_and_covers():
    m = _ring(keep_inside=True)
    area = shapely.Polygon(RING, [RING_HOLE])
    assert area.buffer(1e-6).contains(shapely.LineString(m.plan.waypoints))
    assert _covered(m, area) >= 1 - 1e-9
    assert m.stats.duration < 60
    assert m.stats.duration == pytest.approx(_recomputed_time(m), rel=1e-9)


def _best_fixed_angle(ring, holes, spacing) -> float:
    """The fastest of the plans at every whole degree, lanes laid from the area's edge."""
    area = _as_area(np.asarray(ring, float), None, [np.asarray(h, float) for h in holes])
    frame = _project(area, _Sensor(*_sensor_spacing(spacing)), 0.5, None, None)
    plan_of = _planner(frame, "guaranteed", _path_options(frame, 0.0, SPEED, TURN))
    region = frame.region if frame.region is not None else Region(frame.poly)
    angles = np.radians(np.arange(180.0))
    offsets = centred_offsets(region, angles, spacing, spacing / 2)
    return min(plan_of(a, d).stats.duration for a, d in zip(angles, offsets, strict=True))


def test_l_shape_no_worse_than_the_best_fixed_angle():
    m = plan_area(L_SHAPE, 10.0, crs=None, speed=SPEED, turn_time=TURN, decompose=None)
    best = _best_fixed_angle(L_SHAPE, [], 10.0)
    assert m.stats.duration <= best + 1e-9
    assert m.stats.duration == pytest.approx(_recomputed_time(m), rel=1e-9)
    assert _covered(m, shapely.Polygon(L_SHAPE)) >= 1 - 1e-9


@pytest.mark.parametrize(
    "shell, holes, spacing",
    [
        ([(0, 0), (90, 0), (90, 90), (60, 90), (60, 30), (30, 30), (30, 90), (0, 90)], [], 10.0),
        ([(0, 0), (120, 0), (120, 80), (0, 80)], [[(30, 20), (90, 20), (90, 60), (30, 60)]], 10.0),
        ([(0, 0), (80, 10), (100, 70), (40, 50), (10, 90)], [[(40, 20), (55, 25), (45, 35)]], 8.0),
    ],
)
def test_decomposed_never_worse_than_one_grid(shell, holes, spacing):
    kw = dict(crs=None, holes=holes, speed=SPEED, turn_time=TURN)
    best = plan_area(shell, spacing, **kw)
    one = plan_area(shell, spacing, decompose=False, **kw)
    assert best.stats.duration <= one.stats.duration + 1e-9
    info = best.optimum.info
    assert info["one_grid"] == pytest.approx(one.stats.duration, rel=1e-9)
    assert best.stats.duration == pytest.approx(_recomputed_time(best), rel=1e-9)
    assert _covered(best, shapely.Polygon(shell, holes)) >= 1 - 1e-9


def _random_passes(rng, n: int) -> list[_Pass]:
    """Chains of 1 to 4 random options (entry, exit, points, length) in a 100 x 100 square."""
    out = []
    for k in range(n):
        options = []
        for _ in range(int(rng.integers(1, 5))):
            a, b = rng.uniform(0, 100, 2), rng.uniform(0, 100, 2)
            options.append((a, b, np.stack([a, b]), float(np.linalg.norm(b - a))))
        out.append(_Pass("chain", k, 0.0, options))
    return out


def _brute(passes, start, force_start: bool) -> float:
    """The least cost over every order and every option of every pass; with ``force_start``
    the approach from ``start`` to the first entry counts."""
    best = math.inf
    for order in itertools.permutations(range(len(passes))):
        for choice in itertools.product(*(range(len(passes[k].options)) for k in order)):
            entry, _, _, total = passes[order[0]].options[choice[0]]
            if force_start:
                total += float(np.linalg.norm(entry - start))
            for (k0, c0), (k1, c1) in itertools.pairwise(zip(order, choice, strict=True)):
                exit_ = passes[k0].options[c0][1]
                entry, _, _, length = passes[k1].options[c1]
                total += float(np.linalg.norm(entry - exit_)) + length
            best = min(best, total)
    return best


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("force_start", [False, True])
def test_exact_order_equals_brute_force(seed, force_start):
    rng = np.random.default_rng(seed)
    passes = _random_passes(rng, int(rng.integers(2, 6)))
    router = router_for(Region(Polygon([(-10, -10), (110, -10), (110, 110), (-10, 110)])), 0.0)
    start = rng.uniform(0, 100, 2)
    order, choice, used, _ = solve_order(passes, start, router, force_start=force_start)
    assert used == "exact" and sorted(order) == list(range(len(passes)))
    got = tour_cost(passes, start, router, order, choice, force_start=force_start)
    assert got == pytest.approx(_brute(passes, start, force_start), rel=1e-12)
    for other in ("or-tools", "heuristic"):
        o, c, _, _ = solve_order(passes, start, router, force_start=force_start, solver=other)
        assert tour_cost(passes, start, router, o, c, force_start=force_start) >= got - 1e-9


def test_many_passes_use_or_tools_no_worse_than_greedy():
    rng = np.random.default_rng(7)
    passes = _random_passes(rng, EXACT_PASSES + 6)
    router = router_for(Region(Polygon([(-10, -10), (110, -10), (110, 110), (-10, 110)])), 0.0)
    start = np.zeros(2)
    o, c, used, notes = solve_order(passes, start, router)
    assert used == "or-tools" and not notes  # OR-Tools is in the test extra (boustro[order])
    h_o, h_c, h_used, _ = solve_order(passes, start, router, solver="heuristic")
    assert h_used == "heuristic"
    assert tour_cost(passes, start, router, o, c) <= tour_cost(passes, start, router, h_o, h_c)


def test_without_or_tools_the_greedy_order_with_a_note(monkeypatch):
    monkeypatch.setattr(cell_order, "_ortools", lambda pb: (None, False))
    rng = np.random.default_rng(3)
    passes = _random_passes(rng, EXACT_PASSES + 2)
    router = router_for(Region(Polygon([(-10, -10), (110, -10), (110, 110), (-10, 110)])), 0.0)
    _, _, used, notes = solve_order(passes, np.zeros(2), router)
    assert used == "heuristic" and "boustro[order]" in notes[0]


def test_plan_region_order_option_reports_the_solver():
    u = [(0, 0), (9, 0), (9, 9), (6, 9), (6, 3), (3, 3), (3, 9), (0, 9)]
    plain = plan_region(u, 1.0)
    solved = plan_region(u, 1.0, order="auto")
    assert plain.order_solver is None and solved.order_solver == "exact"
    assert solved.stats.path_length <= plain.stats.path_length + 1e-9


def test_cli_json_says_cells_order_and_comparison(capsys, tmp_path):
    path = tmp_path / "ring.geojson"
    ring = [list(map(float, p)) for p in [*RING, RING[0]]]
    hole = [list(map(float, p)) for p in [*RING_HOLE, RING_HOLE[0]]]
    path.write_text(json.dumps({"type": "Polygon", "coordinates": [ring, hole]}))
    code, out, err = run_cli(
        capsys,
        "plan", str(path), "--spacing", "1", "--crs", "none", "--speed", "5", "--turn-time",
        "10", "--json",
    )  # fmt: skip
    assert code == 0, err
    s = json.loads(out)
    assert s["n_transects"] == 4 and s["cell_order"] == "exact" and s["n_cells"] == 4
    assert all(c["certified"] is True and c["gap"] is not None for c in s["cells"])
    assert s["duration_s"] < s["compared"]["one_grid"]


def test_l_shape_keep_inside_decomposed_inside_and_covered():
    kw = dict(crs=None, speed=SPEED, turn_time=TURN, keep_inside=True)
    m = plan_area(L_SHAPE, 10.0, **kw)
    one = plan_area(L_SHAPE, 10.0, decompose=False, **kw)
    assert m.stats.duration <= one.stats.duration + 1e-9
    area = shapely.Polygon(L_SHAPE)
    assert area.buffer(1e-6).contains(shapely.LineString(m.plan.waypoints))
    assert _covered(m, area) >= 1 - 1e-9
    assert m.stats.duration == pytest.approx(_recomputed_time(m), rel=1e-9)


def test_fewest_transects_objective_decomposes_the_ring():
    from boustro.objectives import FewestTransects

    m = plan_area(RING, 1.0, crs=None, holes=[RING_HOLE], fitness=FewestTransects())
    assert m.stats.n_transects == 4 and m.summary()["cell_order"] == "exact"


SLANT_L = [(0, 0), (100, 0), (90, 30), (30, 30), (30, 100), (0, 100)]


def test_keep_inside_cells_searched_keeping_inside(monkeypatch):
    """The cells' search plans them with keep_inside (the reviewer's slanted L: 211.26 s flown
    when the cells were searched without it), and the flown plan keeps inside and covers."""
    from boustro.mission import decomposed

    seen = []
    real = decomposed.cover_optimum

    def spy(*args, **kw):
        seen.append(kw.get("keep_inside"))
        return real(*args, **kw)

    monkeypatch.setattr(decomposed, "cover_optimum", spy)
    kw = dict(crs=None, speed=SPEED, turn_time=TURN, keep_inside=True, decompose=True)
    m = plan_area(SLANT_L, 10.0, **kw)
    assert True in seen  # the cells' search with keep_inside (and without: the better kept)
    assert m.optimum.method == "decomposed-cover"
    assert m.stats.duration <= 211.26 - 0.4
    area = shapely.Polygon(SLANT_L)
    assert area.buffer(1e-6).contains(shapely.LineString(m.plan.waypoints))
    assert _covered(m, area) >= 1 - 1e-9
    assert m.stats.duration == pytest.approx(_recomputed_time(m), rel=1e-9)


def _comb(teeth: int) -> list[tuple[float, float]]:
    pts = [(0.0, 0.0), (20.0 * teeth, 0.0)]
    for i in reversed(range(teeth)):
        x0 = 20.0 * i
        pts += [(x0 + 20, 10), (x0 + 20, 60), (x0 + 10, 60), (x0 + 10, 10)]
    return [*pts[:2], *pts[3:], (0.0, 10.0)]


def test_decompose_without_a_candidate_plans_the_sweep_cells(monkeypatch):
    """A comb of 13 teeth (14 cells > MAX_CELLS): --decompose never plans one grid, and the
    decomposition search runs once."""
    from boustro.mission import decomposed, pipeline

    calls = []
    real = pipeline.plan_decomposed

    def spy(*args, **kw):
        calls.append(1)
        return real(*args, **kw)

    monkeypatch.setattr(pipeline, "plan_decomposed", spy)
    comb = _comb(13)
    assert shapely.Polygon(comb).is_valid
    m = plan_area(comb, 5.0, crs=None, speed=SPEED, turn_time=TURN, decompose=True)
    assert len(calls) == 1
    assert len(m.plan.cells) > decomposed.MAX_CELLS
    assert m.optimum.method != "certified-cover"
    assert any("no decomposition of at most" in n for n in m.plan.notes)
    assert _covered(m, shapely.Polygon(comb)) >= 1 - 1e-9


#: A random concave field with a hole (spacing 20) whose keep-inside decomposed plan flies two
#: boundary passes one after the other: their contour waypoints make one run.
ADJACENT = (
    [(198.1, 110.3), (147.6, 107.2), (157.6, 172.9), (51.8, 80.9), (26.0, 68.9), (91.4, 23.8),
     (102.6, 38.4), (120.0, 56.8), (148.9, 86.2)],
    [[(134.7, 96.7), (112.7, 109.3), (112.9, 84.0)]],
)  # fmt: skip


def test_recomputed_time_counts_the_passes_flown():
    shell, holes = ADJACENT
    kw = dict(crs=None, holes=holes, speed=SPEED, turn_time=TURN, keep_inside=True)
    m = plan_area(shell, 20.0, decompose=True, **kw)
    assert _passes(m.plan) == m.stats.n_turns + 1
    assert _contour_runs(m.plan) < _passes(m.plan)  # what the old count missed
    assert m.stats.duration == pytest.approx(_recomputed_time(m), rel=1e-9)
    area = shapely.Polygon(shell, holes)
    assert area.buffer(1e-6).contains(shapely.LineString(m.plan.waypoints))
    assert _covered(m, area) >= 1 - 1e-9


def test_decomposed_with_a_vehicle_and_a_headland_covers_inside():
    """The L-shape with a tractor's turns and one headland pass: decomposed (asked), its cells
    searched with the vehicle's turns, the headland noted; the whole field covered and the path
    inside it where the headland promises (turns that would leave keep the straight move)."""
    tractor = Vehicle(turn_radius=4.0, speed=SPEED, turn_time=TURN)
    m = plan_area(L_SHAPE, 10.0, crs=None, vehicle=tractor, headland=1, decompose=True)
    assert m.optimum.method == "decomposed-cover"
    assert any("without the headland passes" in n for n in m.plan.notes)
    area = shapely.Polygon(L_SHAPE)
    assert _covered(m, area) >= 1 - 1e-9
    assert m.coverage.covered_share == pytest.approx(1.0, abs=1e-9)
    assert area.buffer(1e-6).contains(shapely.LineString(m.plan.waypoints))
    assert m.plan.vehicle is not None and m.stats.turn_length > 0


def test_or_tools_order_is_deterministic_and_says_its_cap(monkeypatch):
    """Greedy descent to its local optimum: the same tour twice; a cap hit is noted."""
    rng = np.random.default_rng(5)
    passes = _random_passes(rng, EXACT_PASSES + 10)
    router = router_for(Region(Polygon([(-10, -10), (110, -10), (110, 110), (-10, 110)])), 0.0)
    a = solve_order(passes, np.zeros(2), router, solver="or-tools")
    b = solve_order(passes, np.zeros(2), router, solver="or-tools")
    assert a[:2] == b[:2] and not any("safety cap" in n for n in a[3])
    monkeypatch.setattr(cell_order, "ORTOOLS_SECONDS", 1e-3)
    c = solve_order(passes, np.zeros(2), router, solver="or-tools")
    assert any("safety cap" in n for n in c[3])


def test_cells_searched_largest_first_and_stopped_once_their_bounds_reach_the_grid():
    from types import SimpleNamespace

    from boustro.mission.decomposed import _cell_optima

    cells = [SimpleNamespace(area=a) for a in (1.0, 5.0, 3.0)]
    asked = []

    class Search:
        reach = 0.0  # no area floor, no turn between cells: the bounds alone
        cost = SimpleNamespace(per_turn=0.0, per_length=1.0)

        def optimum(self, cell, cutoff=None):
            asked.append(cell.area)
            return SimpleNamespace(info={"lower_bound": 10.0 * cell.area})

        def finished(self, cell, opt):  # the plans its search left for later
            finished.append(cell.area)
            return SimpleNamespace(info={**opt.info, "done": True})

    finished: list[float] = []
    got = _cell_optima(Search(), cells, beat=None)
    assert asked == [5.0, 3.0, 1.0]
    assert [o.info["lower_bound"] for o in got] == [10.0, 50.0, 30.0]  # the cells' order
    assert finished == [1.0, 5.0, 3.0] and all(o.info["done"] for o in got)
    asked.clear(), finished.clear()
    assert _cell_optima(Search(), cells, beat=70.0) is None  # 50 + 30 >= 70: no third search
    assert asked == [5.0, 3.0] and finished == []  # screened out: nothing finished
    assert _cell_optima(Search(), cells, beat=91.0) is not None  # 50 + 30 + 10 < 91
    assert finished == [1.0, 5.0, 3.0]


@pytest.mark.parametrize("seed", range(3))
def test_or_tools_arc_matrix_gives_the_tour_of_the_python_callback(monkeypatch, seed):
    """The arc costs registered as a matrix (looked up in C++) give OR-Tools' search the same
    costs as the Python callback they replace, so the same tour (random passes, some arcs
    forbidden)."""
    from ortools.constraint_solver import pywrapcp

    rng = np.random.default_rng(seed)
    passes = _random_passes(rng, EXACT_PASSES + 4 + 4 * seed)
    router = router_for(Region(Polygon([(-10, -10), (110, -10), (110, 110), (-10, 110)])), 0.0)
    pb = cell_order._Problem(passes, np.zeros(2), router, force_start=seed == 1)
    if seed == 2:  # some moves impossible (routed through nothing): the big cost
        pb.move[rng.random(pb.move.shape) < 0.05] = math.inf
    found, _ = cell_order._ortools(pb)

    asked, tables = [], []

    class Model(pywrapcp.RoutingModel):
        """The model registering a Python callback over node indices (the code before)."""

        def __init__(self, manager):
            super().__init__(manager)
            self.manager = manager

        def RegisterTransitMatrix(self, table):
            tables.append(table)

            def callback(i: int, j: int) -> int:
                asked.append(1)
                return int(table[self.manager.IndexToNode(i)][self.manager.IndexToNode(j)])

            self.kept = callback  # alive while the model is
            return self.RegisterTransitCallback(callback)

    monkeypatch.setattr(pywrapcp, "RoutingModel", Model)
    old, _ = cell_order._ortools(pb)
    assert asked  # the callback was the one asked
    assert found is not None and found == old
    # the matrix holds the moves' costs by node (row: from, column: to; node 0 the start),
    # in the same integer unit, independently of how OR-Tools reads it
    table = np.array(tables[0], dtype=float)
    move, first = pb.move, pb.first
    unit = 1e6 / max(np.concatenate([move[np.isfinite(move)], first[np.isfinite(first)]]))
    np.testing.assert_array_equal(
        table[1:, 1:], np.where(np.isfinite(move), np.round(move * unit), 1e12)
    )
    np.testing.assert_array_equal(
        table[0, 1:], np.where(np.isfinite(first), np.round(first * unit), 1e12)
    )


def _held_karp_pass_by_pass(pb) -> list[int]:
    """Held-Karp as written before the fourteenth round (each pass not in the subset in turn):
    the reference of the vectorised :func:`cell_order._held_karp`."""
    n, m = pb.n, len(pb.pass_of)
    dp, parent, bit = cell_order._tables(pb)
    for s in range(1, (1 << n) - 1):
        row = dp[s]
        live = np.flatnonzero(np.isfinite(row))
        if len(live) == 0:
            continue
        step = row[live, None] + pb.move[live]
        arg = np.argmin(step, axis=0)
        best = step[arg, np.arange(m)]
        for k in range(n):
            if s >> k & 1:
                continue
            opts = pb.options[k]
            t = s | (1 << k)
            better = best[opts] < dp[t, opts]
            if better.any():
                sel = opts[better]
                dp[t, sel] = best[sel]
                parent[t, sel] = live[arg[sel]]
    return cell_order._backtrack(dp, parent, bit)


@pytest.mark.parametrize("seed", range(8))
def test_held_karp_vectorised_gives_the_pass_by_pass_sequence(seed):
    """All options of the passes outside a subset updated at once give the same sequence as
    the pass-by-pass loop, ties included (points on a coarse integer grid, so that many moves
    cost the same; some moves forbidden)."""
    rng = np.random.default_rng(seed)
    passes = _random_passes(rng, int(rng.integers(2, 10)))
    for p in passes:  # snap to a 3 x 3 grid: equal costs everywhere
        p.options[:] = [
            (np.round(a / 50) * 50, np.round(b / 50) * 50, np.round(pts / 50) * 50, 0.0)
            for a, b, pts, _ in p.options
        ]
    router = router_for(Region(Polygon([(-10, -10), (110, -10), (110, 110), (-10, 110)])), 0.0)
    pb = cell_order._Problem(passes, np.zeros(2), router, force_start=seed % 2 == 1)
    if seed >= 4:
        pb.move[rng.random(pb.move.shape) < 0.2] = math.inf
    assert cell_order._held_karp(pb) == _held_karp_pass_by_pass(pb)
