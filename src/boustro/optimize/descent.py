"""Batched gradient ascent through a guiding model, scored by the exact model."""

from __future__ import annotations

import math
import time
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from .._torch import torch
from ..models import (
    TransectModel,
)
from .problem import _no_transect, _Problem, _progress_bar, _zoom, evaluate_pairs
from .result import OptimizeResult, canonical
from .schedule import TemperatureSchedule, _with_temperature

__all__ = [
    "DescentSettings",
]


def _wrap_(
    theta: torch.Tensor, offset: torch.Tensor, s_n: float, optimizer: torch.optim.Optimizer
) -> torch.Tensor:
    """Wrap angles into ``[0, pi)`` and offsets into ``[0, s_n)`` IN PLACE; returns the flips.

    The parameters stay the same tensors (the optimizer keeps updating them; replacing the
    tensor, as the authors' code did on wrap-around, freezes it). An odd number of half-turns
    maps ``(theta, d)`` to ``(theta - k pi, -d)``, the same layout; the offset's velocity flips
    with it, so the momentum buffer (SGD) and first moment (Adam) of those starts change sign.
    Adam's second moment is even in the sign and stays.
    """
    with torch.no_grad():
        turns = torch.floor(theta / math.pi)
        theta.sub_(turns * math.pi)
        over = theta >= math.pi  # rounding just below a multiple of pi
        theta.copy_(torch.where(over, theta - math.pi, theta).clamp_(min=0.0))
        turns = turns + over
        flip = torch.remainder(turns, 2) == 1
        sign = torch.where(flip, -1.0, 1.0).to(offset.dtype)
        offset.mul_(sign)
        offset.copy_(torch.remainder(offset, s_n))
        offset.copy_(torch.where(offset >= s_n, offset - s_n, offset).clamp_(min=0.0))
        if bool(flip.any()):
            state = optimizer.state.get(offset, {})
            for key in ("momentum_buffer", "exp_avg"):
                buf = state.get(key)
                if isinstance(buf, torch.Tensor):
                    buf.mul_(sign)
    return flip


class DescentSettings(NamedTuple):
    """Validated settings of one batched descent (:class:`~boustro.optimize.GradientOptions`)."""

    model: TransectModel
    optimizer: str  # "adam" or "sgd"
    steps: int
    lr_angle: float
    lr_offset: float  # normalised frame
    lr_decay: float
    momentum: float
    schedule: TemperatureSchedule | None
    patience: int
    tol: float
    check_every: int
    progress: bool | None


class _Descent(NamedTuple):
    best_score: float  # sign * fitness of the best iterate
    best_angle: float
    best_offset: float  # normalised
    evaluations: int
    history: NDArray[np.float64]  # (steps + 1, 3) best so far: angle, offset (normalised), fitness
    trajectory: NDArray[np.float64]  # (steps + 1, S, 2): angle, offset (normalised)
    start_best: torch.Tensor  # (S, 3): each start's best iterate: score, angle, offset
    steps: int
    stopped: str
    temperature: float | None


class _Tracker:
    """The exact scores of a descent's iterates: the best overall, each start's best, the
    history of the best so far, and the steps since it last improved."""

    def __init__(self, p: _Problem, theta: torch.Tensor, offset: torch.Tensor) -> None:
        self.p = p
        self.n_starts = int(theta.shape[0])
        self.best = (-math.inf, float(theta.detach()[0]), float(offset.detach()[0]))
        self.history: list[tuple[float, float, float]] = []
        self.start_best = torch.full((self.n_starts, 3), -math.inf, dtype=theta.dtype)
        self.since_improved = 0

    def check(self, trajectory: list[torch.Tensor]) -> None:
        """Score the iterates since the last check; update the bests, history, since_improved."""
        p, history = self.p, self.history
        pending = torch.stack(trajectory[len(history) :])  # (n, S, 2)
        values = p.sign * evaluate_pairs(
            p.hp, pending[..., 0].flatten(), pending[..., 1].flatten(), p.s_n, fitness=p.fitness
        ).reshape(pending.shape[:2])
        top, when = values.max(dim=0)
        better = top > self.start_best[:, 0]
        found = torch.cat([top[:, None], pending[when, torch.arange(self.n_starts)]], dim=1)
        self.start_best[better] = found[better]
        per_step, which = values.max(dim=1)
        for i in range(len(per_step)):
            if float(per_step[i]) > self.best[0] + 1e-9:
                k = int(which[i])
                self.best = (
                    float(per_step[i]),
                    float(pending[i, k, 0]),
                    float(pending[i, k, 1]),
                )
                self.since_improved = 0
            elif history:
                self.since_improved += 1
            history.append(self.best)


