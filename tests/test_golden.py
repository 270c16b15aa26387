"""Stored outputs of every command, so that restructuring the code cannot change what it computes.

Each case runs one ``boustro`` command in-process and compares its JSON output (and the files it
writes) with ``tests/data/golden/<case>.json``, recorded from the code before the restructuring
of issue 15. Numbers must agree to 1e-9 (relative); keys that hold timings, dates, versions or
paths are left out. Values that depend on the CPU's floating-point paths as well as on the code
are compared more loosely (:data:`LOOSE`, :data:`CHAOTIC`). A deliberate change of results
regenerates the files::

    BOUSTRO_REGENERATE_GOLDEN=1 python -m pytest tests/test_golden.py

and the diff of ``tests/data/golden`` shows what changed.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np
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

# Relative tolerance of the cases whose numbers pass through the float32 network of the learned
# planner: on an AMD EPYC (AVX-512) machine they differ from the recording machine's by up to
# 1.4e-7 relative (torch's and its libraries' kernels round differently per CPU), 1e-6 is kept.
LOOSE = {"optimize_learned": 1e-6, "train_tiny": 1e-6}
# Values of the paper's gradient descent from random starts in ``reproduce --quick``: a step that
# rounds differently on another CPU lands in another local optimum (measured on that machine:
# one polygon's fitness 0.910 -> 0.938, a share 0.6 -> 0.8), so below these JSON paths numbers
# are checked as finite and in [-1, 1] only, and :func:`_gradient_consistent` checks how they
# hang together (its options, counts and every other method's values stay exact).
CHAOTIC = (
    "$.rq/optimizers.json.comparisons.gradient.",
    "$.rq/optimizers.json.comparisons.gradient-final.",
    "$.rq/optimizers.json.methods.gradient.fitness[",
    "$.rq/optimizers.json.methods.gradient.final_iterate_fitness[",
    "$.rq/optimizers.json.methods.gradient.mean_fitness",
)

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


def _compare(got, want, where: str = "$", rel: float = 1e-9) -> None:
    """Assert that ``got`` equals ``want``, numbers to ``rel`` relative (or 1e-12 absolute);
    below a :data:`CHAOTIC` path, numbers only finite and in [-1, 1]."""
    if isinstance(want, dict):
        assert isinstance(got, dict), f"{where}: expected an object"
        assert sorted(got) == sorted(want), f"{where}: keys {sorted(got)} != {sorted(want)}"
        for key in want:
            _compare(got[key], want[key], f"{where}.{key}", rel)
    elif isinstance(want, list):
        assert isinstance(got, list) and len(got) == len(want), f"{where}: length differs"
        for i, (g, w) in enumerate(zip(got, want, strict=True)):
            _compare(g, w, f"{where}[{i}]", rel)
    elif isinstance(want, bool) or want is None:
        assert got == want, f"{where}: {got!r} != {want!r}"
    elif isinstance(want, (int, float)):
        assert isinstance(got, (int, float)) and not isinstance(got, bool), f"{where}: {got!r}"
        if math.isnan(want):
            assert math.isnan(got), f"{where}: {got} is not NaN"
        elif where.startswith(CHAOTIC) and isinstance(want, float):
            assert math.isfinite(got) and -1.0 <= got <= 1.0, f"{where}: {got}"
        else:
            assert math.isclose(got, want, rel_tol=rel, abs_tol=1e-12), f"{where}: {got} != {want}"
    elif isinstance(want, str) and _numeric(want) is not None and _numeric(got) is not None:
        _compare(_numeric(got), _numeric(want), where, rel)
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
    _compare(json.loads(json.dumps(got)), want, rel=LOOSE.get(case, 1e-9))
    if case == "reproduce_quick":
        _gradient_consistent(got["rq/optimizers.json"])


def _gradient_consistent(run: dict) -> None:
    """The :data:`CHAOTIC` values agree with each other and with the exact grid's: the mean is
    the mean, the answer is the best iterate (never below the final one), the comparisons are
    of these values, the shares add up to 1."""
    methods, comparisons = run["methods"], run["comparisons"]
    grid = np.array(methods["grid"]["fitness"])
    best = np.array(methods["gradient"]["fitness"])
    final = np.array(methods["gradient"]["final_iterate_fitness"])
    assert len(best) == len(final) == len(grid)
    assert ((best >= 0) & (best <= 1) & (best >= final)).all()
    assert math.isclose(methods["gradient"]["mean_fitness"], best.mean(), rel_tol=1e-9)
    for key, other in (("gradient", best), ("gradient-final", final)):
        row = comparisons[key]
        assert math.isclose(row["mean_grid_minus_other"], (grid - other).mean(), abs_tol=1e-12)
        shares = row["share_grid_higher"] + row["share_other_higher"] + row["share_equal"]
        assert math.isclose(shares, 1.0) and row["n"] == len(grid)


def test_compare_catches_a_change_everywhere_but_below_a_chaotic_path():
    """The comparison itself: a change beyond the tolerance fails, also in a loose case."""
    _compare({"a": [1.0, "2.5"]}, {"a": [1.0 + 1e-10, "2.5"]})
    for got, rel in (({"a": [1.0 + 1e-7, "2.5"]}, 1e-9), ({"a": [1.0, "2.6"]}, 1e-6)):
        with pytest.raises(AssertionError):
            _compare(got, {"a": [1.0, "2.5"]}, rel=rel)
    chaotic = {"rq/optimizers.json": {"methods": {"gradient": {"fitness": [0.5]}}}}
    _compare({"rq/optimizers.json": {"methods": {"gradient": {"fitness": [0.9]}}}}, chaotic)
    with pytest.raises(AssertionError):  # out of range or not a number
        _compare({"rq/optimizers.json": {"methods": {"gradient": {"fitness": [3.0]}}}}, chaotic)
    with pytest.raises(AssertionError):  # the descent's options stay exact
        _compare(
            {"rq/optimizers.json": {"methods": {"gradient": {"options": {"momentum": 0.5}}}}},
            {"rq/optimizers.json": {"methods": {"gradient": {"options": {"momentum": 0.8}}}}},
        )


def test_the_gradient_values_must_hang_together():
    """A review's mutations of the recorded run that the range check alone let through."""
    want = json.loads((GOLDEN / "reproduce_quick.json").read_text(encoding="utf-8"))
    run = want["rq/optimizers.json"]
    _gradient_consistent(run)  # the recorded run itself
    n = len(run["methods"]["gradient"]["fitness"])
    for where, key, value in (
        (("methods", "gradient"), "fitness", [0.0] * n),  # below the final iterates
        (("methods", "gradient"), "mean_fitness", 0.99),
        (("comparisons", "gradient-final"), "share_grid_higher", 0.0),
        (("comparisons", "gradient"), "mean_grid_minus_other", -0.9),
    ):
        broken = json.loads(json.dumps(run))
        broken[where[0]][where[1]][key] = value
        with pytest.raises(AssertionError):
            _gradient_consistent(broken)
