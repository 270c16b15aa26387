"""`boustro optimize`, tested in-process on exit code and output."""

import json

import pytest

from boustro.cli import main
from boustro.optimize import METHODS, exact_fitness
from boustro.optimize.smith_bb import DEFAULT_TOL
from boustro.scoring import as_polygon

from .conftest import run_cli

PARALLELOGRAM = [[8, 4], [8, 10], [4, 8], [4, 2]]

SCORE_KEYS = (
    "fitness",
    "angle_deg",
    "offset",
    "spacing",
    "model",
    "n_transects",
    "total_length",
    "lengths",
    "transects",
    "a",
    "b",
    "clip",
)


run = run_cli


@pytest.fixture
def polygon_file(tmp_path):
    path = tmp_path / "p.json"
    path.write_text(json.dumps(PARALLELOGRAM))
    return path


@pytest.mark.parametrize("method", list(METHODS))  # every registered method
def test_json_contract(capsys, polygon_file, method):
    steps = ["--steps", "30"] if method in ("gradient", "hybrid") else []
    code, out, err = run(
        capsys,
        "optimize",
        str(polygon_file),
        "--spacing",
        "0.5",
        "--method",
        method,
        *steps,
        "--json",
    )
    assert code == 0, err
    data = json.loads(out)  # stdout is one JSON object and nothing else
    assert set(SCORE_KEYS) <= set(data)
    assert data["method"] == method
    assert isinstance(data["evaluations"], int) and data["evaluations"] > 0
    assert data["seconds"] > 0
    assert data["model"] == "exact" and data["spacing"] == 0.5
    assert 0 <= data["angle_deg"] < 180 and 0 <= data["offset"] < 0.5
    assert len(data["lengths"]) == len(data["transects"]) == data["n_transects"] > 0
    # The same keys and values as `boustro score` at the optimum.
    code, out, err = run(
        capsys,
        "score",
        str(polygon_file),
        "--spacing",
        "0.5",
        "--angle",
        repr(data["angle_deg"]),
        "--offset",
        repr(data["offset"]),
        "--json",
    )
    assert code == 0, err
    scored = json.loads(out)
    certificate = {"upper_bound", "gap", "bound_model", "certified", "note"}  # certified methods
    assert set(scored) == set(data) - {"method", "evaluations", "seconds"} - certificate
    assert scored["fitness"] == pytest.approx(data["fitness"], abs=1e-9)
    assert scored["n_transects"] == data["n_transects"]


def test_json_fitness_is_the_exact_optimum(capsys):
    code, out, _ = run(capsys, "optimize", "--method", "grid", "--paper-grid", "--json")
    assert code == 0
    data = json.loads(out)
    assert data["evaluations"] == 196
    polygon = as_polygon(PARALLELOGRAM)
    angle = data["angle_deg"] * 3.141592653589793 / 180
    assert data["fitness"] == pytest.approx(exact_fitness(polygon, 0.5, angle, data["offset"]))


def test_human_output_and_plot(capsys, polygon_file, tmp_path):
    image = tmp_path / "layout.png"
    code, out, err = run(
        capsys,
        "-q",
        "optimize",
        str(polygon_file),
        "--spacing",
        "0.5",
        "--method",
        "hybrid",
        "--steps",
        "10",
        "--plot",
        str(image),
    )
    assert code == 0, err
    for label in ("angle", "offset", "fitness", "transects", "total length", "method"):
        assert label in out
    assert image.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_options_reach_the_method(capsys):
    argv = ["optimize", "--method", "grid", "--angles", "7", "--offsets", "3", "--json"]
    code, out, _ = run(capsys, *argv)
    assert code == 0 and json.loads(out)["evaluations"] == 21
    argv = [
        "optimize",
        "--method",
        "gradient",
        "--starts",
        "2",
        "--steps",
        "5",
        "--schedule",
        "40:80",
        "--seed",
        "3",
        "--json",
    ]
    code, first, _ = run(capsys, *argv)
    code2, again, _ = run(capsys, *argv)
    assert code == code2 == 0
    a, b = json.loads(first), json.loads(again)
    assert (a["angle_deg"], a["offset"], a["fitness"]) == (
        b["angle_deg"],
        b["offset"],
        b["fitness"],
    )


def test_unused_option_warns(capsys, caplog):
    code, _, _ = run(capsys, "optimize", "--method", "grid", "--seed", "4", "--paper-grid")
    assert code == 0 and "--seed is not used by --method grid" in caplog.text


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["optimize", "missing.json", "--spacing", "1"], "no such file"),
        (["optimize", "{concave}", "--spacing", "0.5"], "convex"),
        (["optimize", "--spacing", "20"], "not smaller than the polygon's diameter"),
        (["optimize", "{polygon}"], "--spacing is required"),
        (["optimize", "--plot", "out.nope"], "unknown image format"),
        (["optimize", "--paper-grid", "--angles", "4"], "--paper-grid fixes the grid"),
    ],
)
def test_bad_input(capsys, tmp_path, polygon_file, argv, message):
    concave = tmp_path / "concave.json"
    concave.write_text(json.dumps([[0, 0], [4, 0], [4, 4], [2, 1], [0, 4]]))
    argv = [a.format(concave=concave, polygon=polygon_file) for a in argv]
    code, out, err = run(capsys, *argv)
    assert code == 2 and out == ""
    assert err.startswith("boustro: error:") and message in err


@pytest.mark.parametrize(
    "argv",
    [
        ["optimize", "--spacing", "-1"],
        ["optimize", "--method", "annealing"],
        ["optimize", "--schedule", "0:10"],
        ["optimize", "--schedule", "1:2:3"],
        ["optimize", "--starts", "0"],
    ],
)
def test_bad_arguments(capsys, argv):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    assert "error" in capsys.readouterr().err


def test_global_method_reports_a_certified_gap(capsys):
    code = main(["optimize", "--method", "global", "--json"])
    out = capsys.readouterr().out
    assert code == 0
    data = json.loads(out)
    assert data["method"] == "global"
    assert 0 <= data["gap"] <= 1e-6
    assert data["upper_bound"] >= data["fitness"]
    # no grid layout beats the certified optimum
    code = main(["optimize", "--method", "grid", "--angles", "720", "--offsets", "40", "--json"])
    assert json.loads(capsys.readouterr().out)["fitness"] <= data["upper_bound"]


def test_learned_method(capsys):
    for extra in ([], ["--refine"]):
        code = main(["optimize", "--method", "learned", *extra, "--json"])
        data = json.loads(capsys.readouterr().out)
        assert code == 0 and data["method"] == "learned"
        assert 0.25 <= data["fitness"] <= 1.0


def test_tol_help_names_the_default_of_each_certified_method(capsys):
    # QA: the help said "global: ... (default 1e-6)" while --tol also sets certified-bb's gap,
    # whose default is smith_bb.DEFAULT_TOL
    with pytest.raises(SystemExit):
        main(["optimize", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "global and certified-bb" in text
    assert f"{DEFAULT_TOL:g} for certified-bb" in text and "1e-6 for global" in text
