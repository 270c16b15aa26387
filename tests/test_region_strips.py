"""The strips of a region's box (``smith_bb/region_strips.py``): the outer intervals hold every
layout's segments, the inner pieces lie in them, and the box bound built from them is sound
and, on noisy traced fields, tighter than the sandwich's."""

from __future__ import annotations

import math

import numpy as np
import pytest

from boustro.geometry.region import Region
from boustro.geometry.traced import traced_field
from boustro.optimize.cover.boxes import Boxes, box_radius, initial_boxes
from boustro.optimize.smith_bb import region_kernel as rk
from boustro.optimize.smith_bb.kernel import lines_range
from boustro.optimize.smith_bb.region import _RegionSearch
from boustro.optimize.smith_bb.region_strips import strip_intervals


def _search(seed: int, n: int, holes: int) -> _RegionSearch:
    return _RegionSearch(traced_field(n, holes, seed=seed, radius=90.0), 10.0, 0.5, 0.5)


def _concave() -> Region:
    shell = [(0, 0), (60, 0), (60, 40), (35, 40), (35, 15), (25, 15), (25, 40), (0, 40)]
    holes = [[(5, 5), (15, 5), (15, 30), (5, 30)], [(45, 20), (55, 25), (48, 33)]]
    return Region(shell, holes=holes)


@pytest.mark.parametrize("which", ["traced", "comb"])
def test_outer_holds_and_inner_lies_in_every_sampled_layout(which: str) -> None:
    rng = np.random.default_rng(3)
    if which == "traced":
        search = _search(7, 300, 3)
    else:
        search = _RegionSearch(_concave(), 4.0, 0.5, 0.5)
    xy, s, radius = search.real[0], search.s, search.radius
    k0, nb = lines_range(xy, s)
    k0, nb = k0 - 4, nb + 8
    checked = 0
    for _ in range(25):
        theta = float(rng.choice([rng.uniform(0, math.pi), math.pi / 2, 0.0]))
        delta, eta = rng.uniform(1e-5, 8e-3), rng.uniform(1e-5, 0.5) * s
        d = rng.uniform(0, s)
        ost, oa, ob, ist, pa, pb = strip_intervals(
            xy, math.cos(theta), math.sin(theta), d, s, k0, nb, radius, math.sin(delta), eta,
            rk.KEEP)  # fmt: skip
        for _ in range(15):
            al, et = rng.uniform(-delta, delta), rng.uniform(-eta, eta)
            st, lo, hi = rk._intervals(xy, math.cos(theta + al), math.sin(theta + al), d + et,
                                       s, k0, nb)  # fmt: skip
            for q in range(nb):
                h = d + et + (k0 + q) * s  # the layout's line; its t = t' cos(al) - h sin(al)
                ca, sa = math.cos(al), math.sin(al)
                seg = [(lo[j] * ca - h * sa, hi[j] * ca - h * sa) for j in range(st[q], st[q + 1])]
                outer = list(zip(oa[ost[q] : ost[q + 1]], ob[ost[q] : ost[q + 1]], strict=True))
                for a, b in seg:
                    assert any(x <= a + 1e-12 and b <= y + 1e-12 for x, y in outer), (q, a, b)
                    checked += 1
                for p in range(ist[q], ist[q + 1]):
                    assert any(a <= pa[p] + 1e-12 and pb[p] <= b + 1e-12 for a, b in seg)
    assert checked > 1000


@pytest.mark.parametrize(("seed", "n", "holes"), [(8, 400, 5), (9, 200, 2)])
def test_strip_bound_is_sound_in_boxes(seed: int, n: int, holes: int) -> None:
    rng = np.random.default_rng(seed)
    search = _search(seed, n, holes)
    search.best, search.tol = 0.0, 0.0  # every box gets its full bound
    assert search.strips == (len(search.xy) > 256)
    search.strips = True
    m = 60
    for delta, eta in ((6e-3, 0.3), (1e-3, 0.05), (1e-4, 0.005)):
        boxes = Boxes(rng.uniform(0, math.pi, m), np.full(m, delta), rng.uniform(0, search.s, m),
                      np.full(m, eta * search.s))  # fmt: skip
        bounds = search.bounds(boxes)
        for _ in range(12):
            t = boxes.theta + rng.uniform(-delta, delta, m)
            o = boxes.d + rng.uniform(-1, 1, m) * boxes.eta
            values = search.values(t, o)
            assert (values <= bounds + 1e-12).all(), (values - bounds).max()


def test_strips_are_tighter_than_the_sandwich_on_a_noisy_field() -> None:
    search = _search(11, 1000, 6)
    search.best, search.tol = 0.0, 0.0
    assert search.strips  # the default above 256 edges
    boxes = initial_boxes(search.s, search.radius, 90)
    search.top_eps = float(box_radius(boxes, search.radius).max())
    rng = np.random.default_rng(0)
    m = 80
    boxes = Boxes(rng.uniform(0, math.pi, m), np.full(m, 1.5e-3), rng.uniform(0, search.s, m),
                  np.full(m, 0.06 * search.s))  # fmt: skip
    strips = search.bounds(boxes)
    search.strips = False
    sandwich = search.bounds(boxes)
    assert np.median(strips - sandwich) < -1e-3
    assert (strips < sandwich).mean() > 0.7


