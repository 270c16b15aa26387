"""The 1-tree's collapsed lane-end ranges (optimize/cover/one_tree.py, ``_lane_ends``;
optimize/cover/extremes.py): a counted line's first lane starts in ``[a - t, a]`` and its last
lane ends in ``[b, b + t]`` (``a, b`` the inner pieces' extremes; wider where only bounds on them
are known) whatever the outer projection's extremes (issue 16, random area 35: a box whose band
catches a wedge beyond a notch let the line's last lane end anywhere in 105 m). Sound on
adversarial areas (a notch with the lines along its step, thin holes, lines along the edges,
holes 0.5 m from the side, run-ins, a turn radius), the real plans' counted lanes start and end
within the ranges by a hole at the edge (the eleventh round's review), and the outer extremes no
longer weaken the bound."""

from __future__ import annotations

import math

import numpy as np
import pytest

import boustro.optimize.cover.bounds as bounds_module
from boustro.geometry import Polygon
from boustro.geometry.region import Region
from boustro.optimize.cover import CoverCost, band_stats
from boustro.optimize.cover.boxes import Boxes
from boustro.optimize.cover.extremes import line_extremes
from boustro.optimize.cover.one_tree import one_tree_bound
from boustro.optimize.cover.search import CoverSearch
from boustro.plan.region import plan_region
from boustro.vehicle import Vehicle

from .plan_samples import SPACING, plan_cost, plans_in_boxes


def _zeros(st, *args, **kw):
    return np.zeros(st.count.shape[0])


def _region(case: str) -> Region:
    """An adversarial area: ``notch`` an L whose step edge runs along the lines (angle 0),
    ``sliver`` a rectangle with a 2 cm wide hole and a square one, ``edges`` a rectangle with a
    rectangular hole (the lines along its edges at angles 0 and pi / 2), ``edge_*`` a hole
    0.5 m from the side (:func:`_edge_hole`)."""
    square = Polygon(np.array([[10, 70], [20, 70], [20, 80], [10, 80]], dtype=float))
    if case.startswith("edge_"):  # a hole 0.5 m from the side (:func:`_edge_hole`)
        return _edge_hole(case[5:], 0.5)
    if case == "notch":
        shell = np.array([[0, 0], [100, 0], [100, 50], [40, 50], [40, 100], [0, 100]], float)
        return Region(Polygon(shell), [square])
    shell = Polygon(np.array([[0, 0], [100, 0], [100, 90], [0, 90]], dtype=float))
    if case == "sliver":
        sliver = np.array([[40.0, 30.0], [55.0, 45.02], [70.0, 60.0]])
        return Region(shell, [Polygon(sliver), square])
    return Region(shell, [Polygon(np.array([[30, 30], [70, 30], [70, 50], [30, 50]], float))])


def _boxes(rng: np.random.Generator, angles: list[float], n: int) -> Boxes:
    """``n`` boxes at ``angles`` (each within 0.03 rad), radii up to 4 mrad and 1.5 m."""
    theta = np.array(angles)[rng.integers(0, len(angles), n)] + rng.uniform(-0.03, 0.03, n)
    return Boxes(
        theta, rng.uniform(0, 4e-3, n), rng.uniform(0, SPACING, n), rng.uniform(0.02, 1.5, n)
    )


CASES = [
    ("notch", "plain", [0.0]),
    ("notch", "turnaround", [0.0]),
    ("notch", "vehicle", [0.0, math.pi / 2]),
    ("sliver", "plain", [math.pi / 4, 0.0]),
    ("sliver", "turnaround", [math.pi / 4]),
    ("edges", "plain", [0.0, math.pi / 2]),
    ("edges", "turnaround", [0.0, math.pi / 2]),
    ("edges", "vehicle", [0.0]),
    ("edge_right", "plain", [0.0]),
    ("edge_left", "turnaround", [0.0]),
    ("edge_both", "vehicle", [0.0]),
]


