"""The vehicle's U-turn floors in the time search's bound (optimize/cover/u_turns.py): below
every real turn, below every real convex plan with a turn radius sampled in boxes (Dubins and
Reeds-Shepp, radii from 0.2 to 3 spacings), and the certificate they give on test.json."""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pytest

from boustro.geometry import Polygon
from boustro.geometry.region import Region
from boustro.io import embedded_field
from boustro.mission import plan_area
from boustro.optimize.cover import CoverCost
from boustro.optimize.cover.boxes import Boxes
from boustro.optimize.cover.search import CoverSearch
from boustro.optimize.cover.u_turns import CONVEX_MAX_LINES, UTurns, u_turn_moves
from boustro.plan import build_plan, vehicle_stats
from boustro.vehicle import Vehicle, dubins_paths, reeds_shepp_paths, turn_length
from boustro.vehicle.turns import skip_order

from .conftest import random_polygons
from .plan_samples import SPACING, bounds_and_plans, sample_boxes

COST = CoverCost.time(5.0, 10.0)


@pytest.mark.parametrize("reverse", [False, True])
def test_floor_below_every_u_turn_and_equal_to_the_half_circle(reverse):
    """Random U-turns (exit heading ``h``, entry ``h + pi``, random offsets): the real shortest
    turn is never below the floor; the floor is the half circle at a lateral ``2R`` and
    Dubins's ``pi R + w - 2R`` beyond (so a floor one spacing too high fails here)."""
    rng = np.random.default_rng(5)
    paths = reeds_shepp_paths if reverse else dubins_paths
    for r in (0.5, 3.0, 11.0):
        turns = UTurns(r, reverse)
        n = 400
        h = rng.uniform(-math.pi, math.pi, n)
        w = rng.uniform(-4 * r, 4 * r, n) * rng.choice([1.0, 0.1], n)
        a = rng.uniform(-3 * r, 3 * r, n) * rng.integers(0, 2, n)
        u, v = np.stack([np.cos(h), np.sin(h)], 1), np.stack([-np.sin(h), np.cos(h)], 1)
        start = np.column_stack([rng.uniform(-50, 50, (n, 2)), h])
        goal = np.column_stack([start[:, :2] + a[:, None] * u + w[:, None] * v, h + math.pi])
        lengths = np.array([p.length for p in paths(start, goal, r)])
        floors = np.array([turns.floor(x) for x in w])
        assert np.all(lengths >= floors * (1 - 1e-9))
        aligned = paths([(0, 0, 0), (0, 0, 0)], [(0, 2 * r, math.pi), (0, 5 * r, math.pi)], r)
        assert aligned[0].length == pytest.approx(turns.floor(2 * r), rel=1e-9)
        if not reverse:
            assert aligned[1].length == pytest.approx(turns.floor(5 * r), rel=1e-9)


def test_dubins_floor_is_the_bulb_closer_than_two_radii():
    """Forward only, lanes closer than ``2R``: the floor is the bulb ``R (pi + 2 acos(w / 2R))``,
    below the shortest Dubins U-turn at every along-offset and equal to the least of them (so
    a floor that stops at ``pi R + 2R - w``, or whose arccosine is taken of ``w / R`` or of
    ``w / 4R``, fails here)."""
    for r in (3.0, 8.0):
        turns = UTurns(r)
        along = np.linspace(-4 * r, 4 * r, 16001)
        for w in [0.0, 1e-6 * r, 0.3 * r, r, 1.7 * r, (2 - 1e-6) * r]:
            bulb = r * (math.pi + 2 * math.acos(w / (2 * r)))
            assert turns.floor(w) == pytest.approx(bulb, rel=1e-6, abs=1e-6 * r)
            assert turns.floor(-w) == turns.floor(w)
            tight = 2 * r * math.sin(math.acos(w / (2 * r)))  # the RL word's along-offset
            offsets = np.concatenate([along, [tight, -tight]])
            shortest = turn_length(Vehicle(turn_radius=r), w, offsets)
            assert np.all(turns.floor(w) <= shortest)
            assert float(np.min(shortest)) == pytest.approx(turns.floor(w), rel=1e-6)


