"""Soundness and effect of the width test of the rigid cuts (:func:`boustro.optimize.cover.rigid.
_wide_cut`): a convex, isolated hole wider than the spacing across every line direction of a box
is cut by every plan of the box (issue 21's 6 m holes, wider than the 10 m band, lost their
passes at boxes of metres). The holes the box marks rigid are in the cut set of the plan's lanes
at layouts sampled in the box, and the box bounds stay below the real plans sampled there."""

from __future__ import annotations

import math

import numpy as np
import pytest

from boustro.geometry import Polygon
from boustro.geometry.region import Region
from boustro.geometry.traced import traced_field
from boustro.optimize.cover import CoverCost
from boustro.optimize.cover import rigid as rigid_mod
from boustro.optimize.cover.boxes import Boxes, box_radius
from boustro.optimize.cover.search import CoverSearch
from boustro.plan.lanes import region_lanes

from .plan_samples import box_stats, plan_cost

SPACING = 10.0
COST = CoverCost.time(5.0, 10.0)
UTM = np.array([512_345.0, 5_401_234.0])


def _search(region: Region) -> CoverSearch:
    return CoverSearch(region, SPACING, SPACING / 2, COST, None, False)


def _rigid(region: Region, box: Boxes) -> set[int]:
    """The holes the box's bound counts as cut by every plan of the box (not by ``cut``)."""
    search = _search(region)
    st = box_stats(search, box)
    return {int(h) for h in np.flatnonzero(st.rigid[0, : search.n_holes])}


def _cut(region: Region, angle: float, offset: float) -> set[int]:
    """The holes that cut a lane of the plan at ``(angle, offset)``."""
    lanes = region_lanes(
        region, SPACING, angle, offset, reach=SPACING / 2, holes=region.holes,
        origin=region.centre,
    )  # fmt: skip
    return set(lanes.cut)


def _samples(box: Boxes, rng: np.random.Generator, n: int) -> list[tuple[float, float]]:
    t, dl, d, e = (float(a[0]) for a in box)
    out = [(t, d), (t - dl, d - e), (t + dl, d + e), (t - dl, d + e), (t + dl, d - e)]
    out += [(t + rng.uniform(-dl, dl), d + rng.uniform(-e, e)) for _ in range(n)]
    return out


def _plan_cost(region: Region, theta: float, offset: float) -> float:
    return plan_cost(region, COST, spacing=SPACING)(theta, offset)


def _moved(region: Region, shift: np.ndarray) -> Region:
    return Region(
        Polygon(region.shell.vertices + shift), [Polygon(h.vertices + shift) for h in region.holes]
    )


def _box(theta: float, d: float, eps: float, radius: float) -> Boxes:
    """A box of sandwich radius about ``eps``: half of it from the angle, half from the offset."""
    return Boxes(
        np.array([theta]), np.array([eps / 2 / radius]), np.array([d]), np.array([eps / 2])
    )


@pytest.mark.parametrize("seed", range(4))
def test_traced_holes_are_rigid_cuts_at_boxes_of_metres_and_every_plan_cuts_them(seed):
    """Traced fields (12-gon holes of 6 m, 10 m from the shell and each other, seed 1 and 3 at
    UTM coordinates): at boxes of 1-4 m the width test marks the holes the lines cross, and
    every plan sampled in the box cuts each of them."""
    rng = np.random.default_rng(seed)
    region = traced_field(120, 3, seed=seed, radius=60.0)
    if seed % 2:
        region = _moved(region, UTM)
    radius = _search(region).radius
    marked = 0
    for eps in (1.0, 2.0, 4.0):
        box = _box(rng.uniform(0, math.pi), rng.uniform(0, SPACING), eps, radius)
        rigid = _rigid(region, box)
        marked += len(rigid)
        for a, o in _samples(box, rng, 6):
            assert rigid <= _cut(region, a, o), (a, o)
    assert marked >= 3  # the test holds something: 3 holes, 3 boxes


def test_without_the_width_test_the_traced_holes_are_not_rigid(monkeypatch):
    """The effect: at a box of 3 m the 6 m holes are rigid only by their width."""
    region = traced_field(120, 3, seed=0, radius=60.0)
    box = _box(0.7, 3.0, 3.0, _search(region).radius)
    assert len(_rigid(region, box)) == 3
    monkeypatch.setattr(rigid_mod, "WIDE_CUTS", False)
    assert _rigid(region, box) == set()


