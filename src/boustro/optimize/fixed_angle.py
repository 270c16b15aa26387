"""The best offset at a fixed transect angle, for any objective, convex areas and regions.

How the offset is found (the result's ``method``):

- ``"exact-offset"``: Eq. 1 (:class:`~boustro.objectives.SmithFitness`) on a convex polygon,
  the closed-form maximum of every piece of the offset circle
  (:func:`boustro.optimize.exact.best_offset`): exact.
- ``"width-offset"``: fewest transects on a convex polygon: ``ceil(width / spacing)`` lanes at
  that angle, centred (equal margins), as :func:`~boustro.optimize.exact.fewest_transects_optimum`
  does at its angle: exact.
- ``"offset-grid"``: any other objective on a convex polygon: a dense scan of the offset
  (:data:`OFFSET_SCAN` offsets over one spacing) with zooms around the best, exact chords.
- ``"region-offset-grid"``: a concave area or one with holes, any objective: the same scan with
  the exact per-segment fitness (:func:`~boustro.optimize.region_grid.evaluate_region_grid`).

Offsets follow the convention of the other optimisers: user units from the shell's vertex mean,
in ``[0, spacing)``, for the angle taken modulo pi.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._torch import torch
from ..errors import InvalidParameterError, NoTransectError
from ..geometry import Polygon
from ..geometry.region import Region, as_region
from ..models import check_spacing
from ..objectives import FewestTransects, SmithFitness, objective_sign
from ..objectives.turns import coverage_count
from .exact import best_offset
from .problem import evaluate_grid, prepare_problem
from .region_grid import evaluate_region_grid
from .result import OptimizeResult, canonical

__all__ = ["OFFSET_SCAN", "OFFSET_ZOOMS", "optimize_offset"]

#: Offsets of the first scan over one spacing (``offset-grid``, ``region-offset-grid``).
OFFSET_SCAN = 512
#: Zooms of the scan: each rescans 33 offsets over two steps of the previous one, around the best.
OFFSET_ZOOMS = 3


def _check_angle(angle: Any) -> float:
    try:
        value = float(angle)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"angle must be a number (radians), got {angle!r}") from None
    if not math.isfinite(value):
        raise InvalidParameterError(f"angle must be a finite number (radians), got {angle!r}")
    return value


def _scan(score: Any, s_n: float, sign: float) -> tuple[float, float, int]:
    """``(value, offset, evaluations)`` of the best offset in ``[0, s_n)``: a dense scan, then
    :data:`OFFSET_ZOOMS` zooms; ``score(offsets) -> values`` (normalised offsets)."""
    offsets = np.arange(OFFSET_SCAN) * (s_n / OFFSET_SCAN)
    values = np.asarray(score(offsets), dtype=np.float64)
    k = int(np.argmax(sign * values))
    best, step, evaluations = (float(values[k]), float(offsets[k])), s_n / OFFSET_SCAN, OFFSET_SCAN
    for _ in range(OFFSET_ZOOMS):
        near = best[1] + np.linspace(-step, step, 33)
        vals = np.asarray(score(near), dtype=np.float64)
        evaluations += len(near)
        k = int(np.argmax(sign * vals))
        if sign * vals[k] > sign * best[0]:
            best = (float(vals[k]), float(near[k]))
        step /= 16
    return best[0], best[1], evaluations


def _convex(
    poly: Polygon, spacing: float, angle: float, fitness: Any
) -> tuple[float, float, str, int]:
    """``(offset, value, method, evaluations)`` on a convex polygon (user units)."""
    if type(fitness) is SmithFitness:
        offset, value = best_offset(poly, spacing, angle, fitness=fitness)
        return offset, value, "exact-offset", 1
    if type(fitness) is FewestTransects and not fitness.maximise:
        v = poly.vertices - poly.centre
        h = v[:, 1] * math.cos(angle) - v[:, 0] * math.sin(angle)
        width = float(h.max() - h.min())
        count = coverage_count(width, spacing)
        first = float(h.min()) + 0.5 * (width - (count - 1) * spacing)
        return first % spacing, float(count), "width-offset", 1
    p = prepare_problem(poly, spacing, fitness, "the fixed-angle offset search")
    theta = torch.tensor([angle], dtype=torch.float64)

    def score(offsets: np.ndarray) -> np.ndarray:
        o = torch.as_tensor(offsets, dtype=torch.float64)
        return evaluate_grid(p.hp, theta, o, p.s_n, fitness=p.fitness)[0].numpy()

    value, offset, evaluations = _scan(score, p.s_n, p.sign)
    return offset * p.scale, value, "offset-grid", evaluations


def _region(r: Region, spacing: float, angle: float, fitness: Any) -> tuple[float, float, int]:
    """``(offset, value, evaluations)`` on a region (user units)."""
    frame = r.frame
    edges = frame.to_normalised(r.edges)
    s_n = spacing / frame.scale

    def score(offsets: np.ndarray) -> np.ndarray:
        return evaluate_region_grid(edges, [angle], offsets, s_n, fitness=fitness)[0]

    value, offset, evaluations = _scan(score, s_n, objective_sign(fitness))
    return offset * frame.scale, value, evaluations


def optimize_offset(
    area: Region | Polygon | ArrayLike,
    spacing: float,
    angle: float,
    *,
    fitness: Any = None,
) -> OptimizeResult:
    """The best offset of the transects at a fixed ``angle`` (radians) for ``fitness``.

    Args:
        area: a convex polygon, or a :class:`~boustro.geometry.region.Region` (concave, holes);
            user units.
        spacing: transect spacing, > 0.
        angle: transect direction, radians counter-clockwise from +x; finite.
        fitness: the objective (default Eq. 1).

    Returns:
        an :class:`OptimizeResult` at ``angle`` modulo pi; ``method`` says how the offset was
        found (see the module docstring), ``info["fixed_angle"]`` is True.

    Raises:
        InvalidParameterError: a non-finite angle or bad spacing. NoTransectError: no transect
        crosses the area at that angle.

    >>> r = optimize_offset([(0, 0), (4, 0), (4, 1), (0, 1)], 0.25, 0.0)
    >>> r.method, round(math.degrees(r.angle), 6)
    ('exact-offset', 0.0)
    """
    t0 = time.perf_counter()
    theta = _check_angle(angle) % math.pi
    if theta >= math.pi:
        theta = 0.0
    fitness = SmithFitness() if fitness is None else fitness
    r = as_region(area)
    s = check_spacing(spacing, extent=r.diameter)
    if r.is_convex and r.n_holes == 0 and s < r.diameter:
        offset, value, method, evaluations = _convex(r.shell, s, theta, fitness)
    else:
        offset, value, evaluations = _region(r, s, theta, fitness)
        method = "region-offset-grid"
    if not math.isfinite(value):
        raise NoTransectError(
            f"no transect crosses the area at angle {math.degrees(theta):g} deg and spacing {s:g}"
        )
    theta, offset = canonical(theta, offset, s)
    return OptimizeResult(
        angle=theta,
        offset=offset,
        fitness=value,
        spacing=s,
        method=method,
        evaluations=int(evaluations),
        seconds=time.perf_counter() - t0,
        info={"fixed_angle": True},
    )
