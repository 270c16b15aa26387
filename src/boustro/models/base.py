"""The transect grid and the interface every transect-length model implements.

``theta`` is the transect direction (``u = (cos, sin)``, left normal ``n = (-sin, cos)``);
transect ``k`` is the line ``n . p = d + k s``. A model maps (half-planes, ``theta``, offset
``d``, spacing ``s``) to :class:`TransectLengths` of shape ``(*, K)``, ``K`` static per grid.
"""

from __future__ import annotations

import math
from typing import NamedTuple, Protocol, runtime_checkable

import numpy as np

from .._torch import as_array, broadcast, namespace, torch
from .._validate import MAX_TRANSECTS, check_finite, check_spacing
from ..errors import InvalidParameterError
from ..geometry import HalfPlanes

__all__ = [
    "MAX_CANDIDATES",
    "MAX_TRANSECTS",
    "PAPER_WINDOW",
    "Chords",
    "TransectLengths",
    "TransectModel",
    "check_finite",
    "check_spacing",
    "grid_size",
    "transect_positions",
]

#: Half-width of the paper's transect window: transects at ``|n . p| <= 0.5`` only, integrated
#: over ``t`` in ``[-0.5, 0.5]`` (used with ``clip=True`` for faithful reproduction).
PAPER_WINDOW = 0.5


class TransectLengths(NamedTuple):
    """What a model says about the grid of transects.

    Attributes:
        lengths: ``(*, K)`` transect lengths, in the units of the half-planes' frame.
        weights: ``(*, K)`` in ``[0, 1]``: how much each transect counts as "shown" (exact: 0 or
            1; soft: the paper's Eq. 7 indicator).
        positions: ``(*, K)`` signed distance ``d + k s`` of each transect from the origin.
    """

    lengths: torch.Tensor
    weights: torch.Tensor
    positions: torch.Tensor


class Chords(NamedTuple):
    """Exact chords of the transect grid: transect ``k`` spans ``t`` in ``[lower, upper]``."""

    positions: torch.Tensor
    lower: torch.Tensor
    upper: torch.Tensor
    lengths: torch.Tensor


@runtime_checkable
class TransectModel(Protocol):
    """Anything that turns (half-planes, theta, offset, spacing) into :class:`TransectLengths`."""

    @property
    def name(self) -> str: ...

    def __call__(
        self, hp: HalfPlanes, theta: torch.Tensor, offset: torch.Tensor, spacing: float
    ) -> TransectLengths: ...


#: Most candidate transects of one (angle, offset) pair in a model's grid, which also covers the
#: model's margin beyond the polygon (32 smoothing lengths for the smooth closed form).
MAX_CANDIDATES = 4 * MAX_TRANSECTS


def _prepare(
    hp: HalfPlanes, theta: torch.Tensor | float, offset: torch.Tensor | float
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]:
    """Angle and offset as tensors of the half-planes' dtype/device, and the per-edge components.

    Returns ``(theta, offset, across, along, b)`` where ``across = n_j . n`` and
    ``along = n_j . u`` have shape ``(*, E)``: edge ``j`` holds at ``(c, t)`` iff
    ``across_j c + along_j t + b_j >= 0``. Rotating the edges instead of the transects is the
    paper's "rotate W, keep B".
    """
    xp = namespace(hp.normals)  # numpy arrays (a plan) or tensors: ``halfplanes(tensors=)``
    theta_t, offset_t = broadcast(as_array(theta, hp.normals), as_array(offset, hp.normals))
    across, along, b = _components(xp.cos(theta_t), xp.sin(theta_t), hp.normals, hp.offsets)
    return theta_t, offset_t, across, along, b


def _components(
    cos: torch.Tensor, sin: torch.Tensor, normals: torch.Tensor, offsets: torch.Tensor
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """``(across, along, b)`` ``(*, E)``: ``across = n_j . n``, ``along = n_j . u`` of edges
    ``normals (*, E, 2)``, ``offsets (*, E)`` seen from transects at angles ``(cos, sin)``
    ``(*)`` (broadcasting), and the offsets broadcast to their shape."""
    nx, ny = normals[..., 0], normals[..., 1]
    cos, sin = cos[..., None], sin[..., None]
    across = -nx * sin + ny * cos
    along = nx * cos + ny * sin
    return across, along, namespace(offsets).broadcast_to(offsets, across.shape)


def grid_size(spacing: float, radius: float) -> tuple[int, int]:
    """``(K, m)``: the ``K`` lines ``d mod s + (k - m) s``, ``0 <= k < K``, cover +-radius.

    Raises:
        InvalidParameterError: more than :data:`MAX_CANDIDATES` lines (a tiny spacing, or a
            model whose margin, e.g. a huge smoothing, grows the disc by as much).
    """
    if 2 * radius / spacing > MAX_CANDIDATES:
        raise InvalidParameterError(
            f"{2 * radius / spacing:.3g} candidate transects at spacing {spacing:.6g} across a "
            f"disc of radius {radius:.6g} (the polygon's, grown by the model's margin): more "
            f"than the {MAX_CANDIDATES} boustro handles; use a larger spacing (or a smoothing "
            "below the spacing)"
        )
    m = math.ceil(radius / spacing) + 1
    return 2 * m, m


def transect_positions(offset: torch.Tensor, spacing: float, radius: float) -> torch.Tensor:
    """Positions ``(*, K)`` of every grid line that can meet a disc of ``radius`` at the origin.

    The offset is wrapped into ``[0, spacing)`` first (``torch.remainder``, whose gradient is 1),
    so any offset, however far it has drifted, gives the same static ``K``.
    """
    d, q = _grid(offset, spacing, radius)
    return d[..., None] + q


def _grid(offset: torch.Tensor, spacing: float, radius: float) -> tuple[torch.Tensor, torch.Tensor]:
    """``(d, q)``: the wrapped offset ``(*)`` and the lines' places ``(K,)`` relative to it, so
    that :func:`transect_positions` is ``d[..., None] + q``."""
    spacing = check_spacing(spacing)
    k_count, m = grid_size(spacing, radius)
    k = as_array(np.arange(k_count) - m, offset)
    return namespace(offset).remainder(offset, spacing), k * spacing


def _window_mask(positions: torch.Tensor, clip: bool) -> torch.Tensor | None:
    if not clip:
        return None
    return (positions >= -PAPER_WINDOW) & (positions < PAPER_WINDOW)
