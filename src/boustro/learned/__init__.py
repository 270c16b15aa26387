"""A learned planner: a small network trained through the differentiable fitness.

Lifecycle: :mod:`~boustro.learned.batch` (polygons as padded tensors, batched scoring),
:mod:`~boustro.learned.network` (the network), :mod:`~boustro.learned.weights` (save, load),
:mod:`~boustro.learned.refine` (batched refinement), :mod:`~boustro.learned.infer` (answers),
:mod:`~boustro.learned.train` (training). The design is described in ``docs/learned.md``.
"""

from __future__ import annotations

from ..objectives import LengthObjective, PlanObjective, PreferredAngle, as_plan_objective
from .batch import PlanBatch, batch_lengths, batch_objective, make_batch, random_batch
from .infer import BatchResult, learned, learned_batch, warm_start
from .network import LearnedPlanner, PlannerConfig, Prediction
from .refine import NUDGE as NUDGE  # defined here before, not in __all__
from .refine import RefineOptions, refine
from .train import TrainConfig, TrainResult, train_planner
from .weights import DEFAULT_WEIGHTS, check_weights_path, load_planner, save_planner

__all__ = [
    "DEFAULT_WEIGHTS",
    "BatchResult",
    "LearnedPlanner",
    "LengthObjective",
    "PlanBatch",
    "PlanObjective",
    "PlannerConfig",
    "Prediction",
    "PreferredAngle",
    "RefineOptions",
    "TrainConfig",
    "TrainResult",
    "as_plan_objective",
    "batch_lengths",
    "batch_objective",
    "check_weights_path",
    "learned",
    "learned_batch",
    "load_planner",
    "make_batch",
    "random_batch",
    "refine",
    "save_planner",
    "train_planner",
    "warm_start",
]