def _rect_with(hole: np.ndarray) -> Region:
    shell = Polygon(np.array([[0, 0], [120, 0], [120, 90], [0, 90]], dtype=float))
    return Region(shell, [Polygon(hole)])


@pytest.mark.parametrize("split", [False, True])
def test_a_square_hole_spanning_the_band_is_not_a_rigid_cut(split):
    """A 12 m square hole with edges along the lines: a line through its middle has the whole
    band inside it, so the band's projection already has the chord as its gap and the planner
    does not cut it (no pass); its perpendicular edges are longer than the band (2 reach), so
    the width test must not apply. The plan at the box's centre does not cut it. With
    ``split`` (review) each side is two 6 m edges, shorter than the band, through a vertex
    dented inwards by 1e-5 m (the line through it meets the hole's side there, its band's
    neighbours farther out: still no cut): the convexity test (``WIDE_TURN``) must refuse it."""
    c = np.array([60.0, 45.0])
    corners = np.array([[-6, -6], [6, -6], [6, 6], [-6, 6]], dtype=float)
    if split:
        corners = np.repeat(corners, 2, axis=0)
        corners[1::2] = (corners[1::2] + np.roll(corners, -2, axis=0)[1::2]) / 2
        corners[1::2] *= 1 - 1e-5 / 6  # dented by 1e-5 m (an exactly straight vertex is dropped)
    square = c + corners
    region = _rect_with(square)
    d = (45.0 - _search(region).origin[1]) % SPACING  # a line through the square's middle
    box = Boxes(np.array([0.0]), np.array([1e-5]), np.array([d]), np.array([0.5]))
    assert _cut(region, 0.0, d) == set()
    assert _rigid(region, box) == set()


def _ellipse(a: float, b: float, phi: float, n: int = 28) -> np.ndarray:
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    xy = np.c_[a * np.cos(t), b * np.sin(t)]
    rot = np.array([[np.cos(phi), -np.sin(phi)], [np.sin(phi), np.cos(phi)]])
    return xy @ rot.T + np.array([60.0, 45.0])


def test_an_elongated_hole_narrower_than_the_spacing_at_the_boxs_edge_is_not_rigid():
    """A convex 36 x 9.6 m hole, the lines' normal 25 degrees off its short axis at the box's
    centre (width about 17.5 m, above the spacing) and along it at the box's edge (9.6 m): the
    width test must count the box's rotation (``wide * delta``). At the layouts of the box
    where no line crosses it the plan does not cut it."""
    region = _rect_with(_ellipse(4.8, 18.0, 0.0))
    theta = math.radians(65.0)
    dl = math.radians(25.0)  # the box reaches the lines along the long axis (normal: short)
    rng = np.random.default_rng(0)
    search = _search(region)
    box = Boxes(np.array([theta]), np.array([dl]), np.array([rng.uniform(0, SPACING)]),
                np.array([SPACING]))  # fmt: skip
    rigid = _rigid(region, box)
    # at the box's edge (lines along the long axis) the lines at x = 55 and 65 miss the hole
    o = (float(region.centre[0]) - 55.0 - box.d[0]) % SPACING + box.d[0]  # in the box
    assert 0 not in _cut(region, theta + dl, o)  # a layout of the box flies past the hole
    assert rigid == set()
    assert search.n_holes == 1


@pytest.mark.parametrize("seed", range(3))
def test_box_bounds_below_plans_sampled_in_the_box_with_wide_holes(seed):
    """Traced fields with holes, one near the shell (3 m: no width test) at UTM coordinates for
    odd seeds; boxes of 0.5-3 m: the bound is at most every plan sampled in the box."""
    rng = np.random.default_rng(10 + seed)
    base = traced_field(100, 2, seed=seed, radius=50.0)
    v = base.shell.vertices
    i = int(np.argmax(v[:, 0]))
    near = v[i] - np.array([9.5, 0.0])  # a 12-gon of 6 m, 3.5 m from the shell's extreme
    t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    extra = Polygon(np.c_[near[0] + 6 * np.cos(t), near[1] + 6 * np.sin(t)])
    region = Region(base.shell, [*base.holes, extra])
    if seed % 2:
        region = _moved(region, UTM)
    search = _search(region)
    for eps in (0.5, 3.0):
        box = _box(rng.uniform(0, math.pi), rng.uniform(0, SPACING), eps, search.radius)
        search.top_eps = 1.5 * float(box_radius(box, search.radius)[0])
        bound = float(search.box_bounds(box)[0])
        for a, o in _samples(box, rng, 1):
            assert bound <= _plan_cost(region, a, o) + 1e-6


