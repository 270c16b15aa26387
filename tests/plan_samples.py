"""Real plans sampled in boxes of (angle, offset): the reference the soundness tests of the
certified time search's bounds (tests/test_cover_*.py, tests/test_inside_bound.py) hold their
bounds to. A bound is sound when it is below the cost of every plan whose layout lies in its
box; the tests assert that on the costs these helpers return (the asserts stay in the tests, so
a wrong bound fails them)."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

from boustro.geometry import Polygon
from boustro.geometry.region import Region, random_region
from boustro.optimize.cover import CoverCost, band_stats
from boustro.optimize.cover.bands import BandStats, RigidBoxes
from boustro.optimize.cover.boxes import Boxes, box_radius
from boustro.optimize.cover.search import CoverSearch
from boustro.plan import vehicle_stats
from boustro.plan.region import plan_region
from boustro.vehicle import Vehicle

__all__ = [
    "SPACING",
    "benchmark_area",
    "bounds_and_plans",
    "count_pass_boxes",
    "inside_areas",
    "plan_cost",
    "plans_in_boxes",
    "sample_boxes",
    "scaled",
]

#: The spacing of the soundness tests' plans, metres.
SPACING = 9.0


def scaled(region: Region, size: float) -> Region:
    """``region`` scaled to a diameter of ``size``."""
    k = size / region.diameter
    return Region(
        Polygon(region.shell.vertices * k), [Polygon(h.vertices * k) for h in region.holes]
    )


def benchmark_area(index: int) -> Region:
    """``benchmarks/mission_time.py``'s random area ``index`` (seed 0, 300 m across)."""
    rng = np.random.default_rng(0)
    for _ in range(index + 1):
        r = random_region(rng, int(rng.integers(6, 16)), int(rng.integers(1, 4)), roughness=0.5)
    return scaled(r, 300.0)


def inside_areas(seed: int, count: int) -> list[Region]:
    """A square, an L, a quadrilateral with a hole and ``count`` random areas with one or two
    holes (150 m): the keep-inside layouts' test areas."""
    from .conftest import random_regions

    square = [(0, 0), (100, 0), (100, 100), (0, 100)]
    ell = [(0, 0), (120, 0), (120, 40), (50, 40), (50, 100), (0, 100)]
    quad = [(0, 0), (160, 10), (140, 90), (20, 120)]
    holes = [[(70, 30), (95, 35), (85, 60)]]
    out = [Region(square), Region(ell), Region(quad, holes)]
    return out + [scaled(r, 150.0) for r in random_regions(seed, count, n_holes=(1, 2))]


def plan_cost(
    region: Region,
    cost: CoverCost,
    *,
    turnaround: float = 0.0,
    vehicle: Vehicle | None = None,
    keep_inside: bool = False,
    spacing: float = SPACING,
) -> Callable[[float, float], float]:
    """``evaluate(angle, offset)``: the cost of the real plan of one grid at that layout (5 m/s,
    10 s a turn in the plan's statistics; ``cost`` prices its length and turns), with the
    vehicle's driven turns where given."""

    def evaluate(a: float, d: float) -> float:
        plan = plan_region(
            region, spacing, decompose_area=False, angle=a, offset=d, speed=5.0,
            turn_time=10.0, turnaround=turnaround, keep_inside=keep_inside,
        )  # fmt: skip
        st = vehicle_stats(plan, vehicle) if vehicle is not None else plan.stats
        return cost.of(st.path_length, st.n_turns)

    return evaluate


def box_stats(
    search: CoverSearch, box: Boxes, *, rigid: bool = True, exact: bool = False
) -> BandStats:
    """The band statistics of the one box ``box`` as ``search``'s bound sees them (its
    sandwich level for the box's radius, or the exact area with ``exact``; the rigid holes'
    cuts and splits where ``rigid``)."""
    eps = float(box_radius(box, search.radius)[0])
    lv = search.sandwich.exact if exact else search.sandwich.level(eps)
    rb = None
    if rigid:
        rb = RigidBoxes(search.hole_xy, search.hole_start, box.delta, box.eta, search.split_rings)
    return band_stats(
        lv.inner, lv.outer, box.theta, box.d, search.s, search.reach, search.origin,
        search.k_range(eps), search.n_holes, search.tol, inner_reach=search._inner_reach(),
        rigid=rb,
    )  # fmt: skip


def sample_boxes(
    rng: np.random.Generator, n: int, spacing: float = SPACING, delta: float = 0.02
) -> Boxes:
    """``n`` random boxes: angles in ``[0, pi)``, half-widths up to ``delta`` radians (half of
    them zero), offsets in ``[0, spacing)``, offset half-widths up to 1.5 m."""
    return Boxes(
        rng.uniform(0, math.pi, n),
        rng.uniform(0, delta, n) * rng.integers(0, 2, n),
        rng.uniform(0, spacing, n),
        rng.uniform(0, 1.5, n),
    )


def plans_in_boxes(
    evaluate: Callable[[float, float], float],
    boxes: Boxes,
    rng: np.random.Generator,
    k: int = 3,
) -> Iterator[list[float]]:
    """For each box, the costs of its centre's plan (first) and of ``k`` plans at layouts drawn
    uniformly in it."""
    for i in range(len(boxes.theta)):
        plans = [evaluate(float(boxes.theta[i]), float(boxes.d[i]))]
        for _ in range(k):
            a = boxes.theta[i] + rng.uniform(-boxes.delta[i], boxes.delta[i])
            o = boxes.d[i] + rng.uniform(-boxes.eta[i], boxes.eta[i])
            plans.append(evaluate(float(a), float(o)))
        yield plans


def bounds_and_plans(
    search: Any,
    evaluate: Callable[[float, float], float],
    boxes: Boxes,
    rng: np.random.Generator,
) -> Iterator[tuple[float, float, list[float]]]:
    """For each box: ``search``'s bound over the box (its sandwich levels from 1.5 times the
    widest box's radius), its point value at the box's centre (the exact area) and the plans of
    :func:`plans_in_boxes` (the centre's first)."""
    search.top_eps = float((boxes.delta * search.radius + boxes.eta).max()) * 1.5
    box = search.box_bounds(boxes)
    points = search.point_values(boxes, exact=True)
    for i, plans in enumerate(plans_in_boxes(evaluate, boxes, rng)):
        yield float(box[i]), float(points[i]), plans


def count_pass_boxes(monkeypatch: Any) -> list[int]:
    """A list that gets the number of boxes of each :meth:`CoverSearch.box_bounds` call made by
    a search's last pass (``branch`` set: :meth:`~CoverSearch.settle_branched`), from now on."""
    bounded: list[int] = []
    box_bounds = CoverSearch.box_bounds

    def count(self: CoverSearch, boxes: Boxes, *args: Any, **kw: Any) -> Any:
        if self.branch is not None:
            bounded.append(len(boxes.theta))
        return box_bounds(self, boxes, *args, **kw)

    monkeypatch.setattr(CoverSearch, "box_bounds", count)
    return bounded
