"""The router's work per plan on traced fields (issue 21): anchors from STRtree candidates,
holes asked by their boxes, routed moves and per-point answers remembered. Every answer must
equal the one computed from scratch, bit for bit, so plans do not depend on what was planned
before them."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from boustro.geometry.traced import traced_field
from boustro.plan.edge_index import EdgeIndex
from boustro.plan.nearest_edge import nearest_feet
from boustro.plan.region import plan_region
from boustro.plan.routing import Router, router_for


@pytest.fixture(scope="module")
def field():
    return traced_field(1200, 6)


def _points(r, n, seed):
    rng = np.random.default_rng(seed)
    lo, hi = r.shell.vertices.min(axis=0), r.shell.vertices.max(axis=0)
    pts = [rng.uniform(lo - 40, hi + 40, (n, 2))]
    v = r.shell.vertices[rng.integers(0, len(r.shell.vertices), n)]
    pts += [v, v + rng.normal(0, 0.5, v.shape)]  # on the boundary, and just off it
    for h in r.holes:
        pts += [h.vertices + rng.normal(0, 0.3, h.vertices.shape), h.vertices.mean(axis=0)[None]]
    return np.vstack(pts)


def test_anchor_from_candidates_equals_the_nearest_of_every_edge(field):
    router = Router(field, 5.0)
    pts = _points(field, 600, 0)
    got = router.anchor(pts)
    bad = router.classify(pts) != 0
    assert bad.sum() > 300  # outside the shell and inside holes
    want = pts.copy()
    want[bad] = nearest_feet(pts[bad], router._e1, router._e2)
    assert np.array_equal(got, want)


def test_classify_asks_only_the_holes_whose_box_holds_the_point(field):
    index = EdgeIndex(field, 1e-9 * field.diameter)
    pts = _points(field, 800, 1)
    got = index.classify(pts)
    far = ~index.near(pts)
    want = np.zeros(len(pts), dtype=np.int64)
    want[far & ~shapely.contains_xy(index.shell, pts[:, 0], pts[:, 1])] = 2
    for hole in index.holes:
        want[far & shapely.contains_xy(hole, pts[:, 0], pts[:, 1])] = 1
    assert np.array_equal(got, want)
    assert {0, 1, 2} <= set(got.tolist())


def test_remembered_routes_and_rows_equal_a_fresh_router(field):
    warm = Router(field, 5.0)
    pts = _points(field, 60, 2)
    a, b = pts[:120], pts[60:180]  # overlapping point sets
    warm.distances(a)
    warm.paths(a[:-1], a[1:])
    fresh = Router(field, 5.0)
    assert np.array_equal(warm.distances(b), fresh.distances(b))
    for x, y in zip(warm.paths(b[:-1], b[1:]), fresh.paths(b[:-1], b[1:]), strict=True):
        assert np.array_equal(x.points, y.points)
        assert (x.length, x.outside, x.straight, x.found) == (
            y.length,
            y.outside,
            y.straight,
            y.found,
        )
    assert warm._routes and warm._row_cache["domains"]  # the traced field routes by domains
    pa = warm.anchor(b)
    for got, want in zip(warm._to_domains(pa), fresh._to_domains_now(pa), strict=True):
        assert np.array_equal(got, want)
    route = warm.path(b[0], b[5])
    assert route is warm.path(b[0], b[5])  # remembered, and read-only
    with pytest.raises(ValueError):
        route.points[0, 0] = 1.0


def test_a_plan_is_the_same_after_other_plans_of_the_field():
    r = traced_field(600, 4, seed=2)
    kw = {"decompose_area": False, "speed": 5.0, "turn_time": 10.0}
    router_for.cache_clear()
    fresh = plan_region(r, 10.0, angle=0.7, offset=2.0, **kw)
    router_for.cache_clear()
    for angle in (0.69, 0.71, 1.9):  # nearby layouts first: the router remembers their moves
        plan_region(r, 10.0, angle=angle, offset=2.0, **kw)
    again = plan_region(r, 10.0, angle=0.7, offset=2.0, **kw)
    assert np.array_equal(fresh.waypoints, again.waypoints)
    assert fresh.stats == again.stats


@pytest.mark.parametrize("limit", [35, 50, 200])
def test_full_caches_forget_and_still_answer(field, monkeypatch, limit):
    """A review: a batch with points remembered before the cache is emptied (past its limit)
    raised KeyError (a 300-vertex traced field at 4 m crashed ``plan_area``). With tiny limits
    every answer still equals a fresh router's."""
    import boustro.plan.routing as routing

    monkeypatch.setattr(routing, "_ROUTES", limit)
    monkeypatch.setattr(routing, "_ROWS", limit)
    warm, fresh = Router(field, 5.0), Router(field, 5.0)
    pts = _points(field, 80, 3)
    for n in (30, len(pts) // 2, len(pts)):  # each batch holds remembered points and new ones
        p, q = pts[: n - 1], pts[1:n]
        for x, y in zip(warm.paths(p, q), fresh._straight_many(p, q)[0], strict=True):
            assert x.straight == bool(y)
        assert np.array_equal(warm.distances(pts[:n]), Router(field, 5.0).distances(pts[:n]))
        pa = warm.anchor(pts[:n])
        for got, want in zip(warm._to_domains(pa), fresh._to_domains_now(pa), strict=True):
            assert np.array_equal(got, want)
    assert len(warm._routes) <= limit
    assert all(len(c) <= limit for c in warm._row_cache.values())


def test_an_anchor_of_a_nan_point_is_nan(field):
    """Above 256 edges the anchors come from STRtree candidates: a NaN point has none, and its
    anchor is NaN (as over every edge), not uninitialised memory."""
    router = Router(field, 5.0)
    got = router.anchor(np.array([[np.nan, np.nan], [np.nan, 0.0], [0.0, np.nan]]))
    assert np.isnan(got).any(axis=1).all()


def _distances_point_by_point(router, p, nearest=24):
    """``Router.distances`` as it was before points given twice were measured once (the
    reference: every point anchored, tested and measured on its own)."""
    m = len(p)
    pa = router.anchor(p)
    legs = np.linalg.norm(pa - p, axis=1)
    euclid = np.linalg.norm(pa[:, None] - pa[None], axis=-1)
    direct = np.full((m, m), np.inf)
    k = min(nearest, m - 1)
    near = np.argsort(euclid, axis=1)[:, 1 : k + 1]
    i, j = np.repeat(np.arange(m), k), near.ravel()
    keep = (i < j) | ~np.isin(j * m + i, i[i < j] * m + j[i < j])
    i, j = i[keep], j[keep]
    vis = np.array(
        [router._visible_many(pa[a][None], pa[b][None])[0] for a, b in zip(i, j, strict=True)]
    )
    direct[i[vis], j[vis]] = euclid[i[vis], j[vis]]
    direct[j[vis], i[vis]] = euclid[i[vis], j[vis]]
    np.fill_diagonal(direct, 0.0)
    v, w = router._via_nodes_now(pa)
    direct = np.minimum(direct, np.min(w[:, None, :] + v[None, :, :], axis=-1))
    out = np.where(np.isfinite(direct), direct, euclid) + legs[:, None] + legs[None, :]
    if router._grown is not None:
        idx = np.flatnonzero(router._grown_ends(p))
        sub = _distances_point_by_point(router._grown, p[idx], nearest)
        out[np.ix_(idx, idx)] = np.minimum(out[np.ix_(idx, idx)], sub)
    np.fill_diagonal(out, 0.0)
    return out


@pytest.mark.parametrize("reach", [0.0, 4.0])
def test_distances_of_points_given_twice_equal_point_by_point(reach):
    """A pass's driving options share their ends: ``Router.distances`` measures each distinct
    point once, and its matrix is the one measured point by point, bit for bit."""
    from boustro.geometry.region import random_region

    rng = np.random.default_rng(12)
    for _ in range(4):
        region = random_region(rng, 12, 2)
        k = 300.0 / region.diameter
        region = type(region)(region.shell.vertices * k, [h.vertices * k for h in region.holes])
        router = Router(region, reach)
        assert len(router.nodes) and (router._grown is not None) == (reach > 0)
        base = _points(region, 15, int(rng.integers(1000)))
        twice = base[rng.integers(0, len(base), 2 * len(base))]
        pts = np.vstack([base, twice])[rng.permutation(3 * len(base))]
        got = router.distances(pts)
        assert np.array_equal(got, _distances_point_by_point(Router(region, reach), pts))
        assert np.isfinite(got).all() and (got > 0).sum() > len(pts) ** 2 // 2


def _same_route(x, y):
    assert np.array_equal(x.points, y.points)
    assert (x.length, x.outside, x.straight, x.found) == (y.length, y.outside, y.straight, y.found)


@pytest.mark.parametrize("reach", [0.0, 5.0])
def test_detours_of_a_batch_equal_one_by_one(field, reach):
    """``Router.paths`` anchors the ends of all its detours and tests their straight moves at
    once: every route equals ``Router.path``'s on a fresh router, one move at a time (on the
    traced field's inner domains and on a random area's visibility graph)."""
    from boustro.geometry.region import random_region

    small = random_region(np.random.default_rng(5), 12, 2)
    small = type(small)(
        small.shell.vertices * (300.0 / small.diameter),
        [h.vertices * (300.0 / small.diameter) for h in small.holes],
    )
    for region, n in ((field, 50), (small, 25)):
        pts = _points(region, n, 4)
        rng = np.random.default_rng(6)
        p, q = pts[rng.permutation(len(pts))], pts[rng.permutation(len(pts))]
        batch = Router(region, reach).paths(p, q)
        fresh = Router(region, reach)
        one = [fresh.path(a, b) for a, b in zip(p, q, strict=True)]
        assert sum(not r.straight for r in one) > 20  # detours, and straight moves between
        assert sum(r.straight for r in one) > 5
        for x, y in zip(batch, one, strict=True):
            _same_route(x, y)
