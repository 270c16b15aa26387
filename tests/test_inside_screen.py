"""The margin screen of :func:`boustro.plan.inside.inside_layout`: margin 0's passes are
completed only when it could still be the shorter; the choice (lanes, passes, what is left
uncovered) is exactly the one of laying both margins in full."""

from __future__ import annotations

import math

import numpy as np
import pytest

from boustro.geometry.region import Region
from boustro.plan import inside
from boustro.plan.lanes import region_lanes

from .plan_samples import SPACING, inside_areas


def _areas() -> list[Region]:
    return inside_areas(23, 2)


def _both_in_full(region, lanes):
    """inside_layout before the screen: both margins laid in full, margin 0 first, margin 1/2
    kept when it leaves less uncovered or is shorter by more than tol."""
    tol = 1e-9 * region.diameter
    best = None
    for m in inside.MARGINS:
        cut = [inside.clip_lanes(ls, region, tol, m * SPACING, SPACING) for ls in lanes]
        passes, uncovered = inside.boundary_passes(region, cut, SPACING, SPACING / 2)
        length = sum(float(np.sum(ls.t1 - ls.t0)) for ls in cut)
        length += sum(float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum()) for p in passes)
        if best is None or (uncovered, length) < (best[3], best[0] - tol):
            best = (length, cut, passes, uncovered)
    return best[1], best[2], best[3]


def _same(a, b):
    (lanes_a, passes_a, unc_a), (lanes_b, passes_b, unc_b) = a, b
    assert unc_a == unc_b
    assert len(lanes_a) == len(lanes_b) and len(passes_a) == len(passes_b)
    for x, y in zip(lanes_a, lanes_b, strict=True):
        for f in ("k", "c", "t0", "t1"):
            assert np.array_equal(getattr(x, f), getattr(y, f))
    for p, q in zip(passes_a, passes_b, strict=True):
        assert np.array_equal(p, q)


def test_the_screen_keeps_the_choice_of_both_margins_in_full(monkeypatch):
    completed = []
    real = inside._completed

    def counted(*args, **kwargs):
        completed.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(inside, "_completed", counted)
    rng = np.random.default_rng(3)
    screened = laid = margin0 = 0
    for region in _areas():
        layouts = [(0.0, SPACING / 2)] + [
            (rng.uniform(0, math.pi), rng.uniform(0, SPACING)) for _ in range(3)
        ]
        for angle, offset in layouts:
            lanes = [region_lanes(region, SPACING, angle, offset, reach=SPACING / 2,
                                  holes=region.holes)]  # fmt: skip
            before = len(completed)
            got = inside.inside_layout(region, lanes, SPACING, SPACING / 2)
            calls = len(completed) - before  # margin 1/2's, and margin 0's unless screened
            _same(got, _both_in_full(region, lanes))
            tol = 1e-9 * region.diameter
            half = [inside.clip_lanes(ls, region, tol, SPACING / 2, SPACING) for ls in lanes]
            chose_half = all(
                np.array_equal(g.t0, h.t0) and np.array_equal(g.t1, h.t1)
                for g, h in zip(got[0], half, strict=True)
            )
            # margin 1/2 always leaves something to its passes (one _completed); margin 0's
            # passes completed: a second one
            margin0 += not chose_half
            screened += chose_half and calls == 1
            laid += calls == 2
    # the square at 0 degrees: margin 0's lanes leave nothing (no passes at all) and win
    assert margin0 >= 1
    assert laid >= 1  # margin 0's passes completed (the screen let it through)
    assert screened >= 2 * len(_areas())  # most layouts: margin 0 screened out


def test_the_screen_is_sound_where_margin_0_has_passes():
    """A square crossed at 45 degrees: both margins need passes; whichever the screen keeps
    is no longer than margin 0 laid in full."""
    region = Region([(0, 0), (100, 0), (100, 100), (0, 100)])
    lanes = [region_lanes(region, SPACING, math.pi / 4, 3.0, reach=SPACING / 2)]
    got = inside.inside_layout(region, lanes, SPACING, SPACING / 2)
    _same(got, _both_in_full(region, lanes))
    tol = 1e-9 * region.diameter
    cut = [inside.clip_lanes(ls, region, tol, 0.0, SPACING) for ls in lanes]
    passes, _ = inside.boundary_passes(region, cut, SPACING, SPACING / 2)
    assert passes  # margin 0 leaves triangles along every edge
    assert inside._length(got[0], got[1]) <= inside._length(cut, passes) + tol
    assert inside.SCREEN_SLACK == pytest.approx(1e-6)


@pytest.mark.parametrize(
    "ring, holes, spacing",
    [
        ([(0, 0), (10, 0), (10, 10), (0, 10)], [[(1, 1), (9, 1), (9, 9), (1, 9)]], 1.0),
        ([(0, 0), (120, 0), (120, 40), (50, 40), (50, 100), (0, 100)],
         [[(10, 10), (30, 10), (30, 25)], [(60, 15), (90, 12), (80, 30)]], 10.0),
    ],
)  # fmt: skip
def test_the_screen_on_a_thin_ring_and_two_lane_directions(ring, holes, spacing):
    """A 1 m ring (margin 1/2 has no lanes at all) and an L with two holes whose lanes come in
    two directions (as a decomposed plan's cells give them): the same choice as both in full."""
    region = Region(ring, holes)
    tol = 1e-9 * region.diameter
    for angles in ([0.3], [0.0, math.pi / 2], [1.1, 2.0]):
        lanes = [region_lanes(region, spacing, a, 0.25 * spacing, reach=spacing / 2,
                              holes=region.holes) for a in angles]  # fmt: skip
        got = inside.inside_layout(region, lanes, spacing, spacing / 2)
        ref = []
        for m in inside.MARGINS:
            cut = [inside.clip_lanes(ls, region, tol, m * spacing, spacing) for ls in lanes]
            passes, unc = inside.boundary_passes(region, cut, spacing, spacing / 2)
            ref.append((unc, inside._length(cut, passes), cut, passes))
        keep = ref[1] if (ref[1][0], ref[1][1]) < (ref[0][0], ref[0][1] - tol) else ref[0]
        _same(got, (keep[2], keep[3], keep[0]))
