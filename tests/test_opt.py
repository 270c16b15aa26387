"""Part "opt" of issue 15: one objective registry, optimiser dispatch, exact-solver table."""

from __future__ import annotations

from dataclasses import dataclass

import pytest
import torch

from boustro import objectives
from boustro.errors import InvalidParameterError
from boustro.objectives import (
    OBJECTIVES,
    BaseObjective,
    FewestTransects,
    LengthObjective,
    ShortestPath,
    SmithFitness,
    as_plan_objective,
    get_objective,
    register_objective,
)

SQUARE = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]


@pytest.fixture
def clean_objectives():
    saved = dict(OBJECTIVES)
    yield OBJECTIVES
    OBJECTIVES.clear()
    OBJECTIVES.update(saved)


def test_get_objective_accepts_snake_and_kebab_case():
    assert get_objective("fewest_transects") == get_objective("fewest-transects")
    assert isinstance(get_objective("shortest-path"), ShortestPath)
    assert get_objective("smith", a=1.0, b=0.0) == SmithFitness(a=1.0, b=0.0)
    with pytest.raises(InvalidParameterError, match="unknown objective"):
        get_objective("no-such")


def test_builtin_objectives_carry_sense_and_keep_maximise():
    assert (SmithFitness().sense, SmithFitness().maximise) == ("max", True)
    assert (FewestTransects().sense, FewestTransects().maximise) == ("min", False)
    assert (ShortestPath().sense, ShortestPath().needs_chords) == ("min", True)
    assert SmithFitness().needs_chords is False
    assert FewestTransects(maximise=True).sense == "max"


def test_register_objective_and_duplicate(clean_objectives):
    register_objective("longest-mean", SmithFitness)
    assert "longest_mean" in OBJECTIVES
    assert isinstance(get_objective("longest_mean"), SmithFitness)
    with pytest.raises(InvalidParameterError, match="already registered"):
        register_objective("longest_mean", SmithFitness)
    register_objective("longest_mean", FewestTransects, replace=True)
    assert isinstance(get_objective("longest-mean"), FewestTransects)


def test_cli_plan_objectives_come_from_the_registry(clean_objectives):
    from boustro.cli import plan as cli_plan

    assert sorted(cli_plan.cli_objectives()) == ["fewest-transects", "smith", "time"]
    register_objective("my_cost", FewestTransects)
    assert "my-cost" in cli_plan.cli_objectives()


def test_fitness_module_is_an_alias_of_objectives_smith():
    import boustro.fitness
    from boustro.objectives import smith

    assert boustro.fitness is smith


@dataclass(frozen=True)
class _DeclaredCost:
    """A plan objective declared as such, minimised: it must not be sniffed."""

    name: str = "declared_cost"
    maximise: bool = False
    plan_aware: bool = True

    def __call__(self, *args):  # a signature sniffing could not classify
        tl, theta = args[0], args[1]
        return tl.lengths.sum(dim=-1) + theta


def test_declared_plan_objective_is_used_without_sniffing():
    obj = as_plan_objective(_DeclaredCost())
    tl = type("TL", (), {"lengths": torch.ones(2, 3)})()
    value = obj(tl, torch.zeros(2), torch.zeros(2), torch.ones(2))
    assert torch.equal(value, -torch.full((2,), 3.0))


def test_builtin_length_objective_is_wrapped_without_sniffing():
    assert isinstance(as_plan_objective(FewestTransects()), LengthObjective)
    assert isinstance(FewestTransects(), BaseObjective)
    assert isinstance(FewestTransects(), objectives.Objective)


# -- optimize(): option check before the call (defect 2) -----------------------------------


def _scaled(values, *, factor=1.0):
    return factor * values


def _buggy_objective(tl):
    """A user's objective with a bug: a misspelt keyword inside it raises TypeError."""
    return _scaled(tl.lengths.sum(dim=-1), scale=2.0)


