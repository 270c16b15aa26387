"""Optimisers over (angle, offset) (layer 4): one interface, one result type.

Every optimiser searches transect angle ``theta`` (radians; the grid is the same under
``(theta + pi, -offset)``, so ``[0, pi)`` covers every layout when the offset is free) and grid
offset ``d`` (periodic in the spacing), and reports the fitness of its answer evaluated with the
EXACT model, whatever model guided the search.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import torch
from numpy.typing import ArrayLike, NDArray

from .errors import InvalidParameterError, NoTransectError
from .fitness import SmithFitness
from .geometry import HalfPlanes, Polygon, halfplanes
from .models import ExactModel, TransectModel, check_spacing, grid_size
from .scoring import as_polygon

__all__ = [
    "GRID_200",
    "OptimizeResult",
    "evaluate_grid",
    "exact_fitness",
    "grid_search",
    "optimize",
]

#: The paper's 200-sample grid search: 14 angles over [0, 180) degrees x 14 offsets over one
#: spacing (196 evaluations).
GRID_200: dict[str, int] = {"n_angles": 14, "n_offsets": 14}

#: Upper bound on the elements of one batched exact evaluation (pairs x transects x edges);
#: larger grids are evaluated in chunks of angles.
_CHUNK_ELEMENTS = 4_000_000


@dataclass(frozen=True)
class OptimizeResult:
    """The answer of any optimiser, in the user's units.

    Attributes:
        angle: best transect direction, radians in ``[0, pi)``.
        offset: best grid offset, user units in ``[0, spacing)``.
        fitness: objective value at (angle, offset) with the exact model.
        spacing: the spacing searched, user units.
        method: name of the optimiser.
        evaluations: number of (angle, offset) pairs evaluated (by any model).
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
    if turns % 2:
        offset = -offset
    offset = math.fmod(offset, spacing)
    if offset < 0:
        offset += spacing
    if angle >= math.pi:  # rounding
        angle = 0.0
    if offset >= spacing:
        offset = 0.0
    return angle, offset


def _empty_to_minus_inf(values: torch.Tensor, weights: torch.Tensor) -> torch.Tensor:
    """Layouts where no transect counts have no defined fitness: never choose them."""
    return torch.where(weights.sum(dim=-1) > 0, values, -math.inf)


def evaluate_grid(
    hp: HalfPlanes,
    angles: torch.Tensor,
    offsets: torch.Tensor,
    spacing: float,
    *,
    model: TransectModel | None = None,
    fitness: SmithFitness | None = None,
) -> torch.Tensor:
    """Fitness ``(A, O)`` of every pair of ``angles (A,)`` and ``offsets (O,)``, batched.

    Runs in chunks of angles to bound memory. Pairs where no transect crosses the polygon get
    ``-inf``. Everything is in the half-planes' frame (normalised for the paper's scale).
    """
    model = ExactModel() if model is None else model
    fitness = SmithFitness() if fitness is None else fitness
    k_count, _ = grid_size(spacing, hp.radius)
    per_angle = max(1, len(offsets) * k_count * hp.normals.shape[-2])
    chunk = max(1, _CHUNK_ELEMENTS // per_angle)
    out = []
    with torch.no_grad():
        for start in range(0, len(angles), chunk):
            theta = angles[start : start + chunk, None]
            tl = model(hp, theta, offsets[None, :], spacing)
            out.append(_empty_to_minus_inf(fitness(tl), tl.weights))
    return torch.cat(out, dim=0)


def exact_fitness(
    polygon: Polygon,
    spacing: float,
    angle: float,
    offset: float,
    fitness: SmithFitness | None = None,
) -> float:
    """Exact-model fitness of one layout (user units); ``-inf`` if no transect crosses."""
    frame = polygon.frame
    hp = halfplanes(polygon)
    value = evaluate_grid(
        hp,
        torch.tensor([angle], dtype=torch.float64),
        torch.tensor([offset / frame.scale], dtype=torch.float64),
        spacing / frame.scale,
        fitness=fitness,
    )
    return float(value[0, 0])


def grid_search(
    polygon: Polygon | ArrayLike,
    spacing: float,
    *,
    n_angles: int = 180,
    n_offsets: int = 20,
    fitness: SmithFitness | None = None,
) -> OptimizeResult:
    """Exhaustive search on a regular grid of angles in ``[0, pi)`` x offsets in ``[0, s)``.

    One batched exact evaluation (chunked for memory), no Python loop over grid points. The
    paper's 200-sample setting is ``grid_search(p, s, **GRID_200)``.

    Raises:
        NoTransectError: no grid point has a transect crossing the polygon.
    """
    t0 = time.perf_counter()
    poly = as_polygon(polygon).require_convex("grid search")
    spacing = check_spacing(spacing)
    for name, count in (("n_angles", n_angles), ("n_offsets", n_offsets)):
        if int(count) != count or count < 1:
            raise InvalidParameterError(f"{name} must be an integer >= 1, got {count!r}")
    frame = poly.frame
    s_n = spacing / frame.scale
    hp = halfplanes(poly)
    angles = torch.arange(n_angles, dtype=torch.float64) * (math.pi / n_angles)
    offsets = torch.arange(n_offsets, dtype=torch.float64) * (s_n / n_offsets)
    values = evaluate_grid(hp, angles, offsets, s_n, fitness=fitness)
    best = int(torch.argmax(values))
    i, j = divmod(best, n_offsets)
    if not math.isfinite(float(values[i, j])):
        raise NoTransectError(
            f"no transect crosses the polygon at spacing {spacing:g} on any grid point "
            f"(polygon diameter {poly.diameter:g})"
        )
    return OptimizeResult(
        angle=float(angles[i]),
        offset=float(offsets[j]) * frame.scale,
        fitness=float(values[i, j]),
        spacing=spacing,
        method="grid",
        evaluations=n_angles * n_offsets,
        seconds=time.perf_counter() - t0,
        info={"n_angles": int(n_angles), "n_offsets": int(n_offsets)},
    )


def optimize(
    polygon: Polygon | ArrayLike,
    spacing: float,
    *,
    method: str = "grid",
    fitness: SmithFitness | None = None,
    **options: Any,
) -> OptimizeResult:
    """Optimise the angle and offset of a boustrophedon layout.

    Args:
        polygon: convex polygon, user units.
        spacing: transect spacing, user units.
        method: ``"grid"`` (see :func:`grid_search`).
        fitness: the objective (default Eq. 1 with a = b = 0.5), maximised.
        **options: passed to the method.
    """
    methods = {"grid": grid_search}
    if method not in methods:
        raise InvalidParameterError(
            f"unknown method {method!r}; expected one of {', '.join(sorted(methods))}"
        )
    return methods[method](polygon, spacing, fitness=fitness, **options)
