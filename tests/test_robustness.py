"""Bad and extreme input: one clear error (exit 2, nothing written) instead of a traceback, an
exhausted memory or a silently wrong file. Cases found by adversarial review."""

from __future__ import annotations

import argparse
import json
import logging
import math
import sys

import numpy as np
import pytest

from boustro.cli import reproduce as reproduce_cli
from boustro.errors import InvalidParameterError, InvalidPolygonError, PolygonFileError
from boustro.formats import _xml_text
from boustro.geometry import Polygon, halfplanes
from boustro.io import area_from_json, polygon_from_json
from boustro.learned import LearnedPlanner, PlannerConfig, save_planner
from boustro.models import MAX_TRANSECTS, PaperModel, check_spacing, exact_chords
from boustro.optimize import optimize
from boustro.smooth import smooth_lengths

from .conftest import run_cli

PENTAGON = [[0, 0], [7, 1], [9, 5], [4, 8], [-1, 4]]


def _one_line_error(code: int, err: str, *, usage: bool = False) -> str:
    """The error line; ``usage``: argparse's refusal (its usage block, then one error line)."""
    assert code == 2, err
    lines = [line for line in err.strip().splitlines() if line]
    assert "Traceback" not in err
    assert lines[-1].startswith("boustro") and "error:" in lines[-1], err
    assert usage or len(lines) == 1, err
    return lines[-1]


def _run(capsys, *argv) -> tuple[int, str, str, bool]:
    """``run_cli``, and whether argparse refused the arguments (SystemExit)."""
    try:
        return (*run_cli(capsys, *argv), False)
    except SystemExit as exc:
        out, err = capsys.readouterr()
        return int(exc.code or 0), out, err, True


@pytest.fixture
def pentagon_file(tmp_path):
    path = tmp_path / "pent.json"
    path.write_text(json.dumps(PENTAGON))
    return path


# -- sizes: refused before any allocation ---------------------------------------------------
def test_too_many_transects_are_refused():
    with pytest.raises(InvalidParameterError, match="too small"):
        check_spacing(1e-7, extent=1.0)
    assert check_spacing(1.0 / MAX_TRANSECTS, extent=1.0) == 1.0 / MAX_TRANSECTS
    hp = halfplanes(Polygon(PENTAGON))
    with pytest.raises(InvalidParameterError, match="candidate transects"):
        exact_chords(hp, 0.3, 0.0, 1e-9)
    with pytest.raises(InvalidParameterError, match="too small"):
        optimize(Polygon(PENTAGON), 1e-6, method="global")


@pytest.mark.parametrize(
    "argv",
    [
        ["score", "--spacing", "1e-7"],
        ["score", "--spacing", "1e-300"],
        ["score", "--model", "soft", "--smoothing", "1e9"],
        ["score", "--model", "paper", "--points-per-transect", "1000000000"],
        ["optimize", "--spacing", "1e-6", "--method", "global"],
        ["optimize", "--spacing", "1e-6", "--method", "grid"],
        ["optimize", "--spacing", "0.7", "--method", "gradient", "--seed", "-1"],
        ["optimize", "--spacing", "0.7", "--method", "global", "--tol", "1e-15"],
        ["score", "--spacing", "12", "--angle", "45", "-a", "1e308", "-b", "1e308", "--json"],
        ["plan", "--spacing", "1e-300"],
        ["plan", "--altitude", "-50"],
    ],
)
def test_cli_refuses_with_one_line(capsys, pentagon_file, argv):
    if argv[0] in ("score", "optimize"):
        argv = [argv[0], pentagon_file, *argv[1:]]
    code, out, err, usage = _run(capsys, *argv)
    _one_line_error(code, err, usage=usage)
    assert out == ""


def test_tiny_smoothing_is_refused_not_wrong():
    hp = halfplanes(Polygon(PENTAGON))
    with pytest.raises(InvalidParameterError, match="smoothing=0"):
        smooth_lengths(hp, 0.5, 0.0, 0.1, smoothing=1e-200)
    small = smooth_lengths(hp, 0.5, 0.0, 0.1, smoothing=1e-60).lengths
    exact = exact_chords(hp, 0.5, 0.0, 0.1).lengths
    np.testing.assert_allclose(small, exact, atol=1e-12)


def test_points_per_transect_has_an_upper_bound():
    hp = halfplanes(Polygon(PENTAGON))
    with pytest.raises(InvalidParameterError, match="points_per_transect"):
        PaperModel(points_per_transect=10**9)(hp, 0.5, 0.0, 0.1)