def test_quarters_of_the_best_boxes_are_scored_with_the_strips() -> None:
    # the region search's polish of a round's best centres also scores the centres of the
    # quarters of the DIVE_PER_ROUND best boxes (values only) and offers the best; small areas
    # (the sandwich's bound) do not
    s = _search(3, 500, 4)
    assert s.strips
    boxes = Boxes(*(np.array(v) for v in ([0.8, 1.9], [0.004, 0.002], [0.01, 0.02], [1e-3, 5e-4])))
    s.polish_best(boxes, s.values(boxes.theta, boxes.d), False)
    sides = np.array([-0.5, 0.5])
    theta = (boxes.theta[:, None] + np.repeat(sides, 2) * boxes.delta[:, None]).ravel()
    d = (boxes.d[:, None] + np.tile(sides, 2) * boxes.eta[:, None]).ravel()
    quarters = s.values(theta, d)
    assert s.best >= np.nanmax(quarters) - 1e-12
    plain = _search(3, 500, 4)
    plain.strips = False  # the sandwich's search: only the two best centres polished
    plain.polish_best(boxes, plain.values(boxes.theta, boxes.d), False)
    assert s.evaluations >= plain.evaluations + 8 + len(quarters)


def _layouts(xy: np.ndarray, s: float, rng: np.random.Generator) -> list[tuple[float, float]]:
    """Random layouts, layouts at whole angles, and layouts whose lines pass exactly (as the
    crossing rule computes ``d + k s``) through a vertex: the edges at the quick tests' edge."""
    out = [(float(rng.uniform(0, math.pi)), float(rng.uniform(0, s))) for _ in range(6)]
    out += [(0.0, 0.3 * s), (math.pi / 2, 0.7 * s)]
    for theta in rng.uniform(0, math.pi, 4):
        v = xy[rng.integers(len(xy)), :2]
        h = -math.sin(theta) * v[0] + math.cos(theta) * v[1]
        out.append((float(theta), float(h - math.floor(h / s) * s)))
    return out


def _sweep_as_the_plain_rule(
    xy: np.ndarray,
    theta: float,
    d: float,
    s: float,
    k0: int,
    nb: int,
    radius: float,
    sdelta: float,
    eta: float,
) -> int:
    """Assert the one-pass sweep of the strips (quick rejection of the edges meeting no strip)
    and the lines' intervals (quick rejection of the edges crossing no line) equal the plain
    rule applied to every edge and every line; returns how many lines have crossings."""
    from boustro.optimize.smith_bb.region_strips import _sweep, strip_halfwidths

    cs, sn = math.cos(theta), math.sin(theta)
    h1, h2 = -sn * xy[:, 0] + cs * xy[:, 1], -sn * xy[:, 2] + cs * xy[:, 3]
    t1, t2 = cs * xy[:, 0] + sn * xy[:, 1], cs * xy[:, 2] + sn * xy[:, 3]
    a, b = np.minimum(h1, h2), np.maximum(h1, h2)
    c = np.array([d + (k0 + q) * s for q in range(nb)])
    half = np.empty(nb)
    strip_halfwidths(c, radius, sdelta, eta, half)
    low, high = c - half, c + half
    lcnt, lt, hcnt, ht, pcnt, plo, phi = _sweep(xy, cs, sn, c, low, high, half.max(), d, s, k0,
                                                nb)  # fmt: skip
    start, lo, hi = rk._intervals(xy, cs, sn, d, s, k0, nb)
    lines = 0
    for q in range(nb):
        with np.errstate(all="ignore"):
            for at, cnt, got in ((low[q], lcnt, lt), (high[q], hcnt, ht), (c[q], None, None)):
                m = (a <= at) & (at < b)
                want = np.sort(t1[m] + (at - h1[m]) * (t2[m] - t1[m]) / (h2[m] - h1[m]))
                if cnt is None:  # the line itself: its intervals pair the crossings
                    assert np.array_equal(lo[start[q] : start[q + 1]], want[0::2])
                    assert np.array_equal(hi[start[q] : start[q + 1]], want[1::2])
                else:
                    assert np.array_equal(got[cnt[q] : cnt[q + 1]], want)
        touch = (low[q] <= b) & (high[q] >= a)
        assert pcnt[q + 1] - pcnt[q] == touch.sum()
        mid = 0.5 * (plo[pcnt[q] : pcnt[q + 1]] + phi[pcnt[q] : pcnt[q + 1]])
        lo_t, hi_t = np.minimum(t1, t2)[touch], np.maximum(t1, t2)[touch]
        assert ((lo_t - 1e-9 <= mid) & (mid <= hi_t + 1e-9)).all()  # each on its edge
        lines += int(m.sum() > 0)
    return lines


