"""The keep-inside bound's moves on top of its boundary passes (optimize/cover/inside_moves.py):
the counts by hand, each counted contour stretch in one pass of the planner and no more such
passes than counted, and the bound below every real plan sampled in boxes, lifted by the term."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

from boustro.geometry import Polygon
from boustro.geometry.region import Region
from boustro.optimize.cover import CoverCost, cover_optimum
from boustro.optimize.cover import inside_bound as ib
from boustro.optimize.cover.boxes import Boxes
from boustro.optimize.cover.inside_bound import MIN_ANGLE, _contour_rings, contour_edges
from boustro.optimize.cover.inside_moves import line_moves, pass_count
from boustro.optimize.cover.search import CoverSearch
from boustro.plan import inside
from boustro.plan.lanes import region_lanes

from .conftest import random_regions
from .plan_samples import SPACING, plan_cost, plans_in_boxes, scaled


def test_line_moves_by_hand():
    """Lines 0, 1, 2, 5, 6 hold lanes (10 m apart): span 60 m, gaps 10, 10, 30, 10."""
    count = np.zeros((4, 8), dtype=np.int64)
    count[:, [0, 1, 2, 5, 6]] = 1
    count[:, 3] = 0
    got = line_moves(count, 10.0, np.array([0, 1, 2, 9]))
    assert np.allclose(got, [60.0, 30.0, 20.0, 0.0])
    assert line_moves(np.zeros((1, 3), dtype=np.int64), 10.0, np.array([0]))[0] == 0.0


def test_pass_count_by_hand():
    """Three cores on a ring 100 m round (spacing 5: merged when under 10 m apart along it),
    one on a second ring: merged or not round the ring, the second ring's own pass."""
    arc = np.array([[0.0, 10.0], [15.0, 30.0], [60.0, 70.0], [5.0, 8.0]])
    total = np.array([100.0, 100.0, 100.0, 40.0])
    ring = np.array([0, 0, 0, 1])
    far = np.array(
        [
            [True, True, True, False],  # 5 m gap merged, 30 m and 30 m round: 2
            [True, False, True, False],  # 50 m and 30 m: 2
            [True, False, False, False],  # one: 1
            [False, False, False, True],  # the other ring: 1
            [True, True, False, True],  # 5 m merged, 70 m round: 1, and 1
            [False, False, False, False],
        ]
    )
    assert pass_count(arc, total, ring, far, None, 5.0).tolist() == [2, 2, 1, 1, 2, 0]
    # 95 m round from 70 to 5 + 100: under 10 m only with the wrap (cores at 0-10 and 92-99)
    arc2 = np.array([[0.0, 10.0], [50.0, 60.0], [92.0, 99.0]])
    got = pass_count(arc2, np.full(3, 100.0), np.zeros(3, dtype=np.int64),
                     np.array([[True, True, True]]), None, 5.0)  # fmt: skip
    assert got.tolist() == [2]  # 10 -> 50 and 60 -> 92 break, 99 -> 100 merges
    parts = np.array([[0, 0, 0, 3]])
    got = pass_count(arc, total, ring, np.array([[True, False, False, False]]), parts, 5.0)
    assert got.tolist() == [4]


