"""Optimisers over (angle, offset) (layer 4): one interface, one result type.

Every optimiser searches transect angle ``theta`` (radians; the grid is the same under
``(theta + pi, -offset)``, so ``[0, pi)`` covers every layout when the offset is free) and grid
offset ``d`` (periodic in the spacing), and reports the fitness of its answer evaluated with the
EXACT model, whatever model guided the search.

Methods (all reachable through :func:`optimize`):

* ``"grid"`` - :func:`grid_search`: one batched exact evaluation of an angles x offsets grid;
  :data:`GRID_200` is the paper's 200-sample setting.
* ``"gradient"`` - :func:`gradient_descent`: SGD with momentum or Adam through a differentiable
  guiding model (default :data:`DEFAULT_GUIDE`), several starts batched in one tensor, a
  temperature schedule (:data:`DEFAULT_SCHEDULE`), early stopping; starts screened from random
  layouts and a final exact zoom, both optional.
* ``"hybrid"`` - :func:`hybrid`: grid search, batched gradient refinement of the best ``k``
  grid points, an exact zoom; never worse than its grid.

Every stage scores its candidates with the exact model and the answer is the best of them.
More methods plug in with :func:`register_method`.

Objectives are maximised unless they carry ``maximise = False`` (then minimised); a layout where
no transect crosses the polygon is never chosen.
"""

from __future__ import annotations

import dataclasses
import inspect
import math
import re
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, NamedTuple, Protocol

import numpy as np
import torch
from numpy.typing import ArrayLike, NDArray

from .errors import InvalidParameterError, NoTransectError, as_number
from .fitness import SmithFitness
from .geometry import HalfPlanes, Polygon, halfplanes
from .models import ExactModel, PaperModel, TransectLengths, TransectModel, check_spacing
from .models import grid_size as _grid_size
from .objectives import objective_sign
from .scoring import as_polygon

__all__ = [
    "DEFAULT_GUIDE",
    "DEFAULT_SCHEDULE",
    "GRID_200",
    "METHODS",
    "OptimizeResult",
    "TemperatureSchedule",
    "canonical",
    "evaluate_grid",
    "evaluate_pairs",
    "exact_fitness",
    "gradient_descent",
    "grid_search",
    "hybrid",
    "optimize",
    "register_method",
]

#: The paper's 200-sample grid search: 14 angles over [0, 180) degrees x 14 offsets over one
#: spacing (196 evaluations).
GRID_200: dict[str, int] = {"n_angles": 14, "n_offsets": 14}

#: Default guiding model of the gradient methods: the paper's sigmoid integral (Eq. 2-7) with
#: 64 points per transect instead of the paper's 1000, 16 times cheaper per step. Gradient
#: descent needs a smooth surface more than a faithful one (every answer is re-scored with the
#: exact model), and the schedule (:data:`DEFAULT_SCHEDULE`) keeps the temperature at 200 or
#: below, where the sigmoid's transition (about ``4 / T`` wide, 0.02 at T = 200) still spans a
#: trapezoid step (``2 radius / 63``, at most 0.032 in the normalised frame). With 64 points
#: the default hybrid meets its benchmark target (mean gap < 0.005 to a dense grid) at about
#: 35 ms of CPU per polygon; see ``benchmarks/optimizers.py``. The smooth closed form
#: (:class:`boustro.smooth.SmoothModel`, ``model=``) is the more accurate model and cheaper per
#: call (0.49 vs 0.60 ms at 4 starts, 0.50 vs 0.91 ms at 16, parallelogram, one thread), but as
#: the guide it gave slightly larger final gaps on the same 200 polygons (0.00156 at the best
#: schedule tried, against 0.00134; README, "Benchmarks"), so it is not the default.
DEFAULT_GUIDE = PaperModel(temperature=100.0, points_per_transect=64)

#: Upper bound on the elements of one batched exact evaluation (pairs x transects x edges);
#: larger grids are evaluated in chunks of angles.
_CHUNK_ELEMENTS = 4_000_000


class Objective(Protocol):
    """Anything that maps :class:`~boustro.models.TransectLengths` ``(*, K)`` to values ``(*)``.

    Maximised unless it has an attribute ``maximise = False``.
    """

    def __call__(self, tl: TransectLengths) -> torch.Tensor: ...


@dataclass(frozen=True)
class OptimizeResult:
    """The answer of any optimiser, in the user's units.

    Attributes:
        angle: best transect direction, radians in ``[0, pi)``.
        offset: best grid offset, user units in ``[0, spacing)``.
        fitness: objective value at (angle, offset) with the exact model.
        spacing: the spacing searched, user units.
        method: name of the optimiser.
        evaluations: number of (angle, offset) pairs evaluated (by any model; a gradient
            evaluation counts as one).
        seconds: wall time of the search.
        upper_bound: a certified upper bound on the fitness over all layouts, where the method
            gives one (``global``); else ``None``.
        history: optional ``(steps, 3)`` array of (angle, offset, fitness) of the best so far.
        info: method-specific extras (e.g. the number of starts).
    """

    angle: float
    offset: float
    fitness: float
    spacing: float
    method: str
    evaluations: int
    seconds: float
    upper_bound: float | None = None
    history: NDArray[np.float64] | None = None
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def gap(self) -> float | None:
        """``upper_bound - fitness``: how far from optimal the answer can be, if certified."""
        return None if self.upper_bound is None else self.upper_bound - self.fitness


