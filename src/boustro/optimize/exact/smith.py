"""The certified global optimum of Eq. 1 and the best offset at given angles."""

from __future__ import annotations

import math
import time
from functools import cache, cached_property
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..._torch import torch
from ...errors import InvalidParameterError, NoTransectError
from ...geometry import Polygon, halfplanes
from ...geometry.polygon import edge_halfplanes
from ...models import (
    check_spacing,
)
from ...objectives import SmithFitness
from ...scoring import as_polygon
from ..problem import evaluate_grid
from ..result import OptimizeResult, canonical
from .bounds import _evaluate_smith, _smith_pieces
from .kernel import (
    exact_smith_compiled,
    finish_smith_compiled,
    pieces_compiled,
    search_smith_compiled,
    use_compiled,
)
from .search import (
    _BATCH,
    _MAX_CHILDREN,
    _MIN_WIDTH,
    _branch_and_bound,
    _check_count,
    _check_tol,
    _Search,
)
from .structure import Array, _check_work, _structure

__all__ = ["best_offset", "global_optimum"]


def _weights(a: float, b: float, fitness: SmithFitness | None) -> tuple[float, float]:
    if fitness is not None:
        if not isinstance(fitness, SmithFitness):
            raise InvalidParameterError(
                "the global optimiser of Eq. 1 takes a SmithFitness (a, b), got "
                f"{type(fitness).__name__}; use fewest_transects_optimum or "
                "shortest_path_optimum for the other objectives"
            )
        return float(fitness.a), float(fitness.b)
    if type(a) is float and type(b) is float:  # exact types: hashable, cached
        return _checked_weights(a, b)
    SmithFitness(a=a, b=b)  # validates a, b >= 0 and finite
    return float(a), float(b)


@cache
def _checked_weights(a: float, b: float) -> tuple[float, float]:
    """``(a, b)`` validated as :class:`SmithFitness` does (once per pair of floats)."""
    SmithFitness(a=a, b=b)
    return a, b


class _Scorer:
    """Eq. 1 by the exact model on an angles x offsets grid of one polygon, normalised frame:
    compiled (:func:`.kernel.exact_smith_compiled`), else :func:`evaluate_grid` (the same
    numbers to rounding)."""

    def __init__(self, poly: Polygon, v: Array, s: float, a: float, b: float, fast: bool) -> None:
        self.poly, self.v, self.s, self.a, self.b, self.fast = poly, v, s, a, b, fast

    @cached_property
    def halfplanes(self) -> tuple[Array, Array, float]:
        """``(normals, offsets, radius)`` of the polygon in the normalised frame."""
        normals, boffs = edge_halfplanes(self.v)
        return normals, boffs, float(np.max(np.linalg.norm(self.v, axis=1)))

    def pairs(self, angles: Array, offsets: Array) -> Array | None:
        """Values of the pairs ``(angles[i], offsets[i])`` by the compiled kernel (if
        ``fast``), or None."""
        if not self.fast:
            return None
        return exact_smith_compiled(
            self.v, self.halfplanes, self.s, angles, offsets, self.a, self.b
        )

    def grid(self, angles: ArrayLike, offsets: ArrayLike) -> Array:
        """Values ``(A, O)``, ``-inf`` where no transect counts."""
        angles = np.asarray(angles, dtype=np.float64)
        offsets = np.asarray(offsets, dtype=np.float64)
        if self.fast:
            v, planes = self.v, self.halfplanes
            fast = exact_smith_compiled(v, planes, self.s, angles, offsets, self.a, self.b, False)
            if fast is not None:
                return fast
        hp = halfplanes(self.poly)
        return evaluate_grid(
            hp,
            torch.as_tensor(angles, dtype=hp.normals.dtype),
            torch.as_tensor(offsets, dtype=hp.normals.dtype),
            self.s,
            fitness=SmithFitness(a=self.a, b=self.b),
        ).numpy()