def _start(
    p: _Problem, theta0: torch.Tensor, offset0: torch.Tensor, settings: DescentSettings
) -> tuple[torch.Tensor, torch.Tensor, torch.optim.Optimizer]:
    """The parameters (wrapped) and their optimizer; a start that no transect crosses has no
    gradient to follow: it is moved to offset 0, whose transect crosses the vertex mean."""
    theta = theta0.detach().clone().requires_grad_(True)
    offset = offset0.detach().clone().requires_grad_(True)
    groups = [
        {"params": [theta], "lr": settings.lr_angle},
        {"params": [offset], "lr": settings.lr_offset},
    ]
    if settings.optimizer == "sgd":
        opt: torch.optim.Optimizer = torch.optim.SGD(groups, momentum=settings.momentum)
    else:
        opt = torch.optim.Adam(groups)
    _wrap_(theta, offset, p.s_n, opt)
    with torch.no_grad():
        empty = ~torch.isfinite(evaluate_pairs(p.hp, theta, offset, p.s_n, fitness=p.fitness))
        if bool(empty.any()):
            offset.copy_(torch.where(empty, torch.zeros_like(offset), offset))
    return theta, offset, opt


def _step(
    p: _Problem,
    theta: torch.Tensor,
    offset: torch.Tensor,
    opt: torch.optim.Optimizer,
    settings: DescentSettings,
    step: int,
) -> float | None:
    """One gradient step of every start (then wrapped); returns the guide's temperature."""
    steps, temperature = settings.steps, None
    if settings.lr_decay != 1.0 and steps > 1:
        factor = settings.lr_decay ** (step / (steps - 1))
        lrs = (settings.lr_angle, settings.lr_offset)
        for group, lr in zip(opt.param_groups, lrs, strict=True):
            group["lr"] = lr * factor
    guide = settings.model
    if settings.schedule is not None:
        temperature = settings.schedule(step, steps)
        guide = _with_temperature(settings.model, temperature)
    opt.zero_grad(set_to_none=True)
    objective = p.sign * p.fitness(guide(p.hp, theta, offset, p.s_n))
    (-objective.sum()).backward()  # starts are independent: each gets its own gradient
    for param in (theta, offset):  # a NaN gradient would poison the momentum
        if param.grad is None:  # a guide that ignores this parameter
            param.grad = torch.zeros_like(param)
        torch.nan_to_num_(param.grad, nan=0.0, posinf=0.0, neginf=0.0)
    opt.step()
    _wrap_(theta, offset, p.s_n, opt)
    return temperature


