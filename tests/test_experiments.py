"""``boustro reproduce`` and :mod:`boustro.experiments`: the quick run end to end, and the
experiment numbers checked independently (library calls, shapely, a direct computation)."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest
import shapely
import torch

from boustro import experiments as ex
from boustro.cli import main
from boustro.fitness import smith_fitness
from boustro.geometry import Polygon, halfplanes
from boustro.models import ExactModel, PaperModel


@pytest.fixture(autouse=True)
def _one_thread():
    """Many small tensor operations: one thread is faster on a shared 2-core machine."""
    previous = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(previous)


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("reproduce")
    code = main(["-q", "reproduce", "--quick", "--out", str(out)])
    return code, out


def test_quick_run_writes_every_file(quick_run):
    code, out = quick_run
    assert code == 0
    for name in ("report.md", "table1.json", "optimizers.json", "figures.json", *ex.FIGURES):
        assert (out / name).stat().st_size > 0, name
    assert not list(out.glob(".*.tmp"))  # atomic writes leave no temporary file


def test_quick_run_json_keys(quick_run):
    _, out = quick_run
    t1 = json.loads((out / "table1.json").read_text())
    assert {"meta", "paper_table1", "protocols", "smooth"} <= set(t1)
    assert t1["meta"]["quick"] is True and t1["meta"]["n_samples"] == 20
    paper = t1["protocols"]["paper"]
    assert paper["temperatures"] == list(ex.TEMPERATURES)
    assert paper["points_per_transect"] == list(ex.POINTS_PER_TRANSECT)
    for key in ("mean_abs_error", "sem", "max_abs_error", "valid_samples", "no_value_model"):
        assert np.asarray(paper[key]).shape == (5, 3), key
    assert paper["no_value_discrete"] + paper["valid_samples"][0][0] == 20
    assert set(t1["protocols"]) == {p.name for p in ex.PROTOCOLS}
    # At T = 1 the authors' weighting of the statistics makes the error about 0.5 (Table I).
    assert 0.45 < paper["mean_abs_error"][0][0] < 0.55
    assert t1["protocols"]["paper-weighted"]["mean_abs_error"][0][0] < 0.2

    opt = json.loads((out / "optimizers.json").read_text())
    assert {"meta", "n", "seed", "methods", "comparisons", "paper"} <= set(opt)
    assert opt["paper"]["grid_minus_gradient"] == ex.PAPER_GRID_MINUS_GRADIENT
    assert set(opt["methods"]) == {"grid", "gradient", "hybrid", "global"}
    grid = opt["methods"]["grid"]
    assert grid["available"] and grid["failures"] == 0 and len(grid["fitness"]) == opt["n"]
    for name, m in opt["methods"].items():
        assert {"available", "fitness", "seconds", "failures", "mean_fitness"} <= set(m), name
    comp = opt["comparisons"]["gradient"]
    shares = comp["share_other_higher"] + comp["share_equal"] + comp["share_grid_higher"]
    assert math.isclose(shares, 1.0)

    fig = json.loads((out / "figures.json").read_text())
    assert {"fitness_vs_angle", "surface_angle_offset", "surface_angle_temperature"} <= set(fig)


def test_quick_run_report(quick_run):
    _, out = quick_run
    report = (out / "report.md").read_text()
    assert "| 1 | 0.5" in report and "(0.50798)" in report  # reproduced beside the paper's
    assert "0.13633" in report and "Gradient descent vs grid search" in report
    for name in ex.FIGURES:
        assert f"]({name})" in report
    assert "`table1.json`" in report and "mean_abs_error" in report  # keys documented


# -- the batched evaluation against the library -----------------------------------------------


@pytest.fixture(scope="module")
def samples():
    s = ex.draw_samples(16, seed=7)
    keep = [i for i in range(len(s)) if s.spacing[i] > 0.02]  # keep the reference loop cheap
    return ex.Samples(
        tuple(s.polygons[i] for i in keep),
        s.angle[keep],
        s.spacing[keep],
        s.phase[keep],
        s.seed,
    )


def _library_fitness(samples, i, protocol, temperature=None, points=None):
    """One unbatched library call: the paper's model (or the exact one) and Eq. 1."""
    hp = halfplanes(samples.polygons[i])
    s = float(samples.spacing[i])
    angle = torch.tensor(samples.angle[i], dtype=torch.float64)
    offset = torch.tensor((samples.phase[i] - 0.5) * s - 0.5, dtype=torch.float64)
    if temperature is None:
        tl = ExactModel(clip=protocol.clip)(hp, angle, offset, s)
        return float(smith_fitness(tl.lengths, tl.weights))
    tl = PaperModel(temperature, points, clip=protocol.clip)(hp, angle, offset, s)
    return float(smith_fitness(tl.lengths, tl.weights, statistics=protocol.statistics))


