"""The exact chords of a convex polygon's transect grid: the one torch chord kernel.

Transect ``c`` (the line ``n . p = c``) meets edge ``j`` where ``across_j c + along_j t + b_j = 0``:
the edge bounds ``t`` from below where ``along_j > 0`` and from above where ``along_j < 0``; an
edge parallel to the transects holds for every ``t`` or empties the chord. The chord is
``[max lower, min upper]``, its length ``max(0, upper - lower)``: O(E) per transect.

Three levels, each built on the one below (use the highest that fits):

* :func:`exact_chords` / :class:`ExactModel`: the chords of a transect GRID (angle, offset,
  spacing) over :class:`~boustro.geometry.HalfPlanes`;
* :func:`chords_at`: the chords of lines at GIVEN positions ``(*B, K)`` and angles ``(*B)``
  (batched, padded half-planes of different vertex counts included);
* :func:`line_chords` / :func:`chord_bounds`: the same from the edges' components
  ``(across, along, b)`` seen from the transects, for callers that already have them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

from .._torch import as_array, namespace, torch
from ..geometry import HalfPlanes
from .base import (
    PAPER_WINDOW,
    Chords,
    TransectLengths,
    _components,
    _prepare,
    _window_mask,
    transect_positions,
)

__all__ = [
    "ChordBounds",
    "Chords",
    "ExactModel",
    "chord_bounds",
    "chords_at",
    "exact_chords",
    "line_chords",
]


class ChordBounds(NamedTuple):
    """The ``t``-interval ``[lower, upper]`` of a line inside every half-plane, ``(*)`` each.

    ``blocked`` marks lines that an edge parallel to them excludes whole (then the interval
    means nothing); elsewhere ``lower > upper`` says the line misses the polygon.
    """

    lower: torch.Tensor
    upper: torch.Tensor
    blocked: torch.Tensor


def chord_bounds(
    lhs: torch.Tensor,
    along: torch.Tensor,
    *,
    delta: float | None = None,
    parallel_tol: float = 0.0,
) -> ChordBounds:
    """The interval of ``t`` where ``lhs_j + along_j t >= delta`` for every edge ``j``.

    Args:
        lhs: ``(*, E)`` the edges' values on the line at ``t = 0`` (``across_j c + b_j``).
        along: ``(*, E)`` (broadcasting with ``lhs``) the edges' slopes along the line.
        delta: the margin (``None``: 0, the chord itself; the paper's band uses others).
        parallel_tol: edges with ``|along| <= parallel_tol`` count as parallel to the line.

    Returns:
        :class:`ChordBounds`, reduced over the last (edge) dimension. Padding half-planes
        (normal 0, offset :data:`~boustro.geometry.PAD_OFFSET`) are parallel and always hold.

    Example:
        >>> lhs = torch.tensor([[1.0, 1.0, 0.5]])  # t >= -1, t <= 1, and a parallel edge
        >>> b = chord_bounds(lhs, torch.tensor([[1.0, -1.0, 0.0]]))
        >>> b.lower.item(), b.upper.item(), b.blocked.item()
        (-1.0, 1.0, False)
    """
    if parallel_tol:
        pos, neg = along > parallel_tol, along < -parallel_tol
        parallel = ~(pos | neg)
    else:
        pos, neg, parallel = along > 0, along < 0, along == 0
    xp = namespace(along)  # numpy arrays or tensors
    num = -lhs if delta is None else delta - lhs
    bound = num / xp.where(parallel, xp.ones_like(along), along)
    inf = as_array(math.inf, bound)
    lower = xp.amax(xp.where(pos, bound, -inf), -1)
    upper = xp.amin(xp.where(neg, bound, inf), -1)
    outside = lhs < 0 if delta is None else lhs < delta
    return ChordBounds(lower, upper, xp.any(parallel & outside, -1))


def line_chords(
    across: torch.Tensor,
    along: torch.Tensor,
    b: torch.Tensor,
    positions: torch.Tensor,
    *,
    clip: bool = False,
    fused: bool = False,
) -> Chords:
    """Exact chords of the lines at ``positions`` ``(*, K)`` given the edges' components.

    Args:
        across, along, b: ``(*, E)`` per edge ``j``: ``n_j . n``, ``n_j . u`` and its offset, as
            :func:`boustro.models.base._prepare` returns them (broadcasting with ``positions``'
            leading dimensions).
        positions: ``(*, K)`` the lines' signed distances ``c`` from the origin along ``n``.
        clip: clamp ``t`` to the paper's window ``[-0.5, 0.5]`` (the positions are not masked).
        fused: write each edge's bound as ``slope * c + intercept`` (one fused multiply-add and
            one reduction per role: about twice as fast on large batches, measured); the same
            chords to rounding (1e-13 relative), not bit for bit. Default: one division per
            (line, edge), the arithmetic boustro has always used.

    Returns:
        :class:`Chords` ``(*, K)``: ``lengths`` is 0 for a line that misses the polygon.
    """
    if fused:
        return _fused_chords(across, along, b, positions, clip)
    xp = namespace(positions)  # numpy arrays or tensors
    across, along, b = across[..., None, :], along[..., None, :], b[..., None, :]
    lhs = across * positions[..., :, None] + b  # (*, K, E): edge j holds iff lhs + along t >= 0
    lower, upper, blocked = chord_bounds(lhs, along)
    if clip:
        lower = xp.clip(lower, -PAPER_WINDOW, None)
        upper = xp.clip(upper, None, PAPER_WINDOW)
    length = xp.where(blocked, xp.zeros_like(lower), xp.clip(upper - lower, 0, None))
    return Chords(xp.broadcast_to(positions, length.shape), lower, upper, length)


def _fused_chords(
    across: torch.Tensor,
    along: torch.Tensor,
    b: torch.Tensor,
    positions: torch.Tensor,
    clip: bool,
) -> Chords:
    """:func:`line_chords` with ``fused=True``: bounds ``slope_j c + intercept_j``, the edges of
    the other role given slope 0 and intercept ``-+inf``, so each max and min is one
    ``addcmul`` and one reduction."""
    parallel = along == 0
    inv = 1.0 / torch.where(parallel, torch.ones_like(along), along)
    slope, intercept = -across * inv, -b * inv  # edge j bounds t by slope_j c + intercept_j
    inf = torch.as_tensor(math.inf, dtype=positions.dtype, device=positions.device)
    is_lower, is_upper = along > 0, along < 0
    cc = positions[..., :, None]
    lower = torch.addcmul(
        torch.where(is_lower, intercept, -inf)[..., None, :],
        torch.where(is_lower, slope, 0.0)[..., None, :],
        cc,
    ).amax(dim=-1)
    upper = torch.addcmul(
        torch.where(is_upper, intercept, inf)[..., None, :],
        torch.where(is_upper, slope, 0.0)[..., None, :],
        cc,
    ).amin(dim=-1)
    if clip:
        lower = lower.clamp(min=-PAPER_WINDOW)
        upper = upper.clamp(max=PAPER_WINDOW)
    length = (upper - lower).clamp(min=0.0)
    if bool(parallel.any()):  # an edge parallel to the transects empties the chords beyond it
        lhs = across[..., None, :] * cc + b[..., None, :]
        length = torch.where((parallel[..., None, :] & (lhs < 0)).any(dim=-1), 0.0, length)
    return Chords(torch.broadcast_to(positions, length.shape), lower, upper, length)


def chords_at(
    hp: HalfPlanes,
    theta: torch.Tensor | float,
    positions: torch.Tensor,
    *,
    clip: bool = False,
    fused: bool = False,
) -> Chords:
    """Exact chords of the lines ``n(theta) . p = c`` for given ``c``: ``positions`` ``(*B, K)``.

    Args:
        hp: half-planes ``(*P, E, 2)`` (padded batches allowed), ``*P`` broadcasting with ``*B``.
        theta: transect direction(s) ``(*B)`` in radians.
        positions: ``(*B, K)`` line positions in the half-planes' frame.
        clip: clamp ``t`` to the paper's window ``[-0.5, 0.5]``.
        fused: the fused arithmetic of :func:`line_chords`.

    Example:
        >>> from boustro.geometry import Polygon, halfplanes
        >>> hp = halfplanes(Polygon([(-1, -0.5), (1, -0.5), (1, 0.5), (-1, 0.5)]), normalise=False)
        >>> c = torch.tensor([0.0, 0.25, 0.75], dtype=torch.float64)
        >>> chords_at(hp, 0.0, c).lengths.tolist()
        [2.0, 2.0, 0.0]
    """
    dtype, device = hp.normals.dtype, hp.normals.device
    theta_t = torch.as_tensor(theta, dtype=dtype, device=device)
    across, along, b = _components(torch.cos(theta_t), torch.sin(theta_t), hp.normals, hp.offsets)
    return line_chords(across, along, b, positions, clip=clip, fused=fused)


def exact_chords(
    hp: HalfPlanes,
    theta: torch.Tensor | float,
    offset: torch.Tensor | float,
    spacing: float,
    *,
    clip: bool = False,
    fused: bool = False,
) -> Chords:
    """Exact chords of a convex polygon's transect grid, in closed form (module docstring).

    Differentiable almost everywhere in ``theta`` and ``offset`` (not at transects through
    vertices); denominators are made safe before ``torch.where`` so gradients stay finite.

    Args:
        hp: half-planes ``(*P, E, 2)``, see :func:`boustro.geometry.halfplanes`.
        theta: transect direction(s) in radians, ``(*B)``.
        offset: grid offset(s) in the half-planes' frame, ``(*B)``.
        spacing: transect spacing in the same frame, > 0.
        clip: restrict to the paper's window (``|c| <= 0.5`` and ``t`` in ``[-0.5, 0.5]``).
        fused: the fused arithmetic of :func:`line_chords` (faster on large batches).

    Returns:
        :class:`Chords` with tensors ``(*, K)``; transects missing the polygon have length 0 and
        ``lower == upper`` undefined (do not use their endpoints).

    Example:
        >>> from boustro.geometry import Polygon, halfplanes
        >>> hp = halfplanes(Polygon([(0, 0), (4, 0), (4, 3), (0, 3)]))  # diameter 1
        >>> ch = exact_chords(hp, 0.0, 0.05, 0.2)
        >>> [round(x, 4) for x in ch.lengths[ch.lengths > 0].tolist()]
        [0.8, 0.8, 0.8]
    """
    theta, offset, across, along, b = _prepare(hp, theta, offset)
    c = transect_positions(offset, spacing, PAPER_WINDOW if clip else hp.radius)
    chords = line_chords(across, along, b, c, clip=clip, fused=fused)
    mask = _window_mask(c, clip)
    if mask is None:
        return chords
    xp = namespace(c)
    length = xp.where(mask, chords.lengths, xp.zeros_like(chords.lengths))
    return chords._replace(lengths=length)


@dataclass(frozen=True)
class ExactModel:
    """Exact chord lengths (closed form); weights are 1 for transects of positive length.

    Differentiable almost everywhere, but its gradient ignores transects entering or leaving
    the polygon: use it to score, and a soft model to descend. ``fused=True`` takes the fused
    arithmetic of :func:`line_chords` (same lengths to 1e-13, faster on large batches).

    Example:
        >>> from boustro.geometry import Polygon, halfplanes
        >>> hp = halfplanes(Polygon([(0, 0), (4, 0), (4, 3), (0, 3)]))
        >>> out = ExactModel()(hp, torch.tensor(0.0), torch.tensor(0.05), 0.2)
        >>> int(out.weights.sum()), round(float(out.lengths.sum()), 4)
        (3, 2.4)
    """

    clip: bool = False
    name: str = "exact"
    fused: bool = False

    def __call__(
        self, hp: HalfPlanes, theta: torch.Tensor, offset: torch.Tensor, spacing: float
    ) -> TransectLengths:
        ch = exact_chords(hp, theta, offset, spacing, clip=self.clip, fused=self.fused)
        # A chord shorter than this is a transect grazing a vertex: rounding, not a transect.
        tiny = 1e-12 * max(hp.radius, 1e-300)
        return TransectLengths(ch.lengths, (ch.lengths > tiny).to(ch.lengths.dtype), ch.positions)
