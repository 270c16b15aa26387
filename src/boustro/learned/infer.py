"""The learned planner's answers: one polygon (:func:`learned`), many, and warm starts."""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import torch
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError, NoTransectError
from ..geometry import Polygon
from ..models import check_spacing
from ..objectives import as_plan_objective, objective_sign
from ..optimize import OptimizeResult, canonical
from ..scoring import as_polygon
from .batch import PlanBatch, batch_objective, make_batch
from .network import LearnedPlanner, hypotheses
from .refine import RefineOptions, refine_evaluations
from .refine import refine as _refine  # the functions below have a parameter named refine
from .weights import as_planner

__all__ = ["BatchResult", "learned", "learned_batch", "warm_start"]


class BatchResult(NamedTuple):
    """Answers of :func:`learned_batch`, ``(P,)`` arrays in each polygon's units.

    ``angle`` radians in ``[0, pi)``, ``offset`` in ``[0, spacing)``, ``fitness`` the exact
    objective (maximised; for an objective with ``maximise = False`` its negation).
    """

    angle: NDArray[np.float64]
    offset: NDArray[np.float64]
    fitness: NDArray[np.float64]
    spacing: NDArray[np.float64]
    seconds: float


def _canonical_arrays(
    theta: torch.Tensor, offset: torch.Tensor, spacing: torch.Tensor
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Angles into ``[0, pi)`` (flipping the offset's sign on odd half-turns), offsets into
    ``[0, spacing)``; same units as given."""
    turns = torch.floor(theta / math.pi)
    angle = theta - turns * math.pi
    sign = torch.where(torch.remainder(turns, 2) == 1, -1.0, 1.0).to(offset.dtype)
    off = torch.remainder(sign * offset, spacing)
    angle = torch.where(angle >= math.pi, angle - math.pi, angle).clamp(min=0.0)
    off = torch.where(off >= spacing, off - spacing, off).clamp(min=0.0)
    return angle.numpy().astype(np.float64), off.numpy().astype(np.float64)


def learned_batch(
    polygons: Sequence[Polygon | ArrayLike] | PlanBatch,
    spacings: ArrayLike | None = None,
    *,
    refine: bool | RefineOptions = False,
    fitness: Any = None,
    planner: LearnedPlanner | str | Path | None = None,
    chunk: int = 256,
) -> BatchResult:
    """The learned planner on many polygons at once: the network's ``k`` hypotheses scored
    exactly, optionally refined (:func:`refine`), the best per polygon.

    Args:
        polygons: convex polygons (user units), or a :class:`PlanBatch` (then ``spacings`` is
            ignored and results are in the batch's user units).
        spacings: one spacing for all or ``(P,)``, user units.
        refine: ``True`` (default :class:`RefineOptions`) or options; ``False``: network only.
        fitness: objective, anything :func:`as_plan_objective` accepts (default Eq. 1).
        planner: a :class:`LearnedPlanner`, a path to saved weights, or ``None`` (shipped).
        chunk: polygons per batched call.

    >>> square, triangle = [(0, 0), (4, 0), (4, 2), (0, 2)], [(0, 0), (3, 0), (0, 3)]
    >>> result = learned_batch([square, triangle], [0.5, 0.4], refine=True)
    >>> result.fitness.round(4).tolist()
    [0.9505, 0.6565]
    """
    t0 = time.perf_counter()
    net = as_planner(planner)
    if isinstance(polygons, PlanBatch):
        batch = polygons.to(torch.float64)
    else:
        if spacings is None:
            raise InvalidParameterError("spacings are required with a list of polygons")
        batch = make_batch(polygons, spacings)
    options = RefineOptions() if refine is True else (refine or None)
    angles, offsets, values = [], [], []
    for start in range(0, batch.size, chunk):
        sub = batch.select(torch.arange(start, min(start + chunk, batch.size)))
        theta, offset = hypotheses(net, sub)
        if options is None:
            v = batch_objective(sub, theta, offset, objective=fitness)
            k = v.argmax(dim=1, keepdim=True)
            v, theta, offset = (
                v.gather(1, k)[:, 0],
                theta.gather(1, k)[:, 0],
                offset.gather(1, k)[:, 0],
            )
        else:
            v, theta, offset = _refine(sub, theta, offset, objective=fitness, options=options)
        a, o = _canonical_arrays(theta, offset * sub.scale, sub.spacing * sub.scale)
        angles.append(a)
        offsets.append(o)
        values.append(v.numpy())
    return BatchResult(
        np.concatenate(angles),
        np.concatenate(offsets),
        np.concatenate(values),
        (batch.spacing * batch.scale).numpy(),
        time.perf_counter() - t0,
    )


def learned(
    polygon: Polygon | ArrayLike,
    spacing: float,
    *,
    refine: bool | RefineOptions = False,
    fitness: Any = None,
    planner: LearnedPlanner | str | Path | None = None,
    progress: bool | None = None,
) -> OptimizeResult:
    """``method="learned"``: the learned planner's layout for one convex polygon.

    The network predicts ``k`` hypotheses (angle, offset) in one forward pass; they are scored
    with the exact model and the best is returned. With ``refine=True`` they are refined first
    (:func:`refine`: exact offset sweep, event layouts, optional gradient ascent through the
    smooth closed form, exact zoom), which is never worse.

    Args:
        polygon: convex polygon, user units.
        spacing: transect spacing, user units, smaller than the polygon's diameter.
        refine: ``False`` (network only), ``True`` or :class:`RefineOptions`.
        fitness: the objective (default Eq. 1); a length objective like
            :class:`~boustro.fitness.SmithFitness` or a :class:`PlanObjective`. The network was
            trained for Eq. 1; with another objective its hypotheses are only starts.
        planner: a :class:`LearnedPlanner`, a path to weights, or ``None`` (the shipped ones).
        progress: accepted for the optimisers' common interface and ignored (milliseconds).

    Returns:
        :class:`~boustro.optimize.OptimizeResult` (``method="learned"``), fitness exact; a
        minimised objective's own value (not negated). ``info`` holds ``hypotheses`` (the
        network's candidates, radians and user units) and ``refined``.

    >>> result = learned([(0, 0), (4, 0), (4, 2), (0, 2)], 0.5)
    >>> result.method, round(result.fitness, 4), result.info["hypotheses"].shape
    ('learned', 0.9501, (16, 2))
    """
    t0 = time.perf_counter()
    poly = as_polygon(polygon).require_convex("the learned planner")
    spacing = check_spacing(spacing, extent=poly.diameter)
    if spacing >= poly.diameter:
        raise NoTransectError(
            f"spacing {spacing:g} is not smaller than the polygon's diameter {poly.diameter:g}: "
            "there is no boustrophedon layout to optimise"
        )
    net = as_planner(planner)
    batch = make_batch([poly], spacing)
    theta, offset = hypotheses(net, batch)
    options = RefineOptions() if refine is True else (refine or None)
    obj = as_plan_objective(fitness)
    values = batch_objective(batch, theta, offset, objective=obj)
    k = int(values[0].argmax())
    if options is None:
        v, t, o = values[0, k], theta[0, k], offset[0, k]
        evaluations = theta.shape[1]
    else:
        vv, tt, oo = _refine(batch, theta, offset, objective=obj, options=options)
        v, t, o = vv[0], tt[0], oo[0]
        evaluations = refine_evaluations(theta.shape[1], len(poly), options)
    if not math.isfinite(float(v)):
        raise NoTransectError(
            f"no transect crosses the polygon at spacing {spacing:g} at any layout the learned "
            "planner found"
        )
    angle, off = canonical(float(t), float(o) * poly.diameter, spacing)
    sign = objective_sign(fitness)
    hyp_angles, hyp_offsets = _canonical_arrays(
        theta[0], offset[0] * poly.diameter, torch.tensor(spacing, dtype=theta.dtype)
    )
    return OptimizeResult(
        angle=angle,
        offset=off,
        fitness=sign * float(v),
        spacing=spacing,
        method="learned",
        evaluations=evaluations,
        seconds=time.perf_counter() - t0,
        info={
            "refined": options is not None,
            "hypotheses": np.stack([hyp_angles, hyp_offsets], axis=1),
            "hypothesis_fitness": sign * values[0].numpy(),
        },
    )


def warm_start(
    polygon: Polygon | ArrayLike,
    spacing: float,
    *,
    planner: LearnedPlanner | str | Path | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The network's ``k`` hypotheses as starts for the other optimisers: ``(angles, offsets)``,
    radians in ``[0, pi)`` and user units in ``[0, spacing)``, best first by the exact model.

    Example::

        gradient_descent(poly, s, init=warm_start(poly, s), steps=40)
    """
    poly = as_polygon(polygon).require_convex("the learned planner")
    spacing = check_spacing(spacing, extent=poly.diameter)
    batch = make_batch([poly], spacing)
    theta, offset = hypotheses(as_planner(planner), batch)
    order = torch.argsort(batch_objective(batch, theta, offset)[0], descending=True)
    return _canonical_arrays(
        theta[0, order], offset[0, order] * poly.diameter, torch.tensor(spacing, dtype=theta.dtype)
    )