def canonical(angle: float, offset: float, spacing: float) -> tuple[float, float]:
    """The same transect grid with ``angle`` in ``[0, pi)`` and ``offset`` in ``[0, spacing)``."""
    turns = math.floor(angle / math.pi)
    angle -= turns * math.pi
    if angle >= math.pi:  # rounding: pi is the next half-turn, angle 0 with the offset flipped
        angle, turns = 0.0, turns + 1
    if turns % 2:
        offset = -offset
    offset = math.fmod(offset, spacing)
    if offset < 0:
        offset += spacing
    if offset >= spacing:
        offset = 0.0
    return angle, offset


# -- the problem every optimiser solves ------------------------------------------------------


class _Problem(NamedTuple):
    """A validated search problem in the normalised frame."""

    polygon: Polygon
    spacing: float  # user units
    s_n: float  # normalised frame
    scale: float  # user length of one normalised unit
    hp: HalfPlanes
    fitness: Objective
    sign: float  # +1 to maximise, -1 to minimise


def _problem(
    polygon: Polygon | ArrayLike, spacing: float, fitness: Objective | None, what: str
) -> _Problem:
    poly = as_polygon(polygon).require_convex(what)
    spacing = check_spacing(spacing, extent=poly.diameter)
    if spacing >= poly.diameter:
        raise NoTransectError(
            f"spacing {spacing:g} is not smaller than the polygon's diameter {poly.diameter:g} "
            "(its widest extent at any angle): at most one transect can cross it, so there is "
            "no boustrophedon layout to optimise"
        )
    fitness = SmithFitness() if fitness is None else fitness
    sign = objective_sign(fitness)
    frame = poly.frame
    return _Problem(
        poly, spacing, spacing / frame.scale, frame.scale, halfplanes(poly), fitness, sign
    )


def _check_count(name: str, value: Any, low: int = 1) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
        raise InvalidParameterError(f"{name} must be an integer >= {low}, got {value!r}")
    return int(value)


