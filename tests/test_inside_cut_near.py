"""Margin 0's passes by the lines' positions (optimize/cover/inside_cut.py, "Where the lines
are"): every stretch counted lies inside the passes the planner builds for lanes cut at the
boundary, a box counts no more than its layouts, and the margin-0 bound with them stays below
the real margin-0 plans (and rises above the bound without them)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from boustro.geometry.region import Region
from boustro.optimize.cover import CoverCost
from boustro.optimize.cover.inside_bound import _near_cut, _with_cut_passes, contour_edges
from boustro.optimize.cover.inside_cut import CUT_DEPTH, NEAR_CUT_ANGLE, cut_lengths, near_cut_use
from boustro.optimize.cover.search import CoverSearch

from .test_inside_bound import _adversarial, _areas
from .test_inside_cut import _forced_plan, _gaps, _margin0, _zero_bound

S = 10.0
#: UTM-sized coordinates (a quadrilateral with a hole near its side, moved)
UTM = np.array([523_417.0, 5_402_871.0])


def _utm() -> Region:
    quad = np.array([(0, 0), (160, 10), (140, 90), (20, 120)], dtype=float) + UTM
    hole = np.array([(30, 12), (120, 16), (118, 19)], dtype=float) + UTM
    return Region(quad, [hole])


def _cases() -> list[Region]:
    return _adversarial() + _areas()[:3] + _gaps() + [_utm()]


def _near_angles(region: Region, rng: np.random.Generator, n: int = 10) -> list[float]:
    """Angles near an edge's direction (0 to 0.55 rad off it, both ways) and two random."""
    e = region.edges
    along = np.arctan2(e[:, 1, 1] - e[:, 0, 1], e[:, 1, 0] - e[:, 0, 0]) % math.pi
    off = rng.choice([0.0, 1e-4, 3e-3, 0.02, 0.08, 0.15, 0.25, 0.4, 0.55], n)
    return list((rng.choice(along, n) + off * rng.choice([-1, 1], n)) % math.pi) + list(
        rng.uniform(0, math.pi, 2)
    )


def _lengths(edges, region: Region, theta: float, d: float) -> np.ndarray:
    """Per stretch, the length margin 0 counts at the layout ``(theta, d)``."""
    th = np.array([theta])
    near = _near_cut(edges, th, np.array([d]), 0.0, region.centre, S)
    return cut_lengths(edges, th, np.zeros(1), S, near)[0]


def _stretch(edges, j: int):
    """The contour stretch ``j`` (its feet ``g0`` to ``g1``, half a spacing off its edge)."""
    import shapely

    a, b = edges.strip[j]
    u = (b - a) / np.linalg.norm(b - a)
    base = a - edges.feet[j, 2] * u + edges.inward[j] * S / 2
    return shapely.LineString([base + edges.feet[j, 0] * u, base + edges.feet[j, 1] * u])


@pytest.mark.parametrize("index", range(len(_adversarial()) + 3 + len(_gaps()) + 1))
def test_counted_lengths_lie_in_the_margin0_passes(index):
    """Per stretch, the length margin 0 counts (its cut rule or the lines' positions, the
    larger) is no more than the planner's passes along that stretch for lanes cut at the
    boundary (shapely, the passes' union within 1e-5 m of it), at layouts near an edge's
    direction; the rule by the lines' positions counts more than the cut rule somewhere."""
    import shapely

    region = _cases()[index]
    edges = contour_edges(region, S, S / 2)
    rng = np.random.default_rng(700 + index)
    gained = 0
    for angle in _near_angles(region, rng):
        offset = rng.uniform(0, S)
        count = _lengths(edges, region, angle, offset)
        plain = cut_lengths(edges, np.array([angle]), np.zeros(1), S)[0]
        gained += int((count > plain + 1e-6).sum())
        if not (count > 0).any():
            continue
        passes = _margin0(region, angle, offset)
        lines = [shapely.LineString(p) for p in passes]
        union = shapely.union_all(lines).buffer(1e-5) if lines else shapely.Polygon()
        for j in np.flatnonzero(count > 0):
            flown = _stretch(edges, j).intersection(union).length
            assert count[j] <= flown + 1e-3, (angle, offset, j, count[j], flown)
    assert gained or not edges.core.any()


@pytest.mark.parametrize("index", range(len(_adversarial()) + 3 + len(_gaps()) + 1))
def test_a_box_counts_no_more_than_its_layouts(index):
    """A box's count by the lines' positions (angles ``theta +- delta``, the area moved by up
    to ``eps`` across the lines) is no more, per stretch, than at layouts inside it: its
    corners and random ones (the angle and the offset moved so that no point moves more than
    ``eps`` across the lines)."""
    region = _cases()[index]
    edges = contour_edges(region, S, S / 2)
    rng = np.random.default_rng(800 + index)
    centre = region.centre
    r = float(np.max(np.linalg.norm(region.shell.vertices - centre, axis=1)))
    checked = 0
    for angle in _near_angles(region, rng, 8):
        delta = float(rng.choice([0.0, 1e-4, 2e-3]))
        eta = float(rng.choice([0.0, 1e-3, 0.02]))
        eps = delta * r + eta
        d = rng.uniform(0, S)
        th = np.array([angle])
        near = _near_cut(edges, th, np.array([d]), eps, centre, S)
        box = cut_lengths(edges, th, np.array([delta]), S, near)[0]
        if not (box > 0).any():
            continue
        inside = [(angle + rng.uniform(-1, 1) * delta, d + rng.uniform(-1, 1) * eta) for _ in "ab"]
        for t, dd in [(angle - delta, d - eta), (angle + delta, d + eta), *inside]:
            at = _lengths(edges, region, t, dd)  # not wrapped: d is for this normal
            assert (box <= at + 1e-9).all(), (angle, delta, eta, t, dd)
            checked += 1
    assert checked or not edges.core.any()