@pytest.mark.parametrize("name", ["boustro-clip", "project"])
@pytest.mark.parametrize("temperature", [1.0, 100.0, 10000.0])
def test_batched_paper_model_equals_library_calls(samples, name, temperature):
    protocol = next(p for p in ex.PROTOCOLS if p.name == name)
    for points in (100, 1000):
        ref = [
            _library_fitness(samples, i, protocol, temperature, points) for i in range(len(samples))
        ]
        # The subset expansion needs many short blocks at high temperature (slow, not used there).
        methods = ("auto", "dense", "band") + (("subsets",) if temperature <= 100 else ())
        for method in methods:
            got = ex.paper_model_fitness(samples, protocol, temperature, points, method=method)
            np.testing.assert_allclose(got, ref, rtol=0, atol=1e-12, err_msg=method)


@pytest.mark.parametrize("name", ["boustro-clip", "project"])
def test_batched_exact_fitness_equals_library_calls(samples, name):
    protocol = next(p for p in ex.PROTOCOLS if p.name == name)
    ref = [_library_fitness(samples, i, protocol) for i in range(len(samples))]
    np.testing.assert_allclose(ex.exact_fitness_batch(samples, protocol), ref, rtol=0, atol=1e-14)


def test_authors_protocol_equals_a_direct_computation(samples):
    """The 'paper' protocol (Eq. 2 as printed, the authors' transects arange(-0.5, 0.5, s) +
    x_offset and step 1/points) against a plain numpy computation of Eq. 2-7 and a shapely
    discrete fitness."""
    protocol = ex.PROTOCOLS[0]
    assert protocol.name == "paper" and protocol.window == "authors"
    temperature, points = 100.0, 200
    got = ex.paper_model_fitness(samples, protocol, temperature, points)
    got_exact = ex.exact_fitness_batch(samples, protocol)
    for i, poly in enumerate(samples.polygons):
        s = samples.spacing[i]
        c = np.arange(-0.5, 0.5, s) + (samples.phase[i] - 0.5) * s
        a = samples.angle[i]
        u, n = np.array([math.cos(a), math.sin(a)]), np.array([-math.sin(a), math.cos(a)])
        t = np.linspace(-0.5, 0.5, points)
        pts = c[:, None, None] * n + t[None, :, None] * u  # (K, P, 2)
        # Eq. 2 as printed: each edge's W has the edge's length (the authors' x1 - x2, y1 - y2,
        # turned by 90 degrees into the inward normal of boustro's frame)
        e = np.roll(poly.vertices, -1, axis=0) - poly.vertices
        normals = np.stack([-e[:, 1], e[:, 0]], axis=1)  # CCW: inward, length |edge|
        offsets = -np.einsum("ij,ij->i", normals, poly.vertices)
        v = pts @ normals.T + offsets
        p = np.exp(-np.logaddexp(0.0, -temperature * v).sum(axis=-1))  # Eq. 4
        p_sigma = 1 / (1 + np.exp(-temperature * (p - 0.5)))  # Eq. 5
        lengths = np.trapezoid(p_sigma, dx=1 / points, axis=-1)  # Eq. 6, the authors' step
        weights = 2 / (1 + np.exp(-temperature * lengths)) - 1  # Eq. 7
        mean = lengths.sum() / weights.sum()
        std = math.sqrt(((weights * (lengths - mean)) ** 2).sum() / weights.sum())
        assert got[i] == pytest.approx(0.5 * mean + 0.5 * (1 - std), abs=1e-12)

        shape = shapely.Polygon(poly.vertices)
        chords = np.array(
            [
                shape.intersection(shapely.LineString([ci * n - 0.5 * u, ci * n + 0.5 * u])).length
                for ci in c
            ]
        )
        chords = chords[chords > 1e-12]
        assert got_exact[i] == pytest.approx(
            0.5 * chords.mean() + 0.5 * (1 - chords.std()), abs=1e-12
        )


