"""The paper's experiments (an edge of the system): Table I, gradient descent vs grid search, the
figures. ``boustro reproduce`` (:mod:`boustro.cli.reproduce`) runs them and writes the report.

Conventions are the library's (README, ``models.py``): ``angle`` is the transect DIRECTION in
radians, ``offset`` the signed distance of the transect grid from the polygon's vertex mean along
the transects' left normal, everything in the paper's normalised frame (vertex mean at the
origin, diameter 1) unless a name says otherwise.

**Table I** (paper, Sec. V) is the mean of ``|differentiable - discrete|`` fitness (Eq. 1) over
random samples, for each temperature x points per transect. A sample is a random convex polygon
(3 to 9 vertices, :func:`polygenerator_convex_polygon`), a random transect angle, spacing and
offset. A :class:`Protocol` fixes the choices that change the numbers: the transect window
(the paper's ``[-0.5, 0.5]`` or the whole polygon), how Eq. 1's statistics are weighted
(``fitness.smith_fitness(statistics=...)``), the spacing distribution and which transects exist.
The same samples serve every protocol (common random numbers), so differences between protocols
are due to the protocol alone.

The costly part is the paper's model at 10000 points per transect (a spacing near 0 means
thousands of transects). :func:`paper_model_fitness` evaluates it for many samples at once,
each with its own spacing and window, with the library's arithmetic
(:func:`boustro.models.paper_lengths`; tests check agreement to 1e-12), choosing per group of
samples the cheapest of three exact ways:

* ``"dense"``: every point, the library's tensor, in chunks;
* ``"band"`` (high temperature): where every edge's ``T * distance`` exceeds :data:`BAND_Z` the
  product of sigmoids (Eq. 4) is 1 to within ``E exp(-BAND_Z)`` (below half an ulp of 1), and
  where one edge's is below ``-BAND_Z`` it is below ``exp(-BAND_Z)``; those points take the
  limits ``sigmoid(+-T/2)`` of Eq. 5 and only the band near the boundary is evaluated;
* ``"subsets"`` (low temperature, few edges): ``1 / P`` is a product over the edges of
  ``1 + exp(-z_j)``, which expands into a sum over subsets of edges of (a factor of the
  transect) x (a factor of the point): a matrix product instead of ``E`` log-sigmoids per point.

No sample is silently redrawn: a sample whose discrete fitness is undefined (no transect crosses
the polygon in the window) or whose differentiable fitness is not finite is counted and reported.
"""

from __future__ import annotations

import inspect
import math
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import torch
import torch.nn.functional as F
from numpy.typing import NDArray

from .errors import InvalidParameterError, InvalidPolygonError
from .fitness import smith_fitness
from .geometry import HalfPlanes, Polygon, halfplanes
from .models import PAPER_WINDOW

__all__ = [
    "BAND_Z",
    "FIGURES",
    "PAPER_GRID_MINUS_GRADIENT",
    "PAPER_TABLE1",
    "PARALLELOGRAM",
    "PARALLELOGRAM_SPACING",
    "POINTS_PER_TRANSECT",
    "PROTOCOLS",
    "TEMPERATURES",
    "OptimizerSpec",
    "Protocol",
    "Samples",
    "Table1",
    "compare_optimizers",
    "draw_samples",
    "exact_fitness_batch",
    "fig_fitness_vs_angle",
    "fig_indicator",
    "fig_surface_angle_offset",
    "fig_surface_angle_temperature",
    "figure_data",
    "optimizer_specs",
    "paper_model_fitness",
    "polygenerator_convex_polygon",
    "protocol_groups",
    "render_report",
    "smooth_model_fitness",
    "smooth_table1",
    "table1",
]

#: Temperatures (rows) and points per transect (columns) of the paper's Table I.
TEMPERATURES: tuple[float, ...] = (1.0, 10.0, 100.0, 1000.0, 10000.0)
POINTS_PER_TRANSECT: tuple[int, ...] = (100, 1000, 10000)

#: The paper's Table I: mean |differentiable - discrete| fitness, by temperature, for 100, 1000
#: and 10000 points per transect.
PAPER_TABLE1: dict[float, tuple[float, float, float]] = {
    1.0: (0.50798, 0.50795, 0.50408),
    10.0: (0.08480, 0.08369, 0.08367),
    100.0: (0.03090, 0.03001, 0.03167),
    1000.0: (0.00374, 0.00271, 0.00306),
    10000.0: (0.00203, 0.00055, 0.00016),
}

#: Sec. VII: grid search (200 samples) found an optimum this much higher, on average, than
#: gradient descent with momentum 0.8, over 1000 random polygons.
PAPER_GRID_MINUS_GRADIENT = 0.13633

#: The paper's Figure 1 parallelogram and the spacing of the authors' scripts (its own units:
#: 0.0559 of the normalised frame, 18 transects in the window).
PARALLELOGRAM: tuple[tuple[float, float], ...] = ((8, 4), (8, 10), (4, 8), (4, 2))
PARALLELOGRAM_SPACING = 0.5

#: Half-width, in units of ``T * distance``, of the band around the polygon's boundary where the
#: paper's model is evaluated point by point (module docstring). ``E exp(-41) < 2e-17`` for
#: ``E <= 9`` edges; 41 rather than 40 leaves room for rounding in the classification.
BAND_Z = 41.0

#: Elements (points x edges) of one batched evaluation (4 MB of float64). Small enough that the
#: allocator reuses its blocks: with 32 MB blocks a third of the time went to page faults.
_CHUNK_ELEMENTS = 1 << 19

Statistics = Literal["paper", "weighted"]
Window = Literal["paper", "authors"]
Trapezoid = Literal["library", "authors"]
Eq2 = Literal["unit", "printed"]


# -- samples ----------------------------------------------------------------------------------


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


# -- protocols --------------------------------------------------------------------------------


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


# -- layouts: the transects of every sample under a protocol ---------------------------------


@dataclass
class _Group:
    """Samples with the same edge count, their transects flattened (no padding)."""

    index: NDArray[np.int64]  # (B,) positions of the samples in the experiment
    across: torch.Tensor  # (B, E) n_j . n(theta): edge j holds iff across c + along t + b >= 0
    along: torch.Tensor  # (B, E) n_j . u(theta)
    b: torch.Tensor  # (B, E)
    half: torch.Tensor  # (B,) half-width of the integration window in t
    radius: torch.Tensor  # (B,) largest vertex distance from the origin
    sample: torch.Tensor  # (M,) long: the sample (row in the group) of each transect
    slot: torch.Tensor  # (M,) long: the transect's column in the (B, K) result
    position: torch.Tensor  # (M,) transect positions c
    width: int  # K: columns of the (B, K) result


def _positions(
    clip: bool, window: Window, half: float, offset: float, spacing: float, phase: float
) -> NDArray[np.float64]:
    """The positions of the transects that exist, as :func:`boustro.models.transect_positions`
    computes them (same arithmetic), masked to the window with ``clip``; or the authors'."""
    if window == "authors":
        return np.arange(-0.5, 0.5, spacing) + (phase - 0.5) * spacing
    m = math.ceil(half / spacing) + 1
    k = torch.arange(2 * m, dtype=torch.float64) - m
    c = torch.remainder(torch.tensor(offset, dtype=torch.float64), spacing) + k * spacing
    if clip:
        c = c[(c >= -PAPER_WINDOW) & (c < PAPER_WINDOW)]
    return c.numpy()


def _layouts(
    polygons: Sequence[Polygon],
    angle: NDArray[np.float64],
    offset: NDArray[np.float64],
    spacing: NDArray[np.float64],
    phase: NDArray[np.float64],
    *,
    clip: bool,
    window: Window = "paper",
    eq2: Eq2 = "unit",
    max_width: int = 1 << 18,
) -> list[_Group]:
    """Group the samples by edge count (and bounded size) and flatten their transects.

    ``offset`` is the library's offset (ignored with the authors' window, which uses
    ``phase``). Half-planes come from :func:`boustro.geometry.halfplanes`, exactly as the
    library's models get them for one polygon.
    """
    n = len(polygons)
    edges = np.array([len(p) for p in polygons])
    radius = np.array(
        [float(np.max(np.linalg.norm(p.normalised().vertices, axis=1))) for p in polygons]
    )
    half = np.full(n, PAPER_WINDOW) if clip else radius
    pos = [_positions(clip, window, half[i], offset[i], spacing[i], phase[i]) for i in range(n)]
    counts = np.array([len(c) for c in pos])
    groups: list[_Group] = []
    for e in np.unique(edges):
        members = np.flatnonzero(edges == e)
        members = members[np.argsort(counts[members], kind="stable")]
        start = 0
        while start < len(members):
            stop = start + 1
            while stop < len(members) and (stop + 1 - start) * counts[members[stop]] <= max_width:
                stop += 1
            groups.append(
                _group(
                    [polygons[i] for i in members[start:stop]],
                    members[start:stop],
                    angle,
                    half,
                    radius,
                    pos,
                    counts,
                    eq2,
                )
            )
            start = stop
    return groups


