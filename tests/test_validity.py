"""Validity through GEOS: agreement with shapely, tolerance at any scale, large rings in bounded
memory, and ``boustro plan --repair``."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import shapely

from boustro.errors import InvalidPolygonError
from boustro.geometry import Polygon, Region
from boustro.geometry import polygon as polygon_module
from boustro.geometry.validity import geos_reason
from boustro.io import Area
from boustro.io.repair import area_problem, detach_holes, repair_area

from .conftest import run_cli


def _star(rng: np.random.Generator, n: int, centre=(0.0, 0.0), size: float = 1.0) -> np.ndarray:
    """A simple ring: sorted random angles, random radii (star-shaped about ``centre``)."""
    angles = np.sort(rng.uniform(0, 2 * math.pi, n))
    radii = size * rng.uniform(0.3, 1.0, n)
    return np.stack([radii * np.cos(angles), radii * np.sin(angles)], axis=1) + centre


def _builds(shell, holes=()) -> bool:
    try:
        Region(shell, list(holes))
    except InvalidPolygonError:
        return False
    return True


def _random_case(rng: np.random.Generator, kind: int):
    n = int(rng.integers(4, 40))
    if kind == 0:  # random order: mostly self-crossing
        return rng.uniform(-1, 1, (int(rng.integers(4, 9)), 2)), []
    if kind == 1:  # simple, or made self-crossing by swapping two vertices
        ring = _star(rng, n)
        if rng.random() < 0.5:
            i, j = rng.choice(n, 2, replace=False)
            ring[[i, j]] = ring[[j, i]]
        return ring, []
    shell = _star(rng, n)  # holes anywhere: inside, crossing, outside, overlapping, nested
    holes = [
        _star(rng, int(rng.integers(3, 8)), rng.uniform(-0.8, 0.8, 2), rng.uniform(0.05, 0.4))
        for _ in range(int(rng.integers(1, 4)))
    ]
    return shell, holes


@pytest.mark.parametrize("kind", [0, 1, 2])
def test_agrees_with_shapely_is_valid_on_random_rings(kind):
    rng = np.random.default_rng(2100 + kind)
    outcomes = set()
    for _ in range(120):
        shell, holes = _random_case(rng, kind)
        expected = bool(shapely.is_valid(shapely.Polygon(shell, holes)))
        assert _builds(shell, holes) == expected, (shell.tolist(), [h.tolist() for h in holes])
        outcomes.add(expected)
    assert outcomes == {True, False}  # both kinds of case were tried


def test_geos_names_the_place():
    assert geos_reason("Ring Self-intersection[2 0]") == "Ring Self-intersection at (2, 0)"
    assert geos_reason("Too few points") == "Too few points"
    with pytest.raises(
        InvalidPolygonError, match=r"self-intersecting: Self-intersection at \(1, 0\)"
    ):
        Polygon([(0, 0), (2, 0), (2, 2), (1, 2), (1, -1), (0, -1)])
    with pytest.raises(InvalidPolygonError, match=r"Ring Self-intersection at \(2, 0\)"):
        Polygon([(0, 0), (4, 0), (4, 4), (2, 0), (0, 4)])  # a vertex on another edge


@pytest.mark.parametrize("scale", [1e-30, 1e-6, 1.0, 1e13, 1e90])
def test_near_touching_edges_are_refused_at_any_scale(scale):
    """A vertex 1e-13 of the extent from a non-adjacent edge touches it (boustro's tolerance,
    1e-12 of the extent; GEOS alone finds the ring valid); 1e-9 away it does not."""
    for gap, valid in ((1e-13, False), (1e-9, True)):
        ring = np.array([(0, 0), (10, 0), (10, 10), (5, 10 * gap), (0, 10)]) * scale
        assert shapely.is_valid(shapely.Polygon(ring))
        if valid:
            assert len(Polygon(ring)) == 5
        else:
            with pytest.raises(InvalidPolygonError, match=r"edge 0 .* comes within .* of edge 2"):
                Polygon(ring)


@pytest.mark.parametrize("scale", [1e-30, 1.0, 1e90])
def test_hole_rules_at_any_scale(scale):
    shell = np.array([(0, 0), (4, 0), (4, 4), (0, 4)]) * scale
    near = 1 + 1e-10  # within TOUCH_TOLERANCE (1e-9) of the diameter of the hole at x = 1
    with pytest.raises(InvalidPolygonError, match="holes 1 and 2 touch or overlap"):
        Region(
            shell,
            [
                np.array(h) * scale
                for h in ([(1, 1), (1, 2), (0.5, 2)], [(near, 1), (2, 1), (2, 2)])
            ],
        )
    with pytest.raises(InvalidPolygonError, match="hole 1 touches or crosses the shell"):
        Region(shell, [np.array([(1e-10, 1), (1, 1), (1, 2)]) * scale])
    ok = Region(
        shell,
        [np.array(h) * scale for h in ([(1, 1), (1, 2), (0.5, 2)], [(1.01, 1), (2, 1), (2, 2)])],
    )
    assert ok.n_holes == 2


def _big_star(n: int) -> np.ndarray:
    rng = np.random.default_rng(n)
    angles = np.linspace(0, 2 * math.pi, n, endpoint=False) + rng.uniform(0, 0.5 / n, n)
    radii = 1.0 + 0.2 * np.cos(3 * angles) + 1e-3 * rng.random(n)  # lobes, traced noise
    return np.stack([radii * np.cos(angles), radii * np.sin(angles)], axis=1)


def test_self_crossing_8000_vertex_ring_is_refused():
    ring = _big_star(8000)
    ring[[10, 4000]] = ring[[4000, 10]]
    with pytest.raises(InvalidPolygonError, match="self-intersecting: Self-intersection at"):
        Polygon(ring)


def test_validating_20000_vertices_takes_little_memory():
    """Peak RSS of building a valid 20000-vertex Polygon (and a Region with it as a hole's
    shell), measured in a fresh process beyond what importing and the input take."""
    code = textwrap.dedent(
        """
        import math, resource
        import numpy as np
        import shapely
        from boustro.geometry import Polygon, Region
        n = 20000
        rng = np.random.default_rng(n)
        angles = np.linspace(0, 2 * math.pi, n, endpoint=False) + rng.uniform(0, 0.5 / n, n)
        radii = 1.0 + 0.2 * np.cos(3 * angles) + 1e-3 * rng.random(n)
        ring = np.stack([radii * np.cos(angles), radii * np.sin(angles)], axis=1)
        before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        p = Polygon(ring)
        r = Region(p, [ring * 0.5])  # the ring and a hole like it
        after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        print(len(p), r.n_holes, (after - before) / 1024)
        """
    )
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True
    ).stdout.split()
    assert out[:2] == ["20000", "1"]
    assert float(out[2]) < 500  # MB; the all-pairs check needed tens of GB here


# -- the command line: refusal with GEOS's reason, --repair -----------------------------------
SLIT = [[0, 0], [40, 0], [40, 40], [20, 40], [20, 20], [20, 40], [0, 40]]  # touches itself
BOW_TIE = [[0, 0], [10, 0], [0, 10], [10, 10]]


def test_repair_area_keeps_one_part_and_says_what_changed():
    fixed, note = repair_area(Area(np.array(SLIT, dtype=float), None, "slit", "slit.json"))
    assert note is not None and "Ring Self-intersection at (20, 40)" in note
    assert "vertices 7 -> 5" in note and "area 1600 -> 1600" in note
    assert area_problem(fixed) is None and Polygon(fixed.ring).area == pytest.approx(1600)
    same, nothing = repair_area(fixed)
    assert same is fixed and nothing is None


def _write(tmp_path, name, ring):
    path = tmp_path / name
    path.write_text(json.dumps(ring))
    return str(path)


def test_cli_refuses_an_invalid_area_with_geos_reason(capsys, tmp_path):
    path = _write(tmp_path, "slit.json", SLIT)
    code, out, err = run_cli(capsys, "plan", path, "--crs", "planar", "--spacing", "5")
    assert code == 2 and out == ""
    assert "GEOS: Ring Self-intersection at (20, 40)" in err and "try --repair" in err
    assert len(err.strip().splitlines()) == 1


def test_cli_repair_plans_the_repaired_area(capsys, tmp_path):
    path = _write(tmp_path, "slit.json", SLIT)
    out_file = tmp_path / "plan.geojson"
    code, out, err = run_cli(
        capsys, "plan", path, "--crs", "planar", "--spacing", "5", "--repair", "--out", out_file
    )
    assert code == 0, err
    assert err.startswith("boustro: --repair: ") and "vertices 7 -> 5" in err
    assert "1600.0 m2" in out and out_file.exists()


def test_cli_repair_refuses_a_split_and_writes_nothing(capsys, tmp_path):
    path = _write(tmp_path, "bowtie.json", BOW_TIE)
    out_file = tmp_path / "plan.geojson"
    code, out, err = run_cli(
        capsys, "plan", path, "--crs", "planar", "--spacing", "5", "--repair", "--out", out_file
    )
    assert code == 2 and out == "" and not out_file.exists()
    assert "Self-intersection at (5, 5)" in err and "2 polygons of areas 25, 25" in err
    assert len(err.strip().splitlines()) == 1


def _traced(n: int = 3000, noise: float = 0.3) -> np.ndarray:
    """A field's boundary walked with a GPS: a 300 m x 200 m rounded rectangle, 0.3 m of noise
    and a duplicate point every 17th (self-intersecting: the noise loops back on itself)."""
    rng = np.random.default_rng(16)
    t = np.linspace(0, 2 * math.pi, n, endpoint=False)
    x = 150 * np.sign(np.cos(t)) * np.abs(np.cos(t)) ** 0.6 + rng.normal(0, noise, n)
    y = 100 * np.sign(np.sin(t)) * np.abs(np.sin(t)) ** 0.6 + rng.normal(0, noise, n)
    return np.repeat(np.stack([x, y], axis=1), [2 if i % 17 == 0 else 1 for i in range(n)], axis=0)


def test_repair_drops_the_loops_of_a_traced_boundary_and_keeps_the_file_holes():
    """QA round 16 (hostile fields): a GPS-traced boundary (self-intersecting) was refused even
    with --repair: make_valid splits it into the field and hundreds of 0.1 m^2 loops ("splits
    the area into 258 polygons of areas ..." on one line of 5000 characters), and its largest
    part kept dozens of loop holes, some touching one another (refused again). The loops, at
    most NEGLIGIBLE of the area together, are now dropped and the holes the repair made filled;
    a hole of the file stays; a bow-tie is still refused, its message short."""
    ring = _traced()
    pylon = np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 3.0], [0.0, 3.0]])
    area = Area(ring, None, "walked", "walked.json", (pylon,))
    made = shapely.make_valid(shapely.Polygon(ring, [pylon]))
    assert len(shapely.get_parts(made)) > 10  # the repair does split it
    fixed, note = repair_area(area)
    assert note is not None and "dropped" in note and "filled" in note, note
    assert len(fixed.holes) == 1 and sorted(map(tuple, fixed.holes[0])) == sorted(map(tuple, pylon))
    Region(fixed.ring, list(fixed.holes))  # plannable
    kept = shapely.Polygon(fixed.ring, list(fixed.holes))
    assert made.difference(kept).area < 1e-3 * made.area  # what was dropped is negligible
    tie = Area(np.array(BOW_TIE, dtype=float) * 10, None, "tie", "tie.json")
    with pytest.raises(InvalidPolygonError, match="2 polygons of areas 2500, 2500"):
        repair_area(tie)
    many = Area(
        np.array([[x, y] for x in range(40) for y in (0, 10)[:: 1 if x % 2 else -1]], dtype=float),
        None,
        "zigzag",
        "z.json",
    )
    with pytest.raises(InvalidPolygonError) as err:
        repair_area(many)
    assert len(str(err.value)) < 400


def test_diameter_of_a_large_ring_is_its_largest_vertex_distance():
    """Above 1024 vertices the diameter is sought on the convex hull, in blocks: the same value
    as the all-pairs maximum."""
    for v in (_big_star(3000), _big_star(1500) * (3.0, 1.0)):
        diffs = v[:, None, :] - v[None, :, :]
        expected = float(np.sqrt(np.max(np.einsum("ijk,ijk->ij", diffs, diffs))))
        assert Polygon(v).diameter == expected


@pytest.mark.parametrize("n", [300, 1000])
@pytest.mark.parametrize("a, b", [(150.0, 105.0), (1.0, 1.0), (1e6, 1e6 * (1 + 1e-12)), (3, 0.1)])
def test_diameter_among_the_far_candidates_is_the_all_pairs_maximum(n, a, b):
    """The vertices that cannot end the farthest pair are left out (an ellipse keeps its ends,
    a circle all): the same float, bit for bit, for ellipses, circles and near-circles with
    noise, far from the origin."""
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    noise = np.random.default_rng(n).normal(0, 1e-9 * a, (n, 2))
    poly = Polygon(np.column_stack([a * np.cos(t), b * np.sin(t)]) + noise + 5e5)
    v = poly.vertices
    diffs = v[:, None, :] - v[None, :, :]
    expected = float(np.sqrt(np.max(np.einsum("ijk,ijk->ij", diffs, diffs))))
    assert poly.diameter == expected
    kept = len(polygon_module._far_candidates(v))
    assert (kept < n // 10) if b < 0.8 * a else (kept > 0)


def test_coordinates_near_the_float_limit_give_one_line_and_no_warning(tmp_path):
    """GEOS overflows on 1e308 coordinates; the user sees the range error alone (found by
    review: a RuntimeWarning with its source line was printed before it)."""
    path = tmp_path / "big.geojson"
    ring = [[0, 0], [1e308, 0], [1e308, 1e308], [0, 0]]
    path.write_text(json.dumps({"type": "Polygon", "coordinates": [ring]}))
    run = subprocess.run(
        [sys.executable, "-m", "boustro", "plan", str(path), "--crs", "planar", "--spacing", "1"],
        capture_output=True,
        text=True,
    )
    assert run.returncode == 2
    assert run.stderr.strip().splitlines() == [run.stderr.strip()]
    assert "within +-1e+100" in run.stderr and "Warning" not in run.stderr


def _covered_share_left(features, shell, holes, half: float) -> float:
    """The share of the file's area (shell less holes) no exported lane covers (shapely, flat
    ends, lanes ``2 half`` wide)."""
    lanes = [
        shapely.geometry.shape(f["geometry"]).buffer(half, cap_style="flat")
        for f in features
        if "transect" in f["properties"]
    ]
    original = shapely.Polygon(shell, holes)
    assert lanes
    return original.difference(shapely.union_all(lanes)).area / original.area


def test_a_hole_touching_the_shell_at_a_point_is_planned_with_full_coverage(tmp_path, capsys):
    """QA round 13: a hole touching the shell at one point (valid for GEOS) was refused. It is
    now cut back from the shell (the area planned contains the file's), and the lanes cover
    the file's own area, measured here with shapely."""
    shell = [[0, 0], [100, 0], [100, 100], [0, 100], [0, 0]]
    hole = [[50, 0], [60, 20], [40, 20], [50, 0]]  # its vertex (50, 0) on the shell's edge
    path = tmp_path / "touch.geojson"
    path.write_text(json.dumps({"type": "Polygon", "coordinates": [shell, hole]}))
    out = tmp_path / "m.geojson"
    argv = ["plan", path, "--crs", "planar", "--spacing", "10", "--out", out]
    code, _, err = run_cli(capsys, *argv)
    assert code == 0 and "hole 1 at [50.0, 0.0] touches the shell" in err
    features = json.loads(out.read_text())["features"]
    assert _covered_share_left(features, shell, [hole], 5.0) < 1e-9


@pytest.mark.parametrize("keep_inside", [False, True])
def test_a_cut_back_hole_counts_in_the_length_outside(keep_inside, tmp_path, capsys):
    """Review of round 14: a hole meeting the shell at a slant (0.14 degrees) is cut back, and
    the path ran 3.98 m through its cut-off part with --keep-inside while outside_length_m said
    0 (207.27 m outside without it, 200.00 reported): the length outside is measured against
    the file's holes, as shapely measures the path's legs on the file's area here."""
    shell = [[0, 0], [100, 0], [100, 100], [0, 100], [0, 0]]
    hole = [[50, 0], [90, 20], [90, 0.1], [50, 0]]
    path = tmp_path / "slant.geojson"
    path.write_text(json.dumps({"type": "Polygon", "coordinates": [shell, hole]}))
    out = tmp_path / "m.geojson"
    argv = ["plan", path, "--crs", "planar", "--spacing", "10", "--json", "--out", out]
    code, stdout, err = run_cli(capsys, *argv, *(["--keep-inside"] if keep_inside else []))
    assert code == 0 and "touches the shell" in err
    got = json.loads(stdout)["outside_length_m"]
    features = json.loads(out.read_text())["features"]
    legs = np.asarray(
        next(f for f in features if f["properties"].get("role") == "path")["geometry"][
            "coordinates"
        ]
    )
    # a pass along the hole's edge is on its boundary, not in it: 1 um of tolerance
    original = shapely.Polygon(shell, [hole]).buffer(1e-6, join_style="mitre")
    want = sum(
        shapely.LineString(legs[i : i + 2]).difference(original).length
        for i in range(len(legs) - 1)
    )
    assert want > 1.0  # the path does cross the cut-off part of the hole
    assert got == pytest.approx(want, rel=1e-3)


def test_a_nan_vertex_is_refused_in_one_line_with_or_without_repair(tmp_path, capsys):
    """QA round 13: a NaN vertex was refused with "try --repair", and --repair then ended in a
    GEOS traceback (make_valid raises on NaN); a zero-area polygon was told to try --repair,
    which leaves no polygon."""
    nan = tmp_path / "nan.json"
    nan.write_text("[[0,0],[10,0],[NaN,5],[0,10]]")
    flat = tmp_path / "flat.json"
    flat.write_text("[[0,0],[10,0],[20,0]]")
    for path, extra in ((nan, []), (nan, ["--repair"]), (flat, [])):
        code, out, err = run_cli(capsys, "plan", path, "--crs", "planar", "--spacing", "1", *extra)
        assert code == 2 and out == "" and "Traceback" not in err, err
        assert len(err.strip().splitlines()) == 1 and "try --repair" not in err


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e6])
def test_detach_holes_cuts_exactly_the_holes_the_region_refuses(scale):
    """Review of round 14: a hole that the Region accepts (farther than TOUCH_TOLERANCE times the
    shell's diameter from it, here 5e-9 of the side) planned before and must be left as it is;
    only a hole the Region refuses as touching is cut back (it was cut within 1e-8 of the
    extent, changing the plan of an input that planned before)."""
    shell = np.array([(0, 0), (100, 0), (100, 100), (0, 100)]) * scale
    for gap, cut in ((5e-7, False), (1e-7, True), (0.0, True)):  # tolerance 1.41e-7 (side 100)
        hole = np.array([(50, gap), (60, 20), (40, 20)]) * scale
        area = Area(shell, None, "x", "f.json", (hole,))
        planned, note = detach_holes(area)
        assert (note is not None) == cut, (gap, note)
        Region(planned.ring, list(planned.holes))  # what is planned is a valid Region
        if not cut:
            assert planned is area