def _attained(
    score: _Scorer, v: Array, s_n: float, thetas: Array, a: float, b: float
) -> tuple[float, float, float]:
    """The best layout near the closed-form optimum, scored by the exact model.

    The closed-form maximum of a piece can sit at its end, where a transect passes a vertex, or
    at an event angle: the supremum then belongs to a limit (a transect of length -> 0 counted,
    or not). The candidates are, at every angle of ``thetas``, the maximisers of the three best
    pieces, as they are and nudged into the pieces' interiors; the best exact score wins.

    Returns:
        ``(fitness, angle, offset)`` in the normalised frame.
    """
    thetas = np.asarray(thetas, dtype=np.float64)
    pieces = pieces_compiled(v, s_n, thetas, a, b) if score.fast else None
    if pieces is None:
        st = _structure(v, s_n, thetas)
        mo = _smith_pieces(st, a, b)
        beta, width, value, lam = st.beta, st.width, mo.value, mo.lam
    else:
        beta, width, value, lam = (pieces[..., i] for i in range(4))
    rows = []
    for row, theta in enumerate(thetas):
        order = np.argsort(-value[row])[: min(3, value.shape[1])]
        cands = []
        for p in order:
            if not np.isfinite(value[row, p]):
                continue
            for eta in (0.0, 1e-9, 1e-6, 1e-3):
                lam_p = min(max(lam[row, p], eta), 1.0 - eta)
                cands.append(beta[row, p] + lam_p * width[row, p])
        if cands:
            rows.append((float(theta), np.array(cands, dtype=np.float64)))
    best = (-math.inf, float(thetas[0]), 0.0)
    if not rows:
        return best
    flat = score.pairs(
        np.concatenate([np.full(len(c), t) for t, c in rows]), np.concatenate([c for _, c in rows])
    )
    start = 0
    for theta, offsets in rows:
        if flat is None:
            values = score.grid(np.array([theta]), offsets)[0]
        else:
            values = flat[start : start + len(offsets)]
            start += len(offsets)
        k = int(np.argmax(values))
        if float(values[k]) > best[0]:
            best = (float(values[k]), float(theta), float(offsets[k]))
    return best


def _candidate_pieces(v: Array, s_n: float, thetas: Array, a: float, b: float) -> NDArray[np.int64]:
    """``(R, 4)``: at each angle of ``thetas`` the number of candidate pieces of
    :func:`_attained` and the pieces (its order: the three largest values, numpy's sort
    deciding ties; finite values only)."""
    pieces = pieces_compiled(v, s_n, thetas, a, b)
    assert pieces is not None  # only called where the compiled kernels run
    value = pieces[..., 2]
    tops = np.zeros((len(thetas), 4), dtype=np.int64)
    for row in range(len(thetas)):
        order = np.argsort(-value[row])[: min(3, value.shape[1])]
        kept = [p for p in order if np.isfinite(value[row, p])]
        tops[row, 0] = len(kept)
        tops[row, 1 : 1 + len(kept)] = kept
    return tops


def best_offset(
    polygon: Polygon | ArrayLike,
    spacing: float,
    angle: float,
    *,
    a: float = 0.5,
    b: float = 0.5,
    fitness: SmithFitness | None = None,
) -> tuple[float, float]:
    """The exact best offset for Eq. 1 at a fixed angle, in closed form.

    Solves every piece of the offset circle (at most one per vertex) exactly: Eq. 1 is concave
    on a piece and its maximum has a closed form (docs/global_optimum.md).

    Args:
        polygon: convex polygon, user units.
        spacing: transect spacing, user units, > 0.
        angle: transect direction, radians.
        a, b: weights of Eq. 1 (ignored when ``fitness`` is given).
        fitness: a :class:`~boustro.fitness.SmithFitness` to take ``a`` and ``b`` from.

    Returns:
        ``(offset, fitness)``: offset in user units in ``[0, spacing)``, fitness by the exact
        model.
    """
    poly = as_polygon(polygon).require_convex("the exact offset optimiser")
    spacing = check_spacing(spacing, extent=poly.diameter)
    a, b = _weights(a, b, fitness)
    angle = float(angle)
    if not math.isfinite(angle):
        raise InvalidParameterError(f"angle must be a finite number, got {angle!r}")
    frame = poly.frame
    v = frame.to_normalised(poly.vertices)
    s_n = spacing / frame.scale
    with np.errstate(all="ignore"):
        score = _Scorer(poly, v, s_n, a, b, use_compiled())
        value, _, d = _attained(score, v, s_n, np.array([angle]), a, b)
    if not math.isfinite(value):
        raise NoTransectError(f"no transect crosses the polygon at spacing {spacing:g}")
    offset = float(np.mod(d * frame.scale, spacing))  # for ``angle`` as given, not mod pi
    return (0.0 if offset >= spacing else offset), value


