"""Score one transect layout of a polygon in the user's units (entry point of layers 1-3).

:func:`score` takes a polygon in user coordinates, a spacing and offset in user units and an angle
in radians, moves everything to the paper's normalised frame, runs a transect model and the fitness
there, and returns lengths and segments back in user units, in driving order.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._torch import torch
from ._validate import check_finite, check_spacing
from .errors import InvalidParameterError, NoTransectError
from .geometry import Polygon, as_polygon, halfplanes
from .models import ExactModel, PaperModel, TransectModel, exact_chords
from .models.smooth import DEFAULT_SMOOTHING, SmoothModel
from .objectives.smith import SmithFitness

__all__ = ["Score", "Segments", "as_polygon", "make_model", "score", "transect_segments"]


def make_model(
    name: str,
    *,
    temperature: float = 1000.0,
    points_per_transect: int = 1000,
    smoothing: float = DEFAULT_SMOOTHING,
    clip: bool = False,
) -> TransectModel:
    """A transect model by name (settings ignored where unused).

    ``"exact"``: closed-form chords; ``"paper"``: the paper's sigmoid integral (``temperature``,
    ``points_per_transect``); ``"soft"``: the smooth closed form (``smoothing``, a length in the
    normalised frame; ``1 / temperature`` gives the paper's softness).
    """
    if name == "exact":
        return ExactModel(clip=clip)
    if name == "paper":
        return PaperModel(
            temperature=temperature, points_per_transect=points_per_transect, clip=clip
        )
    if name == "soft":
        return SmoothModel(smoothing=smoothing, clip=clip)
    raise InvalidParameterError(f"unknown model {name!r}; expected 'exact', 'paper' or 'soft'")


@dataclass(frozen=True)
class Segments:
    """The transects of a layout that cross the polygon, in driving order, in user units.

    Attributes:
        positions: ``(T,)`` signed distance of each transect line from the polygon's vertex mean
            along the left normal of the transect direction.
        segments: ``(T, 2, 2)``: ``segments[i] = [[x_start, y_start], [x_end, y_end]]``; the first
            transect runs along the angle's direction, the next against it, and so on.
        lengths: ``(T,)`` exact lengths.
        index: ``(T,)`` index of each transect in the model's grid of ``K`` candidates.
    """

    positions: NDArray[np.float64]
    segments: NDArray[np.float64]
    lengths: NDArray[np.float64]
    index: NDArray[np.int64]


def transect_segments(
    polygon: Polygon | ArrayLike, spacing: float, angle: float, offset: float = 0.0
) -> Segments:
    """Exact transect segments of a convex polygon in user coordinates, in boustrophedon order.

    Args:
        polygon: convex polygon in user units.
        spacing: distance between neighbouring transects, user units, > 0.
        angle: transect direction in radians, counter-clockwise from +x.
        offset: signed distance of the transect grid from the polygon's vertex mean along the
            transects' left normal ``(-sin angle, cos angle)``, user units; periodic in spacing.
    """
    poly = as_polygon(polygon).require_convex("exact transect segments")
    spacing = check_spacing(spacing, extent=poly.diameter)
    angle, offset = check_finite("angle", angle), check_finite("offset", offset)
    frame = poly.frame
    hp = halfplanes(poly)
    ch = exact_chords(hp, angle, offset / frame.scale, spacing / frame.scale)
    lengths = ch.lengths.numpy()
    index = np.flatnonzero(lengths > 1e-12 * hp.radius)
    u = np.array([math.cos(angle), math.sin(angle)])
    n = np.array([-math.sin(angle), math.cos(angle)])
    c = ch.positions.numpy()[index]
    lo, hi = ch.lower.numpy()[index], ch.upper.numpy()[index]
    start = c[:, None] * n + lo[:, None] * u
    end = c[:, None] * n + hi[:, None] * u
    seg = np.stack([start, end], axis=1)
    seg[1::2] = seg[1::2, ::-1]  # boustrophedon: every other transect driven backwards
    return Segments(
        positions=c * frame.scale,
        segments=frame.to_user(seg),
        lengths=lengths[index] * frame.scale,
        index=index,
    )


@dataclass(frozen=True)
class Score:
    """The fitness of one layout and the layout itself, in user units.

    ``fitness`` is computed by ``model`` in the normalised frame (as in the paper), so it is
    invariant to translation, rotation and scale of the polygon. ``lengths`` holds the model's
    length of each transect that crosses the polygon (exact for the exact model, the soft
    integral for the paper model), in user units, in the order of ``layout``.
    """

    fitness: float
    angle: float
    offset: float
    spacing: float
    model: str
    lengths: NDArray[np.float64]
    layout: Segments

    @property
    def n_transects(self) -> int:
        return len(self.layout.lengths)

    @property
    def total_length(self) -> float:
        """Sum of the exact transect lengths, user units."""
        return float(self.layout.lengths.sum())


def score(
    polygon: Polygon | ArrayLike,
    spacing: float,
    angle: float,
    offset: float = 0.0,
    *,
    model: TransectModel | None = None,
    fitness: SmithFitness | None = None,
) -> Score:
    """Score a transect layout of a convex polygon with Eq. 1 (or another fitness).

    Args:
        polygon: a :class:`~boustro.geometry.Polygon` or ``(N, 2)`` vertices, user units.
        spacing: transect spacing, user units, > 0.
        angle: transect direction, radians CCW from +x.
        offset: grid offset, user units (see :func:`transect_segments`).
        model: transect model (default :class:`~boustro.models.ExactModel`).
        fitness: objective (default :class:`~boustro.fitness.SmithFitness` with a = b = 0.5).

    Raises:
        InvalidPolygonError, NonConvexPolygonError, InvalidParameterError: bad input.
        NoTransectError: with the exact model, when no transect crosses the polygon.

    Example:
        >>> s = score([(0, 0), (4, 0), (4, 3), (0, 3)], spacing=1.0, angle=0.0, offset=0.5)
        >>> round(s.fitness, 4), s.n_transects, s.total_length
        (0.9, 2, 8.0)
    """
    poly = as_polygon(polygon)
    model_: TransectModel = ExactModel() if model is None else model
    fitness_ = SmithFitness() if fitness is None else fitness
    poly.require_convex(f"the {model_.name} model")
    layout = transect_segments(poly, spacing, angle, offset)
    if model_.name == "exact" and len(layout.lengths) == 0:
        raise NoTransectError(
            f"no transect crosses the polygon at spacing {spacing:g} (polygon diameter "
            f"{poly.diameter:g}), angle {math.degrees(angle):g} deg, offset {offset:g}"
        )
    frame = poly.frame
    with torch.no_grad():
        tl = model_(
            halfplanes(poly),
            torch.tensor(float(angle), dtype=torch.float64),
            torch.tensor(float(offset) / frame.scale, dtype=torch.float64),
            float(spacing) / frame.scale,
        )
        value = float(fitness_(tl))
    # The model's grid may span a different window (clip): match transects by position.
    grid = tl.positions.numpy()
    k = np.rint((layout.positions / frame.scale - grid[0]) / (grid[1] - grid[0])).astype(int)
    inside = (k >= 0) & (k < len(grid))
    lengths = np.zeros(len(k))
    lengths[inside] = tl.lengths.numpy()[k[inside]] * frame.scale
    return Score(value, float(angle), float(offset), float(spacing), model_.name, lengths, layout)
