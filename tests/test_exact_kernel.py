"""The compiled path of the certified Eq. 1 optimiser against its numpy and torch references.

``optimize.exact.kernel`` (numba) evaluates the branch and bound's angle intervals and scores
candidate layouts; the numpy code of ``bounds``/``structure`` and ``evaluate_grid`` compute the
same numbers and stay as the references (and the path with ``BOUSTRO_COMPILED=0``). Here the
two agree on seeded random polygons (3-24 vertices, spacings 1/3 .. 1/100 of the diameter), and
the compiled optimiser's certificate holds against a dense independent search.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from boustro import optimize as opt
from boustro.geometry import halfplanes, random_convex_polygon
from boustro.geometry.polygon import edge_halfplanes
from boustro.objectives import SmithFitness
from boustro.optimize.exact import event_angles, global_optimum
from boustro.optimize.exact import kernel as kernel_module
from boustro.optimize.exact.bounds import _evaluate_smith
from boustro.optimize.exact.kernel import evaluate_smith_compiled, exact_smith_compiled
from boustro.optimize.exact.search import _BATCH

SPACINGS = (1 / 3, 1 / 10, 1 / 30, 1 / 100)


def cases(seed: int, count: int, max_vertices: int = 24):
    rng = np.random.default_rng(seed)
    for k in range(count):
        n = int(rng.integers(3, max_vertices + 1))
        polygon = random_convex_polygon(rng, n)
        yield polygon, SPACINGS[k % len(SPACINGS)] * polygon.diameter


def assert_same(reference, compiled, s):
    """Values, offsets (modulo the spacing: equal pieces may tie), bounds and orders."""
    g0, d0, ub0, o0 = reference
    g1, d1, ub1, o1 = compiled
    for x, y in ((g0, g1), (ub0, ub1)):
        finite = np.isfinite(x)
        assert np.array_equal(finite, np.isfinite(y))
        assert np.array_equal(x[~finite], y[~finite])
        np.testing.assert_allclose(y[finite], x[finite], rtol=0, atol=1e-12)
    dd = np.abs(np.mod(d1 - d0 + 0.5 * s, s) - 0.5 * s)
    assert np.all(dd[np.isfinite(g0)] <= 1e-12)
    assert np.array_equal(o0, o1)


def test_compiled_intervals_equal_the_numpy_bounds():
    """Every interval between events, then halves of them against a threshold (the second
    round's shape, where some intervals skip the second-order bound)."""
    checked = 0
    for polygon, spacing in cases(7, 24):
        v = polygon.frame.to_normalised(polygon.vertices)
        s = spacing / polygon.diameter
        edges = event_angles(v, s)[:801]
        lo, hi = edges[:-1], edges[1:]
        mid = 0.5 * (lo + hi)
        with np.errstate(all="ignore"):
            first = _evaluate_smith(v, s, lo, hi, 0.5, 0.5)
            assert_same(first, evaluate_smith_compiled(v, s, lo, hi, 0.5, 0.5, -math.inf, 2048), s)
            threshold = float(np.max(first[0])) + 1e-6
            for a, b in ((0.5, 0.5), (0.9, 0.1), (0.0, 1.0)):
                ref = _evaluate_smith(v, s, mid, hi, a, b, threshold)
                got = evaluate_smith_compiled(v, s, mid, hi, a, b, threshold, _BATCH)
                assert_same(ref, got, s)
        checked += len(lo)
    assert checked > 5_000


def test_compiled_intervals_batch_like_numpy():
    """The threshold of a batch is its best value: a small batch changes which intervals get
    the second-order bound, in both paths alike."""
    polygon, _ = next(cases(11, 1, 9))
    v = polygon.frame.to_normalised(polygon.vertices)
    s = 0.05
    edges = event_angles(v, s)
    lo, hi = edges[:-1], edges[1:]
    with np.errstate(all="ignore"):
        got = evaluate_smith_compiled(v, s, lo, hi, 0.5, 0.5, -math.inf, 7)
        ref_rows = [
            _evaluate_smith(v, s, lo[k : k + 7], hi[k : k + 7], 0.5, 0.5)
            for k in range(0, len(lo), 7)
        ]
    ref = tuple(np.concatenate([r[i] for r in ref_rows]) for i in range(4))
    assert_same(ref, got, s)


def test_compiled_exact_scores_equal_evaluate_grid():
    rng = np.random.default_rng(3)
    for polygon, spacing in cases(5, 60):
        v = polygon.frame.to_normalised(polygon.vertices)
        s = spacing / polygon.diameter
        hp = halfplanes(polygon)
        normals, offsets = edge_halfplanes(v)
        assert np.array_equal(normals, hp.normals.numpy())
        assert np.array_equal(offsets, hp.offsets.numpy())
        angles = np.concatenate([rng.uniform(0, math.pi, 25), [0.0, math.pi / 2]])
        shifts = np.concatenate([rng.uniform(-1.5, 1.5, 10) * s, [0.0, s]])
        fit = SmithFitness(a=0.3, b=0.7)
        ref = opt.evaluate_grid(
            hp, torch.tensor(angles), torch.tensor(shifts), s, fitness=fit
        ).numpy()
        got = exact_smith_compiled(
            v,
            (normals, offsets, float(np.max(np.linalg.norm(v, axis=1)))),
            s,
            np.repeat(angles, len(shifts)),
            np.tile(shifts, len(angles)),
            0.3,
            0.7,
        ).reshape(ref.shape)
        finite = np.isfinite(ref)
        assert finite.any()
        assert np.array_equal(finite, np.isfinite(got))
        np.testing.assert_allclose(got[finite], ref[finite], rtol=0, atol=1e-13)


@pytest.mark.parametrize("seed", [0, 1])
def test_global_optimum_compiled_equals_numpy_path(seed, monkeypatch):
    """The whole optimiser with and without the compiled kernels: the same layouts, values
    and certificates (the reference path is the one BOUSTRO_COMPILED=0 runs)."""
    problems = list(cases(100 + seed, 12, 16))
    monkeypatch.setenv("BOUSTRO_COMPILED", "1")
    fast = [global_optimum(p, s) for p, s in problems]
    monkeypatch.setenv("BOUSTRO_COMPILED", "0")
    slow = [global_optimum(p, s) for p, s in problems]
    for (_, spacing), x, y in zip(problems, fast, slow, strict=True):
        assert x.info["converged"] and y.info["converged"]
        assert x.fitness == pytest.approx(y.fitness, abs=1e-12)
        assert x.upper_bound == pytest.approx(y.upper_bound, abs=1e-12)
        assert x.angle == pytest.approx(y.angle, abs=1e-9)
        shift = abs((x.offset - y.offset + 0.5 * spacing) % spacing - 0.5 * spacing)
        assert shift <= 1e-9 * spacing
        assert x.evaluations == y.evaluations


def test_compiled_certificate_against_a_dense_search():
    """No layout of a dense exact grid beats the certified upper bound, and the returned
    layout's value is what evaluate_grid gives it."""
    fit = SmithFitness()
    for polygon, spacing in cases(21, 10, 24):
        r = global_optimum(polygon, spacing)
        assert r.info["converged"] and 0 <= r.gap <= 1e-6
        s_n = spacing / polygon.diameter
        hp = halfplanes(polygon)
        dense = opt.evaluate_grid(
            hp,
            torch.arange(360, dtype=torch.float64) * (math.pi / 360),
            torch.arange(24, dtype=torch.float64) * (s_n / 24),
            s_n,
            fitness=fit,
        )
        assert float(dense.max()) <= r.upper_bound + 1e-12
        assert float(dense.max()) <= r.fitness + r.gap + 1e-12
        again = opt.evaluate_grid(
            hp,
            torch.tensor([r.angle], dtype=torch.float64),
            torch.tensor([r.offset / polygon.diameter], dtype=torch.float64),
            s_n,
            fitness=fit,
        )
        assert float(again[0, 0]) == pytest.approx(r.fitness, abs=1e-9)


def test_when_the_kernels_are_used(monkeypatch):
    """By default and with ``BOUSTRO_COMPILED=1`` (numba's cache works here), never with
    ``BOUSTRO_COMPILED=0``; the choice does not depend on the process's history."""
    for value, expected in (("", True), ("1", True), ("on", True), ("0", False), ("off", False)):
        monkeypatch.setenv("BOUSTRO_COMPILED", value)
        assert kernel_module.use_compiled() is expected
        assert kernel_module.use_compiled() is expected  # the same again, whatever came before


def test_the_first_compile_is_known_from_the_cache():
    """After a certified optimum the kernels are in numba's cache: no 'compiling' note."""
    global_optimum(np.array([(0, 0), (4, 0), (5, 3), (0, 2)], dtype=float), 0.5)
    assert kernel_module.compiled() is not None and not kernel_module.first_compile()


def test_the_first_compile_is_looked_for_where_numba_caches(monkeypatch, tmp_path):
    """Under ``NUMBA_CACHE_DIR`` (an empty one: a fresh installation's) the kernels are not
    cached, whatever the package's ``__pycache__`` holds; it looked there only."""
    numba = pytest.importorskip("numba")
    global_optimum(np.array([(0, 0), (4, 0), (5, 3), (0, 2)], dtype=float), 0.5)
    assert not kernel_module.first_compile()  # the usual cache holds them
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path / "empty"))
    assert kernel_module.first_compile()
