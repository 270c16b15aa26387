"""boustro.plan.min_plus: the router's min-plus products, compiled, equal numpy's sums and
minima bit for bit (rows mostly ``inf``, as a point's lengths to the nodes it sees)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from boustro.geometry.traced import traced_field
from boustro.plan.min_plus import _min_plus, min_plus
from boustro.plan.routing import Router


def _lengths(rng, shape, hidden):
    x = rng.uniform(0.0, 500.0, shape) * rng.uniform(0.5, 2.0, shape)
    x[rng.random(shape) < hidden] = math.inf
    return x


@pytest.mark.parametrize("hidden", [0.0, 0.5, 0.9, 1.0])
def test_min_plus_equals_numpy_bit_for_bit(hidden):
    rng = np.random.default_rng(7)
    for p, k, m in [(1, 1, 1), (5, 9, 3), (70, 40, 66), (3, 120, 200)]:
        a = _lengths(rng, (p, k), hidden)
        b = _lengths(rng, (k, m), hidden / 2)
        a[0] = math.inf  # a point that sees no node
        want = np.min(a[:, :, None] + b[None], axis=1)
        got = min_plus(a, b)
        assert got.dtype == np.float64 and got.shape == (p, m)
        assert np.array_equal(got, want)
        assert np.isinf(got[0]).all()
        # the plain loop (without numba) gives the same
        out = np.full((p, m), math.inf)
        getattr(_min_plus, "py_func", _min_plus)(a, b, out)
        assert np.array_equal(out, want)


def test_min_plus_of_no_nodes_is_inf():
    assert np.isinf(min_plus(np.zeros((3, 0)), np.zeros((0, 4)))).all()
    assert min_plus(np.zeros((0, 5)), np.zeros((5, 2))).shape == (0, 2)


def test_router_rows_through_the_graph_equal_numpys():
    """A sub-router of a traced field (its graph of reflex vertices): the lengths through the
    visible nodes, and the pairs' lengths through the graph, as numpy computed them."""
    field = traced_field(400, 3)
    router = Router(field, 0.0)
    subs = router._coarse or [router]
    sub = max(subs, key=lambda s: len(s.nodes))
    assert len(sub.nodes) > 10
    rng = np.random.default_rng(3)
    lo, hi = sub.region.shell.vertices.min(axis=0), sub.region.shell.vertices.max(axis=0)
    pts = sub.anchor(rng.uniform(lo, hi, (150, 2)))
    v, w = sub._via_nodes_now(pts)
    assert np.isinf(v).any() and np.isfinite(v).any()
    assert np.array_equal(w, np.min(v[:, :, None] + sub._dist[None], axis=1))
    d = sub.distances(pts, nearest=0)
    via = np.min(w[:, None, :] + v[None, :, :], axis=-1)
    euclid = np.linalg.norm(pts[:, None] - pts[None], axis=-1)
    want = np.where(np.isfinite(via), via, euclid)
    np.fill_diagonal(want, 0.0)
    assert np.array_equal(d, want)
