"""The cover search's CPU cuts of issue 16's 5 s (docs/mission_time.md, "The 1-tree's CPU"):
layouts ruled out by their own bound are not planned, a decomposition's cells are searched
without the brute-force sweep and stop once their candidate is screened out (``cutoff``)."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

import boustro.mission.decomposed as decomposed_module
import boustro.optimize.cover.plans as plans_module
import boustro.optimize.cover.search as search_module
from boustro.geometry.region import Region
from boustro.mission.decomposed import CUTOFF_MARGIN, _cell_optima, _Search
from boustro.optimize import OptimizeResult
from boustro.optimize.cover import CoverCost, cover_optimum
from boustro.optimize.cover.boxes import Boxes
from boustro.plan.region import plan_region

from .conftest import random_regions

SPEED, TURN_TIME, SPACING = 5.0, 10.0, 10.0
COST = CoverCost.time(SPEED, TURN_TIME)


def _region(seed: int, index: int = 0) -> Region:
    region = random_regions(seed, index + 1, n_holes=(1, 3))[index]
    k = 250.0 / region.diameter
    return Region(region.shell.vertices * k, [h.vertices * k for h in region.holes])


def _plans(region: Region, counted: list[int]):
    def evaluate(a: float, d: float) -> float:
        counted.append(1)
        st = plan_region(
            region, SPACING, decompose_area=False, angle=float(a), offset=float(d), speed=SPEED,
            turn_time=TURN_TIME,
        ).stats  # fmt: skip
        return COST.of(st.path_length, st.n_turns)

    return evaluate


def _ruled_out_same_search(region: Region, monkeypatch, **kw) -> None:
    """The search with and without :data:`~.plans.SKIP_RULED_OUT`: the same plan, bound and
    rounds, the layouts tried before now planned or ruled out (some)."""
    runs, calls = [], []
    for on in (False, True):
        monkeypatch.setattr(plans_module, "SKIP_RULED_OUT", on)
        counted: list[int] = []
        runs.append(cover_optimum(region, SPACING, COST, _plans(region, counted), **kw))
        calls.append(len(counted))
    off, on = runs
    assert (on.angle, on.offset, on.fitness) == (off.angle, off.offset, off.fitness)
    assert on.info["lower_bound"] == off.info["lower_bound"]
    assert on.info["rounds"] == off.info["rounds"]
    assert off.info["ruled_out"] == 0 and on.info["ruled_out"] > 0
    # the same layouts tried: planned before, now planned or ruled out
    assert on.info["plans"] + on.info["ruled_out"] == off.info["plans"]
    assert calls == [off.info["plans"], on.info["plans"]]


@pytest.mark.parametrize("seed", [71, 5])
def test_layouts_ruled_out_by_their_bound_are_not_planned_the_same_search(seed, monkeypatch):
    _ruled_out_same_search(_region(seed), monkeypatch)


def test_ruled_out_only_where_a_plan_is_dearer_than_its_model():
    region = _region(71)
    s = search_module.CoverSearch(region, SPACING, SPACING / 2, COST, None, False)
    assert not plans_module.bounds_rule_out(s)  # the model is the plan: nothing to save
    s = search_module.CoverSearch(region, SPACING, SPACING / 2, COST, lambda a, d: 0.0, False)
    assert plans_module.bounds_rule_out(s)
    s = search_module.CoverSearch(
        region, SPACING, SPACING / 2, COST, lambda a, d: 0.0, False, keep_inside=True
    )
    assert not plans_module.bounds_rule_out(s) and plans_module.layout_bounds(s, _one()) is None


def _one() -> Boxes:
    z = np.zeros(1)
    return Boxes(z + 0.3, z, z + 2.0, z)


def test_layout_bounds_leave_the_search_state_alone():
    region = _region(71)
    s = search_module.CoverSearch(region, SPACING, SPACING / 2, COST, lambda a, d: 0.0, False)
    before = (s.work, s.bound_evaluations, s.model_min, len(s.points))
    b = plans_module.layout_bounds(s, _one())
    assert b is not None and math.isfinite(float(b[0])) and b[0] > 0
    assert (s.work, s.bound_evaluations, s.model_min, len(s.points)) == before


def test_cutoff_stops_the_search_with_a_true_bound():
    region = _region(71)
    full = cover_optimum(region, SPACING, COST, _plans(region, []))
    assert not full.info["cut_off"]
    cutoff = 0.98 * full.info["lower_bound"]
    cut = cover_optimum(region, SPACING, COST, _plans(region, []), cutoff=cutoff)
    assert cut.info["cut_off"] and not cut.info["converged"]
    assert cut.info["stopped"] == "the lower bound reached the cutoff"
    assert cutoff <= cut.info["lower_bound"] <= full.fitness
    assert cut.info["rounds"] < full.info["rounds"] and cut.info["plans"] < full.info["plans"]
    # a cutoff never reached: the same search
    same = cover_optimum(region, SPACING, COST, _plans(region, []), cutoff=2 * full.fitness)
    assert not same.info["cut_off"]
    assert (same.angle, same.offset, same.fitness) == (full.angle, full.offset, full.fitness)
    assert same.info["lower_bound"] == full.info["lower_bound"]


def test_plans_left_for_later_give_the_same_result(monkeypatch):
    """A cell's search with ``later`` (:func:`cover_optimum`): its lower bound final before the
    plans after the branch and bound; the function left makes them (here polish finds a
    cheaper plan: 854.2 -> 846.3 s) and returns the result of the search without ``later``.
    The deferred boxes' bounds (:meth:`~.search.CoverSearch.settle_deferred`, none on this
    area) are made to lower the floor by 1 s, once: it must be in the bound of both."""
    settled: list[float] = []
    settle = search_module.CoverSearch.settle_deferred

    def lowered(self, lower):
        settled.append(settle(self, lower) - 1.0)
        return settled[-1]

    monkeypatch.setattr(search_module.CoverSearch, "settle_deferred", lowered)
    region = _region(8)
    full = cover_optimum(region, SPACING, COST, _plans(region, []), centred=False)
    later: list = []
    counted: list[int] = []
    first = cover_optimum(region, SPACING, COST, _plans(region, counted), centred=False,
                          later=later)  # fmt: skip
    assert len(later) == 1 and first.info["plans_later"] and "plans_later" not in full.info
    assert first.info["lower_bound"] == full.info["lower_bound"] == settled[0] == settled[1]
    assert first.fitness > full.fitness  # the plans left for later find the cheaper plan
    assert len(counted) == first.info["plans"] < full.info["plans"]
    done = later[0]()
    assert (done.angle, done.offset, done.fitness) == (full.angle, full.offset, full.fitness)
    keys = ("lower_bound", "gap", "certified", "plans", "ruled_out", "rounds", "cut_off")
    assert {k: done.info[k] for k in keys} == {k: full.info[k] for k in keys}
    assert done.evaluations == full.evaluations and "plans_later" not in done.info
    assert first.seconds <= done.seconds  # the search's and the plans'
    assert len(settled) == 2  # once each
    assert len(counted) == full.info["plans"]
    # cut off: nothing left for later (its candidate is screened out)
    cut = cover_optimum(region, SPACING, COST, _plans(region, []), centred=False,
                        cutoff=0.98 * full.info["lower_bound"], later=later)  # fmt: skip
    assert cut.info["cut_off"] and len(later) == 1 and "plans_later" not in cut.info


def test_without_the_centred_sweep():
    region = _region(71)
    res = cover_optimum(region, SPACING, COST, _plans(region, []), centred=False)
    assert res.info["centred_plans"] == 0 and "centred_complete" not in res.info
    full = cover_optimum(region, SPACING, COST, _plans(region, []))
    assert "centred_complete" in full.info
    assert res.info["lower_bound"] == pytest.approx(full.info["lower_bound"], rel=1e-12)


def _result(lower: float, cut_off: bool) -> OptimizeResult:
    return OptimizeResult(
        angle=0.0, offset=0.0, fitness=lower + 5.0, spacing=SPACING, method="certified-cover",
        evaluations=0, seconds=0.0,
        info={"lower_bound": lower, "cut_off": cut_off, "gap": 5.0, "certified": False},
    )  # fmt: skip


def test_a_cell_cut_off_is_reused_only_where_its_bound_reaches_the_cutoff(monkeypatch):
    asked: list[float | None] = []

    def fake(cell, s, cost, evaluate, *, cutoff=None, centred=True, **kwargs):
        assert centred is False  # the cells need no brute-force sweep
        asked.append(cutoff)
        return _result(120.0, cutoff is not None)

    monkeypatch.setattr(decomposed_module, "cover_optimum", fake)
    search = object.__new__(_Search)
    search.cache, search.searches, search.s, search.reach = {}, 0, SPACING, SPACING / 2
    search.cost, search.keep_inside = COST, False
    search._centred = lambda cell, opt: opt  # type: ignore[method-assign]
    cell = _region(71)
    assert search.optimum(cell, 100.0).info["cut_off"]
    assert search.optimum(cell, 110.0).info["lower_bound"] == 120.0  # reused: 120 >= 110
    assert asked == [100.0]
    search.optimum(cell, 130.0)  # 120 < 130: searched again
    assert asked == [100.0, 130.0]
    full = search.optimum(cell)  # the optimum itself: searched in full
    assert asked == [100.0, 130.0, None] and not full.info["cut_off"]
    search.optimum(cell, 50.0)  # a full search serves every cutoff
    assert asked == [100.0, 130.0, None] and search.searches == 3


def test_cells_get_the_cutoff_that_screens_their_candidate_out():
    cells = [SimpleNamespace(area=a) for a in (1.0, 5.0, 3.0)]
    cutoffs: list[float | None] = []

    class Search:
        reach = 0.0  # no area floor, no turn between cells: the bounds alone
        cost = SimpleNamespace(per_turn=0.0, per_length=1.0)

        def optimum(self, cell, cutoff=None):
            cutoffs.append(cutoff)
            return SimpleNamespace(info={"lower_bound": 10.0 * cell.area})

        def finished(self, cell, opt):
            return opt

    assert _cell_optima(Search(), cells, beat=None) is not None and cutoffs == [None] * 3
    cutoffs.clear()
    assert _cell_optima(Search(), cells, beat=70.0) is None
    # the first cell alone must reach 70, the second 70 - 50 (then 50 + 30 >= 70)
    assert cutoffs == pytest.approx([70.0 * (1 + CUTOFF_MARGIN), 20.0 + 70.0 * CUTOFF_MARGIN])


def _comb(teeth: int) -> Region:
    """A 30 m deep bar with ``teeth`` teeth 10 m wide, 70 m long and 10 m apart: across the
    teeth (sweep 0) one cell per tooth and the bar's."""
    from boustro.geometry import Polygon

    width = 20 * teeth - 10
    pts = [(0.0, 0.0), (float(width), 0.0)]
    for x in range(width, 0, -20):
        pts += [(x, 100.0), (x - 10, 100.0), (x - 10, 30.0), (x - 20, 30.0)]
    return Region(Polygon(pts[:-2]))


