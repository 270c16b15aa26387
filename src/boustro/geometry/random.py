"""Random convex polygons (Valtr's algorithm, as the ``polygenerator`` package the paper used)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidPolygonError
from .polygon import Polygon

__all__ = ["random_convex_polygon"]


def random_convex_polygon(rng: np.random.Generator, n_vertices: int) -> Polygon:
    """A random convex polygon with exactly ``n_vertices`` vertices (Valtr's algorithm).

    The same construction as the ``polygenerator`` package that the paper used: random x and y
    coordinates are split into two chains each, turned into edge vectors, sorted by angle and
    chained. Returned in the normalised frame (centred on the vertex mean, diameter 1). The rare
    draw whose vertices are collinear after rounding is redrawn from ``rng``.
    """
    if int(n_vertices) != n_vertices or n_vertices < 3:
        raise InvalidPolygonError(f"n_vertices must be an integer >= 3, got {n_vertices!r}")
    n = int(n_vertices)
    while True:

        def chains(values: NDArray[np.float64]) -> NDArray[np.float64]:
            values = np.sort(values)
            lo, hi = values[0], values[-1]
            side = rng.random(n - 2) < 0.5
            inner = values[1:-1]
            a = np.concatenate([[lo], inner[side], [hi]])
            b = np.concatenate([[lo], inner[~side], [hi]])
            return np.concatenate([np.diff(a), -np.diff(b)])

        dx, dy = chains(rng.random(n)), chains(rng.random(n))
        rng.shuffle(dy)
        vec = np.stack([dx, dy], axis=1)
        vec = vec[np.argsort(np.arctan2(vec[:, 1], vec[:, 0]))]
        pts = np.cumsum(vec, axis=0)
        try:
            poly = Polygon(pts)
        except InvalidPolygonError:
            continue
        if len(poly) == n:
            return poly.normalised()
