"""The validated search problem, batched exact evaluation, and the exact zoom."""

from __future__ import annotations

import math
import sys
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from .._torch import torch
from .._validate import as_number
from ..errors import InvalidParameterError, NoTransectError
from ..geometry import HalfPlanes, Polygon, halfplanes
from ..models import (
    ExactModel,
    TransectModel,
    check_spacing,
)
from ..models import grid_size as _grid_size
from ..objectives import Objective, SmithFitness, objective_sign
from ..scoring import as_polygon

__all__ = ["Problem", "evaluate_grid", "evaluate_pairs", "exact_fitness", "prepare_problem"]


#: Upper bound on the elements of one batched exact evaluation (pairs x transects x edges);
#: larger grids are evaluated in chunks of angles.
_CHUNK_ELEMENTS = 4_000_000


class _Problem(NamedTuple):
    """A validated search problem in the normalised frame."""

    polygon: Polygon
    spacing: float  # user units
    s_n: float  # normalised frame
    scale: float  # user length of one normalised unit
    hp: HalfPlanes
    fitness: Objective
    sign: float  # +1 to maximise, -1 to minimise


def _check_narrower(poly: Polygon, spacing: float) -> float:
    """The spacing, checked (:func:`check_spacing`) and smaller than the polygon's diameter
    (else :class:`NoTransectError`: at most one transect can cross it)."""
    spacing = check_spacing(spacing, extent=poly.diameter)
    if spacing >= poly.diameter:
        raise NoTransectError(
            f"spacing {spacing:g} is not smaller than the polygon's diameter {poly.diameter:g} "
            "(its widest extent at any angle): at most one transect can cross it, so there is "
            "no boustrophedon layout to optimise"
        )
    return spacing


def _checked(
    polygon: Polygon | ArrayLike, spacing: float, fitness: Objective | None, what: str
) -> tuple[Polygon, float, Objective, float]:
    """The checks of :func:`_problem` without building its half-planes: ``(polygon, spacing,
    objective, sign)``."""
    poly = as_polygon(polygon).require_convex(what)
    spacing = _check_narrower(poly, spacing)
    objective: Objective = SmithFitness() if fitness is None else fitness
    return poly, spacing, objective, objective_sign(objective)


def _problem(
    polygon: Polygon | ArrayLike, spacing: float, fitness: Objective | None, what: str
) -> _Problem:
    poly, spacing, objective, sign = _checked(polygon, spacing, fitness, what)
    frame = poly.frame
    return _Problem(
        poly, spacing, spacing / frame.scale, frame.scale, halfplanes(poly), objective, sign
    )


#: The validated problem every optimiser starts from (public names for new optimisers).
Problem = _Problem


def prepare_problem(
    polygon: Polygon | ArrayLike, spacing: float, fitness: Objective | None, what: str
) -> _Problem:
    """Validate ``polygon`` (convex), ``spacing`` and ``fitness`` (default Eq. 1) for the
    optimiser named ``what`` (in error messages), and move them to the normalised frame.

    >>> p = prepare_problem([(0, 0), (4, 0), (4, 3), (0, 3)], 0.5, None, "a demo")
    >>> round(p.s_n, 4), round(p.scale, 4), p.sign
    (0.1, 5.0, 1.0)
    """
    return _problem(polygon, spacing, fitness, what)


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
    objective: Objective = SmithFitness() if fitness is None else fitness
    sign = objective_sign(objective)
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
                out.append(_invalid_to_worst(objective(tl), tl.weights, sign))
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
    objective: Objective = SmithFitness() if fitness is None else fitness
    sign = objective_sign(objective)
    k_count, _ = _grid_size(spacing, hp.radius)
    chunk = max(1, _CHUNK_ELEMENTS // max(1, k_count * hp.normals.shape[-2]))
    out = []
    with torch.no_grad():
        for start in range(0, len(angles), chunk):
            tl = model(hp, angles[start : start + chunk], offsets[start : start + chunk], spacing)
            out.append(_invalid_to_worst(objective(tl), tl.weights, sign))
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
