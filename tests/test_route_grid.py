"""The router's segment tests on traced fields (issue 21, eleventh round): edges in a uniform
grid instead of STRtree queries, straight-segment answers and rows through the graph remembered
by the router. Every answer must equal the one computed from scratch by the previous method, bit
for bit, so plans do not change."""

from __future__ import annotations

import numpy as np
import pytest

from boustro.geometry.traced import traced_field
from boustro.plan.edge_grid import EdgeGrid
from boustro.plan.route_visibility import visible_tree
from boustro.plan.routing import Router
from boustro.plan.visibility_kernel import points_near, segment_crossings


@pytest.fixture(scope="module")
def field():
    return traced_field(1500, 5)


def _segments(r, n, seed):
    rng = np.random.default_rng(seed)
    v = np.concatenate([r.shell.vertices] + [h.vertices for h in r.holes])
    lo, hi = v.min(0), v.max(0)
    p = rng.uniform(lo - 30, hi + 30, (n, 2))
    q = p + rng.normal(0, 40, (n, 2))  # short ones, as a tour's nearest neighbours
    q[: n // 4] = rng.uniform(lo, hi, (n // 4, 2))  # long ones, across the field
    i = rng.integers(0, len(v), (n // 2, 2))
    p[n // 4 : 3 * n // 4] = v[i[:, 0]]  # vertex to vertex
    q[n // 4 : 3 * n // 4] = v[i[:, 0]] + (v[i[:, 1]] - v[i[:, 0]]) * rng.uniform(0, 1, (n // 2, 1))
    j = rng.integers(0, len(v) - 1, n // 8)  # along an edge, through its vertices
    p[-(n // 8) :], q[-(n // 8) :] = 2 * v[j] - v[j + 1], 3 * v[j + 1] - 2 * v[j]
    return p, q


@pytest.mark.parametrize("small", [False, True])
def test_grid_crossings_equal_every_edges_tests(field, small):
    if small:  # a few hundred edges: inner domains and cells, through the grid too
        field = traced_field(150, 3, seed=2)
    router = Router(field, 5.0)
    grid = EdgeGrid(router._e1, router._e2)
    p, q = _segments(field, 3000, 0)
    p[0], q[1] = np.nan, np.inf  # no candidates, no crash
    got = grid.crossings(p, q, router.tol)
    want = segment_crossings(p, q, router._e1, router._e2, router.tol)
    assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1])
    assert got[0].any() and (~got[0]).any() and got[1].any()


def test_grid_visibility_equals_the_strtree_candidates(field):
    router = Router(field, 5.0)
    assert len(router._e1) > 512  # the grid's path
    p, q = _segments(field, 2000, 1)
    got = router._visible_many(p, q)
    want = visible_tree(router, p, q)
    assert np.array_equal(got, want) and got.any() and (~got).any()


def test_remembered_rows_through_the_graph_equal_a_fresh_routers(field):
    warm = Router(field, 5.0)
    rng = np.random.default_rng(2)
    v = field.shell.vertices
    pts = v[rng.integers(0, len(v), 120)] + rng.normal(0, 3, (120, 2))
    for lo, hi in ((0, 60), (30, 90), (0, 120)):  # each batch shares points with the last
        got = warm.distances(pts[lo:hi])
        assert np.array_equal(got, Router(field, 5.0).distances(pts[lo:hi]))
    assert warm._coarse is not None and warm._coarse[0]._row_cache["via"]  # remembered


def test_grid_nearness_equals_the_strtree_candidates(field):
    router = Router(field, 5.0)
    index, tol = router._index, router.tol
    rng = np.random.default_rng(4)
    v = router._e1
    p = rng.uniform(v.min(0) - 20, v.max(0) + 20, (3000, 2))
    p[:1000] = v[rng.integers(0, len(v), 1000)] + rng.normal(0, 3 * tol, (1000, 2))
    p[1000:1500] = v[rng.integers(0, len(v), 500)] + rng.normal(0, 5.0, (500, 2))
    n_shell = len(field.shell)
    got = index.near(p)
    assert np.array_equal(got, index.near_tree(p, tol, len(v), 2 * tol))
    assert got.any() and (~got).any()
    got = index.within(p, 5.0, n_shell)
    assert np.array_equal(got, index.near_tree(p, 5.0, n_shell, 5.0 * (1 + 1e-6) + tol))
    assert got.any() and (~got).any()


def test_a_grid_of_long_edges_is_coarser_and_answers_the_same():
    """A star of 600 spikes: every edge spans the field, so the grid coarsens (at most 32
    cells an edge) and still keeps every candidate."""
    k = np.arange(1200)
    rad = np.where(k % 2 == 0, 100.0, 3.0)
    ring = np.stack([rad * np.cos(k * np.pi / 600), rad * np.sin(k * np.pi / 600)], axis=1)
    e1, e2 = ring, np.roll(ring, -1, axis=0)
    grid = EdgeGrid(e1, e2)
    assert len(grid.items) <= 32 * len(e1) and grid.nx < 35
    rng = np.random.default_rng(5)
    p, q = rng.uniform(-110, 110, (2000, 2)), rng.uniform(-110, 110, (2000, 2))
    got, want = grid.crossings(p, q, 1e-7), segment_crossings(p, q, e1, e2, 1e-7)
    assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1]) and got[0].any()
    near = grid.near(p, 0.5, len(e1))
    assert np.array_equal(near, points_near(p, e1, e2, 0.5)) and near.any() and (~near).any()
