"""Convex polygons as tensors of inward half-planes (:class:`HalfPlanes`), ready for the models.

A half-plane is ``n . p + b >= 0`` with ``n`` the unit INWARD normal of a counter-clockwise edge
``(x1, y1) -> (x2, y2)``: ``n = [y1 - y2, x2 - x1] / |edge|``, ``b = (x1*y2 - x2*y1) / |edge|``.
:func:`paper_eq2_halfplanes` gives the paper's Eq. 2 as printed (the edge direction, not its
normal) for comparison.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from .._torch import torch
from ..errors import InvalidPolygonError
from .polygon import Polygon

__all__ = ["PAD_OFFSET", "HalfPlanes", "halfplanes", "paper_eq2_halfplanes"]

#: Offset given to padding half-planes when polygons with different vertex counts are batched:
#: ``0 . p + PAD_OFFSET >= 0`` holds everywhere, and ``logsigmoid(T * PAD_OFFSET) == 0``.
PAD_OFFSET = 1.0e6


def paper_eq2_halfplanes(polygon: Polygon) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Eq. 2 of the paper exactly as printed: ``W = [x1 - x2, y1 - y2]``, ``B = x1*y2 - x2*y1``.

    ``W`` is minus the edge direction, i.e. the inward normal rotated by +90 degrees, so the
    region ``W . X + B >= 0`` is the polygon rotated by +90 degrees about the origin. Kept for
    documentation and tests; the models use :meth:`Polygon.halfplanes`.
    """
    p1 = polygon.vertices
    p2 = np.roll(p1, -1, axis=0)
    return p1 - p2, p1[:, 0] * p2[:, 1] - p2[:, 0] * p1[:, 1]


class HalfPlanes(NamedTuple):
    """Polygons as tensors of inward half-planes, ready for the transect models.

    Attributes:
        normals: ``(*P, E, 2)`` unit inward normals. Polygons with fewer than ``E`` edges are
            padded with the always-true half-plane ``0 . p + PAD_OFFSET >= 0``.
        offsets: ``(*P, E)``; a point ``p`` is inside iff ``normals . p + offsets >= 0`` for all E.
        radius: a bound on the distance of every vertex from the origin, over the whole batch.
    """

    normals: torch.Tensor
    offsets: torch.Tensor
    radius: float


def halfplanes(
    polygons: Polygon | Sequence[Polygon],
    *,
    normalise: bool = True,
    dtype: torch.dtype | None = None,
    device: torch.device | str | None = None,
    tensors: bool = True,
) -> HalfPlanes:
    """Tensor half-planes of one convex polygon, or of a batch of them (padded to equal E).

    Args:
        polygons: a convex :class:`Polygon` or a sequence of them.
        normalise: take each polygon in its normalised frame (default), as the paper does.
        dtype, device: of the returned tensors (float64 by default).
        tensors: ``False``: float64 numpy arrays instead, which the chord kernel
            (:func:`boustro.models.exact_chords`) takes as well, for callers that take no
            gradient (a plan): torch is not imported.

    Returns:
        :class:`HalfPlanes` with ``normals`` ``(E, 2)`` for one polygon or ``(P, E, 2)`` for P.

    Raises:
        NonConvexPolygonError: a polygon is concave (half-planes would describe its hull's
            intersection, not the polygon).

    Example:
        >>> hp = halfplanes(Polygon([(0, 0), (4, 0), (4, 3), (0, 3)]))  # normalised: 0.8 x 0.6
        >>> tuple(hp.normals.shape), hp.radius
        ((4, 2), 0.5)
    """
    single = isinstance(polygons, Polygon)
    items: list[Polygon] = [polygons] if isinstance(polygons, Polygon) else list(polygons)
    if not items:
        raise InvalidPolygonError("expected at least one polygon, got an empty sequence")
    items = [p.require_convex("the half-plane representation") for p in items]
    if normalise:
        items = [p.normalised() for p in items]
    n_edges = max(len(p) for p in items)
    normals = np.zeros((len(items), n_edges, 2))
    offsets = np.full((len(items), n_edges), PAD_OFFSET)
    for k, p in enumerate(items):
        n, b = p.halfplanes()
        normals[k, : len(p)] = n
        offsets[k, : len(p)] = b
    radius = max(float(np.max(np.linalg.norm(p.vertices, axis=1))) for p in items)
    if not tensors:
        hp = HalfPlanes(normals, offsets, radius)  # type: ignore[arg-type] # numpy: no torch
        return HalfPlanes(hp.normals[0], hp.offsets[0], radius) if single else hp
    dtype = torch.float64 if dtype is None else dtype
    hp = HalfPlanes(
        torch.as_tensor(normals, dtype=dtype, device=device),
        torch.as_tensor(offsets, dtype=dtype, device=device),
        radius,
    )
    if single:
        return HalfPlanes(hp.normals[0], hp.offsets[0], radius)
    return hp