# -- polygons at any scale -------------------------------------------------------------------
@pytest.mark.parametrize("scale", [1e-30, 1e-13, 1.0, 1e13, 1e90])
def test_valid_polygon_at_any_scale(scale):
    p = Polygon(np.array(PENTAGON, dtype=float) * scale)
    assert len(p) == 5
    assert p.area / scale**2 == pytest.approx(51.0, rel=1e-12)


def test_out_of_range_coordinates_are_refused():
    with pytest.raises(InvalidPolygonError, match="coordinates"):
        Polygon(np.array(PENTAGON, dtype=float) * 1e200)
    with pytest.raises(InvalidPolygonError, match="too small for float64"):
        Polygon(np.array(PENTAGON, dtype=float) * 1e-10 + 1e9)


# -- malformed GeoJSON ---------------------------------------------------------------------
@pytest.mark.parametrize(
    "data",
    [
        {"type": "FeatureCollection", "features": [[1, 2]]},
        {"type": "FeatureCollection", "features": "abc"},
        {"type": "Feature", "geometry": [1]},
        {"type": "MultiPolygon", "coordinates": {"a": 1}},
        {"type": "Polygon", "coordinates": "x"},
        [[0, 0], [1, 0], [1, 1], [0, 10**400]],
    ],
)
def test_malformed_json_raises_the_file_error(data):
    with pytest.raises(PolygonFileError):
        polygon_from_json(data)
    with pytest.raises(PolygonFileError):
        area_from_json(data)


def test_several_polygons_warn_that_only_the_first_is_used(caplog):
    square = [[[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]]]
    data = {
        "type": "FeatureCollection",
        "features": [
            {"type": "Feature", "geometry": {"type": "Point", "coordinates": [0, 0]}},
            {"type": "Feature", "geometry": {"type": "Polygon", "coordinates": square}},
            {"type": "Feature", "geometry": {"type": "Polygon", "coordinates": square}},
        ],
    }
    with caplog.at_level(logging.WARNING):
        area = area_from_json(data, "f.geojson")
    assert len(area.ring) == 4
    assert "only the first (feature 2)" in caplog.text


# -- outputs ---------------------------------------------------------------------------------
def test_plan_writes_nothing_when_an_output_cannot_be(capsys, tmp_path):
    out = tmp_path / "ok.geojson"
    code, _, err = run_cli(
        capsys, "plan", "--spacing", "20", "--out", out, "--plot", tmp_path / "no" / "x.png"
    )
    assert "no such folder" in _one_line_error(code, err)
    assert not out.exists()
    code, _, err = run_cli(capsys, "plan", "--spacing", "20", "--out", tmp_path / "no" / "x.kml")
    assert str(tmp_path / "no") in _one_line_error(code, err)  # the folder, not a temp file


@pytest.mark.parametrize(
    ("crs", "member"), [("28992", "urn:ogc:def:crs:EPSG::28992"), ("planar", None)]
)
def test_geojson_names_its_crs_the_standard_way(capsys, tmp_path, crs, member):
    area = tmp_path / "rd.json"
    ring = [[120000, 480000], [120300, 480000], [120300, 480200], [120000, 480200]]
    area.write_text(json.dumps(ring))
    out = tmp_path / "x.geojson"
    code, _, err = run_cli(capsys, "plan", area, "--crs", crs, "--spacing", "10", "--out", out)
    assert code == 0, err
    written = json.loads(out.read_text()).get("crs")
    assert (written and written["properties"]["name"]) == member


def test_xml_text_drops_characters_xml_forbids():
    assert _xml_text("a\x01b<c>\td") == "a?b&lt;c&gt;\td"


def test_train_refuses_outputs_before_training(capsys, tmp_path):
    tiny = ["--epochs", "1", "--steps-per-epoch", "1", "--batch-size", "2", "--pool", "4"]
    for extra, needle in [
        (["--out", tmp_path / "w.json"], "must not end in .json"),
        (["--out", tmp_path], "is a folder"),
        (["--out", tmp_path / "w.pt", "--plot", tmp_path / "c.xyz"], "unknown image format"),
        (["--out", tmp_path / "w.pt", "--seed", "-1"], ">= 0"),
    ]:
        code, _, err, _ = _run(capsys, "-q", "train", *tiny, "--validation", "2", *extra)
        assert needle in err and code == 2, err
    assert not list(tmp_path.iterdir())


