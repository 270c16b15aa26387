"""Grid search: one batched exact evaluation of an angles x offsets grid."""

from __future__ import annotations

import math
import time

from numpy.typing import ArrayLike

from .._torch import torch
from ..geometry import Polygon
from ..objectives import Objective
from .methods import register_method
from .problem import _check_count, _grid, _no_transect, _problem, evaluate_grid
from .result import OptimizeResult

__all__ = ["GRID_200", "grid_search"]


#: The paper's 200-sample grid search: 14 angles over [0, 180) degrees x 14 offsets over one
#: spacing (196 evaluations).
GRID_200: dict[str, int] = {"n_angles": 14, "n_offsets": 14}


@register_method("grid")
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

    >>> r = grid_search([(0, 0), (2, 0), (2, 1), (0, 1)], 0.25, n_angles=4, n_offsets=4)
    >>> r.method, r.evaluations, round(r.angle, 4), round(r.fitness, 4)
    ('grid', 16, 0.0, 0.9472)
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
