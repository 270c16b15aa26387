"""The keep-inside bound (optimize/cover/inside_bound.py): below every real keep-inside plan
sampled in boxes, tighter than the chords-only bound, the contour's stretches below the passes
the planner builds."""

from __future__ import annotations

import math

import numpy as np
import pytest

from boustro.geometry.region import Region
from boustro.optimize.cover import CoverCost, band_stats, lower_bounds
from boustro.optimize.cover.boxes import Boxes, box_radius, level_radius
from boustro.optimize.cover.inside_bound import (
    MIN_ANGLE,
    _near_lengths,
    _stretches,
    contour_edges,
    path_floor,
    stretch_length,
)
from boustro.optimize.cover.search import CoverSearch
from boustro.plan import inside
from boustro.plan.lanes import region_lanes

from .conftest import random_regions
from .plan_samples import SPACING, plan_cost, plans_in_boxes, sample_boxes, scaled


def _areas() -> list[Region]:
    ell = [(0, 0), (120, 0), (120, 40), (50, 40), (50, 100), (0, 100)]
    quad = [(0, 0), (160, 10), (140, 90), (20, 120)]
    holes = [[(70, 30), (95, 35), (85, 60)]]
    out = [Region(ell), Region(quad), Region(quad, holes)]
    return out + [scaled(r, 150.0) for r in random_regions(17, 2, n_holes=(0, 2))]


def _chords_only(search: CoverSearch, boxes: Boxes, eps: np.ndarray) -> np.ndarray:
    """The keep-inside bound before this module: chords of the inner set shrunk by half a
    spacing, at the same sandwich radius as :meth:`CoverSearch.box_bounds`."""
    out = []
    for i in range(len(boxes.theta)):
        lv = search.sandwich.level(float(eps[i]), search.shrink)
        st = band_stats(
            lv.inner, lv.outer, boxes.theta[i : i + 1], boxes.d[i : i + 1], SPACING, 0.0,
            search.origin, search.k_range(float(eps[i])), search.n_holes, search.tol,
            inner_reach=0.0,
        )  # fmt: skip
        out.append(lower_bounds(st, lv, search.cost, SPACING, boustrophedon=False, runins=False)[0])
    return np.array(out)


@pytest.mark.parametrize("turnaround", [0.0, 3.0])
@pytest.mark.parametrize("index", range(5))
def test_keep_inside_box_bounds_never_exceed_a_plan_in_the_box(index, turnaround):
    region = _areas()[index]
    cost = CoverCost.time(5.0, 10.0, turnaround=turnaround)
    evaluate = plan_cost(region, cost, turnaround=turnaround, keep_inside=True)
    search = CoverSearch(region, SPACING, SPACING / 2, cost, None, False, keep_inside=True)
    rng = np.random.default_rng(40 + index)
    n = 8
    boxes = sample_boxes(rng, n, delta=0.03)
    search.top_eps = float((boxes.delta * search.radius + boxes.eta).max()) * 1.5
    bounds = search.box_bounds(boxes)
    points = search.point_values(boxes, exact=True)
    for i, plans in enumerate(plans_in_boxes(evaluate, boxes, rng)):
        assert bounds[i] <= min(plans) + 1e-9
        assert points[i] <= plans[0] + 1e-9


def test_the_bound_is_tighter_than_the_chords_alone():
    """On straight-edged areas the contour's stretches (or the lanes cut at the boundary) lift
    the bound at a layout above the chords-only bound, by at least 5% of the plan on average."""
    cost = CoverCost.time(5.0, 10.0)
    rng = np.random.default_rng(5)
    lifts = []
    for region in _areas()[:3]:
        search = CoverSearch(region, SPACING, SPACING / 2, cost, None, False, keep_inside=True)
        evaluate = plan_cost(region, cost, keep_inside=True)
        n = 6
        boxes = Boxes(rng.uniform(0, math.pi, n), np.zeros(n), rng.uniform(0, SPACING, n),
                      np.zeros(n))  # fmt: skip
        new = search.point_values(boxes, exact=True)
        old = _chords_only(search, boxes, np.zeros(n))
        assert np.all(new >= old - 1e-9)
        for i in range(n):
            plan = evaluate(float(boxes.theta[i]), float(boxes.d[i]))
            assert new[i] <= plan + 1e-9
            lifts.append((new[i] - old[i]) / plan)
    assert np.mean(lifts) > 0.05


def test_stretches_are_below_the_planners_passes():
    """At the margin half a spacing inside, the planner's boundary passes are at least the
    contour's stretches along edges away from the lanes' direction."""
    rng = np.random.default_rng(9)
    for region in _areas():
        edges = contour_edges(region, SPACING, SPACING / 2)
        tol = 1e-9 * region.diameter
        for _ in range(5):
            angle, offset = rng.uniform(0, math.pi), rng.uniform(0, SPACING)
            lanes = inside.clip_lanes(
                _lanes(region, angle, offset), region, tol, SPACING / 2, SPACING
            )
            passes, uncovered = inside.boundary_passes(region, [lanes], SPACING, SPACING / 2)
            assert uncovered == 0
            length = sum(float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum()) for p in passes)
            assert stretch_length(edges, angle) <= length + 1e-9


