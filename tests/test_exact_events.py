"""The event angles of the compiled certified optimum (kernel_events, issue 21) against
structure.event_angles, the numpy reference: the same angles, bit for bit (an event one unit
in the last place away can move a knife-edge optimum), and the same search."""

from __future__ import annotations

import math

import numpy as np
import pytest

from boustro.geometry import random_convex_polygon
from boustro.optimize.exact import event_angles, global_optimum, kernel_events
from boustro.optimize.exact.kernel import compiled

SPACINGS = (1 / 3, 1 / 10, 1 / 30, 1 / 100)


def compiled_events(v, s):
    """The event angles as the compiled search forms them (kernel.search_smith_compiled)."""
    kernels = compiled()
    assert kernels is not None
    dx, dy, pair, ratio = kernels.event_terms(v, s)
    return kernel_events._event_merge(np.arctan2(-dx, dy), pair, np.arccos(ratio))


def test_compiled_events_are_numpys_bit_for_bit():
    """Seeded random polygons of 3-24 vertices at spacings 1/3 .. 1/100 of the diameter, and
    regular polygons at spacings that divide their widths (coincident events merged)."""
    rng = np.random.default_rng(21)
    problems = []
    for k in range(120):
        polygon = random_convex_polygon(rng, int(rng.integers(3, 25)))
        v = polygon.frame.to_normalised(polygon.vertices)
        problems.append((v, SPACINGS[k % 4]))
    for n in range(3, 13):
        t = np.arange(n) * (2 * math.pi / n)
        v = 0.5 * np.column_stack([np.cos(t), np.sin(t)])
        for s in (math.sqrt(3) / 4, np.nextafter(math.sqrt(3) / 4, 1.0), 0.25, 0.1, 1 / 3):
            problems.append((v, float(s)))
    for v, s in problems:
        ref, got = event_angles(v, s), compiled_events(v, s)
        assert got.shape == ref.shape and np.array_equal(got, ref)


@pytest.mark.parametrize("seed", [3, 4])
def test_compiled_search_counts_the_numpy_events(seed, monkeypatch):
    """The result's event count and search, with and without the kernels."""
    rng = np.random.default_rng(seed)
    for k in range(6):
        polygon = random_convex_polygon(rng, int(rng.integers(3, 13)))
        spacing = SPACINGS[k % 4] * polygon.diameter
        monkeypatch.setenv("BOUSTRO_COMPILED", "1")
        fast = global_optimum(polygon, spacing)
        monkeypatch.setenv("BOUSTRO_COMPILED", "0")
        slow = global_optimum(polygon, spacing)
        assert fast.info["events"] == slow.info["events"]
        assert fast.info["rounds"] == slow.info["rounds"]
        assert fast.evaluations == slow.evaluations
