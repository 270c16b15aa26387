"""Boxes of layouts ``(theta +- delta, d +- eta)`` for the certified branch and bounds over
(angle, offset): the grid of first boxes, halving, and the sandwich radius that holds a box.

Every layout of a box is the box centre's grid after a rotation by at most ``delta`` about the
area's centre and a shift by at most ``eta`` across the lines; moving the area instead of the
grid, its points move by at most ``eps = delta * radius + eta`` (:func:`box_radius`), so the
area's image lies between its erosion and dilation by ``eps``
(:class:`~boustro.optimize.cover.sandwich.Sandwich`). Shared by the cover search (flown plans)
and the Eq. 1 search (:mod:`boustro.optimize.smith_bb`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "Boxes",
    "box_radius",
    "initial_boxes",
    "level_radius",
    "split_boxes",
    "split_parents",
]


class Boxes(NamedTuple):
    """Boxes of layouts: angle ``theta +- delta``, offset ``d +- eta`` (arrays)."""

    theta: NDArray[np.float64]
    delta: NDArray[np.float64]
    d: NDArray[np.float64]
    eta: NDArray[np.float64]

    def take(self, mask: NDArray[np.bool_] | NDArray[np.intp]) -> Boxes:
        return Boxes(*(a[mask] for a in self))

    def centre_key(self, i: int) -> tuple[float, float]:
        """Box ``i``'s centre as a search remembers the layouts it tried (rounded)."""
        return (round(float(self.theta[i]), 12), round(float(self.d[i]), 12))


def box_radius(boxes: Boxes, radius: float) -> NDArray[np.float64]:
    """``eps = delta * radius + eta``: how far a point within ``radius`` of the centre moves
    between the box centre's grid and any layout of the box."""
    return boxes.delta * radius + boxes.eta


def level_radius(eps: NDArray[np.float64], top: float) -> NDArray[np.float64]:
    """The sandwich radius of each ``eps``: ``top / 2^j``, the smallest such radius ``>= eps``
    (a few radii, built once and shared by all boxes)."""
    level = np.maximum(np.floor(np.log2(top / eps)), 0.0)
    return top * 2.0 ** (-level)


def _halves(boxes: Boxes, radius: float) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    """Which boxes are halved in angle and which in offset (:func:`split_boxes`)."""
    rot, shift = boxes.delta * radius, boxes.eta
    return rot >= 0.5 * shift, shift >= 0.5 * rot


def split_parents(boxes: Boxes, radius: float) -> NDArray[np.intp]:
    """The index in ``boxes`` of each box of :func:`split_boxes` ``(boxes, radius)``."""
    cut_t, cut_d = _halves(boxes, radius)
    return np.concatenate(
        [
            np.nonzero((cut_t | (st > 0)) & (cut_d | (sd > 0)))[0]
            for st in (-1.0, 1.0)
            for sd in (-1.0, 1.0)
        ]
    )


def split_boxes(boxes: Boxes, radius: float) -> Boxes:
    """Halve each box along the side that contributes more to its radius (both if close)."""
    cut_t, cut_d = _halves(boxes, radius)
    parts = []
    for st in (-1.0, 1.0):
        for sd in (-1.0, 1.0):
            keep = (cut_t | (st > 0)) & (cut_d | (sd > 0))
            b = boxes.take(keep)
            ct, cd = cut_t[keep], cut_d[keep]
            delta = np.where(ct, b.delta / 2, b.delta)
            eta = np.where(cd, b.eta / 2, b.eta)
            parts.append(
                Boxes(
                    b.theta + np.where(ct, st * delta, 0.0),
                    delta,
                    b.d + np.where(cd, sd * eta, 0.0),
                    eta,
                )
            )
    return Boxes(*(np.concatenate([getattr(p, f) for p in parts]) for f in Boxes._fields))


def initial_boxes(
    spacing: float, radius: float, n_angles: int, angle: float | None = None, n_fixed: int = 64
) -> Boxes:
    """The first boxes: ``n_angles`` angles over ``[0, pi)``, each with as many offset boxes
    over ``[0, spacing)`` as make both sides of a box move the area about equally; at a fixed
    ``angle``, ``n_fixed`` offset boxes only."""
    if angle is not None:
        eta = spacing / (2 * n_fixed)
        d = (np.arange(n_fixed, dtype=np.float64) + 0.5) * (2 * eta)
        return Boxes(np.full(n_fixed, angle), np.zeros(n_fixed), d, np.full(n_fixed, eta))
    delta = math.pi / (2 * n_angles)
    n_off = max(1, math.ceil(spacing / (2 * delta * radius)))
    eta = spacing / (2 * n_off)
    theta = (np.arange(n_angles) + 0.5) * (2 * delta)
    offsets = (np.arange(n_off) + 0.5) * (2 * eta)
    tt, dd = np.meshgrid(theta, offsets, indexing="ij")
    n = tt.size
    return Boxes(tt.ravel(), np.full(n, delta), dd.ravel(), np.full(n, eta))
