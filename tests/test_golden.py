"""Stored outputs of every command, so that restructuring the code cannot change what it computes.

Each case runs one ``boustro`` command in-process and compares its JSON output (and the files it
writes) with ``tests/data/golden/<case>.json``, recorded from the code before the restructuring
of issue 15. Numbers must agree to 1e-9 (relative); keys that hold timings, dates, versions or
paths are left out. A deliberate change of results regenerates the files::

    BOUSTRO_REGENERATE_GOLDEN=1 python -m pytest tests/test_golden.py

and the diff of ``tests/data/golden`` shows what changed.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import pytest

from .conftest import run_cli

GOLDEN = Path(__file__).parent / "data" / "golden"
REGENERATE = os.environ.get("BOUSTRO_REGENERATE_GOLDEN") == "1"

# Keys whose values depend on the machine, the clock or the paths of this run.
VOLATILE = {
    "seconds",
    "total_seconds",
    "date",
    "load_start",
    "command",
    "boustro",
    "torch",
    "threads",
    "cpus",
    "weights",
    "config",
    "plot",
    "written",
    "median_ms",
    "ms",
    "time_ms",
}

# A concave area with a hole, in plain planar coordinates (an L with a square pond).
L_WITH_HOLE = "POLYGON ((0 0, 60 0, 60 20, 25 20, 25 50, 0 50, 0 0), (5 5, 15 5, 15 15, 5 15, 5 5))"

CASES: dict[str, list[str]] = {
    "plan_embedded": ["plan", "--json", "--out", "{tmp}/plan.geojson"],
    "plan_embedded_qgc": [
        "plan",
        "--json",
        "--altitude",
        "30",
        "--speed",
        "5",
        "--turn-time",
        "8",
        "--out",
        "{tmp}/mission.plan",
    ],
    "plan_embedded_wpl": [
        "plan",
        "--json",
        "--altitude",
        "30",
        "--objective",
        "fewest-transects",
        "--out",
        "{tmp}/mission.waypoints",
    ],
    "plan_embedded_hybrid": ["plan", "--json", "--method", "hybrid", "--spacing", "12"],
    "plan_concave": [
        "plan",
        "{tmp}/area.wkt",
        "--crs",
        "planar",
        "--spacing",
        "4",
        "--json",
        "--out",
        "{tmp}/concave.geojson",
    ],
    "plan_concave_decompose": [
        "plan",
        "{tmp}/area.wkt",
        "--crs",
        "planar",
        "--spacing",
        "4",
        "--decompose",
        "--json",
    ],
    "optimize_global": ["optimize", "--json", "--method", "global"],
    "optimize_grid": ["optimize", "--json", "--method", "grid"],
    "optimize_hybrid": ["optimize", "--json", "--method", "hybrid"],
    "optimize_gradient": ["optimize", "--json", "--method", "gradient"],
    "optimize_learned": ["optimize", "--json", "--method", "learned", "--refine"],
    "optimize_paper_grid": ["optimize", "--json", "--method", "grid", "--paper-grid"],
    "score_exact": ["score", "--json", "--angle", "30", "--offset", "0.1"],
    "score_paper": [
        "score",
        "--json",
        "--angle",
        "30",
        "--offset",
        "0.1",
        "--model",
        "paper",
        "--temperature",
        "1000",
    ],
    "score_soft": ["score", "--json", "--angle", "30", "--offset", "0.1", "--model", "soft"],
    "train_tiny": [
        "train",
        "--epochs",
        "1",
        "--steps-per-epoch",
        "2",
        "--batch-size",
        "8",
        "--pool",
        "64",
        "--validation",
        "16",
        "--json",
        "--out",
        "{tmp}/w.pt",
    ],
    "reproduce_quick": ["reproduce", "--quick", "--out", "{tmp}/rq"],
}

# Files a case writes, compared as well (JSON parsed; text line by line).
FILES = {
    "plan_embedded": ["plan.geojson"],
    "plan_embedded_qgc": ["mission.plan"],
    "plan_embedded_wpl": ["mission.waypoints"],
    "plan_concave": ["concave.geojson"],
    "reproduce_quick": ["rq/table1.json", "rq/optimizers.json", "rq/figures.json"],
}


def _strip(value):
    if isinstance(value, dict):
        return {k: _strip(v) for k, v in value.items() if k not in VOLATILE}
    if isinstance(value, list):
        return [_strip(v) for v in value]
    return value


def _load(path: Path):
    text = path.read_text(encoding="utf-8")
    if path.suffix in (".json", ".geojson", ".plan"):
        return _strip(json.loads(text))
    return [line.split("\t") for line in text.splitlines()]


def _numeric(text: str):
    try:
        return float(text)
    except ValueError:
        return None


def _compare(got, want, where: str = "$") -> None:
    """Assert that ``got`` equals ``want``, numbers to 1e-9 relative (or 1e-12 absolute)."""
    if isinstance(want, dict):
        assert isinstance(got, dict), f"{where}: expected an object"
        assert sorted(got) == sorted(want), f"{where}: keys {sorted(got)} != {sorted(want)}"
        for key in want:
            _compare(got[key], want[key], f"{where}.{key}")
    elif isinstance(want, list):
        assert isinstance(got, list) and len(got) == len(want), f"{where}: length differs"
        for i, (g, w) in enumerate(zip(got, want, strict=True)):
            _compare(g, w, f"{where}[{i}]")
    elif isinstance(want, bool) or want is None:
        assert got == want, f"{where}: {got!r} != {want!r}"
    elif isinstance(want, (int, float)):
        assert isinstance(got, (int, float)) and not isinstance(got, bool), f"{where}: {got!r}"
        if math.isnan(want):
            assert math.isnan(got), f"{where}: {got} is not NaN"
        else:
            assert math.isclose(got, want, rel_tol=1e-9, abs_tol=1e-12), f"{where}: {got} != {want}"
    elif isinstance(want, str) and _numeric(want) is not None and _numeric(got) is not None:
        _compare(_numeric(got), _numeric(want), where)
    else:
        assert got == want, f"{where}: {got!r} != {want!r}"


@pytest.mark.parametrize("case", sorted(CASES))
def test_outputs_unchanged(case, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "area.wkt").write_text(L_WITH_HOLE, encoding="utf-8")
    argv = ["-q", *[a.format(tmp=tmp_path) for a in CASES[case]]]
    code, out, err = run_cli(capsys, *argv)
    assert code == 0, err
    got: dict = {"stdout": _strip(json.loads(out)) if out.strip().startswith("{") else None}
    for name in FILES.get(case, []):
        got[name] = _load(tmp_path / name)
    path = GOLDEN / f"{case}.json"
    if REGENERATE:
        path.write_text(json.dumps(got, indent=1, sort_keys=True) + "\n", encoding="utf-8")
    want = json.loads(path.read_text(encoding="utf-8"))
    _compare(json.loads(json.dumps(got)), want)