@pytest.mark.parametrize("name", ["choset", "merged"])
def test_decompositions_of_too_many_cells_are_not_traced(name, monkeypatch):
    """A decomposition of more than MAX_CELLS cells (no candidate) raises before its cells are
    traced; one of MAX_CELLS or fewer is traced as before (the same cells)."""
    import boustro.plan.cells as cells_module
    from boustro.errors import InvalidPolygonError
    from boustro.mission.decomposed import MAX_CELLS, _decomposition

    traced: list[int] = []
    trace = cells_module.trace_region

    def counted(*args, **kwargs):
        traced.append(1)
        return trace(*args, **kwargs)

    monkeypatch.setattr(cells_module, "trace_region", counted)
    many = _comb(MAX_CELLS + 1)  # Choset: 14 cells, merged 13
    with pytest.raises(InvalidPolygonError):
        _decomposition(many, 0.0, SPACING, name)
    assert traced == []
    few = _comb(MAX_CELLS - 2)
    dec = _decomposition(few, 0.0, SPACING, name)
    want = cells_module.decompose(few, 0.0, merge=name == "merged", min_width=2 * SPACING)
    assert 2 < len(dec.cells) <= MAX_CELLS and len(traced) == 2 * len(dec.cells)
    assert [c.shell.vertices.tobytes() for c in dec.cells] == [
        c.shell.vertices.tobytes() for c in want.cells
    ]