def test_pass_count_is_the_planners_merge_of_flagged_runs():
    """The passes :func:`pass_count` counts are those the planner drives (``plan/contour._runs``
    with its ``MERGE_GAP``, on rings sampled every hundredth of a spacing, the samples in the
    counted cores flagged): random cores on three rings, gaps between counted cores from a
    tenth to five spacings (within two samples above the merge gap, where the planner may merge
    what the count keeps apart, skipped), at least 100 rows checked."""
    from boustro.plan.contour import MERGE_GAP, _runs

    spacing, step = 5.0, 0.05
    rng = np.random.default_rng(17)
    checked = 0
    for _ in range(40):
        arcs, totals, rings = [], [], []
        for r in range(3):
            at, cores = rng.uniform(0, spacing), []
            while True:
                lo, hi = at, at + rng.uniform(0.2, 3.0) * spacing
                at = hi + spacing * float(rng.choice([rng.uniform(0.1, 1.9), rng.uniform(2.1, 5)]))
                if at > 40 * spacing:
                    break
                cores.append((lo, hi))
            total = at
            arcs += cores
            totals += [total] * len(cores)
            rings += [r] * len(cores)
        arc, total_a, ring = np.array(arcs), np.array(totals), np.array(rings)
        far = rng.random((8, len(arc))) < 0.5
        got = pass_count(arc, total_a, ring, far, None, spacing)
        for row in range(len(far)):
            want, near_the_merge_gap = 0, False
            for r in range(3):
                cols = np.flatnonzero(far[row] & (ring == r))
                if not len(cols):
                    continue
                total = float(total_a[cols[0]])
                lo, hi = arc[cols, 0], arc[cols, 1]
                gaps = np.r_[lo[1:] - hi[:-1], lo[0] + total - hi[-1]]
                near_the_merge_gap |= bool(
                    ((gaps >= MERGE_GAP * spacing * (1 - 1e-6))
                     & (gaps <= MERGE_GAP * spacing + 2 * step)).any()
                )  # fmt: skip
                n = math.ceil(total / step)
                at = np.linspace(0.0, total, n + 1)[:-1]
                flag = ((at[:, None] >= lo[None]) & (at[:, None] <= hi[None])).any(axis=1)
                runs = _runs(flag, at, total, MERGE_GAP * spacing)
                want += 1 if runs is None else len(runs)
            if not near_the_merge_gap:
                assert got[row] == want, (row, got[row], want)
                checked += 1
    assert checked >= 100


def _areas() -> list[Region]:
    """Straight-edged areas (a rectangle, an L, a quadrilateral with a hole, an obtuse hexagon,
    a ring 13.5 m wide, a hole 5.5 m from the side), random areas with holes, one of them at
    UTM-sized coordinates."""
    rect = Region([(0, 0), (150, 0), (150, 70), (0, 70)])
    ell = Region([(0, 0), (120, 0), (120, 40), (50, 40), (50, 100), (0, 100)])
    quad = Region([(0, 0), (160, 10), (140, 90), (20, 120)], [[(70, 30), (95, 35), (85, 60)]])
    hexagon = Region([(0, 0), (100, 0), (130, 40), (100, 80), (0, 80), (-30, 40)])
    ring = Region(
        [(0, 0), (80, 0), (80, 80), (0, 80)],
        [[(13.5, 13.5), (66.5, 13.5), (66.5, 66.5), (13.5, 66.5)]],
    )
    thin = Region([(0, 0), (120, 0), (120, 70), (0, 70)], [[(10, 5.5), (110, 5.5), (110, 7)]])
    rand = [scaled(r, 160.0) for r in random_regions(23, 3, n_holes=(0, 2))]
    far = rand[0]
    utm = np.array([512346.0, 5412353.0])
    moved = Region(
        Polygon(far.shell.vertices + utm), [Polygon(h.vertices + utm) for h in far.holes]
    )
    return [rect, ell, quad, hexagon, ring, thin, *rand, moved]


def _point_at(ring: np.ndarray, at: float) -> np.ndarray:
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(ring, axis=0), axis=1))])
    return np.array([np.interp(at, arc, ring[:, 0]), np.interp(at, arc, ring[:, 1])])


@pytest.mark.parametrize("index", range(10))
def test_each_counted_core_lies_in_one_pass_and_no_more_passes_than_counted(index):
    """At margin 1/2 (lanes cut half a spacing inside) every stretch counted whole by the angle
    rule lies in one boundary pass the planner builds, and the passes holding one are no more
    than :func:`pass_count`: at random layouts and at layouts just off an edge's direction."""
    region = _areas()[index]
    edges = contour_edges(region, SPACING, SPACING / 2)
    rings = _contour_rings(region, SPACING / 2)
    tol = 1e-9 * region.diameter
    rng = np.random.default_rng(300 + index)
    e = region.edges
    along = np.arctan2(e[:, 1, 1] - e[:, 0, 1], e[:, 1, 0] - e[:, 0, 0]) % math.pi
    angles = list(rng.uniform(0, math.pi, 4)) + list(rng.choice(along, 2) + MIN_ANGLE + 1e-3)
    seen = 0
    for angle in angles:
        offset = rng.uniform(0, SPACING)
        lanes = region_lanes(region, SPACING, angle, offset, reach=SPACING / 2, holes=region.holes)
        cut = inside.clip_lanes(lanes, region, tol, SPACING / 2, SPACING)
        passes, _ = inside.boundary_passes(region, [cut], SPACING, SPACING / 2)
        lines = [shapely.LineString(p) for p in passes]
        theta = np.array([angle % math.pi])
        held: list[np.ndarray] = []
        ib._stretches(edges, theta, np.zeros(1), None, spacing=SPACING, passes=held)
        rel = np.abs((edges.angle - theta[0] + math.pi / 2) % math.pi - math.pi / 2)
        counted = np.flatnonzero((rel >= MIN_ANGLE) & (edges.core > 0))
        holding = set()
        for i in counted:
            lo, hi = edges.arc[i]
            pts = [_point_at(rings[edges.ring[i]], x) for x in np.linspace(lo, hi, 7)]
            hit = [
                j
                for j, line in enumerate(lines)
                if max(line.distance(shapely.Point(p)) for p in pts) <= 1e-6 * SPACING
            ]
            assert hit, "a counted core outside every pass"
            holding.add(hit[0])
        assert len(holding) <= held[0][0]
        seen += len(counted) > 0
    assert seen