def test_no_value_samples_are_counted_not_redrawn():
    thin = Polygon([(0, 0), (1, 0), (0.5, 0.01)]).normalised()
    normal = ex.draw_samples(1, seed=1)
    samples = ex.Samples(
        (thin, normal.polygons[0]),
        np.array([0.0, normal.angle[0]]),  # transects along x: positions are heights
        np.array([0.3, normal.spacing[0]]),
        np.array([0.5, normal.phase[0]]),  # x_offset 0: transects at -0.5, -0.2, 0.1, 0.4
        0,
    )
    protocol = ex.PROTOCOLS[0]
    exact = ex.exact_fitness_batch(samples, protocol)
    assert math.isnan(exact[0]) and math.isfinite(exact[1])
    tables = ex.table1(samples, [protocol], temperatures=(10.0,), points=(100,))
    t = tables["paper"]
    assert t.no_value_discrete == 1 and t.valid[0, 0] == 1 and t.n_samples == 2
    soft = ex.paper_model_fitness(samples, protocol, 10.0, 100)
    assert t.mean[0, 0] == pytest.approx(abs(soft[1] - exact[1]))


# -- samples -------------------------------------------------------------------------------------


@pytest.mark.parametrize("n_vertices", range(3, 10))
def test_polygenerator_polygons(n_vertices):
    rng = np.random.default_rng(n_vertices)
    for _ in range(20):
        poly = ex.polygenerator_convex_polygon(rng, n_vertices)
        assert len(poly) == n_vertices and poly.is_convex
        assert poly.diameter == pytest.approx(1.0, abs=1e-12)
        np.testing.assert_allclose(poly.centre, 0.0, atol=1e-12)


def test_samples_do_not_depend_on_their_number():
    a, b = ex.draw_samples(5, seed=3), ex.draw_samples(12, seed=3).head(5)
    np.testing.assert_array_equal(a.spacing, b.spacing)
    np.testing.assert_array_equal(a.angle, b.angle)
    assert all(
        np.array_equal(p.vertices, q.vertices) for p, q in zip(a.polygons, b.polygons, strict=True)
    )
    assert np.all((a.spacing > 0) & (a.spacing < 1 / 3)) and set(a.n_vertices) <= set(range(3, 10))


# -- optimisers, figures, layering -------------------------------------------------------------


def test_failing_and_missing_optimisers_are_reported_not_fatal():
    def boom(poly, s, seed):
        raise RuntimeError("no luck")

    specs = [
        next(sp for sp in ex.optimizer_specs() if sp.name == "grid"),
        ex.OptimizerSpec("gradient", "always fails", boom),
        ex.OptimizerSpec("global", "missing", None, {}, "not available"),
    ]
    res = ex.compare_optimizers(ex.draw_samples(2, seed=0), specs)
    assert res["methods"]["gradient"]["failures"] == 2
    assert "no luck" in res["methods"]["gradient"]["first_error"]
    assert res["methods"]["gradient"]["fitness"] == [None, None]
    assert res["methods"]["global"]["available"] is False
    assert res["comparisons"]["gradient"] == {"n": 0}
    report = ex.render_report(optimizers_json=res)
    assert "not available" in report and "no luck" in report


def test_figures_have_labelled_axes():
    data = ex.figure_data(quick=True)
    f = data["fitness_vs_angle"]
    # At T = 10000 the paper's model follows the exact fitness closely (Fig. 5).
    assert np.mean(np.abs(f["paper_model"] - f["exact"])) < 0.01
    assert data["surface_angle_temperature"]["fitness"].shape == (10, 36)
    for name, draw in ex.FIGURES.items():
        fig = draw(data)
        for ax in fig.axes:
            if ax.get_label() == "<colorbar>":
                assert "dimensionless" in ax.get_ylabel()
                continue
            assert "(" in ax.get_xlabel() and "(" in ax.get_ylabel(), name  # units


def test_importing_experiments_pulls_in_no_plotting():
    code = "import sys, boustro.experiments; print('matplotlib' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
