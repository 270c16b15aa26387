"""A learned planner: a small network trained through the differentiable fitness.

Lifecycle: :mod:`~boustro.learned.batch` (polygons as padded tensors, batched scoring),
:mod:`~boustro.learned.network` (the network), :mod:`~boustro.learned.weights` (save, load),
:mod:`~boustro.learned.refine` (batched refinement), :mod:`~boustro.learned.infer` (answers),
:mod:`~boustro.learned.train` (training). The design is described in ``docs/learned.md``.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from ..objectives import LengthObjective, PlanObjective, PreferredAngle, as_plan_objective
from .batch import PlanBatch, batch_lengths, batch_objective, make_batch, random_batch
from .config import PlannerConfig, TrainConfig
from .refine import NUDGE as NUDGE  # defined here before, not in __all__
from .refine import RefineOptions, refine

if TYPE_CHECKING:
    from .infer import BatchResult, learned, learned_batch, warm_start
    from .network import LearnedPlanner, Prediction
    from .train import TrainResult, train_planner
    from .weights import DEFAULT_WEIGHTS, check_weights_path, load_planner, save_planner

#: The names of the modules that import torch (the network's), each imported on its first use
#: (PEP 562), so that ``import boustro.learned`` (``train``'s options) imports no torch.
_LAZY = {
    **dict.fromkeys(("BatchResult", "learned", "learned_batch", "warm_start"), "infer"),
    **dict.fromkeys(("LearnedPlanner", "Prediction"), "network"),
    **dict.fromkeys(("TrainResult", "train_planner"), "train"),
    **dict.fromkeys(
        ("DEFAULT_WEIGHTS", "check_weights_path", "load_planner", "save_planner"), "weights"
    ),
}


def __getattr__(name: str) -> object:
    """A name of :data:`_LAZY`, from its module, imported on first use."""
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


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