@pytest.mark.parametrize("which", ["traced", "comb"])
def test_sweep_and_intervals_equal_every_edge_against_every_line(which: str) -> None:
    rng = np.random.default_rng(5)
    if which == "traced":
        search = _search(7, 300, 3)
    else:
        search = _RegionSearch(_concave(), 4.0, 0.5, 0.5)
    xy, s = search.real[0], search.s
    k0, nb = lines_range(xy, s)
    k0, nb = k0 - 4, nb + 8
    lines = 0
    for theta, d in _layouts(xy, s, rng):
        sdelta = math.sin(rng.uniform(0, 3e-3))
        lines += _sweep_as_the_plain_rule(xy, theta, d, s, k0, nb, search.radius, sdelta, 0.02 * s)
    assert lines > 50


def test_the_strips_keep_an_edge_on_a_line_far_from_the_origin():
    """The strips' quick rejection (``_sweep``) has a margin that grows with the line index: at
    raw UTM-like coordinates (northing 5.4e6 m, spacing 0.1 m: line 5.4e7, where ``(k s) / s``
    rounds 7e-9 above ``k``) a fixed 1e-9 dropped a hole's edge lying on a line of a box of one
    layout, so its inner set held the edge (the line along the boundary counted inside)."""
    s, inv = 0.1, 10.0
    k = next(k for k in range(54_000_000, 54_001_000) if math.ceil(k * s * inv - 1e-9) > k)
    y0, x0 = k * s, 450_000.0  # the hole's top edge lies on line k (as d + k s computes it)
    hole = [(x0 + 20, y0 - 0.5), (x0 + 60, y0 - 0.5), (x0 + 60, y0), (x0 + 20, y0)]
    area = Region(
        [(x0, y0 - 1), (x0 + 100, y0 - 1), (x0 + 100, y0 + 1), (x0, y0 + 1)], holes=[hole]
    )
    xy = np.ascontiguousarray(area.edges.reshape(-1, 4))
    k0, nb = k - 15, 30
    radius = float(np.hypot(xy[:, 0], xy[:, 1]).max())
    assert _sweep_as_the_plain_rule(xy, 0.0, 0.0, s, k0, nb, radius, 0.0, 0.0) >= 20
    ost, oa, ob, ist, pa, pb = strip_intervals(xy, 1.0, 0.0, 0.0, s, k0, nb, radius, 0.0, 0.0,
                                               rk.KEEP)  # fmt: skip
    on = k - k0  # the line along the hole's top edge: no inner piece within the edge
    inner = list(zip(pa[ist[on] : ist[on + 1]], pb[ist[on] : ist[on + 1]], strict=True))
    assert inner and all(b <= x0 + 20 or a >= x0 + 60 for a, b in inner)
    below = on - 1  # a line through the hole: the hole is out of its inner and outer sets
    outer = list(zip(oa[ost[below] : ost[below + 1]], ob[ost[below] : ost[below + 1]], strict=True))
    assert len(outer) == 2 and outer[0][1] <= x0 + 20 + 1e-6 and outer[1][0] >= x0 + 60 - 1e-6


def test_an_edge_on_a_line_far_from_the_origin_is_not_dropped():
    """The quick rejection's margin grows with the line index: at raw UTM-like coordinates
    (line 5e7 at 0.1 m) a fixed 1e-9 dropped an edge lying on a line (values -inf; a review)."""
    from boustro.optimize.smith_bb.region_kernel import region_values, ring_starts

    s, inv = 0.1, 10.0
    k = next(k for k in range(50_000_000, 50_001_000) if math.ceil(k * s * inv - 1e-9) > k)
    y0 = k * s
    ring = np.array([(0.0, y0), (100.0, y0), (100.0, y0 + 0.05), (0.0, y0 + 0.05)])
    xy, _ = ring_starts([ring])
    value = region_values(xy, np.array([0.0]), np.array([0.0]), s, 0.5, 0.5, 1e-9)
    assert np.isfinite(value).all() and value[0] > 0


def test_long_runs_sort_stably_as_the_insertion_sort():
    """Runs above LONG_RUN go to numpy's stable sort: the same order (ties keep their order)."""
    from boustro.optimize.cover import band_lines

    band_lines.jit_into({})  # the compiled sorts, as the kernels call them
    assert hasattr(band_lines._sort_pairs, "py_func")
    rng = np.random.default_rng(3)
    for n in (5, band_lines.LONG_RUN + 1, 400):
        key, other = np.round(rng.random(n + 6) * 7), rng.random(n + 6)
        want = np.argsort(key[2 : 2 + n], kind="stable")
        k2, o2 = key.copy(), other.copy()
        band_lines._sort_pairs(k2, o2, 2, 2 + n)
        np.testing.assert_array_equal(k2[2 : 2 + n], key[2 : 2 + n][want])
        np.testing.assert_array_equal(o2[2 : 2 + n], other[2 : 2 + n][want])
        np.testing.assert_array_equal(k2[:2], key[:2])
        k3 = key[::-1].copy()
        band_lines._sort_keys(k3, 0, n + 6)
        np.testing.assert_array_equal(k3, np.sort(key))