def _group(
    polys: list[Polygon],
    index: NDArray[np.int64],
    angle: NDArray[np.float64],
    half: NDArray[np.float64],
    radius: NDArray[np.float64],
    pos: list[NDArray[np.float64]],
    counts: NDArray[np.int64],
    eq2: Eq2 = "unit",
) -> _Group:
    hp = halfplanes(polys)
    if eq2 == "printed":  # Eq. 2's W = (x1 - x2, y1 - y2): unit normals times |edge|
        scale = torch.ones(hp.offsets.shape, dtype=torch.float64)  # padding stays as it is
        for row, poly in enumerate(polys):
            v = poly.normalised().vertices
            scale[row, : len(v)] = torch.as_tensor(
                np.linalg.norm(np.roll(v, -1, axis=0) - v, axis=1)
            )
        hp = HalfPlanes(hp.normals * scale[..., None], hp.offsets * scale, hp.radius)
    theta = torch.as_tensor(angle[index], dtype=torch.float64)
    # The same arithmetic as models._prepare: rotate the edges, keep the offsets.
    cos, sin = torch.cos(theta)[:, None], torch.sin(theta)[:, None]
    nx, ny = hp.normals[..., 0], hp.normals[..., 1]
    across = -nx * sin + ny * cos
    along = nx * cos + ny * sin
    k = counts[index]
    sample = torch.as_tensor(np.repeat(np.arange(len(index)), k), dtype=torch.long)
    slot = torch.as_tensor(np.concatenate([np.arange(c) for c in k]), dtype=torch.long)
    position = torch.as_tensor(np.concatenate([pos[i] for i in index]), dtype=torch.float64)
    return _Group(
        index=index,
        across=across,
        along=along,
        b=hp.offsets,
        half=torch.as_tensor(half[index], dtype=torch.float64),
        radius=torch.as_tensor(radius[index], dtype=torch.float64),
        sample=sample,
        slot=slot,
        position=position,
        width=int(max(1, k.max(initial=1))),
    )


def _scatter(g: _Group, values: torch.Tensor) -> torch.Tensor:
    """Per-transect values ``(M,)`` into the ``(B, K)`` layout, zeros elsewhere."""
    out = torch.zeros(len(g.index), g.width, dtype=values.dtype)
    out[g.sample, g.slot] = values
    return out


# -- the discrete (exact) fitness ------------------------------------------------------------


def _exact_lengths(g: _Group, clip: bool) -> torch.Tensor:
    """Exact chord lengths ``(M,)``: :func:`boustro.models.exact_chords`' arithmetic."""
    across, along, b = g.across[g.sample], g.along[g.sample], g.b[g.sample]
    lhs = across * g.position[:, None] + b
    parallel = along == 0
    bound = -lhs / torch.where(parallel, torch.ones_like(along), along)
    inf = torch.tensor(math.inf, dtype=torch.float64)
    lower = torch.where(along > 0, bound, -inf).amax(dim=-1)
    upper = torch.where(along < 0, bound, inf).amin(dim=-1)
    if clip:
        lower = lower.clamp(min=-PAPER_WINDOW)
        upper = upper.clamp(max=PAPER_WINDOW)
    blocked = (parallel & (lhs < 0)).any(dim=-1)
    return torch.where(blocked, torch.zeros_like(lower), (upper - lower).clamp(min=0))


def _exact_fitness(g: _Group, clip: bool) -> torch.Tensor:
    """Discrete Eq. 1 per sample ``(B,)`` (``ExactModel`` weights); NaN where none crosses."""
    lengths = _scatter(g, _exact_lengths(g, clip))
    tiny = (1e-12 * g.radius.clamp(min=1e-300))[:, None]
    weights = (lengths > tiny).to(lengths.dtype)
    f = smith_fitness(lengths, weights)
    return torch.where(weights.sum(dim=-1) > 0, f, torch.nan)


# -- the paper's model, many samples at once --------------------------------------------------


def _bounds(
    a: torch.Tensor, along: torch.Tensor, delta: float
) -> tuple[torch.Tensor, torch.Tensor]:
    """The ``t``-interval where ``a_j + along_j t >= delta`` for every edge ``j``: ``(M,)`` x 2.

    ``lo > hi`` where it is empty. Edges with ``|along| <= 1e-12`` count as parallel.
    """
    pos, neg = along > 1e-12, along < -1e-12
    par = ~(pos | neg)
    bound = (delta - a) / torch.where(par, torch.ones_like(along), along)
    inf = torch.tensor(math.inf, dtype=a.dtype)
    lo = torch.where(pos, bound, -inf).amax(dim=-1)
    hi = torch.where(neg, bound, inf).amin(dim=-1)
    blocked = (par & (a < delta)).any(dim=-1)
    return torch.where(blocked, inf, lo), torch.where(blocked, -inf, hi)


class _Soft:
    """What every evaluation path of the paper's model needs for one group and setting."""

    def __init__(self, g: _Group, temperature: float, points: int) -> None:
        self.g = g
        self.temperature = float(temperature)
        self.temp = torch.tensor(self.temperature, dtype=torch.float64)
        self.points = int(points)
        self.dx = 2 * g.half / (self.points - 1)  # (B,), the library's trapezoid step
        ta, tb, self.tal = self.temp * g.across, self.temp * g.b, self.temp * g.along
        # T v = (T across) c + (T b) + (T along) t: the library's factors, the same arithmetic.
        self.lhs = ta[g.sample] * g.position[:, None] + tb[g.sample]  # (M, E)
        self.shared_t = bool(torch.all(g.half == g.half[0]))
        if self.shared_t:
            h = float(g.half[0])
            self.t_grid = torch.linspace(-h, h, self.points, dtype=torch.float64)
        else:
            self.t_grid = torch.stack(
                [
                    torch.linspace(-float(h), float(h), self.points, dtype=torch.float64)
                    for h in g.half
                ]
            )  # (B, P)
        counts = torch.bincount(g.sample, minlength=len(g.index))
        self.row_end = torch.cumsum(counts, 0)
        self.row_start = self.row_end - counts

    def t(self, b: int) -> torch.Tensor:
        return self.t_grid if self.shared_t else self.t_grid[b]

    def trapezoid_weights(self, b: int, p0: int, p1: int) -> torch.Tensor:
        w = torch.full((p1 - p0,), float(self.dx[b]), dtype=torch.float64)
        if p0 == 0:
            w[0] *= 0.5
        if p1 == self.points:
            w[-1] *= 0.5
        return w

    def p_sigma(self, log_p: torch.Tensor) -> torch.Tensor:
        """Eq. 5 from Eq. 4 in log space."""
        return torch.sigmoid(self.temp * (torch.exp(log_p) - 0.5))


