"""The compiled evaluation of angle intervals keeps its first pass's structures for its second
(kernel_search._evaluate, issue 21): with slots for every interval, for some, and for none (a
polygon too large for _KEEP_FLOATS), its values, bounds and orders are the numpy reference's."""

from __future__ import annotations

import math

import numpy as np

from boustro.geometry import random_convex_polygon
from boustro.optimize.exact import event_angles
from boustro.optimize.exact.bounds import _evaluate_smith
from boustro.optimize.exact.kernel import evaluate_smith_compiled
from boustro.optimize.exact.kernel_search import _KEEP_FLOATS


def agree(v, s, lo, hi, threshold, batch):
    with np.errstate(all="ignore"):
        ref = _evaluate_smith(v, s, lo, hi, 0.5, 0.5, threshold)
        got = evaluate_smith_compiled(v, s, lo, hi, 0.5, 0.5, threshold, batch)
    g0, _, ub0, o0 = ref
    g1, _, ub1, o1 = got
    for x, y in ((g0, g1), (ub0, ub1)):
        finite = np.isfinite(x)
        assert np.array_equal(finite, np.isfinite(y))
        np.testing.assert_allclose(y[finite], x[finite], rtol=0, atol=1e-12)
    assert np.array_equal(o0, o1)
    return got


def test_kept_structures_give_the_reference_bounds():
    rng = np.random.default_rng(31)
    for n, spacing, count in ((7, 1 / 30, 400), (24, 1 / 10, 300), (150, 1 / 3, 16)):
        polygon = random_convex_polygon(rng, n)
        v = polygon.frame.to_normalised(polygon.vertices)
        edges = event_angles(v, spacing)[: count + 1]
        lo, hi = edges[:-1], edges[1:]
        first = agree(v, spacing, lo, hi, -math.inf, 2048)
        # the second round's shape: halves against a threshold, in small batches too
        threshold = float(np.max(first[0])) + 1e-6
        mid = 0.5 * (lo + hi)
        agree(v, spacing, mid, hi, threshold, 2048)
        agree(v, spacing, mid, hi, threshold, 5)
    # the 150-gon has no slot (its structure is larger than _KEEP_FLOATS): every interval of
    # the second pass is computed again, as before the slots
    assert 21 * 150 + 12 * 150 * 149 > _KEEP_FLOATS
