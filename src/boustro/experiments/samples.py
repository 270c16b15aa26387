"""Table I's random samples (polygons as the authors drew them) and its protocols."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidParameterError, InvalidPolygonError
from ..geometry import Polygon

__all__ = [
    "POINTS_PER_TRANSECT",
    "PROTOCOLS",
    "TEMPERATURES",
    "Eq2",
    "Protocol",
    "Samples",
    "Statistics",
    "Trapezoid",
    "Window",
    "draw_samples",
    "polygenerator_convex_polygon",
]


#: Temperatures (rows) and points per transect (columns) of the paper's Table I.
TEMPERATURES: tuple[float, ...] = (1.0, 10.0, 100.0, 1000.0, 10000.0)
POINTS_PER_TRANSECT: tuple[int, ...] = (100, 1000, 10000)


Statistics = Literal["paper", "weighted"]
Window = Literal["paper", "authors"]
Trapezoid = Literal["library", "authors"]
Eq2 = Literal["unit", "printed"]


def polygenerator_convex_polygon(rng: np.random.Generator, n_vertices: int) -> Polygon:
    """A random convex polygon drawn as ``polygenerator.random_convex_polygon`` does.

    The paper's Table I script used the ``polygenerator`` package (0.2.0). Its construction is
    Valtr's, like :func:`boustro.geometry.random_convex_polygon`, with two differences that
    change the distribution of shapes, both reproduced here: the ``n - 2`` inner coordinates
    are split into two chains of exactly ``(n - 2) // 2`` and the rest (not by coin flips), and
    the polygon is stretched to fill the unit square (x and y scaled separately) before the
    authors' rescaling to the normalised frame. Returned in the normalised frame (vertex mean
    at the origin, diameter 1). A draw that fails validation (collinear vertices after
    rounding, probability ~0) raises :class:`~boustro.errors.InvalidPolygonError`.

    >>> poly = polygenerator_convex_polygon(np.random.default_rng(0), 5)
    >>> len(poly), round(poly.diameter, 6)
    (5, 1.0)
    """
    n = int(n_vertices)
    if n != n_vertices or n < 3:
        raise InvalidParameterError(f"n_vertices must be an integer >= 3, got {n_vertices!r}")

    def chains(values: NDArray[np.float64]) -> NDArray[np.float64]:
        values = np.sort(values)
        inner = values[1:-1]
        first = np.zeros(n - 2, dtype=bool)
        first[rng.permutation(n - 2)[: (n - 2) // 2]] = True
        a = np.concatenate([values[:1], inner[first], values[-1:]])
        b = np.concatenate([values[:1], inner[~first], values[-1:]])
        return np.concatenate([np.diff(a), -np.diff(b)])

    dx = chains(rng.random(n))
    dy = chains(rng.random(n))
    rng.shuffle(dy)
    vec = np.stack([dx, dy], axis=1)
    vec = vec[np.argsort(np.arctan2(vec[:, 1], vec[:, 0]), kind="stable")]
    pts = np.concatenate([np.zeros((1, 2)), np.cumsum(vec[:-1], axis=0)])
    pts = (pts - pts.min(axis=0)) / np.ptp(pts, axis=0)  # fit to the unit square
    poly = Polygon(pts)
    if len(poly) != n:
        raise InvalidPolygonError(f"degenerate draw: {len(poly)} distinct corners, wanted {n}")
    return poly.normalised()


@dataclass(frozen=True)
class Samples:
    """Random Table I samples, normalised frame.

    Attributes:
        polygons: convex polygons, 3 to 9 vertices, vertex mean at the origin, diameter 1.
        angle: ``(N,)`` transect directions, radians, uniform in ``[0, 2 pi)`` (the authors'
            ``theta`` in ``[0, 360)`` degrees; the direction is as uniform as their rotation).
        spacing: ``(N,)`` uniform in ``(0, 1/3)`` (the paper, Sec. V).
        phase: ``(N,)`` uniform in ``[0, 1)``: the authors' ``x_offset = (phase - 1/2) s``,
            uniform in ``[-s/2, s/2]`` whatever the spacing ``s``.
        seed: of :func:`numpy.random.default_rng`.
        redrawn: polygon draws rejected by validation (degenerate), if any.
    """

    polygons: tuple[Polygon, ...]
    angle: NDArray[np.float64]
    spacing: NDArray[np.float64]
    phase: NDArray[np.float64]
    seed: int
    redrawn: int = 0

    def __len__(self) -> int:
        return len(self.polygons)

    @property
    def n_vertices(self) -> NDArray[np.int64]:
        return np.array([len(p) for p in self.polygons], dtype=np.int64)

    def head(self, n: int) -> Samples:
        """The first ``n`` samples (the same whatever the total: samples are drawn in turn)."""
        return Samples(
            self.polygons[:n],
            self.angle[:n],
            self.spacing[:n],
            self.phase[:n],
            self.seed,
            self.redrawn,
        )


def draw_samples(n: int, seed: int = 0) -> Samples:
    """``n`` Table I samples drawn in turn from ``numpy.random.default_rng(seed)``.

    Per sample: the vertex count uniform in 3..9 (the authors' ``randint(3, 10)``), a polygon
    (:func:`polygenerator_convex_polygon`), an angle, a spacing and a phase (see
    :class:`Samples`). Sample ``i`` does not depend on ``n``.

    >>> samples = draw_samples(3, seed=1)
    >>> len(samples), samples.n_vertices.tolist()
    (3, [6, 3, 4])
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise InvalidParameterError(f"the number of samples must be an integer >= 1, got {n!r}")
    rng = np.random.default_rng(seed)
    polys: list[Polygon] = []
    angle = np.empty(n)
    spacing = np.empty(n)
    phase = np.empty(n)
    redrawn = 0
    for i in range(int(n)):
        n_vertices = int(rng.integers(3, 10))
        while True:
            try:
                polys.append(polygenerator_convex_polygon(rng, n_vertices))
                break
            except InvalidPolygonError:
                redrawn += 1
        angle[i] = rng.uniform(0.0, 2.0 * math.pi)
        s = 0.0
        while s <= 0.0:  # uniform(0, 1/3) can return 0 (probability 2^-53)
            s = rng.uniform(0.0, 1.0 / 3.0)
        spacing[i] = s
        phase[i] = rng.random()
    return Samples(tuple(polys), angle, spacing, phase, int(seed), redrawn)


@dataclass(frozen=True)
class Protocol:
    """The choices of a Table I experiment that change its numbers.

    Attributes:
        name: short key (JSON, report).
        description: one line for the report.
        clip: a window for the differentiable model: each transect integrated over ``t`` in
            ``[-0.5, 0.5]``, only the transects of ``window``. ``False``: the whole polygon
            (the library's default; ``window`` then plays no part).
        statistics: how Eq. 1 weights the soft mean and std (:func:`boustro.fitness.smith_fitness`).
        spacing: ``None``: each sample's own spacing, uniform in ``(0, 1/3)``; a number: that
            spacing for every sample (normalised frame).
        window: which transects exist with ``clip``: ``"authors"``, the authors' script's
            ``np.arange(-0.5, 0.5, s) + x_offset`` (a window shifted by the offset), or
            ``"paper"``, the grid lines in ``[-0.5, 0.5)`` (the paper's text, and
            ``clip=True`` of the library).
        trapezoid: the trapezoid step of Eq. 6: ``"library"``, ``2 half / (points - 1)`` (the
            points span the window), or ``"authors"``, the authors' ``1 / points`` (with the
            window's half-width 0.5: every length times ``(points - 1) / points``).
        discrete_clip: the window of the discrete fitness (default: the same as ``clip``).
            ``False`` with ``clip=True`` scores the discrete side over the whole polygon at the
            same offset, as a discrete planner would.
        points: points per transect of the columns computed (the paper's three by default).
        eq2: the magnitude of the edges' half-planes ``W x + B`` in Eq. 3: ``"unit"``, unit
            normals (boustro's models), or ``"printed"``, Eq. 2 as printed and in the authors'
            code, ``W = (x1 - x2, y1 - y2)`` of length ``|edge|``: each edge's sigmoid then has
            the temperature ``T |edge|`` (softer on short edges). The exact side is the same.
    """

    name: str
    description: str
    clip: bool
    statistics: Statistics
    spacing: float | None = None
    window: Window = "paper"
    trapezoid: Trapezoid = "library"
    discrete_clip: bool | None = None
    points: tuple[int, ...] = POINTS_PER_TRANSECT
    eq2: Eq2 = "unit"

    def __post_init__(self) -> None:
        if self.statistics not in ("paper", "weighted"):
            raise InvalidParameterError(f"statistics must be 'paper' or 'weighted', got {self}")
        if self.window not in ("paper", "authors"):
            raise InvalidParameterError(f"window must be 'paper' or 'authors', got {self}")
        if self.trapezoid not in ("library", "authors"):
            raise InvalidParameterError(f"trapezoid must be 'library' or 'authors', got {self}")
        if (self.window == "authors" or self.trapezoid == "authors") and not self.clip:
            raise InvalidParameterError("the authors' window and trapezoid step need clip=True")
        if self.eq2 not in ("unit", "printed"):
            raise InvalidParameterError(f"eq2 must be 'unit' or 'printed', got {self}")
        if self.discrete_clip is None:
            object.__setattr__(self, "discrete_clip", self.clip)

    @property
    def layout(self) -> tuple[bool, str, float | None, str]:
        """What decides the differentiable model's transects: protocols that share it share
        the (costly) soft lengths."""
        return (self.clip, self.window if self.clip else "paper", self.spacing, self.eq2)

    @property
    def variant(self) -> tuple[Statistics, Trapezoid]:
        """What turns the shared lengths into this protocol's fitness."""
        return (self.statistics, self.trapezoid)

    @property
    def discrete_layout(self) -> tuple[bool, bool, str, float | None, str]:
        return (bool(self.discrete_clip), *self.layout)


#: The Table I protocols ``boustro reproduce`` runs. The first follows the paper's text and,
#: where the text is silent, the authors' code; each other changes one choice. The first four
#: share their transects (the costly part) and get the whole table.
PROTOCOLS: tuple[Protocol, ...] = (
    Protocol(
        "paper",
        "the paper's text and the authors' code: Eq. 2 as printed (W of length |edge|), "
        "spacing uniform in (0, 1/3), transects arange(-0.5, 0.5, s) + x_offset integrated "
        "over [-0.5, 0.5] with step 1/points, the authors' weighting of the statistics",
        clip=True,
        statistics="paper",
        window="authors",
        trapezoid="authors",
        eq2="printed",
    ),
    Protocol(
        "paper-unit-normals",
        "as 'paper' with unit normals (boustro's models): isolates Eq. 2's magnitude",
        clip=True,
        statistics="paper",
        window="authors",
        trapezoid="authors",
    ),
    Protocol(
        "paper-weighted",
        "as 'paper' with weighted statistics (exact for 0/1 weights): isolates the authors' "
        "weighting",
        clip=True,
        statistics="weighted",
        window="authors",
        trapezoid="authors",
        eq2="printed",
    ),
    Protocol(
        "paper-step",
        "as 'paper' with the trapezoid step 1/(points - 1) (the points span the window): "
        "isolates the authors' step",
        clip=True,
        statistics="paper",
        window="authors",
        eq2="printed",
    ),
    Protocol(
        "paper-whole-discrete",
        "as 'paper', but the discrete fitness over the whole polygon (same offset): what a "
        "discrete planner would score",
        clip=True,
        statistics="paper",
        window="authors",
        trapezoid="authors",
        discrete_clip=False,
        eq2="printed",
    ),
    Protocol(
        "authors-script",
        "the authors' released script: as 'paper' but the spacing fixed at 0.5 (one or two "
        "transects)",
        clip=True,
        statistics="paper",
        spacing=0.5,
        window="authors",
        trapezoid="authors",
        eq2="printed",
    ),
    Protocol(
        "grid-window",
        "as 'paper' with the grid lines in [-0.5, 0.5) as transects (the paper's text; "
        "boustro's clip=True)",
        clip=True,
        statistics="paper",
        trapezoid="authors",
        points=(1000,),
        eq2="printed",
    ),
    Protocol(
        "boustro-clip",
        "boustro's paper model with clip=True and statistics='paper': grid lines in "
        "[-0.5, 0.5), step 1/(points - 1)",
        clip=True,
        statistics="paper",
        points=(1000,),
    ),
    Protocol(
        "project",
        "boustro's defaults: the whole polygon, weighted statistics, step 1/(points - 1)",
        clip=False,
        statistics="weighted",
        points=(1000,),
    ),
)
