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
import shapely

import boustro.optimize.cover.bounds as bounds_module
from boustro.geometry import Polygon
from boustro.geometry.region import Region
from boustro.optimize.cover import CoverCost, Sandwich, band_stats
from boustro.optimize.cover.boxes import Boxes
from boustro.optimize.cover.extremes import line_extremes
from boustro.optimize.cover.one_tree import one_tree_bound
from boustro.optimize.cover.search import CoverSearch
from boustro.plan.region import plan_region
from boustro.vehicle import Vehicle

from .conftest import random_regions, shapely_region
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


def _extremes(st) -> dict[int, tuple[float, float]]:
    """Per counted line (absolute index) of the first layout: the upper end of its first
    lane's start range and the lower end of its last lane's end range (no run-ins)."""
    ext = line_extremes(st, 0.0)[0]
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
    range, on every counted line (the tenth round's end range ``[in_hi, in_hi]`` was 59.7 m
    past the plan's lane end; ``both``: two inner pieces on the line, where the eleventh
    round's first ranges needed the holes' boxes to see that a chord cuts the projection's
    end)."""
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
        extremes = _extremes(st)
        for _ in range(5):
            a = boxes.theta[i] + rng.uniform(-boxes.delta[i], boxes.delta[i])
            o = boxes.d[i] + rng.uniform(-boxes.eta[i], boxes.eta[i])
            lanes = _lanes(region, search, float(a), float(o))
            for k, (hi, lo) in extremes.items():
                counted = _counted(lanes.get(k, []), int(st.count[0, k - st.k0]))
                if not counted:
                    continue
                assert counted[0][0] <= hi + 1e-6, (i, k, counted, hi)
                assert counted[-1][1] >= lo - 1e-6, (i, k, counted, lo)
                checked += 1
    assert checked > 100


# -- the inner pieces' extremes exported by the band kernel (first_lo, last_hi) --


def _teeth() -> Region:
    """A 100 x 90 m area whose strips ``x < 10`` and ``x > 90`` stop at 38 m, each with a tooth
    whose apex (2.5 and 97.5 m) touches 42 m, the lower edge of the band of the line at 44 m
    (spacing 4, offset 0, origin 0), and a hole ``[40, 60] x [40, 48]`` across that line: the
    band's projection is ``{2.5} + [10, 90] + {97.5}``, its inner pieces ``[10, 40]`` and
    ``[60, 90]`` (the end intervals shorter than ``tol``, followed by gaps; the hole away from
    the projection's ends)."""
    ring = [[0, 0], [100, 0], [100, 38], [97.5, 42], [95, 38], [90, 38], [90, 90], [10, 90],
            [10, 38], [5, 38], [2.5, 42], [0, 38]]  # fmt: skip
    hole = [[40, 40], [60, 40], [60, 48], [40, 48]]
    return Region(Polygon(np.array(ring, dtype=float)), [Polygon(np.array(hole, dtype=float))])


@pytest.mark.parametrize("turnaround", [0.0, 3.0])
def test_extremes_are_the_inner_pieces_past_a_spike_at_the_bands_edge(turnaround):
    """The degenerate case the eleventh round's first ranges left open: a line crossing a hole
    (two inner pieces) whose inner projection's end intervals, away from the hole, are shorter
    than ``tol`` and followed by gaps. The ranges are ``[10 - t, 10]`` and ``[90, 90 + t]``
    (``in_lo`` 2.5 and ``in_hi`` 97.5 m, which the ranges took without a hole's box near them:
    7.5 m before the real plan's first lane's start and after its last lane's end)."""
    region = _teeth()
    lv = Sandwich(region).exact
    st = band_stats(
        lv.inner, lv.outer, np.array([0.0]), np.array([0.0]), 4.0, 2.0, np.zeros(2), (-2, 25),
        1, 1e-9 * region.diameter,
    )  # fmt: skip
    b = 11 - st.k0
    assert st.count[0, b] == 2
    assert (st.in_lo[0, b], st.in_hi[0, b]) == (2.5, 97.5)  # the spikes' points
    assert (st.first_hi[0, b], st.last_lo[0, b]) == (40.0, 60.0)
    assert (st.first_lo[0, b], st.last_hi[0, b]) == (10.0, 90.0)
    t = turnaround
    np.testing.assert_array_equal(line_extremes(st, t)[0, b], [10.0 - t, 10.0, 90.0, 90.0 + t])
    # the real plan's lanes on that line: the first starts at 10 m, the last ends at 90 m
    search = CoverSearch(region, 4.0, 2.0, CoverCost.time(5.0, 10.0), None, False)
    d0 = (44.0 - search.origin[1]) % 4.0
    plan = plan_region(region, 4.0, decompose_area=False, angle=0.0, offset=d0, speed=5.0,
                       turn_time=10.0)  # fmt: skip
    lanes = sorted(
        (float(seg[:, 0].min()), float(seg[:, 0].max()))
        for seg, role in zip(plan.transects, plan.roles, strict=True)
        if role == "lane" and abs(float(seg[:, 1].mean()) - 44.0) < 1.0
    )
    np.testing.assert_allclose(np.array(lanes), [[10.0, 40.0], [60.0, 90.0]], rtol=0, atol=1e-9)


def _inner_pieces(area, holes, o, u, n, c: float, s: float, tol: float) -> list:
    """The band's pieces computed with shapely: the band ``|n . (p - o) - c| <= s / 2`` cut from
    the area, each part projected on ``u`` (merged), minus the holes' chords on the centre line
    ``n . (p - o) = c``; pieces longer than ``tol``, in ``u . (p - o)``."""
    far = 1e4
    band = shapely.Polygon([o + v * n + w * u for v, w in
                            ((c - s / 2, -far), (c - s / 2, far), (c + s / 2, far),
                             (c + s / 2, -far))])  # fmt: skip
    part = area.intersection(band)
    spans = sorted(
        (float(xy.min()), float(xy.max()))
        for g in getattr(part, "geoms", [part])
        if not g.is_empty
        for xy in [np.asarray(g.exterior.coords if hasattr(g, "exterior") else g.coords) @ u]
    )
    merged: list[list[float]] = []
    for lo, hi in spans:
        if merged and lo <= merged[-1][1]:
            merged[-1][1] = max(merged[-1][1], hi)
        else:
            merged.append([lo, hi])
    line = shapely.LineString([o + c * n - far * u, o + c * n + far * u])
    cuts = sorted(
        (float(xy.min()), float(xy.max()))
        for h in holes
        for g in getattr(h.intersection(line), "geoms", [h.intersection(line)])
        if not g.is_empty and g.length > 0
        for xy in [np.asarray(g.coords) @ u]
    )
    pieces = []
    for lo, hi in merged:
        cur = lo
        for a, b in cuts:
            if b <= cur or a >= hi:
                continue
            if a - cur > tol:
                pieces.append((cur - o @ u, a - o @ u))
            cur = max(cur, b)
        if hi - cur > tol:
            pieces.append((cur - o @ u, hi - o @ u))
    return pieces


@pytest.mark.parametrize("index", range(6))
def test_first_lo_and_last_hi_are_the_inner_pieces_extremes(index):
    """At single layouts (box radius 0: inner = outer = the area) of random areas with holes,
    ``first_lo`` / ``last_hi`` are the first and last band pieces computed with shapely
    (:func:`_inner_pieces`), ``first_hi`` / ``last_lo`` their other ends, and ``nan`` exactly
    where the line has no piece; the 1-tree's ranges are ``[first_lo - t, first_lo]`` and
    ``[last_hi, last_hi + t]``."""
    region = random_regions(23, 6, n_holes=(1, 3))[index]
    area = shapely_region(region)
    holes = [shapely.Polygon(h.vertices) for h in region.holes]
    rng = np.random.default_rng(index)
    s = region.diameter / float(rng.uniform(8, 20))
    tol = 1e-9 * region.diameter
    o = region.centre
    far = np.linalg.norm(region.shell.vertices - o, axis=1).max() + s
    k_range = (math.floor(-far / s) - 1, math.ceil(far / s) + 1)
    lv = Sandwich(region).exact
    checked = 0
    for _ in range(4):
        angle, offset = float(rng.uniform(0, math.pi)), float(rng.uniform(0, s))
        st = band_stats(
            lv.inner, lv.outer, np.array([angle]), np.array([offset]), s, s / 2, o, k_range,
            len(region.holes), tol,
        )  # fmt: skip
        u = np.array([math.cos(angle), math.sin(angle)])
        n = np.array([-math.sin(angle), math.cos(angle)])
        ext = line_extremes(st, 2.0)[0]
        for b in range(st.count.shape[1]):
            pieces = _inner_pieces(area, holes, o, u, n, offset + (st.k0 + b) * s, s, tol)
            if not pieces:
                assert np.isnan(st.first_lo[0, b]) and np.isnan(st.last_hi[0, b])
                assert st.count[0, b] == 0
                continue
            got = [st.first_lo[0, b], st.first_hi[0, b], st.last_lo[0, b], st.last_hi[0, b]]
            want = [pieces[0][0], pieces[0][1], pieces[-1][0], pieces[-1][1]]
            np.testing.assert_allclose(got, want, rtol=0, atol=1e-7 * s)
            assert st.count[0, b] >= 1
            np.testing.assert_array_equal(ext[b, [1, 2]], [st.first_lo[0, b], st.last_hi[0, b]])
            np.testing.assert_array_equal(ext[b, [0, 3]], ext[b, [1, 2]] + [-2.0, 2.0])
            checked += 1
    assert checked > 20
