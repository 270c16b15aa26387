"""The vectorised trace of a union of trapezoids (plan/cell_trace.py) against the loops it
replaced: the same rings, vertex for vertex, on traced fields with holes."""

from __future__ import annotations

import numpy as np
import pytest

from boustro.geometry.region import as_region
from boustro.geometry.traced import traced_field
from boustro.plan import cell_trace as ct
from boustro.plan.cells import _TOL, _links, decompose, trace_region, trapezoids


def _rings(tr, idx, diameter, loops):
    idx = np.asarray(idx)
    m = ct._Members(tr.a[idx], tr.b[idx], tr.te_a[idx], tr.te_b[idx], tr.tx_a[idx], tr.tx_b[idx])
    seg, rings = ct._ring_indices(m, _TOL * diameter, loops=loops)
    return [seg[r, :2] for r in rings]


@pytest.mark.parametrize(("n", "holes"), [(60, 1), (300, 4), (800, 10)])
def test_vectorised_trace_matches_loops(n, holes):
    r = traced_field(n, holes)
    rng = np.random.default_rng(n)
    checked = 0
    for sweep in (0.0, 0.4, 1.3, 2.5):
        d = decompose(r, sweep, min_width=20.0)
        tr = d.trapezoids
        q = len(tr.a)
        sets = [np.arange(q)] + [np.flatnonzero(d.membership == k) for k in range(len(d.cells))]
        for _ in range(4):  # runs of trapezoids: unions with holes and pinched corners
            lo = int(rng.integers(0, q))
            sets.append(np.arange(lo, min(q, lo + int(rng.integers(1, 200)))))
        for idx in sets:
            fast = _rings(tr, idx, r.diameter, loops=False)
            slow = _rings(tr, idx, r.diameter, loops=True)
            assert len(fast) == len(slow)
            for a, b in zip(fast, slow, strict=True):
                assert np.array_equal(a, b)
            checked += 1
    assert checked >= 20


def test_whole_area_traced_back():
    """All trapezoids of a field with holes trace back to the field: same area, same holes."""
    r = traced_field(400, 5)
    d = decompose(r, 0.7, min_width=0.0)
    whole = trace_region(d.trapezoids, np.arange(len(d.trapezoids.a)), r.diameter)
    assert whole.n_holes == 5
    assert whole.area == pytest.approx(r.area, rel=1e-9)


def test_interval_difference():
    """Pieces of one slab line: left intervals minus the right ones, as the loop cut them."""
    line = np.zeros(3)
    lo_a, hi_a = np.array([0.0, 5.0, 9.0]), np.array([4.0, 8.0, 12.0])
    lo_b, hi_b = np.array([1.0, 2.0, 6.0, 12.0]), np.array([2.0, 3.0, 7.0, 13.0])
    _, lo, hi = ct._minus(line, lo_a, hi_a, np.zeros(4), lo_b, hi_b, 1e-9)
    want = ct._interval_minus(
        list(zip(lo_a, hi_a, strict=True)), list(zip(lo_b, hi_b, strict=True)), 1e-9
    )
    assert list(zip(lo.tolist(), hi.tolist(), strict=True)) == want
    assert want == [(0.0, 1.0), (3.0, 4.0), (5.0, 6.0), (7.0, 8.0), (9.0, 12.0)]


def _links_dense(tr, tol):
    """The per-slab dense links :func:`_links` replaced (reference)."""
    out = []
    by_slab = {int(s): np.flatnonzero(tr.slab == s) for s in np.unique(tr.slab)}
    for s, lower in by_slab.items():
        upper = by_slab.get(s + 1)
        if upper is None or tr.b[lower[0]] != tr.a[upper[0]]:
            continue
        lo = np.maximum(tr.te_b[lower][:, None], tr.te_a[upper][None])
        hi = np.minimum(tr.tx_b[lower][:, None], tr.tx_a[upper][None])
        overlap = hi - lo
        touching = overlap > tol
        for i, j in zip(*np.nonzero(touching), strict=True):
            single = bool(touching[i].sum() == 1 and touching[:, j].sum() == 1)
            out.append((float(overlap[i, j]), int(lower[i]), int(upper[j]), single))
    return out


@pytest.mark.parametrize(
    "area",
    [
        [(0, 0), (9, 0), (9, 9), (6, 9), (6, 3), (3, 3), (3, 9), (0, 9)],
        [(0, 0), (4, 0), (4, 1), (1, 1), (1, 2), (4, 2), (4, 3), (0, 3)],
        (60, 1),
        (500, 10),
    ],
)
def test_links_sweep_matches_dense(area):
    r = traced_field(*area) if isinstance(area, tuple) else as_region(area)
    for sweep in np.linspace(0.0, np.pi, 9):
        tr = trapezoids(r, sweep)
        tol = _TOL * r.diameter
        assert _links(tr, tol) == _links_dense(tr, tol)
