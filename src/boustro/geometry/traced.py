"""Synthetic traced fields: a lobed boundary sampled at ``n`` noisy points, with small holes.

The shape of a field boundary digitised from a GPS trace (hundreds to thousands of vertices,
about half of them reflex from the noise), for scale tests and benchmarks. shapely is imported
on use.
"""

from __future__ import annotations

import numpy as np

from .polygon import Polygon
from .region import Region

__all__ = ["traced_field"]


def traced_field(n_vertices: int, n_holes: int = 0, seed: int = 0, radius: float = 250.0) -> Region:
    """A traced field of ``n_vertices`` (about ``2 radius x 2.6 radius`` metres, noise 0.3 m)
    with ``n_holes`` 12-gon holes of radius 6 m, at least 10 m from the shell and each other.

    Example:
        >>> r = traced_field(200, 2)
        >>> len(r.shell), r.n_holes
        (200, 2)
    """
    import shapely

    rng = np.random.default_rng(seed)
    t = np.sort(rng.uniform(0, 2 * np.pi, n_vertices))
    r = radius * (1 + 0.25 * np.sin(3 * t) + 0.1 * np.sin(7 * t + 1)) + rng.normal(
        0, 0.3, n_vertices
    )
    shell = np.c_[r * np.cos(t), 1.3 * r * np.sin(t)]
    ring = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    holes: list[np.ndarray] = []
    inner = shapely.Polygon(shell).buffer(-10)
    while len(holes) < n_holes:
        c = rng.uniform(-radius, radius, 2)
        h = np.c_[c[0] + 6 * np.cos(ring), c[1] + 6 * np.sin(ring)]
        hp = shapely.Polygon(h)
        if inner.contains(hp) and all(
            not shapely.Polygon(o).buffer(10).intersects(hp) for o in holes
        ):
            holes.append(h)
    return Region(Polygon(shell), [Polygon(h) for h in holes])
