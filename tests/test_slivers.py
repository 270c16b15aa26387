"""Thin spikes cut off a decomposition's cells (mission/slivers.py, issue 16's 5 s)."""

from __future__ import annotations

import numpy as np
import pytest

from boustro.geometry.region import Region
from boustro.mission import decomposed, plan_area
from boustro.mission.slivers import cut_slivers, cut_spikes

from .plan_samples import benchmark_area


def _area(ring: np.ndarray) -> float:
    x, y = ring[:, 0], ring[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def _folds(ring: np.ndarray, width: float) -> int:
    """Vertices where the ring folds back within ``width`` (what cut_spikes removes)."""
    n = 0
    for i in range(len(ring)):
        u1, u2 = ring[i - 1] - ring[i], ring[(i + 1) % len(ring)] - ring[i]
        l1, l2 = np.hypot(*u1), np.hypot(*u2)
        if u1 @ u2 > 0 and abs(u1[0] * u2[1] - u1[1] * u2[0]) / max(l1, l2) <= width:
            n += 1
    return n


def test_spike_cut_at_its_base():
    ring = np.array([(0, 0), (100, 0), (100, 100), (80, 100.003), (60, 100), (0, 100)], float)
    # at (80, 100.003) the edges go to (100, 100) and (60, 100): no fold (an obtuse vertex)
    assert cut_spikes(ring, 0.01) is ring and _folds(ring, 0.01) == 0
    # the top edge runs on to (-20, 100) and comes back to (0, 99.997): a spike 20 m long,
    # 3 mm wide at its base, nearly along the edge (the fold of random area 37's cell)
    spike = np.array([(0, 0), (100, 0), (100, 100), (-20, 100), (0, 99.997)], float)
    assert _folds(spike, 0.01) == 1
    cut = cut_spikes(spike, 0.01)
    assert _folds(cut, 0.01) == 0
    assert np.allclose(cut[3], (0, 100))  # the tip moved to the base, on the long edge
    assert abs(_area(cut) - _area(spike)) <= 0.003 * 20 / 2 + 1e-9
    assert Region(cut).area == pytest.approx(100 * 100, abs=0.01)
    # wider than the width: kept (the same array)
    assert cut_spikes(spike, 0.001) is spike


def test_no_spike_region_is_returned_unchanged():
    r = Region([(0, 0), (100, 0), (100, 60), (0, 60)], [[(20, 20), (40, 20), (30, 40)]])
    assert cut_slivers(r, 0.01) is r


def test_hole_spike_cut_and_region_valid():
    # a crack of the hole: its top edge runs on to (10, 40) and comes back to (20, 39.998)
    hole = [(20, 20), (40, 20), (40, 40), (10, 40), (20, 39.998)]
    shell = [(0, 0), (100, 0), (100, 100), (0, 100)]
    r = Region(shell, [hole])
    out = cut_slivers(r, 0.01)
    assert out is not r
    assert _folds(out.holes[0].vertices, 0.01) == 0
    assert abs(out.area - r.area) < 0.05


def _random37():
    r = benchmark_area(37)  # the benchmark's random area 37 (mission_time._fields)
    return r.shell.vertices, [h.vertices for h in r.holes]


def test_random37_cells_have_no_spike_and_their_searches_converge(monkeypatch):
    """Random area 37 of benchmarks/mission_time.py: its best candidate had a cell with a
    3.6 mm x 17 m spike, whose search halved 50,000 boxes down to the smallest radius (11 s of
    13 s). With the spike cut, every cell's search converges and the plan is the one before
    (the one grid's, 1382.1253 s, gap 16.343 s: benchmarks' log at 084f409). The candidate's
    cells are planned whole, the cut one marked uncertified (``spikes_cut``)."""
    ring, holes = _random37()
    found: list[tuple[Region, dict]] = []
    real = decomposed.cover_optimum

    def spy(cell, *args, **kw):
        opt = real(cell, *args, **kw)
        found.append((cell, {**opt.info, "evaluations": opt.evaluations}))
        return opt

    planned: list[list[tuple[int, object, object]]] = []
    real_plan = decomposed.plan_region

    def spy_plan(region, s, **kw):
        planned.append(
            [(_folds(c.shell.vertices, 1e-2), o.info.get("certified"), o.info.get("spikes_cut"))
             for c, o in kw.get("cells") or ()]
        )  # fmt: skip
        return real_plan(region, s, **kw)

    monkeypatch.setattr(decomposed, "cover_optimum", spy)
    monkeypatch.setattr(decomposed, "plan_region", spy_plan)
    m = plan_area(ring, 10.0, crs=None, holes=holes, speed=5.0, turn_time=10.0)
    assert len(found) >= 2
    # the cells are planned whole (the spike covered), the cut one without a certificate
    spiked = [cell for cells in planned for cell in cells if cell[0]]
    assert spiked and all(c[1] is False and c[2] is True for c in spiked)
    assert all(c[2] is None for cells in planned for c in cells if not c[0])
    for cell, info in found:
        for r in (cell.shell, *cell.holes):
            assert _folds(r.vertices, decomposed.SLIVER_WIDTH * 10.0) == 0
        # the spiked cell halved about 50,000 boxes down to the smallest radius (11 s); with
        # the certify-first rule a cell may still end there, after about 9,000 (0.14 s)
        assert info["evaluations"] < 25_000
    # the plan before the cut (1382.1253 s); the tour refined lane by lane since: 1372.6 s
    assert m.stats.duration <= 1382.1253238
    assert m.summary()["gap"] <= 16.3431929


RANDOM86_CELL = np.array(
    [
        [-77.32309831913612, -49.02446859156076],
        [-81.40844657607317, -60.52034892012182],
        [-81.26133027853427, -53.759579889596296],
        [-78.68314096639965, -45.432309413670225],
        [-13.803061014921546, 137.31071320899719],
        [-79.15615264450804, 107.12332355145296],
        [-118.15582271681494, 24.234629406887272],
        [-122.21306799392904, -27.874989913476924],
        [-92.13599800061964, -90.74689038304277],
    ]
)


def test_a_tip_moved_to_its_foot_is_not_cut_again():
    """A review's reproducer (a cell of random area 86): after the tip moved to its foot the
    new vertex is a right angle that rounding made acute (cosine 6.5e-14) whose foot is itself,
    and the loop never ended. Now one cut, a valid ring, less area by under width x length."""
    out = cut_spikes(RANDOM86_CELL, 0.01)
    assert len(out) == len(RANDOM86_CELL)
    assert _folds(out, 0.01) <= 1  # the foot: a right angle, not a spike
    lost = _area(RANDOM86_CELL) - _area(out)
    assert 0 < lost <= 0.01 * 12.3


@pytest.mark.parametrize("degrees", [0.1, 0.47, 13.0, 89.9])
def test_a_thin_rotated_rectangle_ends(degrees):
    """A 50 m x 5 mm corridor rotated off the axes (the review: 200 of 200 angles hung)."""
    t = np.radians(degrees)
    rot = np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])
    ring = np.array([[0, 0], [50, 0], [50, 0.005], [0, 0.005]]) @ rot.T + [300, 200]
    out = cut_spikes(ring, 0.01)
    assert len(out) >= 3 and np.isfinite(out).all()
