"""The decomposed plan's screen with ``keep_inside`` (issue 16): the cells searched without
keep-inside first, a candidate whose floor reaches the one grid's cost dropped before the
keep-inside search, and the floor's area term (a length no plan covering the cell beats)."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from boustro.geometry.region import Region
from boustro.mission import decomposed, plan_area
from boustro.plan.region import plan_region

L_SHAPE = [(0, 0), (100, 0), (100, 30), (30, 30), (30, 100), (0, 100)]
SLANT_L = [(0, 0), (100, 0), (90, 30), (30, 30), (30, 100), (0, 100)]
#: Nearly a rectangle: the one grid wins and the free search screens every candidate out.
NOTCH = [(0, 0), (120, 0), (120, 40), (70, 40), (60, 35), (0, 40)]
SPEED, TURN = 5.0, 10.0


def _square(x: float, side: float) -> Region:
    return Region(np.array([(x, 0), (x + side, 0), (x + side, side), (x, side)], dtype=float))


def _fake_search(bounds: dict[float, float], calls: list[float]) -> SimpleNamespace:
    def optimum(cell: Region, cutoff: float | None = None):
        calls.append(cell.area)
        return SimpleNamespace(info={"lower_bound": bounds[cell.area]})

    cost = SimpleNamespace(per_turn=TURN, per_length=1 / SPEED)

    def finished(cell: Region, opt: SimpleNamespace) -> SimpleNamespace:
        return opt  # no plans left for later

    return SimpleNamespace(cost=cost, reach=5.0, optimum=optimum, finished=finished)


def test_the_floor_drops_a_candidate_before_searching_its_cells():
    cells = [_square(0, 100), _square(200, 20)]
    floors = [decomposed._area_floor(_fake_search({}, []), c) for c in cells]
    assert floors[0] == pytest.approx((1e4 - 25 * math.pi) / 10 / SPEED)
    calls: list[float] = []
    search = _fake_search({1e4: 200.0, 400.0: 5.0}, calls)
    # the area floors and one turn reach the beat: nothing searched
    assert decomposed._cell_optima(search, cells, sum(floors) + TURN) is None and not calls
    # below it: the large cell first; its bound (200 > its area floor ~198) reaches the beat
    beat = sum(floors) + TURN + 1.0
    assert decomposed._cell_optima(search, cells, beat) is None and calls == [1e4]
    calls.clear()
    found = decomposed._cell_optima(search, cells, None)
    assert calls == [1e4, 400.0] and [f.info["lower_bound"] for f in found] == [200.0, 5.0]


@pytest.mark.parametrize("shape", [L_SHAPE, SLANT_L])
def test_the_area_floor_is_below_real_plans(shape):
    """The floor's area term: no keep-inside plan covering the area is shorter."""
    region = Region(np.array(shape, dtype=float))
    search = SimpleNamespace(cost=SimpleNamespace(per_length=1.0), reach=5.0)
    floor = decomposed._area_floor(search, region)
    for angle in np.linspace(0, math.pi, 7, endpoint=False):
        plan = plan_region(region, 10.0, decompose_area=False, angle=angle, keep_inside=True)
        assert plan.stats.path_length >= floor


def _spied(monkeypatch, shape, screen: bool) -> tuple[object, list[tuple[bool, bool]]]:
    seen: list[tuple[bool, bool]] = []
    real = decomposed._cell_optima

    def spy(search, cells, beat):
        out = real(search, cells, beat if screen else None)
        seen.append((search.keep_inside, out is None))
        return out

    monkeypatch.setattr(decomposed, "_cell_optima", spy)
    kw = dict(crs=None, speed=SPEED, turn_time=TURN, keep_inside=True)
    return plan_area(shape, 10.0, **kw), seen


@pytest.mark.parametrize(("shape", "screened"), [(NOTCH, True), (SLANT_L, False)])
def test_keep_inside_search_only_after_the_free_search_passes(monkeypatch, shape, screened):
    m, seen = _spied(monkeypatch, shape, screen=True)
    assert seen and seen[0][0] is False  # the free search first
    assert any(not ki and dropped for ki, dropped in seen) == screened
    for (ki, dropped), nxt in zip(seen, [*seen[1:], None], strict=True):
        if not ki and dropped:  # screened out: its keep-inside search never ran
            assert nxt is None or nxt[0] is False
    monkeypatch.undo()
    full, _ = _spied(monkeypatch, shape, screen=False)  # every candidate searched both ways
    assert m.stats.duration <= full.stats.duration + 1e-9
    assert (m.optimum.method == "decomposed-cover") == (not screened)


def _centred_values(
    monkeypatch, shape, holes, screen: bool, inside: bool = True
) -> tuple[object, int]:
    """The plan (``keep_inside`` or not), and the cell plans ``_Search._centred`` made (its
    screen on or off)."""
    made = [0]
    real_centred, real_value = decomposed._Search._centred, decomposed._Search.value

    def centred(self, cell, opt):
        self._in_centred = True
        try:
            return real_centred(self, cell, opt)
        finally:
            self._in_centred = False

    def value(self, cell, angle, offset):
        made[0] += bool(getattr(self, "_in_centred", False))
        return real_value(self, cell, angle, offset)

    monkeypatch.setattr(decomposed._Search, "_centred", centred)
    monkeypatch.setattr(decomposed._Search, "value", value)
    if not screen:
        monkeypatch.setattr(decomposed, "rules_out", lambda floor, best: False)
    kw = dict(crs=None, speed=SPEED, turn_time=TURN, keep_inside=inside, holes=holes)
    m = plan_area(shape, 10.0, **kw)
    monkeypatch.undo()
    return m, made[0]


@pytest.mark.parametrize(
    ("shape", "holes"),
    [
        (L_SHAPE, []),
        pytest.param(
            [(0, 0), (100, 0), (100, 30), (60, 45), (30, 30), (30, 100), (0, 100)],
            [[(10, 10), (20, 10), (15, 20)]],
            marks=pytest.mark.slow,  # 20 s
        ),
    ],
)
def test_centred_layouts_screened_keep_the_same_plan(monkeypatch, shape, holes):
    """Twelfth round: the lanes laid from a keep-inside cell's edges (``_Search._centred``)
    are planned only where their floor is below the cell's best plan: the same plan and
    optimum as planning every one, fewer cell plans."""
    with_screen, fewer = _centred_values(monkeypatch, shape, holes, screen=True)
    without, every = _centred_values(monkeypatch, shape, holes, screen=False)
    assert np.array_equal(with_screen.waypoints, without.waypoints)
    assert with_screen.optimum.fitness == without.optimum.fitness
    assert with_screen.optimum.info["decomposed"] == without.optimum.info["decomposed"]
    assert fewer < every