def _descend(
    p: _Problem,
    theta0: torch.Tensor,
    offset0: torch.Tensor,
    settings: DescentSettings,
) -> _Descent:
    """Gradient ascent of ``sign * fitness`` from the starts ``(S,)``, all in one batch.

    A start where no transect crosses the polygon is moved to offset 0 (the transect through
    the polygon's vertex mean always crosses it): there is no gradient to follow from nothing.
    Every iterate of every start (the starts included) is scored with the exact model, in one
    batched call per ``check_every`` steps; the best one is the answer. Stops after ``steps``
    steps, or at a check when the best exact score has not improved by more than 1e-9 for
    ``patience`` steps, or when no start moved more than ``tol`` (radians, and fractions of the
    spacing) in the last step.
    """
    theta, offset, opt = _start(p, theta0, offset0, settings)
    trajectory = [torch.stack([theta.detach(), offset.detach()], dim=-1).clone()]
    track = _Tracker(p, theta, offset)
    stopped, temperature = "steps", None
    steps, tol, check_every = settings.steps, settings.tol, settings.check_every
    bar = _progress_bar(steps, settings.progress, "gradient")
    try:
        for step in range(steps):
            if step % check_every == 0:
                track.check(trajectory)
                if track.since_improved >= settings.patience:
                    stopped = "patience"
                    break
            temperature = _step(p, theta, offset, opt, settings, step)
            trajectory.append(torch.stack([theta.detach(), offset.detach()], dim=-1).clone())
            if bar is not None:
                bar.update(1)
                if step % check_every == 0:
                    bar.set_postfix(fitness=f"{p.sign * track.best[0]:.5f}", refresh=False)
            if tol > 0:
                moved = _circular_distance(trajectory[-1], trajectory[-2], [math.pi, p.s_n])
                if float((moved / moved.new_tensor([1.0, p.s_n])).max()) < tol:
                    stopped = "converged"
                    break
        if len(track.history) < len(trajectory):
            track.check(trajectory)
    finally:
        if bar is not None:
            bar.close()
    n_steps = len(trajectory) - 1
    best = track.best
    return _Descent(
        best_score=best[0],
        best_angle=best[1],
        best_offset=best[2],
        evaluations=track.n_starts * (2 * n_steps + 2),  # a guided gradient, an exact score a step
        history=np.array(track.history)[:, [1, 2, 0]] * np.array([1.0, 1.0, p.sign]),
        trajectory=torch.stack(trajectory).numpy(),
        start_best=track.start_best,
        steps=n_steps,
        stopped=stopped,
        temperature=temperature,
    )


def _circular_distance(
    a: torch.Tensor, b: torch.Tensor, period: float | list[float]
) -> torch.Tensor:
    """Distance between ``a`` and ``b`` on a circle of ``period`` (broadcast on the last axis)."""
    period_t = torch.as_tensor(period, dtype=a.dtype, device=a.device)
    d = torch.remainder(a - b, period_t)
    return torch.minimum(d, period_t - d)


def _zoom_descent(
    p: _Problem,
    descent: _Descent,
    half_angle: float,
    half_offset: float,
    points: int,
    levels: int,
    info: dict[str, Any],
) -> tuple[_Descent, int]:
    """Zoom (:func:`_zoom`) around every start's best iterate; the better of that and ``descent``.

    Records ``info["zoom_fitness"]`` and appends the zoom's answer to the history if it wins.
    """
    if not levels:
        return descent, 0
    centres = descent.start_best[torch.isfinite(descent.start_best[:, 0])]
    if len(centres) == 0:
        return descent, 0
    score, angle, offset, count = _zoom(
        p, centres[:, 1], centres[:, 2], half_angle, half_offset, points, levels
    )
    info["zoom_fitness"] = p.sign * score
    if score > descent.best_score:
        row = np.array([[angle, offset, p.sign * score]])
        descent = descent._replace(
            best_score=score,
            best_angle=angle,
            best_offset=offset,
            history=np.concatenate([descent.history, row]),
        )
    return descent, count


def _result_from_descent(
    p: _Problem, d: _Descent, method: str, t0: float, info: dict[str, Any]
) -> OptimizeResult:
    if not math.isfinite(d.best_score):
        raise _no_transect(p, "at any angle and offset the search visited")
    angle, offset = canonical(d.best_angle, d.best_offset * p.scale, p.spacing)
    history = d.history.copy()
    history[:, 1] *= p.scale
    trajectory = d.trajectory.copy()
    trajectory[..., 1] *= p.scale
    info = {
        **info,
        "steps": d.steps,
        "stopped": d.stopped,
        "final_temperature": d.temperature,
        "trajectory": trajectory,
    }
    return OptimizeResult(
        angle=angle,
        offset=offset,
        fitness=p.sign * d.best_score,
        spacing=p.spacing,
        method=method,
        evaluations=d.evaluations,
        seconds=time.perf_counter() - t0,
        history=history,
        info=info,
    )