def _arc(pose: tuple[float, float, float], side: int, length: float):
    """The pose after ``length`` along a unit-radius arc (``side`` 1 left, -1 right) or a
    straight (``side`` 0): the words' own geometry, not boustro's closed forms."""
    x, y, h = pose
    if side == 0:
        return x + length * math.cos(h), y + length * math.sin(h), h
    cx, cy = x - side * math.sin(h), y + side * math.cos(h)
    h2 = h + side * length
    return cx + side * math.sin(h2), cy - side * math.cos(h2), h2


@pytest.mark.parametrize("word", ["LSL", "RSR", "LSR", "RSL", "LRL", "RLR"])
def test_bulb_below_every_dubins_word_that_reverses_the_heading(word):
    """The bulb's lemma on every word (not only the shortest, CCC with any middle arc): random
    first two segments, the last arc closing the heading to ``pi``; every word ending less than
    ``2R`` across is at least the floor (unit radius), and the least of them comes close to
    it (the RL and LR words reach it)."""
    rng = np.random.default_rng(len(word) + sum(map(ord, word)))
    sides = [{"L": 1, "R": -1, "S": 0}[c] for c in word]
    turns = UTurns(1.0)
    least = math.inf
    checked = 0
    for _ in range(20000):
        first, second = rng.uniform(0, 2 * math.pi, 2) * rng.choice([1.0, 0.1, 0.01], 2)
        second *= 3.0 if sides[1] == 0 else 1.0
        pose = _arc(_arc((0.0, 0.0, 0.0), sides[0], first), sides[1], second)
        last = (sides[2] * (math.pi - pose[2])) % (2 * math.pi)
        pose = _arc(pose, sides[2], last)
        assert math.cos(pose[2]) == pytest.approx(-1.0, abs=1e-9)
        if abs(pose[1]) < 2.0:
            checked += 1
            margin = first + second + last - turns.floor(pose[1])
            assert margin >= -1e-9, (first, second, last, pose)
            least = min(least, margin)
    assert checked > 1000
    if word in ("LSR", "RSL", "LRL", "RLR"):  # the bulb's own words
        assert least < 1e-3


def test_least_floor_over_the_lines():
    """``least`` is the least floor over lanes one or more lines apart, or at most
    ``max_lines`` (a brute force)."""
    for reverse in (False, True):
        for r in np.linspace(0.1, 40.0, 97):
            for most in (None, 1, 2, 3):
                turns = UTurns(float(r), reverse, most)
                brute = min(turns.floor(j * SPACING) for j in range(1, (most or 40) + 1))
                assert turns.least(SPACING) == pytest.approx(brute, rel=1e-12)
    moves = u_turn_moves(UTurns(8.0), np.array([0, 3]), np.array([0.0, 90.0]), 10.0)
    assert moves[0] == 0.0
    assert moves[1] == pytest.approx(90.0 + 3 * (math.pi - 2) * 8.0, rel=1e-8)


def test_one_move_across_an_odd_number_of_lines_where_the_lines_have_both_parities():
    """Every order of ``n`` consecutive lines whose moves cross at most ``max_lines`` lines
    (any number where that is not known; a brute force over the permutations) has moves at
    least :func:`u_turn_moves` with ``mixed``, and above the same without it where the least
    floor is not at an odd number of lines (so ``least_odd`` taken at two lines or over every
    ``j``, or at one line where ``max_lines`` is not known, fails here); no move, no charge."""
    raised = 0
    for reverse, r, most in itertools.product((False, True), (3.0, 8.0, 15.0, 30.0), (2, 3, None)):
        turns = UTurns(r, reverse, most)
        floors = {j: turns.floor(j * 10.0) for j in range(1, 8)}
        if most is not None:
            assert turns.least_odd(10.0) == min(floors[j] for j in range(1, most + 1, 2))
        for n in range(2, 8):
            best = math.inf
            for order in itertools.permutations(range(n)):
                steps = [abs(b - a) for a, b in itertools.pairwise(order)]
                if most is None or max(steps) <= most:
                    best = min(best, sum(floors[j] for j in steps))
            span = np.array([(n - 1) * 10.0])
            bound = u_turn_moves(turns, np.array([n - 1]), span, 10.0, np.array([True]))[0]
            assert bound <= best * (1 + 1e-12)
            plain = u_turn_moves(turns, np.array([n - 1]), span, 10.0)[0]
            raised += bound > plain * (1 + 1e-9)
        none = u_turn_moves(turns, np.array([0, -1]), np.zeros(2), 10.0, np.array([True, True]))
        assert np.all(none == 0.0)
    assert raised >= 20, raised