@pytest.mark.parametrize("on_shell", [True, False])
def test_holes_touching_each_other_at_a_point_are_planned_with_full_coverage(
    on_shell, tmp_path, capsys
):
    """QA round 16: two holes touching at a point (valid for GEOS, e.g. a trace made valid by
    QGIS) were refused ("holes 0 and 1 touch"), also with --repair. The later hole is now cut
    back from the earlier one as a hole touching the shell is from the shell: planned, the note
    names both touches, and the lanes cover the file's own area (shapely)."""
    shell = [[0, 0], [100, 0], [100, 100], [0, 100], [0, 0]]
    first = [[50, 0], [60, 20], [40, 20], [50, 0]] if on_shell else [[50, 5], [60, 20], [40, 20]]
    second = [[60, 20], [70, 40], [60, 40], [60, 20]]
    path = tmp_path / "chain.geojson"
    path.write_text(json.dumps({"type": "Polygon", "coordinates": [shell, first, second]}))
    out = tmp_path / "m.geojson"
    argv = ["plan", path, "--crs", "planar", "--spacing", "10", "--out", out]
    code, _, err = run_cli(capsys, *argv)
    assert code == 0 and out.exists(), err
    assert "hole 2 touches hole 1 at [60.0, 20.0]" in err
    assert ("hole 1 at [50.0, 0.0] touches the shell" in err) == on_shell
    assert "planned with each hole cut back" in err if on_shell else "the hole cut back" in err
    features = json.loads(out.read_text())["features"]
    assert _covered_share_left(features, shell, [first, second], 5.0) < 1e-9


