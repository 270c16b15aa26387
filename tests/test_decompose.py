"""Decomposition, routing and plans of concave areas with holes; reading holes; the CLI."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import shapely
import torch

from boustro.cli import main
from boustro.decompose import (
    choose_sweep,
    decompose,
    optimize_region,
    plan_region,
    region_lanes,
    trapezoids,
)
from boustro.errors import InvalidParameterError
from boustro.geo import plan_area
from boustro.geometry import Polygon
from boustro.io import area_from_text, read_area
from boustro.plan import KINDS, coverage
from boustro.regions import Region, RegionExactModel, region_edges, region_segments
from boustro.routing import Router

from .conftest import random_regions, shapely_region

L_SHAPE = [(0, 0), (10, 0), (10, 3), (3, 3), (3, 10), (0, 10)]


def _regions(seed: int, count: int, n_vertices=(8, 24), n_holes=(1, 3)) -> list[Region]:
    """Random regions in metres, far from the origin."""
    return [
        r.map(lambda v: 100.0 * v + np.array([5e5, 5e6]))
        for r in random_regions(seed, count, n_vertices, n_holes)
    ]


def _assert_tiles(region: Region, pieces: list[shapely.Polygon]) -> None:
    """Union = area and pairwise overlap zero: every piece lies in the area, the pieces'
    areas add up to the area's, no two overlap. (Checked this way rather than by GEOS's
    union of all pieces, which was seen to lose a piece of a valid tiling.)"""
    target = shapely_region(region)
    for p in pieces:
        assert p.difference(target).area <= 1e-9 * target.area
    assert sum(p.area for p in pieces) == pytest.approx(target.area, rel=1e-9)
    tree = shapely.STRtree(pieces)
    for i, j in zip(*tree.query(pieces, predicate="intersects"), strict=True):
        if i < j:
            assert pieces[i].intersection(pieces[j]).area <= 1e-9 * target.area


# -- trapezoids and cells ---------------------------------------------------------------------
def test_trapezoids_tile_the_area():
    for region in _regions(seed=1, count=4):
        tr = trapezoids(region, 0.6)
        quads = [shapely.Polygon(q) for q in tr.polygons()]
        quads = [q if q.is_valid else q.buffer(0) for q in quads]
        _assert_tiles(region, [q for q in quads if q.area > 0])


@pytest.mark.parametrize("merge", [False, True])
def test_cells_tile_the_area_exactly(merge):
    rng = np.random.default_rng(2)
    for region in _regions(seed=3, count=6):
        for sweep in rng.uniform(0, math.pi, 3):
            dec = decompose(region, float(sweep), merge=merge, min_width=8.0 if merge else 0.0)
            pieces = [shapely_region(c) for c in dec.cells]
            assert all(p.is_valid for p in pieces)
            _assert_tiles(region, pieces)
            assert len(dec.widths) == len(dec.cells)
            assert np.allclose(dec.shared, dec.shared.T)


def test_unmerged_cells_are_monotone_along_the_sweep():
    region = _regions(seed=4, count=1, n_holes=(2, 2))[0]
    for sweep in (0.0, 1.0, 2.2):
        dec = decompose(region, sweep, merge=True)
        for cell in dec.cells:
            seg = region_segments(region_edges(cell), sweep, 0.0013, 0.0171)
            assert int(seg.n_segments.max()) <= 1  # every sweep line meets the cell once at most
    choset = decompose(region, 1.0, merge=False)
    assert len(choset.cells) >= len(decompose(region, 1.0).cells)


def test_cells_union_rebuilds_the_area_with_its_holes():
    region = _regions(seed=5, count=1, n_holes=(3, 3))[0]
    dec = decompose(region, 0.4, merge=False)
    whole = dec.union(list(range(len(dec.cells))), region.diameter)
    # Areas of rings 5e6 m from the origin: the shoelace sum rounds at ~1e-8 relative.
    assert whole.n_holes == 3 and whole.area == pytest.approx(region.area, rel=1e-6)


# -- optimising a region ----------------------------------------------------------------------
def test_optimize_region_beats_random_layouts():
    rng = np.random.default_rng(6)
    for region in _regions(seed=7, count=3):
        spacing = region.diameter / 20
        res = optimize_region(region, spacing)
        assert res.method == "region-grid" and 0 <= res.angle < math.pi
        assert 0 <= res.offset < spacing
        edges = region_edges(region)
        s_n = spacing / region.frame.scale
        angles = torch.as_tensor(rng.uniform(0, math.pi, 300))
        offsets = torch.as_tensor(rng.uniform(0, s_n, 300))
        tl = RegionExactModel()(edges, angles, offsets, s_n)
        from boustro.fitness import smith_fitness

        assert res.fitness >= float(smith_fitness(tl.lengths, tl.weights).max()) - 1e-9
    convex = optimize_region(Polygon([(0, 0), (4, 0), (4, 3), (0, 3)]), 0.5, n_angles=18)
    assert convex.method == "grid"
    tiny = optimize_region(Polygon([(0, 0), (1, 0), (0, 1)]), 5.0)
    assert tiny.method == "single-lane"


# -- routing ----------------------------------------------------------------------------------
def test_router_paths_stay_inside_and_avoid_holes():
    rng = np.random.default_rng(8)
    for region in _regions(seed=9, count=3, n_holes=(2, 3)):
        router = Router(region, reach=0.0)
        area = shapely_region(region).buffer(1e-7 * region.diameter)
        pts = []
        while len(pts) < 24:
            p = rng.uniform(-100, 100, 2) + np.array([5e5, 5e6])
            if region.contains(p[None])[0]:
                pts.append(p)
        pts = np.array(pts)
        dist = router.distances(pts)
        for i in range(12):
            route = router.path(pts[i], pts[i + 12])
            line = shapely.LineString(route.points)
            assert area.covers(line) and route.found
            assert route.length >= np.linalg.norm(pts[i + 12] - pts[i]) - 1e-9
            assert route.length <= dist[i, i + 12] + 1e-6
        np.testing.assert_allclose(dist, dist.T, atol=1e-9)


# -- plans ------------------------------------------------------------------------------------
def _check_plan(region: Region, plan) -> None:
    assert coverage(plan).covered_share >= 1 - 1e-9
    path = shapely.LineString(plan.waypoints)
    for hole in region.holes:
        inner = shapely.Polygon(hole.vertices).buffer(-1e-7 * region.diameter)
        assert path.intersection(inner).length == 0.0  # the path never crosses a hole
    assert set(plan.kinds) <= set(KINDS)
    steps = np.linalg.norm(np.diff(plan.waypoints, axis=0), axis=1).sum()
    assert plan.stats.path_length == pytest.approx(steps)
    passes = (
        plan.stats.n_transects
        + sum(1 for k in plan.kinds if k == "start")
        - len([r for r in plan.role() if r == "lane"])
    )
    assert plan.stats.n_turns == passes - 1
    lanes = np.array(plan.role()) == "lane"
    assert plan.stats.n_transects == int(lanes.sum())


@pytest.mark.parametrize("decomposed", [True, False])
def test_guaranteed_plans_cover_everything_and_never_cross_a_hole(decomposed):
    for region in _regions(seed=10, count=4):
        plan = plan_region(region, region.diameter / 18, decompose_area=decomposed, n_angles=30)
        _check_plan(region, plan)
        if decomposed:
            assert plan.stats.n_cells == len(plan.cells) >= 1


def test_turnaround_never_enters_a_hole():
    region = Region(L_SHAPE, [[(1, 1), (2, 1), (2, 2), (1, 2)], [(5, 0.8), (6, 0.8), (5.5, 2)]])
    plan = plan_region(region, 0.4, turnaround=0.6, decompose_area=False, angle=0.3)
    _check_plan(region, plan)
    assert "run_in" in plan.kinds and "run_out" in plan.kinds


def test_chords_layout_is_the_exact_segments():
    region = Region(L_SHAPE, [[(1, 1), (2, 1), (2, 2), (1, 2)]])
    plan = plan_region(region, 0.5, layout="chords", decompose_area=False, angle=0.2, offset=0.1)
    assert set(plan.role()) == {"lane"}  # no hole passes without the guarantee
    lanes = region_lanes(region, 0.5, 0.2, 0.1, layout="chords")
    shape = shapely_region(region)
    for seg in lanes.segments:
        line = shapely.LineString(seg)
        assert line.length == pytest.approx(shape.intersection(line).length, abs=1e-9)
    assert plan.stats.transect_length == pytest.approx(float(np.sum(lanes.t1 - lanes.t0)))
    assert coverage(plan).covered_share < 1


def test_decomposition_pays_off_on_an_l_and_a_v():
    def arm(angle, length, width):
        u = np.array([math.cos(angle), math.sin(angle)])
        n = np.array([-u[1], u[0]])
        return [a * u + b * n for a, b in [(0, -width / 2), (length, -width / 2),
                                            (length, width / 2), (0, width / 2)]]  # fmt: skip

    vee = shapely.union_all(
        [shapely.Polygon(arm(math.radians(20), 10, 2.5)), shapely.Polygon(arm(1.75, 10, 2.5))]
    )
    for shell in (L_SHAPE, np.asarray(vee.exterior.coords)[:-1]):
        region = Region(shell)
        spacing = region.diameter / 30
        single = plan_region(region, spacing, decompose_area=False)
        cells = plan_region(region, spacing)  # "auto"
        assert cells.stats.n_cells >= 2
        assert cells.stats.n_turns < single.stats.n_turns
        assert cells.stats.path_length < single.stats.path_length
        _check_plan(region, cells)


def test_plan_region_parameters():
    region = Region(L_SHAPE)
    for kwargs, match in (
        ({"reach": 0.1}, "reach"),
        ({"layout": "zigzag"}, "layout"),
        ({"decompose_area": "sometimes"}, "decompose_area"),
        ({"start": (0, float("nan"))}, "start"),
        ({"speed": 0}, "speed"),
    ):
        with pytest.raises(InvalidParameterError, match=match):
            plan_region(region, 0.5, **kwargs)
    holed = Region(L_SHAPE, [[(1, 1), (2, 1), (2, 2), (1, 2)]])
    with pytest.raises(InvalidParameterError, match="nadir gap"):
        plan_region(holed, 0.5, nadir_gap=0.1)
    sweep, (turns, length) = choose_sweep(region, 0.5, candidates=[0.0, 0.5])
    assert sweep in (0.0, 0.5) and turns > 0 and length > 0


# -- files and the command line ---------------------------------------------------------------
SHELL = [(0, 0), (200, 0), (200, 80), (80, 80), (80, 200), (0, 200)]
HOLE = [(20, 20), (50, 20), (50, 40), (20, 40)]


def test_areas_with_holes_are_read(tmp_path):
    ring = [*SHELL, SHELL[0]]
    hole = [*HOLE, HOLE[0]]
    geojson = json.dumps({"type": "Polygon", "coordinates": [ring, hole[::-1]]})
    wkt = (
        "POLYGON (("
        + ", ".join(f"{x} {y}" for x, y in ring)
        + "), ("
        + ", ".join(f"{x} {y}" for x, y in hole)
        + "))"
    )
    kml = (
        '<kml xmlns="http://www.opengis.net/kml/2.2"><Placemark><Polygon><outerBoundaryIs>'
        "<LinearRing><coordinates>" + " ".join(f"{x},{y}" for x, y in ring) + "</coordinates>"
        "</LinearRing></outerBoundaryIs><innerBoundaryIs><LinearRing><coordinates>"
        + " ".join(f"{x},{y}" for x, y in hole)
        + "</coordinates></LinearRing></innerBoundaryIs></Polygon></Placemark></kml>"
    )
    for text in (geojson, wkt, kml):
        area = area_from_text(text, crs="EPSG:28992")
        assert len(area.ring) == 6 and len(area.holes) == 1 and len(area.holes[0]) == 4
    path = tmp_path / "a.wkt"
    path.write_text(wkt)
    assert len(read_area(path).holes) == 1


def test_plan_area_with_holes_planar():
    mission = plan_area(np.array(SHELL, float), 10.0, crs=None, holes=[HOLE])
    assert mission.coverage.covered_share >= 1 - 1e-9
    summary = mission.summary()
    assert summary["holes"] == 1 and summary["n_cells"] >= 1
    assert summary["area_m2"] == pytest.approx(200 * 80 + 80 * 120 - 30 * 20)
    with pytest.raises(InvalidParameterError, match="convex areas only"):
        plan_area(np.array(SHELL, float), 10.0, crs=None, holes=[HOLE], method="hybrid")


def _run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def _lonlat_area(tmp_path) -> str:
    import pyproj

    to_ll = pyproj.Transformer.from_crs("EPSG:32632", "EPSG:4326", always_xy=True)
    origin = np.array([300000.0, 5700000.0])

    def ll(ring):
        pts = np.asarray(ring, float) + origin
        x, y = to_ll.transform(pts[:, 0], pts[:, 1])
        out = np.stack([x, y], axis=1).tolist()
        return [*out, out[0]]

    doc = {"type": "Polygon", "coordinates": [ll(SHELL), ll(HOLE)[::-1]]}
    path = tmp_path / "holes.geojson"
    path.write_text(json.dumps(doc))
    return str(path)


def test_cli_plans_concave_areas_with_holes(capsys, tmp_path):
    area = _lonlat_area(tmp_path)
    code, out, err = _run(capsys, "plan", area, "--spacing", "10", "--json")
    assert code == 0, err
    auto = json.loads(out)
    assert auto["holes"] == 1 and auto["covered_share"] >= 1 - 1e-9
    code, out, err = _run(capsys, "plan", area, "--spacing", "10", "--no-decompose", "--json")
    assert code == 0, err
    single = json.loads(out)
    assert single["n_cells"] == 1 and single["covered_share"] >= 1 - 1e-9
    out_file, png = tmp_path / "m.geojson", tmp_path / "m.png"
    code, out, err = _run(
        capsys, "plan", area, "--spacing", "10", "--decompose", "--sweep", "45",
        "--out", out_file, "--plot", png,
    )  # fmt: skip
    assert code == 0, err
    assert "cells (boustrophedon decomposition)" in out and "cell angles" in out
    assert "100.0000% of the area" in out
    doc = json.loads(out_file.read_text())
    roles = [f["properties"]["role"] for f in doc["features"]]
    assert roles.count("cell") == doc["boustro"]["n_cells"] >= 2
    assert len(doc["features"][0]["geometry"]["coordinates"]) == 2  # the area and its hole
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_plot_shows_holes_and_cells():
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from boustro.plot_plan import plot_plan

    region = Region(L_SHAPE, [[(1, 1), (2, 1), (2, 2), (1, 2)]])
    plan = plan_region(region, 0.4, decompose_area=True, sweep=2.356, merge_angle=0.0)
    fig, ax = plt.subplots()
    try:
        artists = plot_plan(plan, ax=ax)
        assert len(artists["holes"]) == 1
        labels = [a for a in artists["cells"] if hasattr(a, "get_text")]
        assert len(labels) == len(plan.cells) >= 2
        assert "°" in labels[0].get_text()
    finally:
        plt.close(fig)