def _traced() -> Region:
    """A traced field of 324 edges: searched with simplified sandwiches (> SIMPLIFY_EDGES)."""
    from boustro.geometry.traced import traced_field

    region = traced_field(300, 2, radius=120.0)
    assert len(region.edges) > search_module.SIMPLIFY_EDGES
    return region


def _plan_cost(region: Region, a: float, d: float) -> float:
    st = plan_region(
        region, SPACING, decompose_area=False, angle=float(a), offset=float(d), speed=SPEED,
        turn_time=TURN_TIME,
    ).stats  # fmt: skip
    return COST.of(st.path_length, st.n_turns)


def test_simplified_area_layouts_ruled_out_by_their_exact_bound_the_same_search(monkeypatch):
    _ruled_out_same_search(_traced(), monkeypatch, n_angles=12, max_work=3e5)


def test_simplified_area_rules_out_by_the_exact_bound_below_the_plan(monkeypatch):
    """Each layout ruled out on a simplified search is ruled out by its bound on the exact area
    (not the simplified model the search ranks by), which is below its real plan; and so is the
    exact bound of random layouts (the sampler)."""
    region = _traced()
    seen: list[tuple[float, float, float, float]] = []
    rule = plans_module.rules_out
    current: dict[str, float] = {}
    exact_bound = plans_module._exact_bound

    def record_bound(search, boxes, i):
        current.update(theta=float(boxes.theta[i]), d=float(boxes.d[i]))
        return exact_bound(search, boxes, i)

    def record(floor: float, best: float) -> bool:
        out = rule(floor, best)
        if out:
            seen.append((current["theta"], current["d"], floor, best))
        return out

    monkeypatch.setattr(plans_module, "_exact_bound", record_bound)
    monkeypatch.setattr(plans_module, "rules_out", record)
    res = cover_optimum(region, SPACING, COST, _plans(region, []), n_angles=12, max_work=3e5)
    assert seen and len(seen) == res.info["ruled_out"]
    ref = search_module.CoverSearch(region, SPACING, SPACING / 2, COST, None, False)
    assert ref.sandwich.tolerance > 0
    rng = np.random.default_rng(3)
    samples = [(t, d) for t, d, _, _ in seen[:6]]
    samples += [(float(rng.uniform(0, math.pi)), float(rng.uniform(0, SPACING))) for _ in range(6)]
    for k, (theta, d) in enumerate(samples):
        z = np.zeros(1)
        box = Boxes(z + theta, z, z + d, z)
        exact = float(ref.point_values(box, exact=True)[0])
        plan = _plan_cost(region, theta, d)
        assert exact <= plan, (theta, d, exact, plan)
        if k < min(len(seen), 6):
            assert seen[k][2] == pytest.approx(exact, rel=1e-12, abs=1e-9)
            assert plan > seen[k][3]  # it could not have beaten the best plan then