@pytest.mark.parametrize(
    "holes",
    [
        [[(50, 0), (60, 20), (40, 20)]],  # a vertex on the shell's edge
        [[(50, 0), (90, 0.1), (90, 20)]],  # an edge at 0.14 degrees to the shell's
        [[(0, 0), (20, 10), (10, 20)]],  # at the shell's vertex
        [[(50, 0), (60, 20), (50, 12), (40, 20)]],  # concave
        [[(50, 0), (60, 20), (52, 20)], [(50, 0), (48, 20), (40, 20)]],  # two at one point
    ],
)
def test_detach_holes_only_shrinks_the_holes_that_touch(holes):
    """Review of round 14: the area planned contains the file's (the coverage argument of
    detach_holes), is a valid Region, and differs from it only within the gap of the shell or
    of another hole (QA round 16: two holes at one point are cut back from each other); a
    hole along the shell's edge (invalid for GEOS) is left to be refused."""
    shell = np.array([(0, 0), (100, 0), (100, 100), (0, 100)], dtype=float)
    area = Area(shell, None, "x", "f.json", tuple(np.array(h, dtype=float) for h in holes))
    planned, note = detach_holes(area)
    assert note is not None and np.array_equal(planned.ring, area.ring)
    Region(planned.ring, list(planned.holes))
    original = shapely.Polygon(shell, holes)
    after = shapely.Polygon(planned.ring, list(planned.holes))
    assert original.difference(after).area < 1e-12 * original.area  # contains it, to rounding
    gap = 100 * 1e-4  # DETACH_GAP of the side
    rings = [shapely.LinearRing(r) for r in (shell, *holes)]
    band = shapely.union_all(rings).buffer(1.01 * gap)  # the shell's or another hole's gap
    assert after.difference(original).difference(band).area < 1e-12 * original.area
    edge = Area(shell, None, "x", "f.json", (np.array([(40, 0), (60, 0), (50, 20)], float),))
    assert detach_holes(edge) == (edge, None)