def test_an_edge_across_the_lines_within_the_planners_tol_of_the_band_is_not_a_rigid_cut():
    """Review: a strictly convex hole 13 m across, its edges across the lines 10 - 2e-10 m long
    (below ``2 reach``, the band) and the next ones turning by a sine of 2e-6: on the line
    through its middle the band's slabs beyond the edge's ends are 1e-10 m thin, below the
    planner's tolerance (``lanes._band_intervals`` drops them), so the band's projection has
    the chord as its gap already and the plan there does not cut the hole (no pass, no turn).
    The width test must not count it (``WIDE_EDGE_TOLS``); with it the box's bound was 213.8 s
    against that plan's 196.6 s."""
    h, x, r = 5.0 - 1e-10, 3e-6, 4.0
    hole = np.array([(r, -h), (r, h), (r - x, 6.5), (-r + x, 6.5), (-r, h), (-r, -h),
                     (-r + x, -6.5), (r - x, -6.5)]) + np.array([60.0, 45.0])  # fmt: skip
    region = _rect_with(hole)
    search = _search(region)
    d = (45.0 - search.origin[1]) % SPACING  # the line through the hole's middle
    assert _cut(region, 0.0, d) == set()
    box = Boxes(np.array([0.0]), np.array([1e-4]), np.array([d]), np.array([0.05]))
    assert _rigid(region, box) == set()
    search.top_eps = 1.5 * float(box_radius(box, search.radius)[0])
    assert float(search.box_bounds(box)[0]) <= _plan_cost(region, 0.0, d) + 1e-6


def test_the_width_tests_diameter_is_the_rings_largest_vertex_distance():
    """Review: the diameter ``D`` of a ring (``wide_rings``) is the largest distance between two
    of its vertices (the brute force on 40 vertices), and a finely traced circular pond (20000
    vertices, strictly convex, short edges) is admitted without its ``(n, n, 2)`` distance
    array (6.4 GB before, measured 408 MB at 4000 vertices)."""
    shell = np.array([[0, 0], [200, 0], [200, 150], [0, 150]], dtype=float)
    hole = _ellipse(9.0, 6.0, 0.4, n=40)
    rings = rigid_mod.split_rings([hole], SPACING, 1e-7, shell, SPACING / 2)
    assert rings.wide is not None
    v = rings.xy
    brute = max(math.dist(p, q) for p in v for q in v)
    assert rings.wide[0] == pytest.approx(brute, rel=1e-12)
    t = np.linspace(0, 2 * np.pi, 20000, endpoint=False)
    pond = np.c_[100 + 8 * np.cos(t), 75 + 8 * np.sin(t)]
    rings = rigid_mod.split_rings([pond], SPACING, 1e-7, shell, SPACING / 2)
    assert rings.wide is not None and rings.wide[0] == pytest.approx(16.0, rel=1e-6)


def test_a_hole_narrower_than_the_spacing_between_two_lines_is_not_rigid():
    """Review: a 12-gon of 4 m (8 m across, below the 10 m spacing) halfway between two lines
    of the box's centre: no line crosses it there, the plan does not cut it, so the width test
    must not mark it (the mutant comparing the width with half the spacing survived the other
    tests)."""
    t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    region = _rect_with(np.c_[60 + 4 * np.cos(t), 45 + 4 * np.sin(t)])
    d = (45.0 + SPACING / 2 - _search(region).origin[1]) % SPACING  # lines at 45 +- 5
    assert _cut(region, 0.0, d) == set()
    box = Boxes(np.array([0.0]), np.array([1e-5]), np.array([d]), np.array([0.1]))
    assert _rigid(region, box) == set()