def test_save_planner_refuses_non_finite_weights_and_json_names(tmp_path):
    planner = LearnedPlanner(PlannerConfig(hidden=8, hypotheses=2))
    with pytest.raises(InvalidParameterError, match=r"\.json"):
        save_planner(planner, tmp_path / "w.json")
    with pytest.raises(InvalidParameterError, match="not all finite"):
        for p in planner.parameters():
            p.data.fill_(math.nan)
        save_planner(planner, tmp_path / "w.pt")
    assert not list(tmp_path.iterdir())


def test_reproduce_ignores_foreign_result_files(tmp_path, caplog):
    from boustro.cli import reproduce

    (tmp_path / "optimizers.json").write_text("[1, 2]")
    (tmp_path / "table1.json").write_text("{bad")
    with caplog.at_level(logging.WARNING):
        for part in ("table1", "optimizers"):
            assert reproduce._read_json(str(tmp_path / f"{part}.json"), part) is None
        assert reproduce._read_json(str(tmp_path / "figures.json"), "figures") is None  # absent
    assert caplog.text.count("ignoring") == 2


# -- the exact optimiser's work --------------------------------------------------------------
def test_global_optimiser_refuses_work_beyond_its_limit():
    from boustro import global_opt
    from boustro.errors import ProblemTooLargeError

    n = 40
    ring = [(math.cos(2 * math.pi * k / n), math.sin(2 * math.pi * k / n)) for k in range(n)]
    assert global_opt.global_work(ring, 0.02) > global_opt.WORK_LIMIT
    assert global_opt.global_work(PENTAGON, 0.7) < global_opt.WORK_LIMIT
    with pytest.raises(ProblemTooLargeError, match="hybrid"):
        optimize(ring, 0.02, method="global")


def test_plan_falls_back_to_certified_bb_when_global_is_too_large(monkeypatch, caplog):
    from boustro import geo
    from boustro.optimize.exact import structure

    monkeypatch.setattr(structure, "WORK_LIMIT", 10.0)  # its home (global_opt re-exports it)
    with caplog.at_level(logging.INFO, logger="boustro"):
        mission = geo.plan_area(PENTAGON, 0.7, crs=None)
    assert mission.optimum.method == "certified-bb"  # Eq. 1: still certified
    assert mission.optimum.info["converged"] and mission.optimum.gap <= 1e-4
    assert "planning with the certified branch and bound (certified-bb)" in caplog.text
    with pytest.raises(InvalidParameterError, match="units of work"):
        geo.plan_area(PENTAGON, 0.7, crs=None, method="global")  # asked for: no fallback


@pytest.mark.parametrize("holes", [(), ([[4, 4], [6, 4], [6, 6], [4, 6]],)])
def test_plan_starts_at_the_lane_end_nearest_the_start_in_concave_areas(holes, caplog):
    from boustro import geo

    shell = [[0, 0], [20, 0], [20, 8], [8, 8], [8, 20], [0, 20]]  # an L
    for start in ([19.5, 0.5], [0.5, 19.5]):  # lane ends that begin a chain
        mission = geo.plan_area(shell, 1.0, crs=None, holes=holes, start=start)
        wp, kinds = mission.plan.waypoints, np.asarray(mission.plan.kinds)
        ends = wp[np.isin(kinds, ("start", "end"))]  # every lane end flown
        nearest = np.min(np.hypot(*(ends - start).T))
        # a chain of lanes starts at its first or last lane: within two spacings of the nearest
        # lane end (before the fix: across the area, up to 20 spacings away)
        assert np.hypot(*(wp[0] - start)) <= nearest + 2.0, (start, wp[0])
    with caplog.at_level(logging.WARNING):
        geo.plan_area(shell, 1.0, crs=None, start=[5000.0, 0.0])
    # QA round 13: planar (and projected) input has no longitude to swap
    assert "times its size" in caplog.text and "in the area's CRS" in caplog.text
    assert "swapped longitude" not in caplog.text


# -- small API contracts -----------------------------------------------------------------------
def test_flags_are_not_numbers_and_options_are_checked():
    hp = halfplanes(Polygon(PENTAGON))
    with pytest.raises(InvalidParameterError, match="smoothing must be a number"):
        smooth_lengths(hp, 0.5, 0.0, 0.1, smoothing=True)
    with pytest.raises(InvalidParameterError, match="points_per_transect"):
        PaperModel(points_per_transect="x")(hp, 0.5, 0.0, 0.1)
    with pytest.raises(InvalidParameterError, match="no option 'bogus'"):
        optimize(PENTAGON, 0.7, method="global", bogus=1)