@pytest.mark.parametrize(
    ("holes", "said"),
    [
        (
            [[(50, 0), (60, 20), (40, 20)]],
            "hole 1 at [50.0, 0.0] touches the shell; planned with the hole cut back",
        ),
        (
            [
                [(50, 0), (60, 20), (52, 20)],
                [(20, 20), (30, 30), (20, 30)],
                [(0, 50), (9, 60), (9, 50)],
            ],
            "hole 1 at [50.0, 0.0] and hole 3 at [0.0, 50.0] touch the shell; planned with each "
            "hole cut back",
        ),
    ],
)
def test_the_touching_hole_note_agrees_in_number(holes, said):
    """QA round 15: two touching holes were said as 'hole 0 at [...], hole 1 at [...] touches
    the shell; planned with the hole cut back'."""
    shell = np.array([(0, 0), (100, 0), (100, 100), (0, 100)], dtype=float)
    area = Area(shell, None, "x", "f.json", tuple(np.array(h, dtype=float) for h in holes))
    _, note = detach_holes(area)
    assert note is not None and said in note


def test_a_small_hole_at_utm_coordinates_is_not_zero_area():
    """QA round 16 (hostile fields): a GPS-traced boundary fixed by make_valid keeps 1 cm^2 holes
    (its noise's loops); in the UTM frame (x ~ 6.5e5, y ~ 5.8e6 m) the shoelace summed at
    absolute coordinates cancelled to 0.0 and the field was refused ("hole 82: the polygon has
    zero area"). Its area is now summed about a vertex: exact to rounding at any offset."""
    triangle = np.array([[0.0, 0.0], [0.046, 0.001], [0.044, 0.0053]])  # 1.0e-4 m^2
    want = 0.5 * abs(0.046 * 0.0053 - 0.001 * 0.044)
    for offset in ([0.0, 0.0], [650831.0, 5774394.0], [-3e6, 9e6]):
        hole = Polygon(triangle + offset)
        assert hole.area == pytest.approx(want, rel=1e-6)
    far = np.array([650831.0, 5774394.0])
    shell = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]) + far
    Region(shell, [triangle + far])  # planned, not refused