def _lanes(region, angle, offset):
    return region_lanes(region, SPACING, angle, offset, reach=SPACING / 2, holes=region.holes)


def test_path_floor_and_contour_edges():
    square = Region([(0, 0), (100, 0), (100, 100), (0, 100)])
    assert path_floor(square, 5.0) == pytest.approx(100 * math.sqrt(2) - 10, rel=1e-5)
    edges = contour_edges(square, 10.0, 5.0)
    # four stretches of 90 m, each kept whole: the strip the lanes leave along an edge runs
    # between feet 5 and 95, and the samples up to sqrt((5 + step)^2 - 5^2) beyond are flagged
    assert len(edges.core) == 4 and np.allclose(edges.core, 90.0, rtol=1e-5)
    assert np.all(edges.ring == 0)
    # an obtuse corner: the stretch runs to feet 2.5 and 97.5 of the 100 m edge, all of it kept
    hexagon = Region([(0, 0), (100, 0), (130, 40), (100, 80), (0, 80), (-30, 40)])
    cores = contour_edges(hexagon, 10.0, 5.0).core
    assert np.isclose(cores.max(), 95.0, rtol=1e-5)
    # lanes at 0 deg: the two vertical stretches count; at 45 deg all four
    assert stretch_length(edges, 0.0) == pytest.approx(2 * edges.core[0], rel=1e-9)
    assert stretch_length(edges, math.pi / 4) == pytest.approx(edges.core.sum(), rel=1e-9)
    assert not contour_edges(square, 10.0, 6.0).applies  # overlapping swaths: nothing counted


def _adversarial() -> list[Region]:
    """Areas where a stretch's strip is short or its corner sharp: an obtuse hexagon, a sliver
    triangle, a thin hole near the side, a notch, a traced (noisy, 120-vertex) boundary, a
    ring one spacing and a half wide."""
    rng = np.random.default_rng(3)
    t = np.linspace(0, 2 * math.pi, 120, endpoint=False)
    rad = 60 + rng.uniform(-1.5, 1.5, len(t))
    traced = np.stack([rad * np.cos(t), 0.7 * rad * np.sin(t)], axis=1)
    return [
        Region([(0, 0), (100, 0), (130, 40), (100, 80), (0, 80), (-30, 40)]),
        Region([(0, 0), (150, 0), (150, 14)]),
        Region([(0, 0), (120, 0), (120, 70), (0, 70)], [[(10, 5.5), (110, 5.5), (110, 7)]]),
        Region([(0, 0), (60, 0), (60, 40), (64, 40), (64, 0), (120, 0), (120, 60), (0, 60)]),
        Region(traced),
        Region(
            [(0, 0), (80, 0), (80, 80), (0, 80)],
            [[(13.5, 13.5), (66.5, 13.5), (66.5, 66.5), (13.5, 66.5)]],
        ),
    ]


@pytest.mark.parametrize("index", range(9))
def test_stretches_and_rings_below_the_passes_on_adversarial_areas(index):
    """``P`` below the margin-1/2 passes' length and the rings holding a counted stretch no
    more than the passes, at random layouts and at layouts along an edge or across a corner."""
    region = (_adversarial() + _areas()[:3])[index]
    edges = contour_edges(region, SPACING, SPACING / 2)
    tol = 1e-9 * region.diameter
    rng = np.random.default_rng(70 + index)
    e = region.edges
    along = np.arctan2(e[:, 1, 1] - e[:, 0, 1], e[:, 1, 0] - e[:, 0, 0]) % math.pi
    angles = list(rng.uniform(0, math.pi, 5)) + list(rng.choice(along, 3) + MIN_ANGLE + 1e-3)
    # along an edge (the parallel rule: counted where no line's swath reaches the strip)
    angles += list(rng.choice(along, 6) + rng.choice([0.0, 1e-4, -3e-3, 0.02], 6))
    counted = 0
    for angle in angles:
        offset = rng.uniform(0, SPACING)
        lanes = inside.clip_lanes(_lanes(region, angle, offset), region, tol, SPACING / 2, SPACING)
        passes, _ = inside.boundary_passes(region, [lanes], SPACING, SPACING / 2)
        length = sum(float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum()) for p in passes)
        theta, d = np.array([angle % math.pi]), np.array([offset])
        near = _near_lengths(edges, theta, d, np.zeros(1), region.centre, SPACING)
        p, _, rings = _stretches(edges, theta, np.zeros(1), near)
        assert p[0] <= length + 1e-9
        assert rings[0] <= len(passes)
        counted += p[0] > stretch_length(edges, angle)
    assert counted or not edges.core.any()