@pytest.mark.parametrize(("area", "case", "angles"), CASES)
def test_collapsed_one_tree_never_exceeds_a_plan_in_the_box(area, case, angles, monkeypatch):
    """The box bound with the 1-tree as its only bound on the moves beyond the lines' span (the
    lane-ends and piece-ends bounds switched off) is at most every real plan sampled in the box
    (centre and three random layouts): 3 m run-ins or a 6 m turn radius's driven turns."""
    monkeypatch.setattr(bounds_module, "lane_end_bound", _zeros)
    monkeypatch.setattr(bounds_module, "piece_end_bound", _zeros)
    region = _region(area)
    rng = np.random.default_rng(len(area) * 7 + len(case))
    turnaround = 3.0 if case == "turnaround" else 0.0
    cost = CoverCost.time(5.0, float(rng.uniform(2.0, 30.0)), turnaround=turnaround)
    vehicle = Vehicle(turn_radius=6.0) if case == "vehicle" else None
    evaluate = plan_cost(region, cost, turnaround=turnaround, vehicle=vehicle)
    search = CoverSearch(region, SPACING, SPACING / 2, cost, None, False)
    boxes = _boxes(rng, angles, 12)
    search.top_eps = float((boxes.delta * search.radius + boxes.eta).max()) * 1.5
    box = search.box_bounds(boxes)
    for i, plans in enumerate(plans_in_boxes(evaluate, boxes, rng)):
        assert box[i] <= min(plans) + 1e-9


@pytest.mark.parametrize("turnaround", [0.0, 3.0])
def test_the_outer_extremes_do_not_weaken_the_one_tree(turnaround):
    """Boxes straddling the notch's step (the band's edge catches the wide part beyond it at
    some layouts of the box, not at others): the outer projection reaches 60 m past the inner
    one on some counted line, and the 1-tree bound is the same with the outer extremes moved to
    the inner ones (before the collapse it was up to 3.2 s lower there)."""
    region = _region("notch")
    cost = CoverCost.time(5.0, 10.0, turnaround=turnaround)
    search = CoverSearch(region, SPACING, SPACING / 2, cost, None, False)
    rng = np.random.default_rng(0)
    boxes = _boxes(rng, [0.0], 40)
    eps = float((boxes.delta * search.radius + boxes.eta).max())
    lv = search.sandwich.level(eps, 0.0)
    st = band_stats(
        lv.inner, lv.outer, boxes.theta, boxes.d, SPACING, SPACING / 2, search.origin,
        search.k_range(eps + SPACING), search.n_holes, search.tol,
        inner_reach=search._inner_reach(),
    )  # fmt: skip
    counted = st.count >= 1
    reach = np.where(counted, st.out_hi - st.in_hi, 0.0)
    assert np.nanmax(reach) > 50.0  # the wide part beyond the step, on a counted line
    tree = one_tree_bound(st, SPACING, cost, steps=60)
    inner = st._replace(out_lo=st.in_lo.copy(), out_hi=st.in_hi.copy())
    assert (tree > 0).all()
    np.testing.assert_array_equal(tree, one_tree_bound(inner, SPACING, cost, steps=60))


# -- the lines' extremes: the inner pieces', not the inner projection's (a hole by the edge) --


def _edge_hole(side: str, gap: float) -> Region:
    """A 100 x 90 m rectangle with a 4 m high hole along the line at 45 m reaching ``gap`` from
    the right side (``right``: ``[40, 100 - gap] x [43, 47]``, the review's with ``gap`` 0.5) or
    from the left one (``left``: ``[gap, 60] x [43, 47]``); ``both``: ``[60, 100 - gap] x [43,
    47]`` and a hole ``[20, 30] x [38, 52]`` on the same lines (two inner pieces there, the
    second's lane ending at 60 m); ``notch``: the first reaching the side (``gap`` 0)."""
    if side == "notch":  # the hole reaching the side: a notch [40, 100] x [43, 47]
        ring = [[0, 0], [100, 0], [100, 43], [40, 43], [40, 47], [100, 47], [100, 90], [0, 90]]
        return Region(Polygon(np.array(ring, dtype=float)), [])
    shell = Polygon(np.array([[0, 0], [100, 0], [100, 90], [0, 90]], dtype=float))
    x0, x1 = {"right": (40.0, 100.0 - gap), "left": (gap, 60.0)}.get(side, (60.0, 100.0 - gap))
    holes = [np.array([[x0, 43], [x1, 43], [x1, 47], [x0, 47]], dtype=float)]
    if side == "both":
        holes.append(np.array([[20, 38], [30, 38], [30, 52], [20, 52]], dtype=float))
    return Region(shell, [Polygon(h) for h in holes])


def _extremes(st, chords) -> dict[int, tuple[float, float]]:
    """Per counted line (absolute index) of the first layout: the upper end of its first
    lane's start range and the lower end of its last lane's end range (no run-ins)."""
    ext = line_extremes(st, SPACING, 0.0, chords)[0]
    return {st.k0 + int(k): (ext[k, 1], ext[k, 2]) for k in np.nonzero(st.count[0] >= 1)[0]}