def test_a_lonlat_hole_that_crosses_the_shell_only_in_the_utm_frame_is_cut_back(tmp_path, capsys):
    """QA round 16 (hostile fields): a hole with a vertex snapped onto a 300 m shell edge, given
    in lon/lat, lies 2 mm inside the shell in the file (valid, farther than the touching
    tolerance) but crosses the edge in the UTM frame (a straight lon/lat edge bends there), and
    was refused ("hole 0 touches or crosses the shell's boundary near [650785.378,
    5774443.868]", plan-frame coordinates). detach_holes now applies the Region's rule in both
    frames: the hole is cut back and the field planned, its own area covered (shapely)."""
    from pyproj import Transformer

    to_ll = Transformer.from_crs("EPSG:32631", "EPSG:4326", always_xy=True)
    x0, y0 = 650685.0, 5774443.0

    def ll(ring):
        return [list(to_ll.transform(x0 + x, y0 + y)) for x, y in ring]

    shell = ll([(0, 0), (300, 0), (300, 200), (0, 200), (0, 0)])
    hole = ll([(100, 0), (150, 50), (120, 60), (100, 0)])  # (100, 0) on the shell's edge
    original = shapely.Polygon(shell, [hole])
    assert original.is_valid and original.exterior.distance(original.interiors[0]) > 1e-8
    area = Area(np.array(shell[:-1]), "EPSG:4326", "x", "f.json", (np.array(hole[:-1]),))
    _, note = detach_holes(area)
    assert note is not None and "hole 1" in note
    path = tmp_path / "snapped.geojson"
    path.write_text(json.dumps({"type": "Polygon", "coordinates": [shell, hole]}))
    out = tmp_path / "m.geojson"
    code, stdout, err = run_cli(capsys, "plan", path, "--spacing", "10", "--json", "--out", out)
    assert code == 0, err
    assert json.loads(stdout)["covered_share"] > 1 - 1e-9
    to_utm = Transformer.from_crs("EPSG:4326", "EPSG:32631", always_xy=True)

    def utm(geom):
        return shapely.transform(geom, lambda c: np.column_stack(to_utm.transform(*c.T)))

    features = json.loads(out.read_text())["features"]
    swaths = [
        utm(shapely.geometry.shape(f["geometry"])).buffer(5.0, cap_style="flat")
        for f in features
        if f["properties"].get("role") == "transect"
    ]
    field = utm(original)
    assert field.difference(shapely.union_all(swaths)).area < 1e-6 * field.area
