"""Training of the learned planner without labels, through the smooth closed form."""

from __future__ import annotations

import copy
import sys
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from typing import Any, NamedTuple

import numpy as np
import torch
from torch import nn

from ..geometry import random_convex_polygon
from ..objectives import as_plan_objective
from .batch import PlanBatch, batch_objective, from_normalised, random_batch
from .config import TrainConfig
from .network import LearnedPlanner, PlannerConfig, hypotheses

__all__ = ["TrainConfig", "TrainResult", "train_planner"]


@dataclass
class TrainResult:
    """What :func:`train_planner` returns: the trained network and its curves.

    ``history`` holds per step ``loss``, ``train_fitness`` (the soft winner-takes-all fitness
    of the batch, through the smooth model) and ``smoothing``, and per epoch ``val_fitness`` (mean
    exact fitness of the best hypothesis on held-out polygons), ``val_mean_fitness`` (mean over
    all hypotheses) and ``epoch_seconds``; ``initial_val_fitness`` is before any step.
    """

    planner: LearnedPlanner
    config: TrainConfig
    history: dict[str, list[float]] = field(default_factory=dict)
    seconds: float = 0.0

    def metadata(self) -> dict[str, Any]:
        h = self.history
        return {
            "train": asdict(self.config),
            "seconds": round(self.seconds, 1),
            "val_fitness": h["val_fitness"][-1] if h.get("val_fitness") else None,
            "initial_val_fitness": h.get("initial_val_fitness", [None])[0],
            "val_fitness_per_epoch": [round(x, 6) for x in h.get("val_fitness", [])],
            "torch": torch.__version__,
        }


def _validate(net: LearnedPlanner, batch: PlanBatch, objective: Any) -> tuple[float, float]:
    net.eval()
    theta, offset = hypotheses(net, batch)
    values = batch_objective(batch, theta, offset, objective=objective, mask_empty=False)
    net.train()
    return float(values.max(dim=1).values.mean()), float(values.mean())


class _Data(NamedTuple):
    """The training pool (spacings redrawn every batch) and the held-out validation batch."""

    pool: PlanBatch
    val: PlanBatch


def _data(cfg: TrainConfig, rng: np.random.Generator) -> _Data:
    pool_polys = [random_convex_polygon(rng, int(rng.integers(3, 10))) for _ in range(cfg.pool)]
    pool = from_normalised(
        [p.vertices for p in pool_polys],
        np.full(cfg.pool, 0.1),
        np.ones(cfg.pool),
        np.zeros((cfg.pool, 2)),
        torch.float32,
    )
    val = random_batch(
        np.random.default_rng(cfg.seed + 10_000_019),
        cfg.validation,
        min_spacing=cfg.min_spacing,
        max_spacing=cfg.max_spacing,
    )
    return _Data(pool, val)


@dataclass
class _Loop:
    """What one training step needs: the network, its optimiser and schedule, the data."""

    net: LearnedPlanner
    cfg: TrainConfig
    objective: Any
    data: _Data
    rng: np.random.Generator
    opt: torch.optim.Optimizer
    sched: Any
    total: int

    def step(self, step: int) -> tuple[float, float, float]:
        """One Adam step on a random batch: ``(loss, soft winner-takes-all fitness, sigma)``."""
        cfg, net = self.cfg, self.net
        frac = step / max(self.total - 1, 1)
        sigma = cfg.smoothing_start * (cfg.smoothing_end / cfg.smoothing_start) ** frac
        idx = torch.as_tensor(self.rng.integers(0, cfg.pool, cfg.batch_size))
        spacing = self.rng.uniform(cfg.min_spacing, cfg.max_spacing, cfg.batch_size)
        batch = self.data.pool.select(idx)._replace(
            spacing=torch.as_tensor(spacing, dtype=torch.float32)
        )
        pred = net(batch)
        f = batch_objective(
            batch, pred.theta, pred.offset, smoothing=sigma, objective=self.objective
        )
        w = torch.softmax(f.detach() / cfg.wta_temperature, dim=1)
        wta = (w * f).sum(dim=1)
        loss = -(wta + cfg.wta_floor * f.mean(dim=1)).mean()
        self.opt.zero_grad(set_to_none=True)
        loss.backward()
        for p in net.parameters():
            if p.grad is not None:
                torch.nan_to_num_(p.grad, nan=0.0, posinf=0.0, neginf=0.0)
        nn.utils.clip_grad_norm_(net.parameters(), 1.0)
        self.opt.step()
        self.sched.step()
        return float(loss.detach()), float(wta.detach().mean()), sigma