def _lengths_dense(s: _Soft, rows: torch.Tensor | None = None) -> torch.Tensor:
    """Every point of every transect (or of ``rows``): the library's tensor, sample by sample,
    in chunks of transects; in-place where the library allocates."""
    g = s.g
    m = len(g.position)
    selected = torch.ones(m, dtype=torch.bool) if rows is None else torch.zeros(m, dtype=torch.bool)
    if rows is not None:
        selected[rows] = True
    n_edges = s.lhs.shape[-1]
    out = torch.zeros(m, dtype=torch.float64)
    chunk = max(1, _CHUNK_ELEMENTS // (s.points * n_edges))
    for b in range(len(g.index)):
        r0, r1 = int(s.row_start[b]), int(s.row_end[b])
        mine = torch.nonzero(selected[r0:r1])[:, 0] + r0
        if len(mine) == 0:
            continue
        tal_t = s.tal[b] * s.t(b)[:, None]  # (P, E): the library's (T along) * t
        for start in range(0, len(mine), chunk):
            r = mine[start : start + chunk]
            tv = s.lhs[r, None, :] + tal_t
            p = torch.exp(F.logsigmoid(tv).sum(dim=-1))  # Eq. 4
            del tv
            p_sigma = torch.sigmoid_(p.sub_(0.5).mul_(s.temp))  # Eq. 5
            out[r] = torch.trapezoid(p_sigma, dx=float(s.dx[b]), dim=-1)  # Eq. 6
    return out if rows is None else out[rows]


#: ``|exponent|`` bounds of the subset expansion (:func:`_lengths_subsets`): the point factors
#: stay in ``[exp(-300), exp(300)]``, the transect factors are capped at ``exp(400)``, so no
#: product or sum of 2^9 of them overflows and none is 0 x inf.
_GAMMA_EXP = 300.0
_ALPHA_EXP = 400.0


def _lengths_subsets(s: _Soft) -> torch.Tensor:
    """Eq. 3-6 by a matrix product: ``1 / P = prod_j (1 + exp(-z_j)) = sum_S alpha_S gamma_S``.

    On a transect ``z_j(t) = lhs_j + tal_j t``. Around a centre ``t_m``,
    ``exp(-z_j(t)) = exp(-z_j(t_m)) exp(-tal_j (t - t_m))``, so the product over the edges
    expands into a sum over the ``2^E`` subsets ``S`` of the edges of (a factor of the transect,
    ``alpha``) x (a factor of the point, ``gamma``): one ``(K, 2^E) @ (2^E, points)`` matrix
    product per sample instead of ``K x points x E`` log-sigmoids. All terms are positive (no
    cancellation); the points are cut into blocks short enough that ``gamma`` stays within
    ``exp(+-300)``. A transect factor above ``exp(400)`` is capped there: the point is then
    outside by so much that ``P < exp(-100)``, and Eq. 5 gives the same value to the last bit.
    """
    g = s.g
    n_edges = s.lhs.shape[-1]
    n_sub = 1 << n_edges
    bits = ((torch.arange(n_sub)[:, None] >> torch.arange(n_edges)) & 1).to(torch.float64)
    e_lo = n_edges // 2
    bits_lo = bits[: 1 << e_lo, :e_lo]  # subsets of the first e_lo edges (low bits)
    bits_hi = bits[:: 1 << e_lo, e_lo:]  # subsets of the others (high bits)
    out = torch.zeros(len(g.position), dtype=torch.float64)
    for b in range(len(g.index)):
        r0, r1 = int(s.row_start[b]), int(s.row_end[b])
        if r0 == r1:
            continue
        tal = s.tal[b]
        reach = float(tal.abs().sum())  # >= |sum of tal over any subset|
        t = s.t(b)
        step = float(t[1] - t[0])
        block = max(2, min(s.points, int(2 * _GAMMA_EXP / max(reach * step, 1e-300))))
        rows_chunk = max(1, _CHUNK_ELEMENTS // min(block, s.points))
        acc = torch.zeros(r1 - r0, dtype=torch.float64)
        sig_lo, sig_hi = bits_lo @ tal[:e_lo], bits_hi @ tal[e_lo:]
        for p0 in range(0, s.points, block):
            p1 = min(s.points, p0 + block)
            tt = t[p0:p1]
            tm = 0.5 * (tt[0] + tt[-1])
            dt = tt - tm
            gamma = (
                torch.exp(-sig_hi[:, None, None] * dt) * torch.exp(-sig_lo[None, :, None] * dt)
            ).reshape(n_sub, -1)  # (2^E, block): subset index = hi * 2^e_lo + lo
            w = s.trapezoid_weights(b, p0, p1)
            for q0 in range(r0, r1, rows_chunk):
                q1 = min(r1, q0 + rows_chunk)
                zc = s.lhs[q0:q1] + tal * tm  # z at the block's centre, (rows, E)
                alpha = torch.exp(-(zc @ bits.T).clamp(min=-_ALPHA_EXP))
                p = torch.reciprocal(alpha @ gamma)
                acc[q0 - r0 : q1 - r0] += torch.sigmoid(s.temp * (p - 0.5)) @ w
        out[r0:r1] = acc
    bad = ~torch.isfinite(out)
    if bool(bad.any()):  # cannot happen (see the bounds above); the direct way as a guard
        out[bad] = _lengths_dense(s, torch.nonzero(bad)[:, 0])
    return out


def _band_counts(s: _Soft) -> dict[str, torch.Tensor]:
    """Per transect, the index ranges of the "in" points and of the band (module docstring)."""
    g = s.g
    a = g.across[g.sample] * g.position[:, None] + g.b[g.sample]
    along = g.along[g.sample]
    lo_in, hi_in = _bounds(a, along, BAND_Z / s.temperature)
    lo_d, hi_d = _bounds(a, along, -BAND_Z / s.temperature)
    h_m, dx_m = g.half[g.sample], s.dx[g.sample]
    last = s.points - 1

    def index(x: torch.Tensor, ceil: bool, shift: int, low: int, high: int) -> torch.Tensor:
        f = (x + h_m) / dx_m
        f = (torch.ceil(f) if ceil else torch.floor(f)) + shift
        return torch.nan_to_num(f, nan=float(low)).clamp(low, high).to(torch.long)

    # One point of margin on each side for the rounding of linspace and of the bounds.
    p_lo_in = index(lo_in, True, 1, 0, s.points)
    p_hi_in = index(hi_in, False, -1, -1, last)
    p_lo_d = index(lo_d, False, -1, 0, s.points)
    p_hi_d = index(hi_d, True, 1, -1, last)
    n_in = (p_hi_in - p_lo_in + 1).clamp(min=0)
    has_in = n_in > 0
    n_d = (p_hi_d - p_lo_d + 1).clamp(min=0)
    n1 = torch.where(has_in, (p_lo_in - p_lo_d).clamp(min=0), n_d)
    n2 = torch.where(has_in, (p_hi_d - p_hi_in).clamp(min=0), torch.zeros_like(n_d))
    return {
        "p_lo_in": p_lo_in,
        "p_hi_in": p_hi_in,
        "p_lo_d": p_lo_d,
        "p_hi_d": p_hi_d,
        "n_in": n_in,
        "has_in": has_in,
        "n1": n1,
        "n2": n2,
    }


def _lengths_band(s: _Soft, c: dict[str, torch.Tensor]) -> torch.Tensor:
    """Only the points near the boundary, point by point (ragged); the others at Eq. 5's
    limits ``sigmoid(T / 2)`` (inside) and ``sigmoid(-T / 2)`` (outside)."""
    g = s.g
    m = len(g.position)
    n_edges = s.lhs.shape[-1]
    last = s.points - 1
    dx_m = s.dx[g.sample]
    n1, n2, has_in = c["n1"], c["n2"], c["has_in"]
    s2 = c["p_hi_in"] + 1
    lengths = torch.zeros(m, dtype=torch.float64)
    per = n1 + n2
    budget = max(s.points, _CHUNK_ELEMENTS // n_edges)
    cum = torch.cumsum(per, 0)
    begin = 0
    while begin < m:  # chunks of whole transects, about `budget` points each
        done = int(cum[begin - 1]) if begin else 0
        end = min(m, max(begin + 1, int(torch.searchsorted(cum, done + budget, right=True))))
        rows = torch.arange(begin, end)
        starts = torch.stack([c["p_lo_d"][rows], s2[rows]], dim=-1).flatten()
        counts = torch.stack([n1[rows], n2[rows]], dim=-1).flatten()
        seg = torch.repeat_interleave(torch.arange(len(counts)), counts)
        first = torch.repeat_interleave(torch.cumsum(counts, 0) - counts, counts)
        pi = starts[seg] + (torch.arange(len(seg)) - first)
        ti = rows.repeat_interleave(2)[seg]
        t = s.t_grid[pi] if s.shared_t else s.t_grid[g.sample[ti], pi]
        tv = s.lhs[ti] + s.tal[g.sample[ti]] * t[:, None]
        p_sigma = s.p_sigma(F.logsigmoid(tv).sum(dim=-1))
        weight = torch.where((pi == 0) | (pi == last), 0.5, 1.0).to(torch.float64) * dx_m[ti]
        lengths.index_add_(0, ti, p_sigma * weight)
        begin = end
    f64 = torch.float64
    n_in = c["n_in"]
    ends_in = (has_in & (c["p_lo_in"] == 0)).to(f64) + (has_in & (c["p_hi_in"] == last)).to(f64)
    band_first = (n1 > 0) & (c["p_lo_d"] == 0)
    band_last = torch.where(has_in, n2 > 0, n1 > 0) & (c["p_hi_d"] == last)
    ends_out = 2.0 - ends_in - band_first.to(f64) - band_last.to(f64)
    n_out = s.points - n_in - n1 - n2
    w_in = dx_m * (n_in.to(f64) - 0.5 * ends_in)
    w_out = dx_m * (n_out.to(f64) - 0.5 * ends_out)
    return lengths + w_in * torch.sigmoid(s.temp / 2) + w_out * torch.sigmoid(-s.temp / 2)


Method = Literal["auto", "dense", "band", "subsets"]


def _soft_lengths(
    g: _Group, temperature: float, points: int, method: Method = "auto"
) -> torch.Tensor:
    """The paper's transect lengths (Eq. 3-6) ``(M,)``, equal to
    :func:`boustro.models.paper_lengths`' to rounding, by the cheapest of three ways:
    ``"dense"`` (the library's tensor), ``"band"`` (only the points near the boundary) and
    ``"subsets"`` (a matrix product, :func:`_lengths_subsets`). ``"auto"`` picks the cheapest
    by a cost model in nanoseconds per point, measured on a 2-core CPU."""
    s = _Soft(g, temperature, points)
    if method == "dense":
        return _lengths_dense(s)
    if method == "subsets":
        return _lengths_subsets(s)
    counts = _band_counts(s)
    if method == "band":
        return _lengths_band(s, counts)
    n_edges, n_sub = s.lhs.shape[-1], 1 << s.lhs.shape[-1]
    m, points = len(g.position), s.points
    reach = float((s.tal.abs().sum(dim=-1) * 2 * g.half).max())
    blocks = max(1.0, reach / (2 * _GAMMA_EXP))
    costs = {
        "band": (40.0 + 8.0 * n_edges) * float((counts["n1"] + counts["n2"]).sum()),
        "dense": (25.0 + 5.0 * n_edges) * m * points,
        "subsets": (10.0 + 0.15 * n_sub) * m * points
        + n_sub * (len(g.index) * points + 10.0 * m * blocks),
    }
    best = min(costs, key=costs.__getitem__)
    if best == "band":
        return _lengths_band(s, counts)
    return _lengths_dense(s) if best == "dense" else _lengths_subsets(s)


def _soft_fitness(
    g: _Group,
    temperature: float,
    points: int,
    variants: Sequence[tuple[Statistics, Trapezoid]],
    method: Method = "auto",
) -> dict[tuple[Statistics, Trapezoid], torch.Tensor]:
    """Eq. 1 of the paper's model per sample ``(B,)`` for each (statistics, trapezoid step)
    variant (see :class:`Protocol`), from one evaluation of the lengths."""
    library = _scatter(g, _soft_lengths(g, temperature, points, method))
    temp = torch.tensor(float(temperature), dtype=torch.float64)
    out = {}
    for statistics, trapezoid in variants:
        # The authors' step 1 / points instead of 2 half / (points - 1): with the window's half
        # of 0.5, every length times (points - 1) / points.
        lengths = library * ((points - 1) / points) if trapezoid == "authors" else library
        weights = 2 * torch.sigmoid(temp * lengths) - 1  # Eq. 7; 0 where padded (length 0)
        out[(statistics, trapezoid)] = smith_fitness(lengths, weights, statistics=statistics)
    return out


def _sample_offsets(samples: Samples, spacing: NDArray[np.float64]) -> NDArray[np.float64]:
    """The library's offset of the authors' grid ``-0.5 + x_offset + k s``."""
    return (samples.phase - 0.5) * spacing - 0.5


def _protocol_spacing(samples: Samples, protocol: Protocol) -> NDArray[np.float64]:
    if protocol.spacing is None:
        return samples.spacing
    return np.full(len(samples), float(protocol.spacing))


def protocol_groups(samples: Samples, protocol: Protocol) -> list[_Group]:
    """The samples' transects under ``protocol`` (see :class:`Protocol`), grouped."""
    spacing = _protocol_spacing(samples, protocol)
    return _layouts(
        samples.polygons,
        samples.angle,
        _sample_offsets(samples, spacing),
        spacing,
        samples.phase,
        clip=protocol.clip,
        window=protocol.window,
        eq2=protocol.eq2,
    )


def exact_fitness_batch(samples: Samples, protocol: Protocol) -> NDArray[np.float64]:
    """The discrete fitness of every sample under ``protocol`` (its ``discrete_clip``); NaN
    where no transect crosses the polygon."""
    out = np.full(len(samples), np.nan)
    clip = bool(protocol.discrete_clip)
    if clip != protocol.clip:  # the whole polygon: the library's grid at the same offset
        protocol = Protocol(
            "discrete", "", clip=False, statistics="weighted", spacing=protocol.spacing
        )
    with torch.no_grad():
        for g in protocol_groups(samples, protocol):
            out[g.index] = _exact_fitness(g, clip).numpy()
    return out


def paper_model_fitness(
    samples: Samples,
    protocol: Protocol,
    temperature: float,
    points: int,
    groups: list[_Group] | None = None,
    method: Method = "auto",
) -> NDArray[np.float64]:
    """The paper's model's fitness (Eq. 1-7) of every sample under ``protocol``, ``(N,)``.

    Equal, to rounding, to ``smith_fitness(*PaperModel(T, points, clip)(hp, angle, offset,
    spacing)[:2], statistics=...)`` called once per sample (for the ``"paper"`` window; the
    authors' window has its own transects), but batched and with the savings of the module
    docstring.
    """
    out = np.full(len(samples), np.nan)
    groups = protocol_groups(samples, protocol) if groups is None else groups
    with torch.no_grad():
        for g in groups:
            f = _soft_fitness(g, temperature, points, [protocol.variant], method)
            out[g.index] = f[protocol.variant].numpy()
    return out


# -- Table I ----------------------------------------------------------------------------------


def _progress(total: float, desc: str, progress: bool, unit: str = "it") -> Any:
    """A tqdm bar on stderr (a no-op one when ``progress`` is false)."""
    from tqdm.auto import tqdm

    return tqdm(
        total=total,
        desc=desc,
        file=sys.stderr,
        disable=not progress,
        unit=unit,
        unit_scale=True,
        leave=True,
        dynamic_ncols=True,
    )


@dataclass(frozen=True)
class Table1:
    """One Table I: mean ``|differentiable - discrete|`` fitness per temperature x column.

    Attributes:
        protocol: the protocol the numbers come from.
        model: ``"paper"`` (Eq. 2-7) or ``"smooth"`` (the closed form, :mod:`boustro.smooth`,
            smoothing ``1 / T``).
        temperatures: the rows.
        points: the columns: points per transect (``None`` for the closed form).
        mean: ``(rows, columns)`` mean absolute error over the samples with a value.
        sem: standard error of that mean (sample std / sqrt(n)).
        max: largest absolute error.
        valid: samples with both fitnesses defined, per cell.
        no_value_discrete: samples whose discrete fitness is undefined (no transect crosses the
            polygon in the window); left out of every cell, never redrawn.
        no_value_model: per cell, samples whose differentiable fitness is not finite.
        n_samples: samples drawn.
    """

    protocol: Protocol
    model: str
    temperatures: tuple[float, ...]
    points: tuple[int | None, ...]
    mean: NDArray[np.float64]
    sem: NDArray[np.float64]
    max: NDArray[np.float64]
    valid: NDArray[np.int64]
    no_value_discrete: int
    no_value_model: NDArray[np.int64]
    n_samples: int

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> Table1:
        """Inverse of :meth:`to_json` (for reports of earlier runs)."""
        st = d["settings"]
        spacing = None if isinstance(st["spacing"], str) else float(st["spacing"])
        protocol = Protocol(
            d["protocol"],
            d["description"],
            clip=st["clip"],
            statistics=st["statistics"],
            spacing=spacing,
            window=st["window"],
            trapezoid=st.get("trapezoid", "library"),
            discrete_clip=st["discrete_clip"],
        )

        def arr(key: str, dtype: Any = np.float64) -> NDArray[Any]:
            return np.array(
                [[np.nan if v is None else v for v in row] for row in d[key]], dtype=dtype
            )

        return cls(
            protocol,
            d["model"],
            tuple(d["temperatures"]),
            tuple(d["points_per_transect"]),
            arr("mean_abs_error"),
            arr("sem"),
            arr("max_abs_error"),
            arr("valid_samples", np.int64),
            int(d["no_value_discrete"]),
            arr("no_value_model", np.int64),
            int(d["n_samples"]),
        )

    def to_json(self) -> dict[str, Any]:
        def cells(a: NDArray[Any]) -> list[list[Any]]:
            return [[_json_number(v) for v in row] for row in a.tolist()]

        return {
            "protocol": self.protocol.name,
            "description": self.protocol.description,
            "settings": {
                "clip": self.protocol.clip,
                "discrete_clip": self.protocol.discrete_clip,
                "statistics": self.protocol.statistics,
                "spacing": "uniform(0, 1/3)"
                if self.protocol.spacing is None
                else self.protocol.spacing,
                "window": self.protocol.window,
                "trapezoid": self.protocol.trapezoid,
            },
            "model": self.model,
            "temperatures": list(self.temperatures),
            "points_per_transect": list(self.points),
            "mean_abs_error": cells(self.mean),
            "sem": cells(self.sem),
            "max_abs_error": cells(self.max),
            "valid_samples": cells(self.valid),
            "no_value_discrete": self.no_value_discrete,
            "no_value_model": cells(self.no_value_model),
            "n_samples": self.n_samples,
        }


def _json_number(v: Any) -> Any:
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v


def _summarise(
    protocol: Protocol,
    model: str,
    temperatures: Sequence[float],
    points: Sequence[int | None],
    exact: NDArray[np.float64],
    soft: dict[tuple[float, int | None], NDArray[np.float64]],
) -> Table1:
    shape = (len(temperatures), len(points))
    mean, sem, mx = np.full(shape, np.nan), np.full(shape, np.nan), np.full(shape, np.nan)
    valid, no_model = np.zeros(shape, dtype=np.int64), np.zeros(shape, dtype=np.int64)
    has_exact = np.isfinite(exact)
    for i, t in enumerate(temperatures):
        for j, pts in enumerate(points):
            f = soft[(t, pts)]
            no_model[i, j] = int(np.sum(~np.isfinite(f)))
            ok = has_exact & np.isfinite(f)
            err = np.abs(f[ok] - exact[ok])
            valid[i, j] = len(err)
            if len(err):
                mean[i, j] = float(err.mean())
                mx[i, j] = float(err.max())
                sem[i, j] = float(err.std(ddof=1) / math.sqrt(len(err))) if len(err) > 1 else 0.0
    return Table1(
        protocol,
        model,
        tuple(float(t) for t in temperatures),
        tuple(points),
        mean,
        sem,
        mx,
        valid,
        int(np.sum(~has_exact)),
        no_model,
        len(exact),
    )


def table1(
    samples: Samples,
    protocols: Sequence[Protocol] = PROTOCOLS,
    temperatures: Sequence[float] = TEMPERATURES,
    *,
    points: Sequence[int] | None = None,
    progress: bool = False,
) -> dict[str, Table1]:
    """Table I of the paper for every protocol, by name.

    The differentiable model is evaluated once per (transect layout, temperature, points) and
    serves every protocol with that layout (each with its own statistics and discrete side).

    Args:
        samples: from :func:`draw_samples`.
        protocols: see :data:`PROTOCOLS`.
        temperatures: rows.
        points: columns for every protocol (default: each protocol's own ``points``).
        progress: a tqdm bar on stderr, in transect points evaluated.
    """
    cols = {p.name: tuple(points) if points is not None else p.points for p in protocols}
    layouts: dict[tuple[Any, ...], list[Protocol]] = {}
    for p in protocols:
        layouts.setdefault(p.layout, []).append(p)
    exact: dict[tuple[Any, ...], NDArray[np.float64]] = {}
    for p in protocols:
        if p.discrete_layout not in exact:
            exact[p.discrete_layout] = exact_fitness_batch(samples, p)
    groups = {key: protocol_groups(samples, ps[0]) for key, ps in layouts.items()}
    work = {
        key: (
            sum(len(g.position) for g in groups[key]),
            sorted({c for p in ps for c in cols[p.name]}),
        )
        for key, ps in layouts.items()
    }
    total = sum(m * sum(pts) * len(temperatures) for m, pts in work.values())
    soft: dict[str, dict[tuple[float, int | None], NDArray[np.float64]]] = {
        p.name: {} for p in protocols
    }
    with _progress(total, "Table I", progress, unit="pt") as bar:
        for key, ps in layouts.items():
            m, pts_list = work[key]
            stats = sorted({p.variant for p in ps})
            for pts in pts_list:
                for t in temperatures:
                    values = {v: np.full(len(samples), np.nan) for v in stats}
                    with torch.no_grad():
                        for g in groups[key]:
                            f = _soft_fitness(g, float(t), int(pts), stats)
                            for v in stats:
                                values[v][g.index] = f[v].numpy()
                    for p in ps:
                        if pts in cols[p.name]:
                            soft[p.name][(float(t), pts)] = values[p.variant]
                    bar.update(m * pts)
    return {
        p.name: _summarise(
            p, "paper", temperatures, cols[p.name], exact[p.discrete_layout], soft[p.name]
        )
        for p in protocols
    }


def smooth_model_fitness(
    samples: Samples, protocol: Protocol, temperature: float
) -> NDArray[np.float64]:
    """Eq. 1 of the closed-form smooth model (:class:`boustro.smooth.SmoothModel`, smoothing
    ``1 / T``) of every sample under ``protocol`` (``"paper"`` window only: the model places
    its own grid), one call per sample.

    Raises:
        ImportError: :mod:`boustro.smooth` is not available.
    """
    from .smooth import SmoothModel

    if protocol.window != "paper":
        raise InvalidParameterError("the smooth model places the library's grid ('paper' window)")
    model = SmoothModel.from_temperature(float(temperature), clip=protocol.clip)
    spacing = _protocol_spacing(samples, protocol)
    offset = _sample_offsets(samples, spacing)
    out = np.empty(len(samples))
    with torch.no_grad():
        for i, poly in enumerate(samples.polygons):
            tl = model(
                halfplanes(poly),
                torch.tensor(samples.angle[i], dtype=torch.float64),
                torch.tensor(offset[i], dtype=torch.float64),
                float(spacing[i]),
            )
            out[i] = float(smith_fitness(tl.lengths, tl.weights, statistics=protocol.statistics))
    return out


def smooth_table1(
    samples: Samples,
    protocols: Sequence[Protocol],
    temperatures: Sequence[float] = TEMPERATURES,
    *,
    progress: bool = False,
) -> dict[str, Table1]:
    """Table I for the closed-form smooth model (one column), for the protocols it applies
    to: the library's grid (``"paper"`` window) and no trapezoid (``trapezoid="library"``).
    Empty if :mod:`boustro.smooth` is not available."""
    try:
        from .smooth import SmoothModel  # noqa: F401
    except ImportError:
        return {}
    usable = [p for p in protocols if p.window == "paper" and p.trapezoid == "library"]
    out: dict[str, Table1] = {}
    with _progress(len(usable) * len(temperatures), "Table I, closed form", progress) as bar:
        for p in usable:
            exact = exact_fitness_batch(samples, p)
            soft: dict[tuple[float, int | None], NDArray[np.float64]] = {}
            for t in temperatures:
                soft[(float(t), None)] = smooth_model_fitness(samples, p, t)
                bar.update(1)
            out[p.name] = _summarise(p, "smooth", temperatures, (None,), exact, soft)
    return out


# -- gradient descent vs grid search (Sec. VII) ------------------------------------------------


def _supported(fn: Callable[..., Any], options: dict[str, Any]) -> dict[str, Any]:
    """The options ``fn``'s signature accepts (the optimisers are still evolving)."""
    params = inspect.signature(fn).parameters
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values()):
        return dict(options)
    return {k: v for k, v in options.items() if k in params}


@dataclass(frozen=True)
class OptimizerSpec:
    """An optimiser of the comparison: a name, what it is, and how to run it."""

    name: str
    description: str
    run: Callable[[Polygon, float, int], Any] | None  # (polygon, spacing, seed) -> OptimizeResult
    options: dict[str, Any] = field(default_factory=dict)
    unavailable: str | None = None


def _describe_guide(opt: Any) -> str:
    """boustro's default guiding model and temperature schedule, in words."""
    guide = getattr(opt, "DEFAULT_GUIDE", None)
    schedule = getattr(opt, "DEFAULT_SCHEDULE", None)
    if guide is None:
        return "boustro's default guiding model"
    words = getattr(guide, "name", type(guide).__name__) + " model"
    if hasattr(guide, "points_per_transect"):
        words += f", {guide.points_per_transect} points per transect"
    if schedule is not None:
        words += f", temperature {schedule} (start:end, annealed)"
    return words


def optimizer_specs() -> list[OptimizerSpec]:
    """The optimisers compared: the paper's grid search and gradient descent, and boustro's
    hybrid and certified global optimisers where this installation has them."""
    from . import optimize as opt

    specs: list[OptimizerSpec] = []
    grid_options = dict(getattr(opt, "GRID_200", {"n_angles": 14, "n_offsets": 14}))
    specs.append(
        OptimizerSpec(
            "grid",
            "grid search, the paper's 200 samples "
            f"({grid_options['n_angles']} angles x {grid_options['n_offsets']} offsets)",
            lambda poly, s, seed: opt.optimize(poly, s, method="grid", **grid_options),
            grid_options,
        )
    )
    # The paper's experiment as optimize.gradient_descent documents it: plain SGD with momentum
    # 0.8, one random start, 200 steps, no screening, no exact zoom, no early stop.
    gradient_options = {
        "optimizer": "sgd",
        "momentum": 0.8,
        "steps": 200,
        "starts": 1,
        "screen": 0,
        "zoom_levels": 0,
        "patience": None,
    }
    methods = getattr(opt, "METHODS", {})
    if "gradient" in methods:
        gradient = methods["gradient"]
        applied = _supported(gradient, gradient_options)
        dropped = sorted(set(gradient_options) - set(applied))
        specs.append(
            OptimizerSpec(
                "gradient",
                "gradient descent with momentum 0.8 (SGD), one random start, 200 steps, "
                f"guided by {_describe_guide(opt)}; its answer is the best iterate by the "
                "exact fitness"
                + (f" (options this version lacks: {', '.join(dropped)})" if dropped else ""),
                lambda poly, s, seed: gradient(poly, s, seed=seed, **applied),
                applied,
            )
        )
    else:
        specs.append(OptimizerSpec("gradient", "gradient descent", None, {}, "not available"))
    if "hybrid" in methods:
        specs.append(
            OptimizerSpec(
                "hybrid",
                "boustro's hybrid: grid, gradient refinement of the best grid points, exact zoom",
                lambda poly, s, seed: opt.optimize(poly, s, method="hybrid"),
            )
        )
    else:
        specs.append(OptimizerSpec("hybrid", "hybrid", None, {}, "not available"))
    run_global = None
    try:
        from . import global_opt

        if hasattr(global_opt, "global_optimum"):
            run_global = lambda poly, s, seed: global_opt.global_optimum(poly, s)  # noqa: E731
    except ImportError:
        pass
    if run_global is None and "global" in methods:
        run_global = lambda poly, s, seed: opt.optimize(poly, s, method="global")  # noqa: E731
    specs.append(
        OptimizerSpec(
            "global",
            "boustro's certified global optimum (branch and bound over the exact fitness)",
            run_global,
            {},
            None if run_global is not None else "not available",
        )
    )
    return specs


def _final_iterate_fitness(result: Any, poly: Polygon, spacing: float) -> float:
    """Exact fitness of the LAST iterate of a gradient run (the paper reports where gradient
    descent ends, not the best point it passed), or NaN if the result has no trajectory."""
    from .optimize import exact_fitness

    trajectory = getattr(result, "info", {}).get("trajectory")
    if trajectory is None:
        return math.nan
    last = np.asarray(trajectory)[-1]
    last = last.reshape(-1, 2)
    values = [exact_fitness(poly, spacing, float(a), float(d)) for a, d in last]
    return float(max(values)) if values else math.nan


def compare_optimizers(
    samples: Samples,
    specs: Sequence[OptimizerSpec] | None = None,
    *,
    progress: bool = False,
) -> dict[str, Any]:
    """Sec. VII: every optimiser on every sample (polygon and spacing of Table I's samples).

    Each answer is scored with the exact fitness (whole polygon, Eq. 1, weighted statistics:
    the library's default). A run that raises is counted as a failure (with its first message)
    and left out of the comparisons that need it.

    Returns:
        A JSON-ready dict: ``n``, ``seed``, ``methods`` (per optimiser: ``available``,
        ``description``, ``options``, ``fitness`` per sample (null for a failure),
        ``seconds`` per sample, ``failures``, ``first_error``, ``mean_fitness``,
        ``total_seconds``; the gradient also ``final_iterate_fitness``) and ``comparisons``
        (see :func:`_compare`).
    """
    specs = optimizer_specs() if specs is None else list(specs)
    n = len(samples)
    fitness = {sp.name: np.full(n, np.nan) for sp in specs}
    seconds = {sp.name: np.full(n, np.nan) for sp in specs}
    failures = {sp.name: 0 for sp in specs}
    first_error: dict[str, str | None] = {sp.name: None for sp in specs}
    final = np.full(n, np.nan)
    runnable = [sp for sp in specs if sp.run is not None]
    with _progress(n * len(runnable), "optimisers", progress, unit="run") as bar:
        for i, poly in enumerate(samples.polygons):
            s = float(samples.spacing[i])
            for sp in runnable:
                t0 = time.perf_counter()
                try:
                    result = sp.run(poly, s, samples.seed * 1_000_003 + i)  # type: ignore[misc]
                    fitness[sp.name][i] = float(result.fitness)
                    if sp.name == "gradient":
                        final[i] = _final_iterate_fitness(result, poly, s)
                except Exception as exc:  # counted and reported, never fatal
                    failures[sp.name] += 1
                    if first_error[sp.name] is None:
                        first_error[sp.name] = f"sample {i}: {type(exc).__name__}: {exc}"
                seconds[sp.name][i] = time.perf_counter() - t0
                bar.update(1)
    methods: dict[str, Any] = {}
    for sp in specs:
        f = fitness[sp.name]
        entry = {
            "available": sp.run is not None,
            "unavailable_reason": sp.unavailable,
            "description": sp.description,
            "options": sp.options,
            "fitness": [_json_number(float(v)) for v in f],
            "seconds": [_json_number(float(v)) for v in seconds[sp.name]],
            "failures": failures[sp.name],
            "first_error": first_error[sp.name],
            "mean_fitness": _json_number(float(np.nanmean(f))) if np.isfinite(f).any() else None,
            "total_seconds": float(np.nansum(seconds[sp.name])),
        }
        if sp.name == "gradient":
            entry["final_iterate_fitness"] = [_json_number(float(v)) for v in final]
        methods[sp.name] = entry
    comparisons: dict[str, Any] = {}
    for name in ("gradient", "gradient-final", "hybrid", "global"):
        other = final if name == "gradient-final" else fitness.get(name)
        if other is None or "grid" not in fitness:
            continue
        comparisons[name] = _compare(fitness["grid"], other)
    if "global" in fitness and np.isfinite(fitness["global"]).any():
        # A consistency check: no optimiser should beat the certified optimum (tolerance 1e-6).
        others = [f for k, f in fitness.items() if k != "global"]
        excess = np.nanmax(np.stack(others), axis=0) - fitness["global"] if others else None
        if excess is not None and np.isfinite(excess).any():
            comparisons["global_check"] = {
                "n": int(np.isfinite(excess).sum()),
                "largest_excess_over_global": float(np.nanmax(excess)),
                "beaten_by_more_than_1e-6": int(np.sum(excess > 1e-6)),
            }
    return {
        "n": n,
        "seed": samples.seed,
        "methods": methods,
        "comparisons": comparisons,
        "paper": {"grid_minus_gradient": PAPER_GRID_MINUS_GRADIENT, "n": 1000},
    }


def _compare(grid: NDArray[np.float64], other: NDArray[np.float64]) -> dict[str, Any]:
    """Grid search against another optimiser on the samples where both have an answer:
    ``mean_grid_minus_other`` (the paper's 0.13633 for gradient descent), ``sem``,
    ``share_other_higher`` / ``share_equal`` / ``share_grid_higher`` (equal: within 1e-9)."""
    ok = np.isfinite(grid) & np.isfinite(other)
    n = int(ok.sum())
    if n == 0:
        return {"n": 0}
    diff = grid[ok] - other[ok]
    return {
        "n": n,
        "mean_grid_minus_other": float(diff.mean()),
        "sem": float(diff.std(ddof=1) / math.sqrt(n)) if n > 1 else 0.0,
        "share_other_higher": float(np.mean(diff < -1e-9)),
        "share_equal": float(np.mean(np.abs(diff) <= 1e-9)),
        "share_grid_higher": float(np.mean(diff > 1e-9)),
    }


# -- the figures (the paper's parallelogram) -------------------------------------------------


def _parallelogram() -> tuple[Polygon, float]:
    """The paper's parallelogram in the normalised frame and its spacing there (0.0559)."""
    poly = Polygon(PARALLELOGRAM)
    return poly.normalised(), PARALLELOGRAM_SPACING / poly.diameter


def _parallelogram_fitness(
    angle: NDArray[np.float64],
    phase: NDArray[np.float64],
    temperature: float | None,
    points: int = 1000,
) -> NDArray[np.float64]:
    """Eq. 1 of the paper's model (or the exact one, ``temperature=None``) of the
    parallelogram at each (angle, phase), the authors' script's protocol: transects
    ``arange(-0.5, 0.5, s) + x_offset`` (18 of them), window ``[-0.5, 0.5]``, their weighting."""
    poly, s = _parallelogram()
    n = len(angle)
    spacing = np.full(n, s)
    groups = _layouts(
        [poly] * n,
        np.asarray(angle, dtype=np.float64),
        (phase - 0.5) * s - 0.5,
        spacing,
        np.asarray(phase, dtype=np.float64),
        clip=True,
        window="authors",
    )
    out = np.full(n, np.nan)
    with torch.no_grad():
        for g in groups:
            if temperature is None:
                out[g.index] = _exact_fitness(g, True).numpy()
            else:
                v: tuple[Statistics, Trapezoid] = ("paper", "authors")
                out[g.index] = _soft_fitness(g, temperature, points, [v])[v].numpy()
    return out


def _indicator(
    angle: float, temperature: float, n_points: int
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Eq. 5 along the parallelogram's 18 transects at ``angle``, x_offset 0: the points'
    ``(x, y)`` in the normalised frame ``(K, n_points)`` each, the values, and the outline."""
    poly, s = _parallelogram()
    hp = halfplanes(poly)
    c = torch.as_tensor(np.arange(-0.5, 0.5, s), dtype=torch.float64)
    t = torch.linspace(-0.5, 0.5, n_points, dtype=torch.float64)
    temp = torch.tensor(float(temperature), dtype=torch.float64)
    u = torch.tensor([math.cos(angle), math.sin(angle)], dtype=torch.float64)
    nrm = torch.tensor([-math.sin(angle), math.cos(angle)], dtype=torch.float64)
    pts = c[:, None, None] * nrm + t[None, :, None] * u  # (K, P, 2)
    v = pts @ hp.normals.T + hp.offsets  # (K, P, E)
    p = torch.exp(F.logsigmoid(temp * v).sum(dim=-1))  # Eq. 4
    p_sigma = torch.sigmoid(temp * (p - 0.5))  # Eq. 5
    outline = np.vstack([poly.vertices, poly.vertices[:1]])
    return pts[..., 0].numpy(), pts[..., 1].numpy(), p_sigma.numpy(), outline


def figure_data(quick: bool = False, *, progress: bool = False) -> dict[str, Any]:
    """Everything the four figures plot (JSON-ready after ``tolist``), on the parallelogram.

    Angles are the library's transect direction in degrees; ``x_offset`` is the authors' offset
    of their transects ``arange(-0.5, 0.5, s) + x_offset``, in the parallelogram's units.
    """
    _, s = _parallelogram()
    scale = Polygon(PARALLELOGRAM).diameter
    n_angle = 36 if quick else 180
    out: dict[str, Any] = {"spacing_normalised": s, "spacing": PARALLELOGRAM_SPACING}
    with _progress(4, "figures", progress, unit="fig") as bar:
        fig2 = {}
        for temp in (17.0, 100.0):
            x, y, z, outline = _indicator(math.pi / 2, temp, 100 if quick else 400)
            fig2[temp] = {"x": x, "y": y, "p_sigma": z}
        out["indicator"] = {"angle_deg": 90.0, "outline": outline, "by_temperature": fig2}
        bar.update(1)

        angles = np.arange(4 * n_angle) * (180.0 / (4 * n_angle))
        half = np.full(len(angles), 0.5)
        out["fitness_vs_angle"] = {
            "angle_deg": angles,
            "temperature": 10000.0,
            "points_per_transect": 1000,
            "paper_model": _parallelogram_fitness(np.radians(angles), half, 10000.0),
            "exact": _parallelogram_fitness(np.radians(angles), half, None),
        }
        bar.update(1)

        a = np.arange(n_angle) * (180.0 / n_angle)
        phases = (np.arange(8 if quick else 24) + 0.5) / (8 if quick else 24)
        aa, pp = np.meshgrid(a, phases, indexing="ij")
        f = _parallelogram_fitness(np.radians(aa.ravel()), pp.ravel(), 10000.0)
        out["surface_angle_offset"] = {
            "angle_deg": a,
            "x_offset": (phases - 0.5) * s * scale,
            "temperature": 10000.0,
            "points_per_transect": 1000,
            "fitness": f.reshape(aa.shape),
        }
        bar.update(1)

        temps = np.linspace(1.0, 200.0, 10 if quick else 50)
        rows = [
            _parallelogram_fitness(np.radians(a), np.full(len(a), 0.5), float(t)) for t in temps
        ]
        out["surface_angle_temperature"] = {
            "angle_deg": a,
            "temperature": temps,
            "points_per_transect": 1000,
            "fitness": np.stack(rows),
        }
        bar.update(1)
    return out


_SUBTITLE = "paper's parallelogram, spacing 0.5 (18 transects), window [-0.5, 0.5]"


def fig_indicator(data: dict[str, Any]) -> Any:
    """Fig. 2: Eq. 5's soft indicator along the transects at T = 17 and T = 100."""
    from matplotlib.figure import Figure
    from mpl_toolkits.mplot3d import Axes3D  # noqa: F401  (registers the 3-D projection)

    d = data["indicator"]
    fig = Figure(figsize=(12, 5.2), layout="constrained")
    for k, (temp, v) in enumerate(sorted(d["by_temperature"].items())):
        ax = fig.add_subplot(1, 2, k + 1, projection="3d")
        for x, y, z in zip(v["x"], v["y"], v["p_sigma"], strict=True):
            ax.plot(x, y, z, lw=1.0, color="tab:blue")
        o = d["outline"]
        ax.plot(o[:, 0], o[:, 1], np.zeros(len(o)), color="k", lw=1.2)
        ax.set_xlabel("x (normalised units)")
        ax.set_ylabel("y (normalised units)")
        ax.set_zlabel("soft indicator $P_\\sigma$ (dimensionless)")
        ax.set_zlim(0, 1)
        ax.set_title(f"Temperature = {temp:g}")
    fig.suptitle(
        f"Fig. 2: Eq. 5 along the transects (direction {d['angle_deg']:g}°, x_offset 0); "
        + _SUBTITLE,
        fontsize=10,
    )
    return fig


def fig_fitness_vs_angle(data: dict[str, Any]) -> Any:
    """Fig. 5: fitness against angle at x_offset 0, T = 10000, with the exact fitness."""
    from matplotlib.figure import Figure

    d = data["fitness_vs_angle"]
    fig = Figure(figsize=(8, 4.5), layout="constrained")
    ax = fig.add_subplot()
    ax.plot(
        d["angle_deg"],
        d["paper_model"],
        lw=1.2,
        label=f"paper's model, T = {d['temperature']:g}, {d['points_per_transect']} points",
    )
    ax.plot(d["angle_deg"], d["exact"], lw=1.0, ls="--", color="k", label="exact (discrete)")
    ax.set_xlabel("transect direction θ (degrees)")
    ax.set_ylabel("fitness, Eq. 1 (dimensionless)")
    ax.set_xlim(0, 180)
    ax.legend()
    ax.set_title("Fig. 5: fitness against angle, x_offset 0\n" + _SUBTITLE, fontsize=10)
    return fig


def _surface(
    x: Any, y: Any, z: Any, xlabel: str, ylabel: str, title: str, vmax: float | None = None
) -> Any:
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8, 5), layout="constrained")
    ax = fig.add_subplot()
    mesh = ax.pcolormesh(x, y, z, shading="nearest", cmap="viridis", vmax=vmax)
    extend = "max" if vmax is not None and np.nanmax(z) > vmax else "neither"
    fig.colorbar(mesh, ax=ax, label="fitness, Eq. 1 (dimensionless)", extend=extend)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    return fig


def fig_surface_angle_offset(data: dict[str, Any]) -> Any:
    """Fig. 3: the fitness surface over angle x offset at T = 10000."""
    d = data["surface_angle_offset"]
    return _surface(
        d["angle_deg"],
        d["x_offset"],
        d["fitness"].T,
        "transect direction θ (degrees)",
        "x_offset (parallelogram units)",
        f"Fig. 3: paper's model over angle x offset, T = {d['temperature']:g}\n" + _SUBTITLE,
    )


def fig_surface_angle_temperature(data: dict[str, Any]) -> Any:
    """Fig. 4: the fitness surface over angle x temperature (T up to 200), x_offset 0."""
    d = data["surface_angle_temperature"]
    # The authors' weighting of the statistics lifts the fitness above 1 at the lowest
    # temperatures (Table I's first row); the colours stop at 1 so the rest stays readable.
    return _surface(
        d["angle_deg"],
        d["temperature"],
        d["fitness"],
        "transect direction θ (degrees)",
        "temperature T (dimensionless)",
        "Fig. 4: paper's model over angle x temperature, x_offset 0 (colours capped at 1)\n"
        + _SUBTITLE,
        vmax=1.0,
    )


#: The figures ``boustro reproduce figures`` writes: file name -> function of :func:`figure_data`.
FIGURES: dict[str, Callable[[dict[str, Any]], Any]] = {
    "fig2_indicator.png": fig_indicator,
    "fig3_surface_angle_offset.png": fig_surface_angle_offset,
    "fig4_surface_angle_temperature.png": fig_surface_angle_temperature,
    "fig5_fitness_vs_angle.png": fig_fitness_vs_angle,
}


# -- the report --------------------------------------------------------------------------------


def _fmt(v: float | None, digits: int = 5) -> str:
    if v is None or not math.isfinite(v):
        return "n/a"
    return f"{v:.{digits}f}"


def _column_label(points: int | None) -> str:
    return "closed form" if points is None else f"{points} PPT"


def _table_markdown(table: Table1, with_paper: bool) -> list[str]:
    head = "| Temperature | " + " | ".join(_column_label(p) for p in table.points) + " |"
    lines = [head, "|---:|" + "---:|" * len(table.points)]
    for i, t in enumerate(table.temperatures):
        cells = []
        for j, p in enumerate(table.points):
            cell = _fmt(float(table.mean[i, j]))
            if with_paper and p in POINTS_PER_TRANSECT and t in PAPER_TABLE1:
                cell += f" ({PAPER_TABLE1[t][POINTS_PER_TRANSECT.index(p)]:.5f})"
            cells.append(cell)
        lines.append(f"| {t:g} | " + " | ".join(cells) + " |")
    return lines


def _counts_line(table: Table1) -> str:
    model = int(table.no_value_model.max()) if table.no_value_model.size else 0
    return (
        f"{table.n_samples} samples; discrete fitness undefined (no transect in the window, "
        f"left out, not redrawn): {table.no_value_discrete}; model fitness not finite: "
        f"{model} (largest over the cells); largest standard error of a cell: "
        f"{_fmt(float(np.nanmax(table.sem)) if np.isfinite(table.sem).any() else None, 6)}."
    )


def _compact_markdown(tables: dict[str, Table1], points: int) -> list[str]:
    """One column (``points``) of every protocol that has it, side by side."""
    names = [n for n, t in tables.items() if points in t.points]
    if not names:
        return []
    lines = [
        "| Temperature | paper, Table I | " + " | ".join(f"`{n}`" for n in names) + " |",
        "|---:|---:|" + "---:|" * len(names),
    ]
    temps = tables[names[0]].temperatures
    for i, t in enumerate(temps):
        paper = PAPER_TABLE1.get(t)
        cells = [
            _fmt(float(tables[n].mean[i, tables[n].points.index(points)]))
            if t in tables[n].temperatures
            else "n/a"
            for n in names
        ]
        ref = f"{paper[POINTS_PER_TRANSECT.index(points)]:.5f}" if paper else "n/a"
        lines.append(f"| {t:g} | {ref} | " + " | ".join(cells) + " |")
    return lines


PROTOCOL_NOTES = """\
- **Samples.** Each sample is a random convex polygon with 3 to 9 vertices (the authors'
  `randint(3, 10)`), a transect angle uniform over the circle, a spacing uniform in (0, 1/3) of
  the normalised frame (diameter 1) and the authors' `x_offset` uniform in [-s/2, s/2]. The
  polygons are drawn as `polygenerator.random_convex_polygon` (0.2.0) draws them, re-implemented
  in `boustro.experiments.polygenerator_convex_polygon`: Valtr's construction like
  `boustro.geometry.random_convex_polygon`, but with the inner coordinates split into two
  chains of exactly half each and the polygon stretched to fill the unit square before the
  rescaling to diameter 1; both change the distribution of shapes. The same samples serve every
  protocol and both models (common random numbers), so differences between protocols come
  from the protocol alone. Sample `i` does not depend on N.
- **Window.** The paper integrates each transect over y in [-0.5, 0.5]. A polygon centred on its
  vertex mean can reach beyond 0.5 (a triangle reaches 0.577), so the window cuts such
  polygons; the discrete fitness is cut the same way, except in `paper-whole-discrete`, which
  scores the discrete side over the whole polygon as a planner would. The transects are the
  authors' script's `np.arange(-0.5, 0.5, s) + x_offset`, a window shifted by the offset; the
  paper's text and boustro's `clip=True` keep the grid lines in [-0.5, 0.5) instead
  (`grid-window`, `boustro-clip`). `project` uses the whole polygon for both sides.
- **Statistics.** The authors' code computes the soft mean as `sum(L) / sum(S)` and the variance
  as `sum((S (L - mean))^2) / sum(S)` (`statistics="paper"`). At T = 1 every transect's weight S
  is about a quarter, the "mean" about 2 and the error about 0.5: that is Table I's first row.
  Weighted statistics (`paper-weighted`, `project`) do not have it.
- **Trapezoid step.** The authors' points are `arange(-0.5, 0.5, 1 / points)` integrated with
  step `1 / points`: a consistent step over the window less its last `1 / points`.
  `trapezoid="authors"` (the `paper` protocol) approximates it with the library's points, which
  span the whole window, and the step `1 / points`: every length `(points - 1) / points` of its
  value, 1% short at 100 points; `paper-step` (the library's step `1 / (points - 1)`, as in
  `boustro-clip` and `project`) is the closer reading of their code. The difference shows only
  in the 100-PPT column at T >= 1000.
- **Spacing.** The paper says the spacings are random; uniform in (0, 1/3) comes from the
  authors' script (a commented-out line), which as released fixes the spacing at 0.5, leaving
  one or two transects in the window (`authors-script`); compare its T = 1 and T = 10 rows with
  the paper's. Spacings near 0 give thousands of transects (the cost of a sample grows as 1/s;
  all are evaluated).
- **Temperature.** The same temperature in Eq. 4/5 and Eq. 7, as in the authors' code.
- **No value.** The authors' script silently redraws a sample whose fitness is NaN (in practice:
  no transect crosses the polygon in the window, so the discrete mean is undefined). Here such
  samples are counted and left out of the means, never redrawn.
- **Arithmetic.** float64. The paper's model is evaluated with the library's arithmetic
  (`boustro.models.paper_lengths`); the batched evaluation agrees with one library call per
  sample to 1e-12 (tested), and points deep inside or outside the polygon (every edge's
  `T * distance` beyond 41) take the limits of Eq. 5, exact to below an ulp.
- **Eq. 2.** As printed, and in the authors' code, Eq. 2's `W = (x1 - x2, y1 - y2)` is the edge
  vector: not a normal (the polygon comes out turned by 90 degrees, which uniform angles do not
  see) and not of unit length. The length is what matters: each edge's sigmoid in Eq. 3 gets the
  temperature `T |edge|`, softer on short edges (a normalised polygon's edges are 0.1 to 1
  long). The `paper` protocol and its one-change variants follow it (`eq2="printed"`);
  `paper-unit-normals` (and boustro's models) use unit normals. With unit normals the rows
  T = 10 to 1000 come out 1.6 to 5 times lower than the paper's; with Eq. 2 as printed they
  are reproduced. (Found by an adversarial review of this reproduction, which re-implemented
  the authors' arithmetic independently.) The figures' angle axis is boustro's: the transect
  direction counter-clockwise from +x, which may be shifted or mirrored against the paper's
  plots.
"""

JSON_KEYS = """\
Every file has `meta`: `command`, `date` (UTC), `n_samples`, `seed`, `quick`, `seconds` (wall
time of the part), `boustro` and `torch` versions, `threads`, `cpus`, `load_start`.

`table1.json`:

- `paper_table1`: the paper's values, `{temperature: [100 PPT, 1000 PPT, 10000 PPT]}`.
- `polygon_redraws`: polygon draws rejected as degenerate and drawn again (expected 0).
- `protocols` (paper's model) and `smooth` (closed-form model), by protocol name, each with
  `description`, `settings` (`clip`, `discrete_clip`, `statistics`, `spacing`, `window`,
  `trapezoid`),
  `model`, `temperatures` (rows), `points_per_transect` (columns; `null` = closed form),
  `mean_abs_error`, `sem` (standard error of the mean), `max_abs_error`, `valid_samples` (rows x
  columns), `no_value_discrete` (samples left out: discrete fitness undefined),
  `no_value_model` (per cell: model fitness not finite), `n_samples`.

`optimizers.json`:

- `n`, `seed`; `paper`: `grid_minus_gradient` (0.13633) and its `n`.
- `methods`, by name (`grid`, `gradient`, `hybrid`, `global`): `available`,
  `unavailable_reason`, `description`, `options`, `fitness` and `seconds` per sample (`null`
  where a run failed), `failures`, `first_error`, `mean_fitness`, `total_seconds`; `gradient`
  also has `final_iterate_fitness` (the exact fitness where the descent ended).
- `comparisons`, by method (`gradient`, `gradient-final`, `hybrid`, `global`) against grid
  search, over the samples where both have an answer: `n`, `mean_grid_minus_other`, `sem`,
  `share_other_higher`, `share_equal` (within 1e-9), `share_grid_higher`; and
  `global_check`: `n`, `largest_excess_over_global` (the most any other optimiser's answer
  exceeds the certified optimum), `beaten_by_more_than_1e-6` (should be 0).

`figures.json`: the data of Figs. 3-5 (`fitness_vs_angle`, `surface_angle_offset`,
`surface_angle_temperature`: `angle_deg`, `x_offset` (parallelogram units), `temperature`,
`fitness`; Fig. 5 has `paper_model` and `exact` instead of `fitness`).
"""


def _meta_line(part: str, meta: dict[str, Any]) -> str:
    n = meta.get("n_samples")
    return (
        f"- {part}: {'' if n is None else f'N = {n}, '}seed {meta.get('seed', 'n/a')}"
        f"{', --quick' if meta.get('quick') else ''}; {meta.get('seconds', float('nan')):.1f} s "
        f"wall time on {meta.get('date', '?')} (boustro {meta.get('boustro')}, torch "
        f"{meta.get('torch')}, {meta.get('threads')} thread(s), {meta.get('cpus')} CPU(s), "
        f"load average {meta.get('load_start', 'n/a')} at the start)."
    )


def render_report(
    table1_json: dict[str, Any] | None = None,
    optimizers_json: dict[str, Any] | None = None,
    figures_json: dict[str, Any] | None = None,
    figure_files: Sequence[str] = (),
) -> str:
    """``report.md`` from the JSON files of the parts run (any subset): the reproduced tables
    beside the paper's, the comparison of optimisers, the figures, the protocol notes and the
    keys of the JSON files."""
    out = ["# Reproducing Manzini & Murphy (ICRA 2024) with boustro", ""]
    runs = [
        ("Table I", table1_json),
        ("optimisers", optimizers_json),
        ("figures", figures_json),
    ]
    command = next((j["meta"].get("command") for _, j in runs if j and "meta" in j), None)
    if command:
        out += [f"Command: `{command}`", ""]
    out += [_meta_line(name, j["meta"]) for name, j in runs if j and "meta" in j]
    out.append("")
    if table1_json:
        tables = {k: Table1.from_json(v) for k, v in table1_json.get("protocols", {}).items()}
        smooth = {k: Table1.from_json(v) for k, v in table1_json.get("smooth", {}).items()}
        out += ["## Table I: mean |differentiable - discrete| fitness", ""]
        paper = tables.get("paper")
        if paper is not None:
            out += [
                "Protocol `paper` (the paper's text and, where it is silent, the authors' "
                "code): reproduced (the paper's value).",
                "",
                *_table_markdown(paper, True),
                "",
                _counts_line(paper),
                "",
            ]
        out += [
            "Every protocol at 1000 points per transect (PPT), one choice changed at a time "
            "(definitions below):",
            "",
            *_compact_markdown(tables, 1000),
            "",
        ]
        for name, t in tables.items():
            if name == "paper":
                continue
            out += [
                f"`{name}`: {t.protocol.description}.",
                "",
                *_table_markdown(t, True),
                "",
                _counts_line(t),
                "",
            ]
        if smooth:
            out += [
                "### The closed-form smooth model",
                "",
                "`boustro.smooth.SmoothModel` with smoothing length 1/T (no points per "
                "transect), the same samples and discrete side as each protocol:",
                "",
                "| Temperature | " + " | ".join(f"`{n}`" for n in smooth) + " |",
                "|---:|" + "---:|" * len(smooth),
            ]
            first = next(iter(smooth.values()))
            for i, temp in enumerate(first.temperatures):
                out.append(
                    f"| {temp:g} | "
                    + " | ".join(_fmt(float(tb.mean[i, 0])) for tb in smooth.values())
                    + " |"
                )
            out += ["", _counts_line(first), ""]
        else:
            out += ["The closed-form smooth model (`boustro.smooth`) is not available here.", ""]
        out += ["### Protocol choices that change the numbers", "", PROTOCOL_NOTES]
    if optimizers_json:
        out += _optimizers_markdown(optimizers_json)
    if figure_files:
        out += ["## Figures (the paper's parallelogram)", ""]
        captions = {
            "fig2_indicator.png": "Fig. 2: Eq. 5 along the transects, T = 17 and T = 100.",
            "fig3_surface_angle_offset.png": "Fig. 3: fitness over angle x offset, T = 10000.",
            "fig4_surface_angle_temperature.png": "Fig. 4: fitness over angle x temperature.",
            "fig5_fitness_vs_angle.png": "Fig. 5: fitness against angle, T = 10000, with the "
            "exact fitness.",
        }
        for name in figure_files:
            out += [f"![{captions.get(name, name)}]({name})", "", captions.get(name, name), ""]
        out += [
            "Vertices (8,4), (8,10), (4,8), (4,2), spacing 0.5 of its units (0.0559 of the "
            "normalised frame), the authors' 18 transects `arange(-0.5, 0.5, s) + x_offset`, "
            "window [-0.5, 0.5], the authors' statistics, 1000 points per transect. Angles: the "
            "transect direction, degrees counter-clockwise from +x.",
            "",
        ]
    out += ["## JSON files", "", JSON_KEYS]
    return "\n".join(out).rstrip() + "\n"


def _optimizers_markdown(res: dict[str, Any]) -> list[str]:
    out = [
        "## Gradient descent vs grid search (Sec. VII)",
        "",
        f"{res['n']} random polygons and spacings (Table I's first {res['n']} samples, seed "
        f"{res['seed']}); every answer scored with the exact fitness (whole polygon, Eq. 1). "
        f"Paper: grid search higher than gradient descent by {PAPER_GRID_MINUS_GRADIENT} on "
        "average over 1000 polygons, gradient descent occasionally higher.",
        "",
        "| method | mean fitness | grid - method (mean ± s.e.) | method higher | equal | "
        "grid higher | failures | time (s) |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    methods, comps = res["methods"], res["comparisons"]
    rows = [("grid", "grid", None)]
    rows += [(m, m, comps.get(m)) for m in ("gradient",)]
    rows += [("gradient (last iterate)", "gradient", comps.get("gradient-final"))]
    rows += [(m, m, comps.get(m)) for m in ("hybrid", "global")]
    for label, key, comp in rows:
        m = methods.get(key)
        if m is None:
            continue
        if not m["available"]:
            out.append(f"| {label} | {m['unavailable_reason']} | | | | | | |")
            continue
        if label.endswith("(last iterate)"):
            vals = [v for v in m.get("final_iterate_fitness", []) if v is not None]
            mean = float(np.mean(vals)) if vals else None
            fails, secs = "", ""
        else:
            mean, fails, secs = m["mean_fitness"], str(m["failures"]), f"{m['total_seconds']:.1f}"
        if comp and comp.get("n"):
            diff = f"{comp['mean_grid_minus_other']:+.5f} ± {comp['sem']:.5f}"
            shares = [
                f"{100 * comp[k]:.1f}%"
                for k in ("share_other_higher", "share_equal", "share_grid_higher")
            ]
        else:
            diff, shares = "", ["", "", ""]
        out.append(
            f"| {label} | {_fmt(mean)} | {diff} | " + " | ".join(shares) + f" | {fails} | {secs} |"
        )
    out.append("")
    check = comps.get("global_check")
    if check:
        out += [
            f"Check against the certified optimum, over {check['n']} samples: largest "
            f"(other optimiser - global) {check['largest_excess_over_global']:+.2e}; samples "
            f"where another optimiser beats it by more than 1e-6: "
            f"{check['beaten_by_more_than_1e-6']}.",
            "",
        ]
    for name, m in methods.items():
        if m["available"]:
            opts = ", ".join(f"{k}={v}" for k, v in m["options"].items()) or "defaults"
            out.append(f"- `{name}`: {m['description']} ({opts}).")
            if m["first_error"]:
                out.append(f"  First failure: {m['first_error']}")
    out.append("")
    return out