def test_typeerror_inside_a_users_objective_propagates():
    from boustro.optimize import optimize

    with pytest.raises(TypeError, match="unexpected keyword argument 'scale'") as info:
        optimize(SQUARE, 0.25, method="grid", fitness=_buggy_objective, n_angles=4)
    assert any(entry.name == "_buggy_objective" for entry in info.traceback)


@pytest.mark.parametrize("method", ["grid", "hybrid", "global"])
def test_unknown_option_is_refused_before_the_call(method):
    from boustro.optimize import optimize

    with pytest.raises(InvalidParameterError, match="takes no option 'n_angle'"):
        optimize(SQUARE, 0.25, method=method, n_angle=4)


# -- method="global": the exact-solver table, hybrid fallback, one option rule (defect 3) --


def _sum_of_lengths(tl):
    return tl.lengths.sum(dim=-1)


def test_global_falls_back_to_hybrid_for_an_objective_without_exact_solver(caplog):
    from boustro.optimize import optimize

    with caplog.at_level("WARNING", logger="boustro"):
        result = optimize(SQUARE, 0.25, method="global", fitness=_sum_of_lengths, steps=5)
    assert result.method == "hybrid"
    assert "no exact optimiser" in result.info["note"]
    assert "hybrid" in caplog.text


def test_plan_area_reaches_the_fallback_with_a_users_objective():
    from boustro import geo

    mission = geo.plan_area(
        [(0, 0), (40, 0), (40, 20), (0, 20)], 5.0, crs=None, fitness=_sum_of_lengths
    )
    assert mission.optimum.method == "hybrid"


@pytest.mark.parametrize("objective", [SmithFitness(), FewestTransects(), ShortestPath()])
def test_global_option_check_is_the_same_for_every_objective(objective):
    from boustro.optimize import optimize

    with pytest.raises(InvalidParameterError, match="takes no option 'bogus'"):
        optimize(SQUARE, 0.25, method="global", fitness=objective, bogus=1)


def test_exact_table_is_keyed_by_objective_type():
    from boustro.optimize.exact import EXACT, exact_solver, global_optimum

    assert set(EXACT) == {SmithFitness, FewestTransects, ShortestPath}
    assert exact_solver(SmithFitness(a=1.0, b=0.0)) is global_optimum

    class Tweaked(SmithFitness):
        pass

    assert exact_solver(Tweaked()) is None  # a subclass may compute something else
    assert exact_solver(FewestTransects(maximise=True)) is None  # not what its solver does


# -- the method registry reaches `boustro optimize` (defect 4), lazy "learned" -------------


def test_registered_method_reaches_the_optimize_command(tmp_path, capsys):
    import json

    from boustro.cli import main
    from boustro.optimize import METHODS, OptimizeResult, register_method

    def constant(polygon, spacing, *, fitness=None, progress=None):
        return OptimizeResult(0.25, 0.0, 0.5, spacing, "constant", 1, 0.0)

    path = tmp_path / "square.json"
    path.write_text(json.dumps([[0, 0], [4, 0], [4, 4], [0, 4]]))
    register_method("constant-cli-test", constant)
    try:
        code = main(
            ["optimize", str(path), "--spacing", "1", "--method", "constant-cli-test", "--json"]
        )
    finally:
        METHODS.pop("constant-cli-test")
    out = capsys.readouterr().out
    assert code == 0
    assert json.loads(out)["method"] == "constant"


def test_learned_is_a_declared_lazy_entry():
    from boustro.optimize import METHODS, resolve_method

    assert METHODS["learned"] == "boustro.learned:learned"
    import boustro.learned

    assert resolve_method("learned") is boustro.learned.learned


def test_boustro_plan_with_a_registered_objective_falls_back_to_hybrid(capsys, caplog):
    import json

    from boustro.cli import main

    register_objective("length-sum-test", lambda: _sum_of_lengths)
    try:
        with caplog.at_level("WARNING", logger="boustro"):
            code = main(["plan", "--objective", "length-sum-test", "--json"])
    finally:
        OBJECTIVES.pop("length_sum_test")
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert json.loads(captured.out)["method"] == "hybrid"  # was refused with advice for Eq. 1
    assert "no exact optimiser" in caplog.text