def _rectangle() -> Region:
    return Region(np.array([(0, 0), (100, 0), (100, 60), (0, 60)], dtype=float))


def test_a_cells_optimum_finished_is_the_search_without_later(monkeypatch):
    """:meth:`_Search.finished` on a real cell: the optimum a search without ``later`` gives
    (the plans after the branch and bound made, the lanes from the cell's edges tried, the
    ``keep_inside`` flag), remembered in the cache (kills: ``finished`` not making the plans,
    not trying the edges' lanes, not caching its result)."""
    from .test_open_floor import _open_search

    cell = _region(8)
    search = _open_search()
    opt = search.optimum(cell)
    assert opt is not None and opt.info["plans_later"] and "keep_inside" not in opt.info
    done = search.finished(cell, opt)
    key = decomposed_module._key(cell)
    assert done is not None and search.cache[key] is done and key not in search.later
    assert done.info["plans"] > opt.info["plans"]  # the plans left for later were made
    real = decomposed_module.cover_optimum

    def without_later(*args, later=None, **kwargs):
        return real(*args, **kwargs)

    monkeypatch.setattr(decomposed_module, "cover_optimum", without_later)
    full = _open_search().optimum(cell)
    assert full is not None and "plans_later" not in full.info
    assert (done.angle, done.offset, done.fitness) == (full.angle, full.offset, full.fitness)
    keys = ("lower_bound", "gap", "certified", "plans", "keep_inside", "rounds")
    assert {k: done.info[k] for k in keys} == {k: full.info[k] for k in keys}


def test_plans_left_for_later_that_raise_drop_the_candidate(monkeypatch):
    """A cell whose plans after the branch and bound raise (no lane at a layout planned, an
    invalid plan): without ``later`` its search raised inside :meth:`_Search.optimum`, which
    returned ``None`` (the candidate dropped; the cache ``None`` where no cutoff was asked, a
    search with a cutoff asked again); with the plans left for later :meth:`_Search.finished`
    does the same instead of letting the error out of the decomposed plan."""
    from boustro.errors import NoTransectError

    from .test_open_floor import _open_search

    def raising(search):
        raise NoTransectError("no lane")

    monkeypatch.setattr(search_module, "refine_offsets", raising)
    cell = _rectangle()
    key = decomposed_module._key(cell)
    for cutoff, cached in ((None, True), (1e9, False)):
        search = _open_search()
        opt = search.optimum(cell, cutoff)
        assert opt is not None and opt.info["plans_later"]
        assert search.finished(cell, opt) is None
        assert (key in search.cache) == cached and key not in search.later
        assert search.cache.get(key) is None
    assert _cell_optima(_open_search(), [cell], beat=None) is None


@pytest.mark.parametrize(("name", "teeth"), [("choset", 11), ("merged", 12)])
def test_a_decomposition_of_max_cells_cells_is_kept(name, teeth):
    """Exactly :data:`MAX_CELLS` cells (a comb: Choset's cells one per tooth and the bar's,
    merged one per tooth) is still a decomposition; one more tooth raises (kills ``>=``)."""
    from boustro.errors import InvalidPolygonError
    from boustro.mission.decomposed import MAX_CELLS, _decomposition

    assert len(_decomposition(_comb(teeth), 0.0, SPACING, name).cells) == MAX_CELLS == 12
    with pytest.raises(InvalidPolygonError):
        _decomposition(_comb(teeth + 1), 0.0, SPACING, name)
