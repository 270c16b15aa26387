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

    assert sorted(cli_plan.cli_objectives()) == ["fewest-transects", "smith"]
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