@pytest.mark.parametrize("index", [0, 2, 4, 7, 9, 10, 12, 13])
def test_margin0_bound_with_the_lines_below_the_margin0_plans(index):
    """The margin-0 bound with its passes by the lines' positions at a layout is below the real
    margin-0 plan there (lanes, passes, moves and turns, the planner forced to margin 0), and
    above the bound without them at some layouts (holes near the side, a slot, a neck, UTM
    coordinates, a traced boundary)."""
    region = _cases()[index]
    cost = CoverCost.time(5.0, 10.0)
    search = CoverSearch(region, S, S / 2, cost, None, False, keep_inside=True)
    rng = np.random.default_rng(900 + index)
    lifted = 0
    for angle in _near_angles(region, rng, 5)[:6]:
        offset = rng.uniform(0, S)
        theta, d = np.array([angle]), np.array([offset])
        zero, st0 = _zero_bound(search, theta, d)
        args = (zero, st0, cost, S, search.contour, theta, np.zeros(1))
        before = _with_cut_passes(*args)
        near = _near_cut(search.contour, theta, d, 0.0, search.origin, S)
        bound = _with_cut_passes(*args, near)
        plan = _forced_plan(region, angle, offset, cost)
        assert bound[0] <= plan + 1e-6, (angle, offset, bound[0], plan)
        lifted += bound[0] > before[0] + 1e-6
    # the traced ellipse (index 4): its 3 m edges hold almost no stretch, nothing to lift
    assert lifted or index == 4


def test_where_the_rule_counts():
    """``NEAR_CUT``: on (the default) a box's bound is no lower than with it off and higher at
    some boxes; the layouts' own bounds are those with it off, though the rule counts at some
    of those layouts (so they would rise with it there)."""
    import boustro.optimize.cover.inside_bound as ib
    from boustro.optimize.cover.boxes import Boxes

    region = _areas()[0]
    cost = CoverCost.time(5.0, 10.0)
    rng = np.random.default_rng(11)
    n = 16
    e = region.edges
    along = np.arctan2(e[:, 1, 1] - e[:, 0, 1], e[:, 1, 0] - e[:, 0, 0]) % math.pi
    theta = (rng.choice(along, n) + rng.uniform(-0.4, 0.4, n)) % math.pi
    d = rng.uniform(0, S, n)
    points, boxes = {}, {}
    for on in (False, True):
        search = CoverSearch(region, S, S / 2, cost, None, False, keep_inside=True)
        ib.NEAR_CUT = on
        try:
            points[on] = search.point_values(Boxes(theta, np.zeros(n), d, np.zeros(n)))
            search.top_eps = 0.05
            boxes[on] = search.box_bounds(Boxes(theta, np.full(n, 1e-4), d, np.full(n, 1e-3)))
        finally:
            ib.NEAR_CUT = True
    assert np.array_equal(points[True], points[False])
    assert (boxes[True] >= boxes[False]).all() and (boxes[True] > boxes[False] + 1e-6).any()
    near = _near_cut(search.contour, theta, d, 0.0, search.origin, S)
    zero = np.zeros(n)
    counted = cut_lengths(search.contour, theta, zero, S, near)
    assert (counted > cut_lengths(search.contour, theta, zero, S) + 1e-6).any()


def test_the_rule_needs_the_box_within_its_angle_and_clearance():
    """:func:`near_cut_use`: a stretch counts only when every lane angle of the box (``rel +-
    delta``) is within ``NEAR_CUT_ANGLE`` of it (the band's lower end divides by the cosine
    there) and its clearance holds half a spacing and ``CUT_DEPTH`` of it (1e-4 less: not)."""
    region = Region([(0, 0), (150, 0), (150, 80), (0, 80)])
    edges = contour_edges(region, S, S / 2)
    j = int(np.flatnonzero(edges.core > 0)[0])
    theta = np.array([edges.angle[j] + NEAR_CUT_ANGLE - 0.01])
    for delta, counts in ((0.0, True), (0.0099, True), (0.0101, False)):
        assert near_cut_use(edges, theta, np.array([delta]), S)[0, j] == counts, delta
    need = S / 2 * (1 + CUT_DEPTH)
    for clear, counts in ((need * (1 + 1e-4), True), (need * (1 - 1e-4), False)):
        tight = edges._replace(clear=np.full_like(edges.clear, clear))
        assert near_cut_use(tight, theta, np.zeros(1), S)[0, j] == counts, clear
