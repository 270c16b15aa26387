"""Validity of a ring and of a shell with holes, decided by GEOS (through shapely).

GEOS decides whether a ring is simple (no self-intersection, no self-touching) in about
``O(n log n)`` time and ``O(n)`` memory, and names the place it found, e.g. "Ring
Self-intersection at (1, 0.5)". boustro's tolerance rules come on top, with GEOS distance
predicates over an STRtree (never an all-pairs array):

- a ring: two non-adjacent edges closer than the given tolerance (``RELATIVE_TOLERANCE`` times
  the ring's extent, see :class:`~boustro.geometry.Polygon`) touch;
- holes: a hole closer than the tolerance (``TOUCH_TOLERANCE`` times the shell's diameter, see
  :class:`~boustro.geometry.Region`) to the shell or to another hole touches it; a hole must lie
  inside the shell and outside every other hole.

shapely (a dependency) is imported on use, so that ``import boustro`` does not load it.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

__all__ = ["geos_reason", "holes_problem", "ring_problem"]

_REASON = re.compile(r"\s*(.*?)\s*\[\s*(\S+)\s+(\S+)\s*\]\s*")


def geos_reason(reason: str) -> str:
    """GEOS's reason in words: ``"Self-intersection[1 0.5]"`` -> ``"Self-intersection at
    (1, 0.5)"`` (any other text unchanged).

    Example:
        >>> geos_reason("Ring Self-intersection[2 0]")
        'Ring Self-intersection at (2, 0)'
    """
    m = _REASON.fullmatch(reason)
    return f"{m.group(1)} at ({m.group(2)}, {m.group(3)})" if m else reason


def _first_pair(i: NDArray[np.intp], j: NDArray[np.intp]) -> tuple[int, int] | None:
    """The lexicographically first pair ``(i, j)``, or None when there is none."""
    if len(i) == 0:
        return None
    k = int(np.lexsort((j, i))[0])
    return int(i[k]), int(j[k])


def ring_problem(v: NDArray[np.float64], tol: float) -> str | None:
    """Why the closed ring ``v`` ``(N, 2)`` (no closing vertex, no repeated or collinear
    vertices) is not simple, or None when it is.

    GEOS decides crossing and touching; then two non-adjacent edges within ``tol`` (absolute,
    in the ring's units) of each other count as touching too.
    """
    n = len(v)
    if n < 4:
        return None  # three distinct, non-collinear vertices: always simple, no edge pairs
    import shapely

    with np.errstate(all="ignore"):  # coordinates near the float limit: the range check says
        reason = shapely.is_valid_reason(shapely.polygons(v))
    if reason != "Valid Geometry":
        kind = "self-intersecting" if "intersection" in reason.lower() else "invalid"
        return f"the polygon is {kind}: {geos_reason(reason)}"
    w = np.roll(v, -1, axis=0)
    segments = shapely.linestrings(np.stack([v, w], axis=1))
    # Candidates: edges whose boxes, grown by tol, overlap (an STRtree query: O(n log n) and as
    # many pairs as overlap); then the exact distance of those pairs only. Faster than the
    # tree's own "dwithin" predicate, which prepares every edge.
    lo, hi = np.minimum(v, w) - tol, np.maximum(v, w) + tol
    i, j = shapely.STRtree(segments).query(shapely.box(lo[:, 0], lo[:, 1], hi[:, 0], hi[:, 1]))
    gap = j - i
    keep = (gap >= 2) & (gap <= n - 2)  # neither the edge itself nor a neighbour, each pair once
    i, j = i[keep], j[keep]
    near = shapely.dwithin(segments[i], segments[j], tol)
    pair = _first_pair(i[near], j[near])
    if pair is None:
        return None
    a, b = pair
    return (
        f"the polygon is self-intersecting: edge {a} ({v[a].tolist()} -> "
        f"{v[(a + 1) % n].tolist()}) comes within {tol:.3g} of edge {b} ({v[b].tolist()} -> "
        f"{v[(b + 1) % n].tolist()})"
    )


def _near(a, b) -> list[float]:
    """A point of ``a`` nearest to ``b`` (for messages)."""
    import shapely

    x, y = shapely.get_coordinates(shapely.shortest_line(a, b))[0]
    return [float(x), float(y)]


def holes_problem(
    shell: NDArray[np.float64], holes: Sequence[NDArray[np.float64]], tol: float
) -> str | None:
    """Why ``holes`` (simple rings) are not disjoint holes strictly inside the simple ring
    ``shell``, or None when they are. Distances up to ``tol`` count as touching.

    The first problem in this order: for each hole in turn, touching the shell, then lying
    outside it; then for each pair of holes ``(i, j)``, ``i < j``, in order: touching, or one
    inside the other.
    """
    if not holes:
        return None
    import shapely

    shell_ring = shapely.linearrings(shell)
    shell_area = shapely.polygons(shell)
    shapely.prepare(shell_ring)
    shapely.prepare(shell_area)
    rings = [shapely.linearrings(h) for h in holes]
    areas = [shapely.polygons(h) for h in holes]
    touching = shapely.dwithin(shell_ring, rings, tol)
    for i, hole in enumerate(holes):
        if touching[i]:
            return (
                f"hole {i + 1} touches or crosses the shell's boundary near "
                f"{_near(rings[i], shell_ring)} (holes must lie strictly inside the shell)"
            )
        if not shapely.contains_xy(shell_area, hole[0, 0], hole[0, 1]):
            return (
                f"hole {i + 1} lies outside the shell (its vertex {hole[0].tolist()} is not "
                "inside the shell)"
            )
    first, second = shapely.STRtree(areas).query(areas, predicate="dwithin", distance=tol)
    keep = first < second
    first, second = first[keep], second[keep]
    for k in np.lexsort((second, first)):
        i, j = int(first[k]), int(second[k])
        if shapely.dwithin(rings[i], rings[j], tol):
            return (
                f"holes {i + 1} and {j + 1} touch or overlap near {_near(rings[i], rings[j])} "
                "(holes must be disjoint)"
            )
        if shapely.contains_xy(areas[i], holes[j][0, 0], holes[j][0, 1]):
            return f"hole {j + 1} lies inside hole {i + 1} (holes must be disjoint)"
        if shapely.contains_xy(areas[j], holes[i][0, 0], holes[i][0, 1]):
            return f"hole {i + 1} lies inside hole {j + 1} (holes must be disjoint)"
    return None