def _check_positive(name: str, value: Any, *, allow_zero: bool = False) -> float:
    v = as_number(name, value)
    if not math.isfinite(v) or v < 0 or (v == 0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise InvalidParameterError(f"{name} must be a finite number {bound}, got {value!r}")
    return v


def _invalid_to_worst(values: torch.Tensor, weights: torch.Tensor, sign: float) -> torch.Tensor:
    """Layouts where no transect counts have no defined fitness: never choose them."""
    worst = -math.inf * sign
    return torch.where((weights.sum(dim=-1) > 0) & ~torch.isnan(values), values, worst)


def _progress_bar(total: int, progress: bool | None, desc: str, unit: str = "step") -> Any:
    """A tqdm bar on stderr, or None: shown when asked, or (``None``) when stderr is a TTY."""
    show = sys.stderr.isatty() if progress is None else bool(progress)
    if not show:
        return None
    from tqdm.auto import tqdm

    return tqdm(total=total, desc=desc, file=sys.stderr, leave=False, unit=unit)


def evaluate_grid(
    hp: HalfPlanes,
    angles: torch.Tensor,
    offsets: torch.Tensor,
    spacing: float,
    *,
    model: TransectModel | None = None,
    fitness: Objective | None = None,
    progress: bool | None = False,
) -> torch.Tensor:
    """Fitness ``(A, O)`` of every pair of ``angles (A,)`` and ``offsets (O,)``, batched.

    Runs in chunks of angles to bound memory (a tqdm bar over the angles on stderr with
    ``progress=True``, or ``None``: if stderr is a TTY and there is more than one chunk).
    Pairs where no transect crosses the polygon get the worst value (``-inf`` for a maximised
    objective, ``+inf`` for a minimised one). Everything is in the half-planes' frame
    (normalised for the paper's scale).
    """
    model = ExactModel() if model is None else model
    fitness = SmithFitness() if fitness is None else fitness
    sign = objective_sign(fitness)
    k_count, _ = _grid_size(spacing, hp.radius)
    per_angle = max(1, len(offsets) * k_count * hp.normals.shape[-2])
    chunk = max(1, _CHUNK_ELEMENTS // per_angle)
    bar = None
    if progress or (progress is None and len(angles) > chunk):
        bar = _progress_bar(len(angles), progress, "grid", unit="angle")
    out = []
    try:
        with torch.no_grad():
            for start in range(0, len(angles), chunk):
                theta = angles[start : start + chunk, None]
                tl = model(hp, theta, offsets[None, :], spacing)
                out.append(_invalid_to_worst(fitness(tl), tl.weights, sign))
                if bar is not None:
                    bar.update(len(theta))
    finally:
        if bar is not None:
            bar.close()
    return torch.cat(out, dim=0)


def evaluate_pairs(
    hp: HalfPlanes,
    angles: torch.Tensor,
    offsets: torch.Tensor,
    spacing: float,
    *,
    model: TransectModel | None = None,
    fitness: Objective | None = None,
) -> torch.Tensor:
    """Fitness ``(N,)`` of the pairs ``(angles[i], offsets[i])``, ``(N,)`` each, batched.

    The element-wise counterpart of :func:`evaluate_grid` (exact model by default, no
    gradient, the worst value where no transect crosses, chunked to bound memory).
    """
    model = ExactModel() if model is None else model
    fitness = SmithFitness() if fitness is None else fitness
    sign = objective_sign(fitness)
    k_count, _ = _grid_size(spacing, hp.radius)
    chunk = max(1, _CHUNK_ELEMENTS // max(1, k_count * hp.normals.shape[-2]))
    out = []
    with torch.no_grad():
        for start in range(0, len(angles), chunk):
            tl = model(hp, angles[start : start + chunk], offsets[start : start + chunk], spacing)
            out.append(_invalid_to_worst(fitness(tl), tl.weights, sign))
    if not out:
        return torch.empty(0, dtype=hp.normals.dtype, device=hp.normals.device)
    return torch.cat(out) if len(out) > 1 else out[0]


def exact_fitness(
    polygon: Polygon,
    spacing: float,
    angle: float,
    offset: float,
    fitness: Objective | None = None,
) -> float:
    """Exact-model fitness of one layout (user units); the worst value if no transect crosses."""
    frame = polygon.frame
    hp = halfplanes(polygon)
    value = evaluate_pairs(
        hp,
        torch.tensor([angle], dtype=torch.float64),
        torch.tensor([offset / frame.scale], dtype=torch.float64),
        spacing / frame.scale,
        fitness=fitness,
    )
    return float(value[0])


# -- grid search ------------------------------------------------------------------------------


def _grid(p: _Problem, n_angles: int, n_offsets: int) -> tuple[torch.Tensor, torch.Tensor]:
    """Angles ``pi i / A`` and offsets ``s j / O``. The fraction ``i / A`` is rounded once, so a
    finer grid whose counts are multiples (42 x 28 of 14 x 14) holds the coarser one's points
    bit for bit."""
    angles = torch.arange(n_angles, dtype=torch.float64) / n_angles * math.pi
    offsets = torch.arange(n_offsets, dtype=torch.float64) / n_offsets * p.s_n
    return angles, offsets


def _no_transect(p: _Problem, where: str) -> NoTransectError:
    return NoTransectError(
        f"no transect crosses the polygon at spacing {p.spacing:g} {where} "
        f"(polygon diameter {p.polygon.diameter:g})"
    )


def grid_search(
    polygon: Polygon | ArrayLike,
    spacing: float,
    *,
    n_angles: int = 180,
    n_offsets: int = 20,
    fitness: Objective | None = None,
    progress: bool | None = False,
) -> OptimizeResult:
    """Exhaustive search on a regular grid of angles in ``[0, pi)`` x offsets in ``[0, s)``.

    One batched exact evaluation (chunked for memory), no Python loop over grid points. The
    paper's 200-sample setting is ``grid_search(p, s, **GRID_200)``. ``progress``: see
    :func:`evaluate_grid`.

    Raises:
        NoTransectError: the spacing is not smaller than the polygon's diameter, or no grid
            point has a transect crossing the polygon.
    """
    t0 = time.perf_counter()
    p = _problem(polygon, spacing, fitness, "grid search")
    n_angles = _check_count("n_angles", n_angles)
    n_offsets = _check_count("n_offsets", n_offsets)
    angles, offsets = _grid(p, n_angles, n_offsets)
    values = evaluate_grid(p.hp, angles, offsets, p.s_n, fitness=p.fitness, progress=progress)
    best = int(torch.argmax(p.sign * values))
    i, j = divmod(best, n_offsets)
    if not math.isfinite(float(values[i, j])):
        raise _no_transect(p, "on any grid point")
    return OptimizeResult(
        angle=float(angles[i]),
        offset=float(offsets[j]) * p.scale,
        fitness=float(values[i, j]),
        spacing=p.spacing,
        method="grid",
        evaluations=n_angles * n_offsets,
        seconds=time.perf_counter() - t0,
        info={"n_angles": n_angles, "n_offsets": n_offsets},
    )


# -- temperature schedules --------------------------------------------------------------------


@dataclass(frozen=True)
class TemperatureSchedule:
    """The guiding model's temperature at each step of gradient descent.

    Constant (``end is None``) or annealed geometrically from ``start`` at the first step to
    ``end`` at the last: ``T_i = start * (end / start) ** (i / (steps - 1))``. The paper
    (Sec. VI) suggests starting low, where the surface is smooth, and raising the temperature
    to refine; ``end < start`` is allowed too.
    """

    start: float
    end: float | None = None

    def __post_init__(self) -> None:
        _check_positive("temperature", self.start)
        if self.end is not None:
            _check_positive("temperature", self.end)

    @classmethod
    def constant(cls, temperature: float) -> TemperatureSchedule:
        return cls(float(temperature))

    @classmethod
    def anneal(cls, start: float, end: float) -> TemperatureSchedule:
        return cls(float(start), float(end))

    def __call__(self, step: int, steps: int) -> float:
        if self.end is None or steps <= 1:
            return self.start
        return self.start * (self.end / self.start) ** (min(step, steps - 1) / (steps - 1))

    def __str__(self) -> str:
        return f"{self.start:g}" if self.end is None else f"{self.start:g}:{self.end:g}"


#: Half-widths of the first zoom window of :func:`gradient_descent` around each start's best
#: iterate: radians, and fractions of the spacing.
ZOOM_ANGLE = 0.05
ZOOM_OFFSET = 0.1

#: Default schedule of the gradient methods: annealed from 50 to 200 (normalised frame). Below
#: about 30 the double sigmoid of Eq. 4-5 melts the polygon into a nearly flat surface (every
#: fitness near ``b``: no gradient to follow); above about 200, 64 points per transect no longer
#: resolve the transition (see :data:`DEFAULT_GUIDE`).
DEFAULT_SCHEDULE = TemperatureSchedule(50.0, 200.0)


def _as_schedule(
    temperature: float | tuple[float, float] | TemperatureSchedule | None,
) -> TemperatureSchedule | None:
    if temperature is None or isinstance(temperature, TemperatureSchedule):
        return temperature
    if isinstance(temperature, (tuple, list)):
        if len(temperature) != 2:
            raise InvalidParameterError(
                f"a temperature schedule is T or (T0, T1), got {temperature!r}"
            )
        return TemperatureSchedule.anneal(*temperature)
    return TemperatureSchedule.constant(_check_positive("temperature", temperature))


def _with_temperature(model: TransectModel, temperature: float) -> TransectModel:
    """``model`` at another temperature.

    Asks the model, in this order: a ``with_temperature(T)`` method; a dataclass field
    ``temperature`` (:class:`~boustro.models.PaperModel`); a ``from_temperature(T, **settings)``
    class method, given those of its keyword arguments that the model has as attributes
    (e.g. ``clip`` of the smooth closed form, whose smoothing length is ``1 / T``).
    """
    if hasattr(model, "with_temperature"):
        return model.with_temperature(temperature)
    if dataclasses.is_dataclass(model) and any(
        f.name == "temperature" for f in dataclasses.fields(model)
    ):
        return dataclasses.replace(model, temperature=temperature)
    factory = getattr(type(model), "from_temperature", None)
    if callable(factory):
        params = list(inspect.signature(factory).parameters.values())[1:]
        settings = {
            q.name: getattr(model, q.name)
            for q in params
            if q.kind is inspect.Parameter.KEYWORD_ONLY and hasattr(model, q.name)
        }
        return factory(temperature, **settings)
    raise InvalidParameterError(
        f"the {getattr(model, 'name', type(model).__name__)} model has no temperature to "
        "schedule; pass temperature=None"
    )


# -- gradient descent -------------------------------------------------------------------------


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


def _descend(
    p: _Problem,
    theta0: torch.Tensor,
    offset0: torch.Tensor,
    *,
    model: TransectModel,
    optimizer: str,
    steps: int,
    lr_angle: float,
    lr_offset: float,
    lr_decay: float,
    momentum: float,
    schedule: TemperatureSchedule | None,
    patience: int,
    tol: float,
    check_every: int,
    progress: bool | None,
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
    n_starts = theta0.shape[0]
    theta = theta0.detach().clone().requires_grad_(True)
    offset = offset0.detach().clone().requires_grad_(True)
    groups = [{"params": [theta], "lr": lr_angle}, {"params": [offset], "lr": lr_offset}]
    if optimizer == "sgd":
        opt: torch.optim.Optimizer = torch.optim.SGD(groups, momentum=momentum)
    else:
        opt = torch.optim.Adam(groups)
    _wrap_(theta, offset, p.s_n, opt)

    with torch.no_grad():  # a start that no transect crosses has no gradient to follow:
        empty = ~torch.isfinite(evaluate_pairs(p.hp, theta, offset, p.s_n, fitness=p.fitness))
        if bool(empty.any()):  # move it to offset 0, whose transect crosses the vertex mean
            offset.copy_(torch.where(empty, torch.zeros_like(offset), offset))
    trajectory = [torch.stack([theta.detach(), offset.detach()], dim=-1).clone()]
    best = (-math.inf, float(theta.detach()[0]), float(offset.detach()[0]))
    history: list[tuple[float, float, float]] = []
    start_best = torch.full((n_starts, 3), -math.inf, dtype=theta.dtype)
    since_improved = 0
    stopped = "steps"
    temperature = None

    def check() -> None:
        """Score the iterates since the last check; update the bests, history, since_improved."""
        nonlocal best, since_improved
        pending = torch.stack(trajectory[len(history) :])  # (n, S, 2)
        values = p.sign * evaluate_pairs(
            p.hp, pending[..., 0].flatten(), pending[..., 1].flatten(), p.s_n, fitness=p.fitness
        ).reshape(pending.shape[:2])
        top, when = values.max(dim=0)
        better = top > start_best[:, 0]
        found = torch.cat([top[:, None], pending[when, torch.arange(n_starts)]], dim=1)
        start_best[better] = found[better]
        per_step, which = values.max(dim=1)
        for i in range(len(per_step)):
            if float(per_step[i]) > best[0] + 1e-9:
                k = int(which[i])
                best = (float(per_step[i]), float(pending[i, k, 0]), float(pending[i, k, 1]))
                since_improved = 0
            elif history:
                since_improved += 1
            history.append(best)

    bar = _progress_bar(steps, progress, "gradient")
    try:
        for step in range(steps):
            if step % check_every == 0:
                check()
                if since_improved >= patience:
                    stopped = "patience"
                    break
            if lr_decay != 1.0 and steps > 1:
                factor = lr_decay ** (step / (steps - 1))
                for group, lr in zip(opt.param_groups, (lr_angle, lr_offset), strict=True):
                    group["lr"] = lr * factor
            guide = model
            if schedule is not None:
                temperature = schedule(step, steps)
                guide = _with_temperature(model, temperature)
            opt.zero_grad(set_to_none=True)
            objective = p.sign * p.fitness(guide(p.hp, theta, offset, p.s_n))
            (-objective.sum()).backward()  # starts are independent: each gets its own gradient
            for param in (theta, offset):  # a NaN gradient would poison the momentum
                if param.grad is None:  # a guide that ignores this parameter
                    param.grad = torch.zeros_like(param)
                torch.nan_to_num_(param.grad, nan=0.0, posinf=0.0, neginf=0.0)
            opt.step()
            _wrap_(theta, offset, p.s_n, opt)
            trajectory.append(torch.stack([theta.detach(), offset.detach()], dim=-1).clone())
            if bar is not None:
                bar.update(1)
                if step % check_every == 0:
                    bar.set_postfix(fitness=f"{p.sign * best[0]:.5f}", refresh=False)
            if tol > 0:
                moved = _circular_distance(trajectory[-1], trajectory[-2], [math.pi, p.s_n])
                if float((moved / moved.new_tensor([1.0, p.s_n])).max()) < tol:
                    stopped = "converged"
                    break
        if len(history) < len(trajectory):
            check()
    finally:
        if bar is not None:
            bar.close()
    n_steps = len(trajectory) - 1
    return _Descent(
        best_score=best[0],
        best_angle=best[1],
        best_offset=best[2],
        evaluations=n_starts * (2 * n_steps + 2),  # a guided gradient, an exact score a step
        history=np.array(history)[:, [1, 2, 0]] * np.array([1.0, 1.0, p.sign]),
        trajectory=torch.stack(trajectory).numpy(),
        start_best=start_best,
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


#: Default learning rates ``(angle, offset)`` of a search from random starts and of a
#: refinement from grid points. Angle: radians. Offset: normalised-frame units (polygon
#: diameter 1), except that Adam's default is given per unit of spacing (Adam's step length is
#: about ``lr``, so a step is then the same fraction of the offset's period for every polygon
#: and spacing). SGD's step is ``lr * gradient``, amplified up to ``1 / (1 - momentum)`` times
#: by momentum. Tuned on random convex polygons (see ``benchmarks/optimizers.py``).
_DEFAULT_LR = {"adam": (0.05, 0.05), "sgd": (0.3, 0.01)}
_REFINE_LR = {"adam": (0.01, 0.05), "sgd": (0.06, 0.002)}


def _gradient_options(
    p: _Problem,
    *,
    optimizer: str,
    steps: int,
    lr_angle: float | None,
    lr_offset: float | None,
    lr_decay: float,
    momentum: float,
    temperature: float | tuple[float, float] | TemperatureSchedule | None,
    patience: int | None,
    tol: float,
    check_every: int,
    model: TransectModel | None,
    progress: bool | None,
    refine: bool = False,
) -> dict[str, Any]:
    if optimizer not in _DEFAULT_LR:
        raise InvalidParameterError(f"optimizer must be 'sgd' or 'adam', got {optimizer!r}")
    steps = _check_count("steps", steps, low=0)
    default_angle, default_offset = (_REFINE_LR if refine else _DEFAULT_LR)[optimizer]
    lr_angle = default_angle if lr_angle is None else _check_positive("lr_angle", lr_angle)
    if lr_offset is None:
        lr_offset = default_offset * (p.s_n if optimizer == "adam" else 1.0)
    else:
        lr_offset = _check_positive("lr_offset", lr_offset)
    lr_decay = _check_positive("lr_decay", lr_decay)
    if lr_decay > 1:
        raise InvalidParameterError(f"lr_decay must be in (0, 1], got {lr_decay!r}")
    momentum = _check_positive("momentum", momentum, allow_zero=True)
    if momentum >= 1:
        raise InvalidParameterError(f"momentum must be in [0, 1), got {momentum!r}")
    model = DEFAULT_GUIDE if model is None else model
    schedule = _as_schedule(temperature)
    if schedule is not None:
        _with_temperature(model, schedule.start)  # fail early for a model without temperature
    patience = steps if patience is None else _check_count("patience", patience)
    tol = _check_positive("tol", tol, allow_zero=True)
    check_every = _check_count("check_every", check_every)
    return {
        "model": model,
        "optimizer": optimizer,
        "steps": steps,
        "lr_angle": lr_angle,
        "lr_offset": lr_offset,
        "lr_decay": lr_decay,
        "momentum": momentum,
        "schedule": schedule,
        "patience": patience,
        "tol": tol,
        "check_every": check_every,
        "progress": progress,
    }


def _as_starts(
    p: _Problem,
    init: tuple[ArrayLike, ArrayLike] | None,
    starts: int,
    screen: int,
    seed: int | None,
) -> tuple[torch.Tensor, torch.Tensor]:
    """Starting angles and normalised offsets ``(S,)``.

    Given (``init``, user units), or the best ``starts`` of ``max(starts, screen)`` seeded
    uniform random candidates by the exact model (one batched evaluation).
    """
    if init is not None:
        try:
            given_a = np.atleast_1d(np.asarray(init[0], dtype=np.float64))
            given_o = np.atleast_1d(np.asarray(init[1], dtype=np.float64)) / p.scale
            given_a, given_o = np.broadcast_arrays(given_a, given_o)
        except (TypeError, ValueError, IndexError) as exc:
            raise InvalidParameterError(
                f"init must be (angles, offsets), two broadcastable 1-D arrays: {exc}"
            ) from None
        if given_a.ndim != 1 or len(given_a) == 0 or not np.all(np.isfinite(given_a + given_o)):
            raise InvalidParameterError("init must hold at least one finite (angle, offset) pair")
        return torch.tensor(given_a), torch.tensor(given_o)
    starts = _check_count("starts", starts)
    screen = _check_count("screen", screen, low=0)
    rng = np.random.default_rng(seed)
    count = max(starts, screen)
    angles = torch.tensor(rng.uniform(0.0, math.pi, count))
    offsets = torch.tensor(rng.uniform(0.0, p.s_n, count))
    if count > starts:  # keep the best `starts` candidates by the exact model
        values = p.sign * evaluate_pairs(p.hp, angles, offsets, p.s_n, fitness=p.fitness)
        keep = torch.argsort(values, descending=True, stable=True)[:starts]
        angles, offsets = angles[keep], offsets[keep]
    return angles, offsets


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


def _describe(options: dict[str, Any]) -> dict[str, Any]:
    schedule = options["schedule"]
    return {
        "model": getattr(options["model"], "name", type(options["model"]).__name__),
        "optimizer": options["optimizer"],
        "lr_angle": options["lr_angle"],
        "lr_offset": options["lr_offset"],
        "momentum": options["momentum"] if options["optimizer"] == "sgd" else None,
        "temperature": None if schedule is None else str(schedule),
    }


def gradient_descent(
    polygon: Polygon | ArrayLike,
    spacing: float,
    *,
    fitness: Objective | None = None,
    model: TransectModel | None = None,
    optimizer: str = "adam",
    steps: int = 200,
    starts: int = 8,
    screen: int = 1024,
    init: tuple[ArrayLike, ArrayLike] | None = None,
    lr_angle: float | None = None,
    lr_offset: float | None = None,
    lr_decay: float = 1.0,
    momentum: float = 0.8,
    temperature: float | tuple[float, float] | TemperatureSchedule | None = DEFAULT_SCHEDULE,
    patience: int | None = 40,
    tol: float = 1e-7,
    check_every: int = 5,
    zoom_levels: int = 2,
    zoom_points: int = 11,
    seed: int | None = 0,
    progress: bool | None = False,
) -> OptimizeResult:
    """Gradient ascent of the fitness through a differentiable model, several starts at once.

    The angle and offset of all ``S`` starts are two leaf tensors of shape ``(S,)`` created here
    and stepped together (the fitness of the batch is summed, so each start gets its own
    gradient). After every step the angles are wrapped into ``[0, pi)`` and the offsets into
    ``[0, spacing)`` in place (see :func:`_wrap_`), so the optimizer's state is kept. Every
    iterate is scored with the exact model and the best one is the answer.

    Stages: (1) screening: the starts are the best ``starts`` of ``screen`` seeded random
    layouts by the exact model (``screen=0``: plain random starts, as in the paper);
    (2) gradient ascent from them; (3) a coarse-to-fine exact zoom around each start's best
    iterate (``zoom_levels=0`` skips it). The paper's experiment (Sec. VII) is
    ``gradient_descent(p, s, optimizer="sgd", momentum=0.8, steps=200, starts=1, screen=0,
    zoom_levels=0, patience=None)``.

    Args:
        polygon: convex polygon, user units.
        spacing: transect spacing, user units, smaller than the polygon's diameter.
        fitness: objective (default Eq. 1, a = b = 0.5).
        model: differentiable guiding model (default :data:`DEFAULT_GUIDE`, the paper's model
            with 64 points per transect); anything with the
            :class:`~boustro.models.TransectModel` interface, e.g. a smooth closed form.
        optimizer: ``"adam"`` (default) or ``"sgd"`` (with ``momentum``).
        steps: most gradient steps.
        starts: number of starts descended together (ignored with ``init``).
        screen: number of seeded random layouts the starts are picked from.
        init: explicit starts ``(angles, offsets)``, radians and user units, broadcastable 1-D.
        lr_angle: learning rate of the angle, radians (default 0.05 for Adam, whose step is
            about ``lr``; 0.3 for SGD).
        lr_offset: learning rate of the offset, normalised-frame units (polygon diameter 1).
            Default for Adam ``0.05 * spacing`` (a twentieth of the offset's period per
            step); for SGD 0.01.
        lr_decay: the learning rates fall geometrically to ``lr_decay`` times their initial
            value at the last step (1: constant).
        momentum: SGD momentum (the paper's 0.8).
        temperature: the guiding model's temperature: a number (constant), ``(T0, T1)``
            (annealed geometrically over ``steps``, the paper's Sec. VI suggestion), a
            :class:`TemperatureSchedule`, or ``None`` to keep the model's own temperature
            (required for a model without one). Default :data:`DEFAULT_SCHEDULE`, 50 to 200.
        patience: stop when the best exact fitness has not improved for this many steps
            (``None``: never).
        tol: stop when no start moved more than this (radians; fractions of the spacing) in a
            step.
        check_every: score the iterates exactly in batches of this many steps (the patience
            is checked then).
        zoom_levels, zoom_points: the final zoom; its first window spans :data:`ZOOM_ANGLE`
            radians and :data:`ZOOM_OFFSET` spacings either side of each start's best iterate.
        seed: seed of the random starts.
        progress: tqdm bar on stderr: ``True``, ``False`` (default), or ``None`` (if a TTY).

    Returns:
        :class:`OptimizeResult` with ``history`` ``(steps + 1, 3)`` (best so far by the exact
        model; one more row if the zoom improved it) and ``info["trajectory"]``
        ``(steps + 1, S, 2)``: every start's (angle, offset) after every step, user units.

    Raises:
        NoTransectError: the spacing is not smaller than the polygon's diameter, or no iterate
            had a transect crossing the polygon.
    """
    t0 = time.perf_counter()
    p = _problem(polygon, spacing, fitness, "gradient descent")
    options = _gradient_options(
        p,
        optimizer=optimizer,
        steps=steps,
        lr_angle=lr_angle,
        lr_offset=lr_offset,
        lr_decay=lr_decay,
        momentum=momentum,
        temperature=temperature,
        patience=patience,
        tol=tol,
        check_every=check_every,
        model=model,
        progress=progress,
    )
    theta0, offset0 = _as_starts(p, init, starts, screen, seed)
    descent = _descend(p, theta0, offset0, **options)
    screened = screen if init is None and screen > int(theta0.shape[0]) else 0
    info = {
        "starts": int(theta0.shape[0]),
        "screen": 0 if init is not None else screen,
        "seed": seed,
        "descent_fitness": p.sign * descent.best_score,
        **_describe(options),
    }
    zoom_levels = _check_count("zoom_levels", zoom_levels, low=0)
    zoom_points = _check_count("zoom_points", zoom_points, low=2)
    descent, zoomed = _zoom_descent(
        p, descent, ZOOM_ANGLE, ZOOM_OFFSET * p.s_n, zoom_points, zoom_levels, info
    )
    descent = descent._replace(evaluations=descent.evaluations + screened + zoomed)
    return _result_from_descent(p, descent, "gradient", t0, info)


# -- hybrid -----------------------------------------------------------------------------------


def _grid_peaks(values: torch.Tensor, k: int, sign: float) -> torch.Tensor:
    """Flat indices of up to ``k`` grid points, local maxima of ``sign * values`` first.

    Neighbours wrap around both axes the way layouts do: offset index ``j`` wraps modulo the
    offset count, and angle ``pi`` is angle 0 with the offset negated (index ``-j``).
    """
    score = sign * values
    n_angles, n_offsets = score.shape
    j = torch.arange(n_offsets)
    # Rows -1 and A: the last/first angle, half a turn away, with the offsets negated.
    padded = torch.cat([score[-1:, (-j) % n_offsets], score, score[:1, (-j) % n_offsets]], dim=0)
    padded = torch.cat([padded[:, -1:], padded, padded[:, :1]], dim=1)
    neighbours = torch.stack(
        [
            padded[1 + di : 1 + di + n_angles, 1 + dj : 1 + dj + n_offsets]
            for di in (-1, 0, 1)
            for dj in (-1, 0, 1)
            if (di, dj) != (0, 0)
        ]
    )
    flat = score.flatten()
    peak = (score >= neighbours.amax(dim=0)).flatten() & torch.isfinite(flat)
    # Sort key: peaks before the rest, then by value (ties: lower index first, stable).
    order = torch.argsort(torch.where(peak, flat, flat - math.inf), descending=True, stable=True)
    rest = torch.argsort(flat, descending=True, stable=True)
    ranked = torch.cat([order[peak[order]], rest[~peak[rest] & torch.isfinite(flat[rest])]])
    return ranked[:k]


def _zoom(
    p: _Problem,
    angles: torch.Tensor,
    offsets: torch.Tensor,
    half_angle: float,
    half_offset: float,
    points: int,
    levels: int,
) -> tuple[float, float, float, int]:
    """Coarse-to-fine exact search around each centre ``(C,)``; returns the best and a count.

    Each level evaluates a ``points x points`` grid spanning ``+- half`` around every centre
    (one batched exact call for all centres), moves each centre to its best point and shrinks
    the window to one cell of the level before. Returns ``(score, angle, offset, evaluations)``
    with ``score = sign * fitness`` (``-inf`` if nothing crossed).
    """
    u = torch.linspace(-1.0, 1.0, points, dtype=angles.dtype)
    best = (-math.inf, float(angles[0]), float(offsets[0]))
    evaluations = 0
    for _ in range(levels):
        a = (angles[:, None, None] + half_angle * u[:, None]).expand(-1, points, points)
        o = (offsets[:, None, None] + half_offset * u).expand(-1, points, points)
        a, o = a.reshape(len(angles), -1), o.reshape(len(angles), -1)
        values = p.sign * evaluate_pairs(
            p.hp, a.flatten(), o.flatten(), p.s_n, fitness=p.fitness
        ).reshape(a.shape)
        evaluations += values.numel()
        top, where = values.max(dim=1)
        angles = a.gather(1, where[:, None])[:, 0]
        offsets = o.gather(1, where[:, None])[:, 0]
        k = int(torch.argmax(top))
        if float(top[k]) > best[0]:
            best = (float(top[k]), float(angles[k]), float(offsets[k]))
        half_angle *= 2 / (points - 1)
        half_offset *= 2 / (points - 1)
    return (*best, evaluations)


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


def hybrid(
    polygon: Polygon | ArrayLike,
    spacing: float,
    *,
    fitness: Objective | None = None,
    n_angles: int = 42,
    n_offsets: int = 28,
    top_k: int = 3,
    model: TransectModel | None = None,
    optimizer: str = "adam",
    steps: int = 30,
    lr_angle: float | None = None,
    lr_offset: float | None = None,
    lr_decay: float = 1.0,
    momentum: float = 0.8,
    temperature: float | tuple[float, float] | TemperatureSchedule | None = DEFAULT_SCHEDULE,
    patience: int | None = 25,
    tol: float = 1e-7,
    check_every: int = 5,
    zoom_levels: int = 2,
    zoom_points: int = 11,
    progress: bool | None = False,
) -> OptimizeResult:
    """Grid search, batched gradient refinement of the best ``top_k`` grid points, exact zoom.

    The paper's proposal (Sec. VII): a grid search gets near the optimum and gradient descent
    refines it. Three stages, every answer scored with the exact model:

    1. an ``n_angles x n_offsets`` grid, one batched exact evaluation. The default 42 x 28
       contains every point of :data:`GRID_200` (14 x 14), so the answer is never worse than
       the paper's grid search; it costs about as little (one batched call either way);
    2. gradient ascent (as :func:`gradient_descent`) from the grid's local maxima, best first
       (so the starts land in different basins), all ``top_k`` starts in one batch;
    3. a coarse-to-fine exact zoom (``zoom_levels`` levels of ``zoom_points`` squared points,
       the first spanning one grid cell either side) around each start's best iterate. The
       exact optimum of Eq. 1 often sits on an edge where a transect leaves the polygon, a
       jump that the smooth guiding model rounds off; the zoom lands on the right side of it.
       ``zoom_levels=0`` skips it.

    The answer is the best layout over all stages, so it is never worse than the grid's own
    answer. Deterministic (no random starts). Gradient options (``model``, ``optimizer``,
    ``steps``, learning rates, ``temperature``, ``patience``, ...) as in
    :func:`gradient_descent`, except that the default learning rates are those of a
    refinement: 0.01 radians for Adam's angle.

    Raises:
        NoTransectError: the spacing is not smaller than the polygon's diameter, or no grid
            point has a transect crossing the polygon.
    """
    t0 = time.perf_counter()
    p = _problem(polygon, spacing, fitness, "hybrid search")
    n_angles = _check_count("n_angles", n_angles)
    n_offsets = _check_count("n_offsets", n_offsets)
    top_k = _check_count("top_k", top_k)
    zoom_levels = _check_count("zoom_levels", zoom_levels, low=0)
    zoom_points = _check_count("zoom_points", zoom_points, low=2)
    options = _gradient_options(
        p,
        optimizer=optimizer,
        steps=steps,
        lr_angle=lr_angle,
        lr_offset=lr_offset,
        lr_decay=lr_decay,
        momentum=momentum,
        temperature=temperature,
        patience=patience,
        tol=tol,
        check_every=check_every,
        model=model,
        progress=progress,
        refine=True,
    )
    angles, offsets = _grid(p, n_angles, n_offsets)
    values = evaluate_grid(p.hp, angles, offsets, p.s_n, fitness=p.fitness, progress=progress)
    chosen = _grid_peaks(values, top_k, p.sign)
    if len(chosen) == 0:
        raise _no_transect(p, "on any grid point")
    rows, cols = chosen // n_offsets, chosen % n_offsets
    grid_best = p.sign * float(values[rows[0], cols[0]])
    descent = _descend(p, angles[rows], offsets[cols], **options)
    evaluations = n_angles * n_offsets + descent.evaluations
    if descent.best_score < grid_best:  # cannot happen (the grid's best is a start): a guard
        descent = descent._replace(
            best_score=grid_best,
            best_angle=float(angles[rows[0]]),
            best_offset=float(offsets[cols[0]]),
        )
    info = {
        "n_angles": n_angles,
        "n_offsets": n_offsets,
        "top_k": len(chosen),
        "grid_fitness": p.sign * grid_best,
        "descent_fitness": p.sign * descent.best_score,
        **_describe(options),
    }
    descent, count = _zoom_descent(
        p, descent, math.pi / n_angles, p.s_n / n_offsets, zoom_points, zoom_levels, info
    )
    evaluations += count
    result = _result_from_descent(p, descent, "hybrid", t0, info)
    return dataclasses.replace(result, evaluations=evaluations, seconds=time.perf_counter() - t0)


# -- one entry point --------------------------------------------------------------------------

Method = Callable[..., OptimizeResult]


def _global(polygon: Polygon | ArrayLike, spacing: float, **options: Any) -> OptimizeResult:
    """``method="global"``: the certified optimum of Eq. 1, or of fewest transects / shortest
    path when ``fitness`` is :class:`~boustro.objectives.FewestTransects` / ``ShortestPath``."""
    # lazy: global_opt imports this module
    from .global_opt import fewest_transects_optimum, global_optimum, shortest_path_optimum
    from .objectives import FewestTransects, ShortestPath

    # The same rule as every other method: a spacing at least the diameter is refused here
    # (global_optimum itself answers it: one transect along the diameter, fitness a + b).
    fitness = options.get("fitness")
    _problem(polygon, spacing, fitness, "the global optimiser")
    # Each objective has its own exact machinery; options that only Eq. 1's uses are dropped.
    if isinstance(fitness, FewestTransects):
        return fewest_transects_optimum(polygon, spacing)
    if isinstance(fitness, ShortestPath):
        return shortest_path_optimum(polygon, spacing)
    return global_optimum(polygon, spacing, **options)


def _learned(polygon: Polygon | ArrayLike, spacing: float, **options: Any) -> OptimizeResult:
    """``method="learned"``: :func:`boustro.learned.learned` (``refine=True`` to refine)."""
    from .learned import learned  # lazy: boustro.learned imports this module

    return learned(polygon, spacing, **options)


#: Optimisers by name; :func:`optimize` dispatches here. Each is called as
#: ``method(polygon, spacing, fitness=fitness, **options)`` and returns an
#: :class:`OptimizeResult`.
METHODS: dict[str, Method] = {
    "grid": grid_search,
    "gradient": gradient_descent,
    "hybrid": hybrid,
    "global": _global,
    "learned": _learned,
}


def register_method(name: str, method: Method, *, replace: bool = False) -> None:
    """Register an optimiser: ``optimize(p, s, method=name, fitness=f, **opts)`` will call
    ``method(p, s, fitness=f, **opts)``, which must return an :class:`OptimizeResult`."""
    if not isinstance(name, str) or not name:
        raise InvalidParameterError(f"a method name must be a non-empty string, got {name!r}")
    if name in METHODS and not replace:
        raise InvalidParameterError(f"method {name!r} is already registered")
    METHODS[name] = method


def optimize(
    polygon: Polygon | ArrayLike,
    spacing: float,
    *,
    method: str = "grid",
    fitness: Objective | None = None,
    **options: Any,
) -> OptimizeResult:
    """Optimise the angle and offset of a boustrophedon layout.

    Args:
        polygon: convex polygon, user units.
        spacing: transect spacing, user units (smaller than the polygon's diameter).
        method: a name in :data:`METHODS`: ``"grid"`` (:func:`grid_search`), ``"gradient"``
            (:func:`gradient_descent`), ``"hybrid"`` (:func:`hybrid`) or ``"global"``
            (:func:`boustro.global_opt.global_optimum`: the certified optimum of Eq. 1, with an
            upper bound in ``upper_bound``) or ``"learned"`` (:func:`boustro.learned.learned`:
            the shipped planner network, ``refine=True`` for its exact refinement).
        fitness: the objective (default Eq. 1 with a = b = 0.5), maximised.
        **options: passed to the method.
    """
    if method not in METHODS:
        raise InvalidParameterError(
            f"unknown method {method!r}; expected one of {', '.join(sorted(METHODS))}"
        )
    try:
        return METHODS[method](polygon, spacing, fitness=fitness, **options)
    except TypeError as exc:  # a misspelt option: the library's error, naming it
        match = re.search(r"unexpected keyword argument '(\w+)'", str(exc))
        if match is None:
            raise
        raise InvalidParameterError(
            f"method {method!r} takes no option {match.group(1)!r} (see its function's "
            "documentation)"
        ) from None