def _bar(progress: bool | None, total: int) -> Any:
    """A tqdm bar on stderr, or ``None``."""
    show = sys.stderr.isatty() if progress is None else bool(progress)
    if not show:
        return None
    from tqdm.auto import tqdm

    return tqdm(total=total, desc="train", file=sys.stderr, unit="step")


def _epochs(
    loop: _Loop,
    history: dict[str, list[float]],
    bar: Any,
    t0: float,
    callback: Callable[[int, dict[str, list[float]]], None] | None,
) -> None:
    """Run every epoch of ``loop``, appending to ``history``."""
    cfg, step = loop.cfg, 0
    for epoch in range(cfg.epochs):
        for _ in range(cfg.steps_per_epoch):
            loss, wta, sigma = loop.step(step)
            history["loss"].append(loss)
            history["train_fitness"].append(wta)
            history["smoothing"].append(sigma)
            step += 1
            if bar is not None:
                bar.update(1)
                if step % 10 == 0:
                    bar.set_postfix(loss=f"{loss:.4f}", refresh=False)
        best, mean = _validate(loop.net, loop.data.val, loop.objective)
        history["val_fitness"].append(best)
        history["val_mean_fitness"].append(mean)
        history["epoch_seconds"].append(time.perf_counter() - t0)
        if bar is not None:
            bar.set_postfix(loss=f"{history['loss'][-1]:.4f}", val=f"{best:.4f}")
        if callback is not None:
            callback(epoch, history)


def train_planner(
    config: TrainConfig | None = None,
    *,
    planner: LearnedPlanner | None = None,
    planner_config: PlannerConfig | None = None,
    objective: Any = None,
    progress: bool | None = None,
    callback: Callable[[int, dict[str, list[float]]], None] | None = None,
) -> TrainResult:
    """Train a :class:`LearnedPlanner` without labels: maximise the smooth fitness of its
    hypotheses on random convex polygons.

    Loss per polygon: ``-(sum_m w_m f_m + wta_floor * mean_m f_m)``, ``f_m`` the objective of
    hypothesis ``m`` through the smooth closed form (smoothing annealed from
    ``smoothing_start`` to ``smoothing_end`` spacings) and ``w = softmax(f / wta_temperature)``
    (detached): a soft winner-takes-all. float32, Adam, cosine learning-rate decay, gradient
    clipping. Validation: exact fitness of the best hypothesis on ``validation`` held-out
    polygons (a separate seed), every epoch.

    Args:
        config: :class:`TrainConfig`.
        planner: a network to continue training from (copied: it is left unchanged; default:
            a new one, seeded).
        planner_config: its hyperparameters when new.
        objective: the training objective (default Eq. 1), see :func:`as_plan_objective`.
        progress: tqdm bar on stderr: True, False, or None (if stderr is a TTY).
        callback: called as ``callback(epoch, history)`` after every epoch.
    """
    cfg = config or TrainConfig()
    obj = as_plan_objective(objective)
    t0 = time.perf_counter()
    old_threads = torch.get_num_threads()
    if cfg.threads:
        torch.set_num_threads(cfg.threads)
    try:
        torch.manual_seed(cfg.seed)
        rng = np.random.default_rng(cfg.seed)
        # a copy: the planner passed in (perhaps the shipped, cached one) stays as it was
        net = copy.deepcopy(planner) if planner is not None else LearnedPlanner(planner_config)
        net.to(torch.float32).train()
        data = _data(cfg, rng)
        total = cfg.epochs * cfg.steps_per_epoch
        opt = torch.optim.AdamW(net.parameters(), lr=cfg.lr, weight_decay=cfg.weight_decay)
        sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, T_max=max(total, 1))
        keys = ("loss", "train_fitness", "smoothing", "val_fitness", "val_mean_fitness")
        history: dict[str, list[float]] = {key: [] for key in (*keys, "epoch_seconds")}
        best0, _ = _validate(net, data.val, obj)
        history["initial_val_fitness"] = [best0]
        bar = _bar(progress, total)
        try:
            _epochs(_Loop(net, cfg, obj, data, rng, opt, sched, total), history, bar, t0, callback)
        finally:
            if bar is not None:
                bar.close()
        net.eval()
        return TrainResult(net, cfg, history, time.perf_counter() - t0)
    finally:
        torch.set_num_threads(old_threads)