def _boxes(region: Region, rng: np.random.Generator, n: int) -> Boxes:
    """Boxes at random layouts and along the area's edges, 1 mm-2 cm wide."""
    e = region.edges
    along = np.arctan2(e[:, 1, 1] - e[:, 0, 1], e[:, 1, 0] - e[:, 0, 0]) % math.pi
    theta = np.r_[rng.uniform(0, math.pi, n - n // 2), rng.choice(along, n // 2)]
    return Boxes(
        theta % math.pi,
        rng.choice([0.0, 1e-4], n),
        rng.uniform(0, SPACING, n),
        rng.choice([1e-3, 0.02], n),
    )


def _tight(region: Region, cost: CoverCost, boxes: Boxes, flag: bool = True) -> tuple:
    """``(decided, certified)``: the box bounds the search keeps boxes by and the certificate's
    (:attr:`CoverSearch.tight`), with or without the moves on top of the passes."""
    ib.MOVES_ON_PASSES = flag
    try:
        search = CoverSearch(region, SPACING, SPACING / 2, cost, None, False, keep_inside=True)
        search.top_eps = float((boxes.delta * search.radius + boxes.eta).max()) * 1.5
        decided = search.box_bounds(boxes)
        return decided, search.tight.copy()
    finally:
        ib.MOVES_ON_PASSES = True


@pytest.mark.parametrize("index", range(10))
def test_the_bound_with_moves_on_passes_stays_below_the_plans(index):
    """The certificate's keep-inside box bounds (the moves on top of the passes) are below every
    real keep-inside plan sampled in their boxes, never below the bounds the search decides by,
    and those are the bounds without the term (the same search)."""
    region = _areas()[index]
    cost = CoverCost.time(5.0, 10.0)
    evaluate = plan_cost(region, cost, keep_inside=True)
    rng = np.random.default_rng(500 + index)
    boxes = _boxes(region, rng, 6)
    decided, tight = _tight(region, cost, boxes)
    before, same = _tight(region, cost, boxes, flag=False)
    assert np.array_equal(decided, before) and np.array_equal(same, before)
    assert np.all(tight >= decided)
    for i, plans in enumerate(plans_in_boxes(evaluate, boxes, rng, k=2)):
        assert tight[i] <= min(plans) + 1e-9


def test_the_term_lifts_the_bound_on_straight_edged_areas():
    """In boxes 1 mm wide at random layouts of the first six areas the moves on top of the
    passes lift the certificate's bound on half the areas, by over 2% of the plan on some (the
    bound stays below it)."""
    cost = CoverCost.time(5.0, 10.0)
    rng = np.random.default_rng(8)
    lifted, big = 0, 0
    for region in _areas()[:6]:
        evaluate = plan_cost(region, cost, keep_inside=True)
        n = 6
        boxes = Boxes(rng.uniform(0, math.pi, n), np.zeros(n), rng.uniform(0, SPACING, n),
                      np.full(n, 1e-3))  # fmt: skip
        decided, tight = _tight(region, cost, boxes)
        i = int(np.argmax(tight - decided))
        plan = evaluate(float(boxes.theta[i]), float(boxes.d[i]))
        assert tight[i] <= plan + 1e-9
        lifted += tight[i] > decided[i] + 1e-9
        big += tight[i] - decided[i] > 0.02 * plan
    assert lifted >= 3 and big >= 1


def test_the_search_plans_the_same_layouts_with_a_higher_floor():
    """A keep-inside search over an L with the term decides by the same bounds: the same plan,
    the same number of plans and boxes, and a lower bound at least as high (higher here, with
    the fourteenth round's margin-0 passes and near rule at the layouts off: with them the L's
    floor, 277.6 s instead of 251.5 s, is set where the term adds nothing)."""
    region = Region([(0, 0), (120, 0), (120, 40), (50, 40), (50, 100), (0, 100)])
    cost = CoverCost.time(5.0, 10.0)
    evaluate = plan_cost(region, cost, keep_inside=True)
    got = {}
    for flag in (False, True):
        ib.MOVES_ON_PASSES, ib.CUT_PASSES, ib.NEAR_AT_LAYOUTS = flag, "off", False
        try:
            got[flag] = cover_optimum(region, SPACING, cost, evaluate, keep_inside=True,
                                      n_angles=24, max_work=3e5)  # fmt: skip
        finally:
            ib.MOVES_ON_PASSES, ib.CUT_PASSES, ib.NEAR_AT_LAYOUTS = True, "bound", True
    old, new = got[False], got[True]
    assert (new.angle, new.offset, new.fitness) == (old.angle, old.offset, old.fitness)
    for key in ("plans", "rounds", "screened", "ruled_out"):
        assert new.info.get(key) == old.info.get(key)
    assert new.info["lower_bound"] > old.info["lower_bound"]
    assert new.info["lower_bound"] <= new.fitness


def test_a_decomposition_decides_its_keep_inside_cells_without_the_moves_term(monkeypatch):
    """A decomposition's cell searches decide which candidates it plans by their floor (a
    screen: a cell alone counts passes along its cut edges): they keep the floor without the
    moves on top of the passes, so the decomposition decides as before the term (a review saw
    the L with a pond's cell floors rise 274.565 -> 276.565 with it)."""
    from boustro.mission import decomposed, plan_area

    seen = []
    real = decomposed.cover_optimum

    def spy(*args, **kwargs):
        seen.append((kwargs.get("keep_inside"), kwargs.get("moves_on_passes", True)))
        return real(*args, **kwargs)

    monkeypatch.setattr(decomposed, "cover_optimum", spy)
    shell = np.array([(0, 0), (200, 0), (200, 60), (60, 60), (60, 200), (0, 200)], float)
    hole = np.array([(20, 20), (40, 20), (40, 40), (20, 40)], float)
    plan_area(shell, 10.0, crs=None, holes=[hole], speed=5.0, turn_time=10.0, keep_inside=True)
    assert any(k for k, _ in seen)  # keep-inside cells were searched
    assert all(not moves for k, moves in seen if k)


def test_an_invalid_moves_decide_is_refused_where_it_is_read(monkeypatch):
    """``search.MOVES_DECIDE`` outside its three values raises a clear error where a keep-inside
    search reads it (a layout's bound and a box's), rather than deciding as ``"boxes"``; the
    three values are read without error."""
    from boustro.errors import InvalidParameterError
    from boustro.optimize.cover import search as search_mod

    region = _areas()[0]
    cost = CoverCost.time(5.0, 10.0)
    boxes = Boxes(np.array([0.3, 1.2]), np.zeros(2), np.array([1.0, 4.0]), np.full(2, 1e-3))
    search = CoverSearch(region, SPACING, SPACING / 2, cost, None, False, keep_inside=True)
    search.top_eps = float((boxes.delta * search.radius + boxes.eta).max()) * 1.5
    for value in search_mod.MOVES_DECIDE_VALUES:
        monkeypatch.setattr(search_mod, "MOVES_DECIDE", value)
        assert np.isfinite(search.point_values(boxes)).all()
        assert np.isfinite(search.box_bounds(boxes)).all()
    monkeypatch.setattr(search_mod, "MOVES_DECIDE", "certificates")
    for bound in (search.point_values, search.box_bounds):
        with pytest.raises(
            InvalidParameterError, match=r"MOVES_DECIDE must be one of.*'certificates'"
        ):
            bound(boxes)