def test_point_value_charges_the_odd_move():
    """The bound itself (:func:`~boustro.optimize.cover.bounds.lower_bounds`, through the
    search's point value) charges one move of the convex planner's plan as the bulb of one
    line: a 130 x 70 m rectangle, lines along its long side (9 m spacing, an 8 m radius
    forward), is exactly its lanes plus one bulb ``R (pi + 2 acos(9 / 16))`` and ``n - 2``
    half circles with ``2 (9 - 8)`` m across (the skip pattern's turns, along-offset 0), and
    below the real flown plan; without the odd move (``bounds.py`` not passing the lines'
    parities) it is 2.7 s lower and fails here."""
    r = 8.0
    rect = Polygon([(0, 0), (130, 0), (130, 70), (0, 70)])
    cost = dataclasses.replace(COST, u_turns=UTurns(r, False, CONVEX_MAX_LINES))
    search = CoverSearch(Region(rect), SPACING, SPACING / 2, cost, None, False)
    offsets = np.array([0.0, 1.3, 4.5])
    zeros = np.zeros(len(offsets))
    points = search.point_values(Boxes(zeros, zeros, offsets, zeros), exact=True)
    for d, point in zip(offsets, points, strict=True):
        plan = build_plan(rect, SPACING, 0.0, float(d), speed=5.0, turn_time=10.0)
        n = plan.stats.n_transects
        bulb = r * (math.pi + 2 * math.acos(SPACING / (2 * r)))
        moves = bulb + (n - 2) * (math.pi * r + 2 * SPACING - 2 * r)
        assert point == pytest.approx(COST.of(plan.stats.transect_length + moves, n - 1), rel=1e-9)
        flown = vehicle_stats(plan, Vehicle(turn_radius=r))
        assert point <= COST.of(flown.path_length, flown.n_turns)


@pytest.mark.parametrize("n", range(1, 12))
def test_convex_orders_cross_at_most_two_lines(n):
    """The premise of :data:`CONVEX_MAX_LINES`: :func:`lane_order`'s candidates (the
    boustrophedon, every other lane) never join lanes more than two lines apart."""
    for order in (list(range(n)), skip_order(n)):
        assert sorted(order) == list(range(n))
        assert all(abs(b - a) <= CONVEX_MAX_LINES for a, b in itertools.pairwise(order))


def _convex_cost(poly: Polygon, vehicle: Vehicle):
    """The convex planner's plan driven by ``vehicle``, from the better of the first lane's two
    ends (as :func:`boustro.mission.cover.plan_cover` does without a start point)."""

    def evaluate(a: float, d: float) -> float:
        plan = build_plan(poly, SPACING, a, d, speed=5.0, turn_time=10.0)
        end = plan.waypoints[list(plan.kinds).index("end")]
        other = build_plan(poly, SPACING, a, d, speed=5.0, turn_time=10.0, start=end)
        costs = []
        for p in (plan, other):
            st = vehicle_stats(p, vehicle)
            costs.append(COST.of(st.path_length, st.n_turns))
        return min(costs)

    return evaluate


def _areas() -> list[Polygon]:
    rect = Polygon([(0, 0), (130, 0), (130, 70), (0, 70)])
    thin = Polygon([(0, 0), (160, 20), (150, 45), (-5, 30)])
    return [rect, thin] + [Polygon(p.vertices * 150.0) for p in random_polygons(7, 3)]


