"""Named objectives of a transect layout, and the one registry of their names."""

from __future__ import annotations

from .base import _DIRECTION_FLAGS as _DIRECTION_FLAGS  # re-exported (private)
from .base import (
    BaseObjective,
    Objective,
    PlanObjective,
    Sense,
    objective_sense,
    objective_sign,
)
from .path import ShortestPath, path_length
from .plan_objective import LengthObjective, PreferredAngle, as_plan_objective
from .plan_objective import _Negated as _Negated  # re-exported (private)
from .registry import OBJECTIVES, get_objective, objective_key, register_objective
from .smith import SmithFitness, smith_fitness
from .time import MissionTime
from .turns import GRAZE, FewestTransects, coverage_count

__all__ = [
    "GRAZE",
    "OBJECTIVES",
    "BaseObjective",
    "FewestTransects",
    "LengthObjective",
    "MissionTime",
    "Objective",
    "PlanObjective",
    "PreferredAngle",
    "Sense",
    "ShortestPath",
    "SmithFitness",
    "as_plan_objective",
    "coverage_count",
    "get_objective",
    "objective_key",
    "objective_sense",
    "objective_sign",
    "path_length",
    "register_objective",
    "smith_fitness",
]

OBJECTIVES.discover()  # every module of the package registers its objectives