def test_smith_fitness_checks_its_weights_and_ignores_rounding_noise_chords():
    import torch

    from boustro.fitness import smith_fitness

    with pytest.raises(InvalidParameterError, match="a must be"):
        smith_fitness(torch.ones(3, dtype=torch.float64), a=-1.0)
    with pytest.raises(InvalidParameterError, match="b must be"):
        smith_fitness(torch.ones(3, dtype=torch.float64), b=math.nan)
    lengths = torch.tensor([1.0, 0.8, 1.4e-17], dtype=torch.float64)  # a chord through a vertex
    expect = smith_fitness(lengths[:2])
    assert float(smith_fitness(lengths)) == pytest.approx(float(expect), abs=1e-15)


def test_decompose_refuses_a_nan_sweep():
    from boustro.decompose import decompose

    with pytest.raises(InvalidParameterError, match="sweep"):
        decompose(PENTAGON, math.nan)


def test_python_dash_m_and_byte_order_mark(tmp_path):
    import subprocess
    import sys

    path = tmp_path / "bom.json"
    path.write_bytes(b"\xef\xbb\xbf" + json.dumps(PENTAGON).encode())
    done = subprocess.run(
        [sys.executable, "-m", "boustro", "score", str(path), "--spacing", "0.7", "--json"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["n_transects"] > 0


def test_atomic_write_keeps_a_symlink_and_writes_its_target(tmp_path):
    from boustro.io import atomic_write

    target = tmp_path / "target.txt"
    target.write_text("old")
    link = tmp_path / "link.txt"
    link.symlink_to(target)
    atomic_write(link, "new")
    assert link.is_symlink() and target.read_text() == "new"


def test_gml_axis_order_follows_the_srs_name_form():
    from boustro.io import area_from_kml

    def gml(srs: str, pairs: list[tuple[float, float]]) -> str:
        pos = " ".join(f"{a} {b}" for a, b in pairs)
        return (
            f'<gml:Polygon xmlns:gml="http://www.opengis.net/gml/3.2" srsName="{srs}">'
            "<gml:exterior><gml:LinearRing><gml:posList>"
            f"{pos}</gml:posList></gml:LinearRing></gml:exterior></gml:Polygon>"
        )

    lonlat = [(10.0, 45.0), (10.01, 45.0), (10.01, 45.01), (10.0, 45.01), (10.0, 45.0)]
    latlon = [(b, a) for a, b in lonlat]
    short = area_from_kml(gml("EPSG:4326", lonlat))
    for srs in ("urn:ogc:def:crs:EPSG::4326", "http://www.opengis.net/def/crs/EPSG/0/4326"):
        np.testing.assert_array_equal(area_from_kml(gml(srs, latlon)).ring, short.ring)
    assert short.ring[:, 0].max() < 11  # longitude first
    projected = area_from_kml(gml("urn:ogc:def:crs:EPSG::28992", [(0, 0), (9, 0), (9, 9)]))
    np.testing.assert_array_equal(projected.ring, [[0, 0], [9, 0], [9, 9]])  # easting first


# -- the learned planner's files and refinement --------------------------------------------------
def test_planner_files_errors_and_cache(tmp_path):
    import torch

    from boustro.learned import load_planner

    planner = LearnedPlanner(PlannerConfig(hidden=8, hypotheses=2))
    weights, _ = save_planner(planner, tmp_path / "p.pt")
    first = load_planner(weights)
    assert load_planner(weights) is first  # cached
    other = LearnedPlanner(PlannerConfig(hidden=8, hypotheses=2))
    with torch.no_grad():
        for p in other.parameters():
            p.add_(1.0)
    save_planner(other, weights)  # the same name, new contents: not the cached network
    second = load_planner(weights)
    assert second is not first
    for a, b in zip(second.parameters(), other.parameters(), strict=True):
        torch.testing.assert_close(a, b.to(a.dtype))
    for bad in (b"garbage", None):
        broken = tmp_path / "broken.pt"
        if bad is None:
            torch.save(planner.state_dict(), broken)
            broken.with_suffix(".json").write_text("{}")
        else:
            broken.write_bytes(bad)
            broken.with_suffix(".json").write_text(json.dumps({"config": {}}))
        with pytest.raises(InvalidParameterError, match="not a planner saved by boustro"):
            load_planner(broken)


def test_event_layouts_in_chunks_equal_one_batch(monkeypatch):
    import importlib

    refine_module = importlib.import_module("boustro.learned.refine")  # its function shadows it

    ring = [(math.cos(2 * math.pi * k / 12), math.sin(2 * math.pi * k / 12)) for k in range(12)]
    whole = optimize(ring, 0.1, method="learned", refine=True)
    monkeypatch.setattr(refine_module, "_EVENT_CHUNK_ELEMENTS", 1)  # one layout a chunk
    chunked = optimize(ring, 0.1, method="learned", refine=True)
    assert chunked.fitness == pytest.approx(whole.fitness, abs=1e-12)
    assert chunked.angle == pytest.approx(whole.angle, abs=1e-9)


def test_holes_touching_the_shell_in_lon_lat_are_refused():
    from boustro import geo

    shell = [[5, 52], [5.01, 52], [5.01, 52.01], [5, 52.01]]
    touching = [[5, 52.002], [5.003, 52.002], [5.003, 52.004], [5, 52.004]]
    with pytest.raises(InvalidPolygonError, match="file's coordinates"):
        geo.plan_area(shell, 20.0, crs="EPSG:4326", holes=[touching])
    inside = [[5.001, 52.002], [5.003, 52.002], [5.003, 52.004], [5.001, 52.004]]
    assert geo.plan_area(shell, 20.0, crs="EPSG:4326", holes=[inside]).plan.region is not None


def test_concave_plans_do_not_depend_on_the_clock(monkeypatch):
    import time

    from boustro import geo

    shell = [[0, 0], [20, 0], [20, 8], [8, 8], [8, 20], [0, 20]]
    holes = [[[2 + 4 * i, 2], [3 + 4 * i, 2], [3 + 4 * i, 3], [2 + 4 * i, 3]] for i in range(4)]
    first = geo.plan_area(shell, 0.5, crs=None, holes=holes).plan.waypoints
    slow = time.perf_counter
    monkeypatch.setattr(time, "perf_counter", lambda: slow() * 1000.0)  # a very busy machine
    again = geo.plan_area(shell, 0.5, crs=None, holes=holes).plan.waypoints
    np.testing.assert_array_equal(first, again)


def test_kml_names_lanes_and_hole_passes_apart():
    import re

    from boustro import geo
    from boustro.formats import render

    shell = [[10, 45], [10.01, 45], [10.01, 45.01], [10, 45.01]]
    hole = [[10.004, 45.004], [10.006, 45.004], [10.006, 45.006], [10.004, 45.006]]
    mission = geo.plan_area(shell, 50.0, crs="EPSG:4326", holes=[hole])
    names = re.findall(r"<name>(Transect|Hole pass) \d+</name>", render(mission, "kml"))
    roles = mission.plan.role()
    assert names.count("Transect") == roles.count("lane") > 0
    assert names.count("Hole pass") == roles.count("hole") > 0


@pytest.mark.parametrize(
    "argv",
    [
        ["plan", "--spacing", "0"],
        ["plan", "--spacing", "nan"],
        ["plan", "--spacing", "5", "--camera", "dji-phantom-4-pro"],
        ["plna"],
        ["batch"],
        ["optimize", "--method", "nope"],
        ["score", "--angle", "x"],
    ],
)
def test_an_argument_refused_by_argparse_is_one_line(capsys, argv):
    # QA: argparse printed its usage block (17 lines for plan) before the line saying what was
    # wrong; the README promises one line and exit status 2 for bad input
    code, out, err, refused = _run(capsys, *argv)
    assert refused and out == ""
    line = _one_line_error(code, err)
    assert "--help" in line and "usage:" not in err


def test_reproduce_shows_bars_only_on_a_terminal(monkeypatch):
    # QA: `boustro reproduce > log 2>&1` wrote tqdm frames into the log (the other commands
    # show their bars only when stderr is a terminal)
    for tty, quiet, shown in ((True, False, True), (False, False, False), (True, True, False)):
        monkeypatch.setattr(sys.stderr, "isatty", lambda tty=tty: tty)
        assert reproduce_cli._show_progress(argparse.Namespace(quiet=quiet)) is shown


def test_a_far_start_names_the_cause_of_its_crs(caplog):
    """QA round 13: a distant start in a projected CRS was warned as "swapped longitude and
    latitude?", which lon/lat input alone can have."""
    from boustro import geo
    from boustro.io import embedded_field

    square = np.array([[0, 0], [200, 0], [200, 200], [0, 200]], float) + np.array([155e3, 463e3])
    with caplog.at_level(logging.WARNING):
        geo.plan_area(square, 20.0, crs="EPSG:28992", start=[0.0, 0.0])
    assert "times its size" in caplog.text and "swapped longitude" not in caplog.text
    caplog.clear()
    field = embedded_field()
    with caplog.at_level(logging.WARNING):
        geo.plan_area(field.ring, 20.0, crs=field.crs, start=field.ring[0][::-1])
    assert "swapped longitude and latitude?" in caplog.text