@pytest.mark.parametrize("reverse", [False, True])
@pytest.mark.parametrize("radius", [0.2, 1.0, 3.0])
def test_box_bounds_and_point_values_below_convex_plans_with_a_turn_radius(radius, reverse):
    """The box bound and the point value (the exact area at the box's centre) with the U-turn
    floors are below every real plan sampled in the box (the vehicle's Dubins or Reeds-Shepp
    turns, every other lane where that turns less), at radii of 0.2 to 3 spacings; and the
    floors raise the bound from a radius of one spacing on."""
    r = radius * SPACING
    vehicle = Vehicle(turn_radius=r, reverse=reverse)
    cost = dataclasses.replace(COST, u_turns=UTurns(r, reverse, CONVEX_MAX_LINES))
    rng = np.random.default_rng(int(radius * 10) + 2 * reverse)
    raised = 0
    for poly in _areas():
        search = CoverSearch(Region(poly), SPACING, SPACING / 2, cost, None, False)
        plain = CoverSearch(Region(poly), SPACING, SPACING / 2, COST, None, False)
        boxes = sample_boxes(rng, 6)
        rows = list(bounds_and_plans(search, _convex_cost(poly, vehicle), boxes, rng))
        before = plain.point_values(boxes, exact=True)
        for i, (box, point, plans) in enumerate(rows):
            assert box <= min(plans) + 1e-6
            assert point <= plans[0] + 1e-6
            raised += point > before[i] + 1e-3
    if radius >= 1.0:  # at 0.2 spacings the lane ends' bounds often see as much
        assert raised >= 15, raised


def test_test_json_certified_with_reeds_shepp_turns():
    """Fields2Cover's test.json, 10 m spacing, 5 m/s, 10 s a turn, an 8 m radius with reverse:
    certified within 0.1% (before the U-turn floors: 59.0 s of gap, not certified); without a
    radius nothing changes (the golden tests)."""
    m = plan_area(
        embedded_field(), 10.0, speed=5.0, turn_time=10.0,
        vehicle=Vehicle(turn_radius=8.0, reverse=True),
    )  # fmt: skip
    s = m.summary()
    assert s["certified"]
    assert s["gap"] < 2.0
    assert s["lower_bound"] <= s["fitness"] + 1e-9


@pytest.mark.parametrize(
    "case, charged",
    [("plain", True), ("keep_inside", False), ("headland", False), ("holes", False)],
)
def test_u_turns_charged_only_where_every_move_is_a_flown_u_turn(monkeypatch, case, charged):
    """The floors reach the bound for the convex planner's plans only: not for a region plan
    (its routed tour joins some lanes flown the same way, and hole passes' loops leave at
    another heading than they enter), nor where turns must stay inside a field (headland
    passes, keep-inside: a turn that would leave it keeps its straight move)."""
    import boustro.optimize.cover.bounds as bounds

    calls = []

    def spy(*args):
        calls.append(args)
        return u_turn_moves(*args)

    monkeypatch.setattr(bounds, "u_turn_moves", spy)
    area: object = embedded_field()
    kw: dict = {"keep_inside": True} if case == "keep_inside" else {}
    if case == "headland":  # a rectangle: its inner field is convex (the convex planner's)
        area = [(0, 0), (120, 0), (120, 80), (0, 80)]
        kw = {"crs": None, "headland": 1}
    if case == "holes":
        area = [(0, 0), (120, 0), (120, 80), (0, 80)]
        kw = {"crs": "EPSG:32632", "holes": [[(40, 30), (70, 30), (60, 50)]]}
    m = plan_area(area, 10.0, speed=5.0, turn_time=10.0, vehicle=Vehicle(turn_radius=8.0), **kw)
    assert bool(calls) == charged
    if charged:  # the radius in plan units (test.json's UTM scale is not 1), two lines at most
        turns = calls[0][0]
        assert turns.radius == pytest.approx(8.0 * m.plan.ground_scale, rel=1e-12)
        assert turns.max_lines == CONVEX_MAX_LINES and not turns.reverse