@pytest.mark.parametrize("index", [0, 2, 3, 6, 7])
def test_small_boxes_along_an_edge_never_exceed_a_plan(index):
    """Boxes a few centimetres wide around lanes along an edge (where the stretches near the
    lanes' direction count, :func:`_near_lengths`): below every real plan sampled in them."""
    region = (_adversarial() + _areas()[:3])[index]
    cost = CoverCost.time(5.0, 10.0)
    evaluate = plan_cost(region, cost, keep_inside=True)
    search = CoverSearch(region, SPACING, SPACING / 2, cost, None, False, keep_inside=True)
    rng = np.random.default_rng(90 + index)
    e = region.edges
    along = np.arctan2(e[:, 1, 1] - e[:, 0, 1], e[:, 1, 0] - e[:, 0, 0]) % math.pi
    n = 6
    theta = (rng.choice(along, n) + rng.choice([0.0, 2e-3, -0.02, 0.1], n)) % math.pi
    boxes = Boxes(theta, rng.choice([0.0, 1e-4], n), rng.uniform(0, SPACING, n),
                  rng.choice([1e-3, 0.02], n))  # fmt: skip
    search.top_eps = float((boxes.delta * search.radius + boxes.eta).max()) * 1.5
    bounds = search.box_bounds(boxes)
    for i, plans in enumerate(plans_in_boxes(evaluate, boxes, rng, k=2)):
        assert bounds[i] <= min(plans) + 1e-9


def _split_edges(vertices: list[tuple[float, float]], step: float) -> np.ndarray:
    """``vertices`` with every edge split into collinear pieces about ``step`` long."""
    out = []
    v = np.asarray(vertices, dtype=np.float64)
    for a, b in zip(v, np.roll(v, -1, axis=0), strict=True):
        m = max(1, int(np.linalg.norm(b - a) // step))
        out += [a + (b - a) * t / m for t in range(m)]
    return np.array(out)


def _rect(x0: float, y0: float, x1: float, y1: float) -> list[tuple[float, float]]:
    return [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]


#: (area, turnaround, a box (theta, delta, d, eta) a review found the bound above every plan
#: in when the ring turns were counted three times): a rectangle whose edges are split into
#: collinear 3 m pieces, and a square whose hole leaves a ring one spacing wide (4 contour rings)
_RING_CASES = [
    (Region(_split_edges(_rect(0, 0, 100, 70), 3.0)), 0.0, (1e-4, 2e-3, 4.6635, 1e-3)),
    (Region(_rect(0, 0, 90, 90), [_rect(9, 9, 81, 81)]), 2.0, (1.9717, 0.0, 6.9072, 1e-3)),
]


@pytest.mark.parametrize("index", range(len(_RING_CASES)))
def test_ring_turns_carry_the_bound_and_stay_below_the_plans(index):
    """With 100 s a turn the turn per contour ring holding a counted stretch is what lifts the
    keep-inside box bound: it rises with the turn cost at least one turn faster than the
    chords-only bound at the same radius, and stays below every real plan sampled in the box
    (counting each ring's turn three times puts it above them)."""
    region, turnaround, box = _RING_CASES[index]
    rng = np.random.default_rng(110 + index)
    n = 5
    boxes = Boxes(
        np.r_[box[0], (rng.choice([0.0, math.pi / 2], n) + rng.choice([0.0, 1e-4, 0.05], n))],
        np.r_[box[1], rng.choice([0.0, 1e-4, 2e-3], n)],
        np.r_[box[2], rng.uniform(0, SPACING, n)],
        np.r_[box[3], rng.choice([1e-3, 0.02], n)],
    )
    bounds, chords = {}, {}
    for turn in (0.0, 100.0):
        cost = CoverCost.time(5.0, turn, turnaround=turnaround)
        search = CoverSearch(region, SPACING, SPACING / 2, cost, None, False, keep_inside=True)
        search.top_eps = float((boxes.delta * search.radius + boxes.eta).max()) * 1.5
        bounds[turn] = search.box_bounds(boxes)
        radius = level_radius(box_radius(boxes, search.radius), search.top_eps)
        chords[turn] = _chords_only(search, boxes, radius)
    # the chords-only bound's rise is its turns (lanes and hole passes); without the ring
    # turns the keep-inside bound adds none to them (its other terms are lengths)
    carried = bounds[100.0] - bounds[0.0] >= chords[100.0] - chords[0.0] + 100.0 - 1e-6
    assert carried[0] and carried.sum() >= 4
    evaluate = plan_cost(region, cost, turnaround=turnaround, keep_inside=True)
    for i, plans in enumerate(plans_in_boxes(evaluate, boxes, rng)):
        assert bounds[100.0][i] <= min(plans) + 1e-9