def global_optimum(
    polygon: Polygon | ArrayLike,
    spacing: float,
    *,
    a: float = 0.5,
    b: float = 0.5,
    fitness: SmithFitness | None = None,
    tol: float = 1e-6,
    max_evaluations: int = 2_000_000,
    progress: bool | None = None,
) -> OptimizeResult:
    """The global maximum of Eq. 1 over every angle and offset, with a certified upper bound.

    Branch and bound over the angle (docs/global_optimum.md): the angle range ``[0, pi]`` is cut
    at every *event* (where the piece structure of the offset circle changes); on each interval
    the exact best offset at its centre is a lower bound, and a rigorous bound on how far the
    pieces' maxima can move over the interval (first order from the chords' angular speed,
    second order from a supergradient of the concave Eq. 1 and the chords' curvature) gives an
    upper bound. Intervals whose bound exceeds the best value found by more than ``tol`` are cut,
    until none is left.

    Args:
        polygon: convex polygon, user units (a :class:`~boustro.geometry.Polygon` or vertices).
        spacing: transect spacing, user units, > 0.
        a, b: weights of Eq. 1, any finite values >= 0 (ignored when ``fitness`` is given).
        fitness: a :class:`~boustro.fitness.SmithFitness` to take ``a`` and ``b`` from.
        tol: absolute optimality gap to certify (Eq. 1 lies in ``[b/2, a + b]``).
        max_evaluations: cap on angle evaluations; if reached, the bound is still valid but the
            gap may exceed ``tol`` (``info["converged"]`` is False).
        progress: accepted for the common optimiser interface; the search shows no bar.

    Returns:
        :class:`~boustro.optimize.OptimizeResult` with ``method="global"``, the fitness of the
        returned layout by the exact model, ``upper_bound`` >= the fitness of every layout
        (``gap = upper_bound - fitness``), ``evaluations`` = angles solved exactly over the
        offset, and ``info`` with ``events``, ``rounds``, ``converged``, ``tol``.

    Raises:
        NonConvexPolygonError, InvalidPolygonError, InvalidParameterError: bad input.

    >>> r = global_optimum([(0, 0), (2, 0), (2, 1), (0, 1)], 0.25)
    >>> round(r.fitness, 4), r.gap <= 1e-6
    (0.9505, True)
    """
    t0 = time.perf_counter()
    del progress
    poly = as_polygon(polygon).require_convex("the global optimiser")
    spacing = check_spacing(spacing, extent=poly.diameter)
    _check_work(poly, spacing, "the global optimiser")
    fast = use_compiled()
    a, b = _weights(a, b, fitness)
    tol = _check_tol(tol)
    frame = poly.frame
    v = frame.to_normalised(poly.vertices)
    s_n = spacing / frame.scale

    cap = _check_count("max_evaluations", max_evaluations)
    with np.errstate(all="ignore"):  # infinities are meant: they mark missing bounds
        search = _search_smith(v, s_n, a, b, tol, cap, fast)
        angles = np.array([search.theta, search.lo, search.hi])
        score = _Scorer(poly, v, s_n, a, b, fast)
        # the candidates' scores and the spot check in one compiled call (where it can)
        check_grid = _check_grid(v, s_n)
        done = finish_smith_compiled(v, s_n, angles, a, b, *check_grid) if fast else None
        if done is not None and done[6] == 2.0:  # tied pieces: numpy orders them
            tops = _candidate_pieces(v, s_n, angles, a, b)
            done = finish_smith_compiled(v, s_n, angles, a, b, *check_grid, tops)
        if done is None or done[6] != 0.0:
            value, theta, d = _attained(score, v, s_n, angles, a, b)
            check = _spot_check(score, v, s_n)
        else:
            value, theta, d = (float(x) for x in done[:3])
            check = (float(done[3]), float(done[4]), float(done[5]))
    upper = search.upper_bound
    if not search.converged and not math.isfinite(upper):
        upper = a + b  # every length is at most the diameter (1) and std >= 0
    answer = _reconcile(score, v, s_n, a, b, search, tol, upper, (value, theta, d), check)
    value, theta, d, upper, notes = answer
    converged = search.converged and not notes
    angle, offset = canonical(theta, d * frame.scale, spacing)
    info: dict[str, Any] = {
        "events": search.events,
        "rounds": search.rounds,
        "converged": converged,
        "tol": tol,
        "a": a,
        "b": b,
        "closed_form_value": search.value,
    }
    if notes:
        info["note"] = "; ".join(notes)
    return OptimizeResult(
        angle=angle,
        offset=offset,
        fitness=value,
        spacing=spacing,
        method="global",
        evaluations=search.evaluations,
        seconds=time.perf_counter() - t0,
        upper_bound=max(upper, value),
        info=info,
    )


