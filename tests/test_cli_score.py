"""`boustro score`, tested in-process on exit code and output."""

import json
import math

import pytest

from boustro import __version__
from boustro.cli import main

from .conftest import run_cli

PARALLELOGRAM = [[8, 4], [8, 10], [4, 8], [4, 2]]


run = run_cli


@pytest.fixture
def polygon_file(tmp_path):
    path = tmp_path / "p.json"
    path.write_text(json.dumps(PARALLELOGRAM))
    return path


def test_version(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert __version__ in capsys.readouterr().out


def test_no_command_prints_help(capsys):
    code, _, err = run(capsys)
    assert code == 2 and "score" in err


def test_json_contract(capsys, polygon_file):
    code, out, err = run(
        capsys,
        "score",
        str(polygon_file),
        "--spacing",
        "0.5",
        "--angle",
        "30",
        "--offset",
        "0.1",
        "--json",
    )
    assert code == 0, err
    data = json.loads(out)
    for key in ("fitness", "angle_deg", "offset", "spacing", "model", "lengths", "transects"):
        assert key in data
    assert data["angle_deg"] == pytest.approx(30.0)
    assert data["model"] == "exact" and data["spacing"] == 0.5 and data["offset"] == 0.1
    assert len(data["lengths"]) == len(data["transects"]) == data["n_transects"] > 0
    for (x1, y1), (x2, y2) in data["transects"][:1]:
        assert math.hypot(x2 - x1, y2 - y1) == pytest.approx(data["lengths"][0])
        assert (x2 - x1) * math.cos(math.radians(30)) + (y2 - y1) * math.sin(math.radians(30)) > 0


def test_default_polygon_and_paper_model(capsys):
    code, out, _ = run(capsys, "score", "--model", "paper", "--temperature", "10000", "--json")
    data = json.loads(out)
    assert code == 0 and data["model"] == "paper" and data["temperature"] == 10000
    code, out, _ = run(capsys, "score", "--json")
    assert abs(json.loads(out)["fitness"] - data["fitness"]) < 1e-3


def test_geojson_input(capsys, tmp_path):
    path = tmp_path / "f.geojson"
    ring = [*PARALLELOGRAM, PARALLELOGRAM[0]]
    path.write_text(
        json.dumps(
            {
                "type": "FeatureCollection",
                "features": [
                    {
                        "type": "Feature",
                        "properties": {},
                        "geometry": {"type": "Point", "coordinates": [0, 0]},
                    },
                    {
                        "type": "Feature",
                        "properties": {},
                        "geometry": {
                            "type": "Polygon",
                            "coordinates": [[[x, y, 0] for x, y in ring]],
                        },
                    },
                ],
            }
        )
    )
    code, out, err = run(capsys, "score", str(path), "--spacing", "0.5", "--json")
    assert code == 0, err
    assert json.loads(out)["n_transects"] == 15


def test_human_output(capsys):
    code, out, _ = run(capsys, "score", "--angle", "90")
    assert code == 0 and "fitness" in out and "transects" in out


@pytest.mark.parametrize(
    "content, args, message",
    [
        (None, ["--spacing", "1"], "no such file"),
        ("{not json", ["--spacing", "1"], "malformed JSON"),
        # QA: a KML, WKT or empty file said "malformed JSON at line 1 column 1"
        ("POLYGON ((0 0, 1 0, 0 1, 0 0))", ["--spacing", "1"], "not JSON: a planar polygon"),
        ("<kml></kml>", ["--spacing", "1"], "boustro plan"),
        ("", ["--spacing", "1"], "the file is empty"),
        ('[[0, 0], ["a", 1], [1, 1]]', ["--spacing", "1"], "two numbers"),
        ('{"type": "Point", "coordinates": [0, 0]}', ["--spacing", "1"], "Polygon"),
        (
            "[[0,0],[2,0],[2,1],[1,1],[1,2],[0,2]]",
            ["--spacing", "0.1", "--model", "paper"],
            "convex",
        ),
        ("[[0,0],[1,0],[0,1],[1,1]]", ["--spacing", "0.1"], "self-intersecting"),
        ("[[0,0],[1,0],[0,1]]", [], "--spacing is required"),
        ("[[0,0],[1,0],[0,1]]", ["--spacing", "100", "--offset", "50"], "no transect"),
    ],
)
def test_bad_input_exits_2_with_one_line(capsys, tmp_path, content, args, message):
    path = tmp_path / "in.json"
    if content is not None:
        path.write_text(content)
    code, out, err = run(capsys, "score", str(path), *args)
    assert code == 2
    assert out == ""
    assert message in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1


@pytest.mark.parametrize(
    "args",
    [
        ["--spacing", "0"],
        ["--spacing", "-1"],
        ["--spacing", "nan"],
        ["--angle", "x"],
        ["--temperature", "0"],
        ["--points-per-transect", "1.5"],
    ],
)
def test_bad_numbers_are_usage_errors(capsys, args):
    with pytest.raises(SystemExit) as exc:
        main(["score", *args])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "error" in err and "Traceback" not in err


def test_soft_model(capsys):
    code, out, err = run(
        capsys, "score", "--model", "soft", "--angle", "20", "--offset", "0.1", "--json"
    )
    assert code == 0, err
    soft = json.loads(out)
    assert soft["model"] == "soft" and soft["smoothing"] == pytest.approx(1e-4)
    code, out, _ = run(capsys, "score", "--angle", "20", "--offset", "0.1", "--json")
    assert abs(json.loads(out)["fitness"] - soft["fitness"]) < 1e-3


@pytest.mark.parametrize(
    "argv, quiet, verbose",
    [
        (["-q", "score", "x.json"], True, 0),
        (["score", "x.json", "-q"], True, 0),
        (["score", "x.json"], False, 0),
        (["-v", "score", "x.json"], False, 1),
        (["score", "-v", "x.json"], False, 1),
    ],
)
def test_verbosity_before_or_after_the_command(argv, quiet, verbose):
    from boustro.cli import build_parser

    args = build_parser().parse_args(argv)
    assert (args.quiet, args.verbose) == (quiet, verbose)


@pytest.mark.parametrize("command", ["score", "optimize"])
def test_concave_polygon_points_to_plan(capsys, tmp_path, command):
    """QA round 13: a concave polygon was refused without saying that ``boustro plan`` plans it."""
    path = tmp_path / "l.json"
    path.write_text("[[0,0],[2,0],[2,1],[1,1],[1,2],[0,2]]")
    code, out, err = run(capsys, command, str(path), "--spacing", "0.25")
    assert code == 2 and out == ""
    assert "convex" in err and len(err.strip().splitlines()) == 1
    assert f"boustro plan {path} --crs planar --spacing 0.25" in err
