"""The settings of the learned planner: its network's and its training's (no torch: the command
line reads their defaults for its help)."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["PlannerConfig", "TrainConfig"]


@dataclass(frozen=True)
class PlannerConfig:
    """Hyperparameters of :class:`LearnedPlanner` (saved next to the weights as JSON)."""

    hidden: int = 64
    hypotheses: int = 16
    rounds: int = 1
    profile: bool = True  # chord-length profile near both extremes as offset-head features


@dataclass(frozen=True)
class TrainConfig:
    """Settings of :func:`train_planner` (the defaults made the shipped weights)."""

    epochs: int = 30
    steps_per_epoch: int = 40
    batch_size: int = 128
    pool: int = 6000  # random polygons generated once; spacings are redrawn every batch
    validation: int = 256
    lr: float = 3e-3
    weight_decay: float = 1e-5
    smoothing_start: float = 0.2  # fractions of the spacing, annealed geometrically
    smoothing_end: float = 0.02
    wta_temperature: float = 0.01  # soft winner-takes-all over the hypotheses (fitness units)
    wta_floor: float = 0.05  # weight of the plain mean of the hypotheses in the loss
    min_spacing: float = 0.01
    max_spacing: float = 1.0 / 3.0
    seed: int = 0
    threads: int | None = 1  # the shipped weights were trained on 1 thread