def _search_smith(
    v: Array, s: float, a: float, b: float, tol: float, cap: int, fast: bool
) -> _Search:
    """The branch and bound over the angle: one compiled call (:mod:`.kernel_search`) if
    ``fast``, else the numpy evaluation of the intervals in :func:`_branch_and_bound` (the same
    search)."""
    out = None
    if fast:
        out = search_smith_compiled(v, s, a, b, tol, cap, _BATCH, _MIN_WIDTH, _MAX_CHILDREN)
    if out is None:

        def evaluate(lo: Array, hi: Array, threshold: float) -> tuple[Array, Array, Array, Array]:
            return _evaluate_smith(v, s, lo, hi, a, b, threshold)

        return _branch_and_bound(v, s, evaluate, tol, cap)
    theta, lo, hi, offset, value, upper = (float(x) for x in out[:6])
    evaluations, rounds, converged = int(out[6]), int(out[7]), bool(out[8])
    return _Search(theta, lo, hi, offset, value, upper, evaluations, rounds, int(out[9]), converged)


class _Answer(NamedTuple):
    """The layout a global search returns, its bound, and what keeps it from being certified."""

    value: float
    theta: float
    d: float  # normalised offset
    upper: float
    notes: list[str]


def _reconcile(
    score: _Scorer,
    v: Array,
    s_n: float,
    a: float,
    b: float,
    search: _Search,
    tol: float,
    upper: float,
    attained: tuple[float, float, float],
    check: tuple[float, float, float],
) -> _Answer:
    """The search's attained layout checked against an independent spot check.

    An independent spot check, exact fitness on a coarse grid: in degenerate configurations
    (a symmetric polygon whose width is a multiple of the spacing, to the last bits) the
    search's best value can be a limit that no layout attains, or float64 can misplace an
    event; the check then finds a better layout, and the result says it is not certified.
    """
    value, theta, d = attained
    check_theta, check_d, check_value = check
    notes = []
    if check_value > value + 1e-12:
        with np.errstate(all="ignore"):
            better, theta_b, d_b = _attained(score, v, s_n, np.array([check_theta]), a, b)
        if better >= check_value:
            value, theta, d = better, theta_b, d_b
        else:
            value, theta, d = check_value, check_theta, check_d
        notes.append("a spot check found a better layout than the search")
    if value > upper + 1e-12:
        notes.append(
            "the upper bound is not valid here (float64 cannot resolve this degenerate "
            "configuration)"
        )
        upper = value
    elif upper - value > tol * (1 + 1e-9) and search.converged:
        notes.append(
            "the search's best value is a limit no layout attains (a transect grazing "
            "a vertex); the layout returned is the best attained one found"
        )
    return _Answer(value, theta, d, upper, notes)


_CHECK_ANGLES = np.arange(90) * (math.pi / 90)
_CHECK_STEPS = np.arange(9.0)  # the same numbers as integers times a float


def _check_grid(v: Array, s: float) -> tuple[Array, Array]:
    """The spot check's angles (90 angles, every edge's direction and its normal) and offsets
    (9, 0 included), normalised frame (``v``: the polygon's vertices in it)."""
    n, k = len(v), len(_CHECK_ANGLES)
    edges = np.empty_like(v)  # np.roll(v, -1, axis=0) - v, without np.roll's overheads
    np.subtract(v[1:], v[:-1], out=edges[:-1])
    np.subtract(v[0], v[-1], out=edges[-1])
    angles = np.empty(k + 2 * n)
    angles[:k] = _CHECK_ANGLES
    edge_angles = angles[k : k + n]
    np.mod(np.arctan2(edges[:, 1], edges[:, 0]), math.pi, out=edge_angles)
    normal_angles = angles[k + n :]
    np.add(edge_angles, math.pi / 2, out=normal_angles)
    np.mod(normal_angles, math.pi, out=normal_angles)
    return angles, _CHECK_STEPS * (s / 9)


def _spot_check(score: _Scorer, v: Array, s: float) -> tuple[float, float, float]:
    """``(angle, offset, fitness)``, normalised frame: the best of the exact fitness on the
    grid of :func:`_check_grid`."""
    angles, offsets = _check_grid(v, s)
    values = score.grid(angles, offsets)
    i, j = np.unravel_index(int(np.argmax(values)), values.shape)
    return float(angles[i]), float(offsets[j]), float(values[i, j])