def _lanes(region: Region, search: CoverSearch, theta: float, d: float) -> dict[int, list]:
    """The real plan's lanes at layout ``(theta, d)``, per line, in that
    layout's frame (the area moves, not the grid: the centre grid's frame of the moved area)."""
    plan = plan_region(
        region, SPACING, decompose_area=False, angle=theta, offset=d, speed=5.0, turn_time=10.0
    )
    cs, sn = math.cos(theta), math.sin(theta)
    out: dict[int, list] = {}
    for seg, role in zip(plan.transects, plan.roles, strict=True):
        xy = seg - search.origin
        u = cs * xy[:, 0] + sn * xy[:, 1]
        v = -sn * xy[:, 0] + cs * xy[:, 1] - d
        if role == "lane":
            out.setdefault(round(float(v.mean()) / SPACING), []).append((u.min(), u.max()))
    return {k: sorted(x) for k, x in out.items()}


def _counted(lanes: list, count: int) -> list:
    """The plan's lanes on a line that are the ``count`` counted ones where that is plain: all
    of them, or those longer than 5 m (the short ones beyond the holes, holding no inner
    length, where these are ``count``); else none."""
    long = [x for x in lanes if x[1] - x[0] > 5.0]
    return lanes if len(lanes) == count else (long if len(long) == count else [])


@pytest.mark.parametrize(
    ("side", "gap"),
    [("right", 0.5), ("right", 1.5), ("left", 0.5), ("both", 0.5), ("notch", 0.0)],
)
def test_counted_lanes_start_and_end_inside_the_one_trees_extremes_by_a_hole_at_the_edge(side, gap):
    """The review's area (``right``, 0.5 m: count 1 on the line at 45 m, the inner projection
    reaching 99.7 m past the hole while every plan's counted lane ends at 40 m) and its kin: in
    boxes of radius 0.1-1.2 m around that line, every real plan sampled in the box (five
    layouts drawn in it) has its first counted lane (:func:`_counted`) start at or before the
    first lane's start range and its last counted lane end at or beyond the last lane's end
    range, on every counted line, with the holes' boxes and without (before: the
    end range ``[in_hi, in_hi]``, 59.7 m past the plan's lane end; ``both``: two inner pieces on
    the line, where only the boxes say that a chord cuts the projection's end)."""
    region = _edge_hole(side, gap)
    search = CoverSearch(region, SPACING, SPACING / 2, CoverCost.time(5.0, 10.0), None, False)
    rng = np.random.default_rng(int(gap * 10))
    n = 8
    d0 = (45.0 - search.origin[1]) % SPACING
    boxes = Boxes(
        rng.uniform(-0.01, 0.01, n), rng.uniform(0, 2e-3, n),
        d0 + rng.uniform(-0.5, 0.5, n), rng.uniform(0.05, 1.0, n),
    )  # fmt: skip
    eps = boxes.delta * search.radius + boxes.eta
    checked = 0
    for i in range(n):
        lv = search.sandwich.level(float(eps[i]), 0.0)
        st = band_stats(
            lv.inner, lv.outer, boxes.theta[i : i + 1], boxes.d[i : i + 1], SPACING,
            SPACING / 2, search.origin, search.k_range(float(eps[i]) + SPACING),
            search.n_holes, search.tol, inner_reach=search._inner_reach(),
        )  # fmt: skip
        grow = float(eps[i]) + search.sandwich.slack(float(eps[i]))
        boxes_i = search._hole_boxes(boxes.theta[i : i + 1], boxes.d[i : i + 1], grow)
        with_chords = _extremes(st, bounds_module._chord_boxes(boxes_i, lv))
        without = _extremes(st, None)
        for _ in range(5):
            a = boxes.theta[i] + rng.uniform(-boxes.delta[i], boxes.delta[i])
            o = boxes.d[i] + rng.uniform(-boxes.eta[i], boxes.eta[i])
            lanes = _lanes(region, search, float(a), float(o))
            for k, (start_hi, end_lo) in with_chords.items():
                counted = _counted(lanes.get(k, []), int(st.count[0, k - st.k0]))
                if not counted:
                    continue
                for hi, lo in ((start_hi, end_lo), without[k]):
                    assert counted[0][0] <= hi + 1e-6, (i, k, counted, hi)
                    assert counted[-1][1] >= lo - 1e-6, (i, k, counted, lo)
                checked += 1
    assert checked > 100
