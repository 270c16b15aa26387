"""Gradient descent from screened random starts: ``gradient_descent`` and its options."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._torch import torch
from ..errors import InvalidParameterError
from ..geometry import Polygon
from ..models import (
    PaperModel,
    TransectModel,
)
from ..objectives import Objective
from .descent import DescentSettings, _descend, _result_from_descent, _zoom_descent
from .methods import register_method
from .problem import _check_count, _check_positive, _Problem, _problem, evaluate_pairs
from .result import OptimizeResult
from .schedule import DEFAULT_SCHEDULE, TemperatureSchedule, _as_schedule, _with_temperature

__all__ = ["DEFAULT_GUIDE", "ZOOM_ANGLE", "ZOOM_OFFSET", "GradientOptions", "gradient_descent"]


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
#: schedule tried, against 0.00134; docs/benchmarks.md, "Optimisers on convex polygons"), so
#: it is not the default.
DEFAULT_GUIDE = PaperModel(temperature=100.0, points_per_transect=64)


#: Half-widths of the first zoom window of :func:`gradient_descent` around each start's best
#: iterate: radians, and fractions of the spacing.
ZOOM_ANGLE = 0.05


ZOOM_OFFSET = 0.1


#: Default learning rates ``(angle, offset)`` of a search from random starts and of a
#: refinement from grid points. Angle: radians. Offset: normalised-frame units (polygon
#: diameter 1), except that Adam's default is given per unit of spacing (Adam's step length is
#: about ``lr``, so a step is then the same fraction of the offset's period for every polygon
#: and spacing). SGD's step is ``lr * gradient``, amplified up to ``1 / (1 - momentum)`` times
#: by momentum. Tuned on random convex polygons (see ``benchmarks/optimizers.py``).
_DEFAULT_LR = {"adam": (0.05, 0.05), "sgd": (0.3, 0.01)}


_REFINE_LR = {"adam": (0.01, 0.05), "sgd": (0.06, 0.002)}


@dataclass(frozen=True)
class GradientOptions:
    """The settings of the gradient stage of :func:`gradient_descent` and
    :func:`~boustro.optimize.hybrid` (their keyword arguments); :meth:`resolve` validates them.
    The defaults are :func:`gradient_descent`'s; :func:`~boustro.optimize.hybrid` refines with
    ``steps=30``, ``patience=25`` and smaller default learning rates (``refine=True``).

    Attributes:
        model: differentiable guiding model (default :data:`DEFAULT_GUIDE`, the paper's model
            with 64 points per transect); anything with the
            :class:`~boustro.models.TransectModel` interface, e.g. a smooth closed form.
        optimizer: ``"adam"`` (default) or ``"sgd"`` (with ``momentum``).
        steps: most gradient steps.
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
        progress: tqdm bar on stderr: ``True``, ``False`` (default), or ``None`` (if a TTY).

    >>> GradientOptions(steps=30).resolve(0.25, refine=True).lr_angle
    0.01
    """

    model: TransectModel | None = None
    optimizer: str = "adam"
    steps: int = 200
    lr_angle: float | None = None
    lr_offset: float | None = None
    lr_decay: float = 1.0
    momentum: float = 0.8
    temperature: float | tuple[float, float] | TemperatureSchedule | None = DEFAULT_SCHEDULE
    patience: int | None = 40
    tol: float = 1e-7
    check_every: int = 5
    progress: bool | None = False

    def resolve(self, s_n: float, *, refine: bool = False) -> DescentSettings:
        """The validated settings at normalised spacing ``s_n``, with the default learning
        rates of a search from random starts, or of a refinement (``refine``)."""
        optimizer = self.optimizer
        if optimizer not in _DEFAULT_LR:
            raise InvalidParameterError(f"optimizer must be 'sgd' or 'adam', got {optimizer!r}")
        steps = _check_count("steps", self.steps, low=0)
        default_angle, default_offset = (_REFINE_LR if refine else _DEFAULT_LR)[optimizer]
        lr_angle = self.lr_angle
        lr_angle = default_angle if lr_angle is None else _check_positive("lr_angle", lr_angle)
        if self.lr_offset is None:
            lr_offset = default_offset * (s_n if optimizer == "adam" else 1.0)
        else:
            lr_offset = _check_positive("lr_offset", self.lr_offset)
        lr_decay = _check_positive("lr_decay", self.lr_decay)
        if lr_decay > 1:
            raise InvalidParameterError(f"lr_decay must be in (0, 1], got {lr_decay!r}")
        momentum = _check_positive("momentum", self.momentum, allow_zero=True)
        if momentum >= 1:
            raise InvalidParameterError(f"momentum must be in [0, 1), got {momentum!r}")
        model = DEFAULT_GUIDE if self.model is None else self.model
        schedule = _as_schedule(self.temperature)
        if schedule is not None:  # fail early for a model without temperature
            _with_temperature(model, schedule.start)
        patience = self.patience
        patience = steps if patience is None else _check_count("patience", patience)
        return DescentSettings(
            model=model,
            optimizer=optimizer,
            steps=steps,
            lr_angle=lr_angle,
            lr_offset=lr_offset,
            lr_decay=lr_decay,
            momentum=momentum,
            schedule=schedule,
            patience=patience,
            tol=_check_positive("tol", self.tol, allow_zero=True),
            check_every=_check_count("check_every", self.check_every),
            progress=self.progress,
        )


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


def _describe(options: DescentSettings) -> dict[str, Any]:
    schedule = options.schedule
    return {
        "model": getattr(options.model, "name", type(options.model).__name__),
        "optimizer": options.optimizer,
        "lr_angle": options.lr_angle,
        "lr_offset": options.lr_offset,
        "momentum": options.momentum if options.optimizer == "sgd" else None,
        "temperature": None if schedule is None else str(schedule),
    }


@register_method("gradient")
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
        starts: number of starts descended together (ignored with ``init``).
        screen: number of seeded random layouts the starts are picked from.
        init: explicit starts ``(angles, offsets)``, radians and user units, broadcastable 1-D.
        model, optimizer, steps, lr_angle, lr_offset, lr_decay, momentum, temperature,
            patience, tol, check_every: the gradient stage, see :class:`GradientOptions`.
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
    options = GradientOptions(
        model=model,
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
        progress=progress,
    ).resolve(p.s_n)
    theta0, offset0 = _as_starts(p, init, starts, screen, seed)
    descent = _descend(p, theta0, offset0, options)
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
