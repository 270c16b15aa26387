"""How much of a path leaves its area: :func:`outside_length` measures, segment by segment
with shapely, the length of a path outside an area or inside one of its holes (the
``outside_length`` statistic of every plan; :func:`with_outside_length` sets it), and
:func:`shapely_area` gives an area as a shapely Polygon (their home was
:mod:`boustro.plan.inside` before). Shapely is imported inside the functions."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..geometry import Polygon
from ..geometry.region import Region, as_region
from .types import Plan

__all__ = ["outside_length", "shapely_area", "with_outside_length"]


def shapely_area(area: Region | Polygon | ArrayLike) -> Any:
    """The area (shell and holes) as a shapely Polygon."""
    import shapely

    r = as_region(area)
    return shapely.Polygon(r.shell.vertices, [h.vertices for h in r.holes])


def outside_length(waypoints: ArrayLike, area: Region | Polygon | ArrayLike | Any) -> float:
    """The length of the path through ``waypoints`` outside ``area`` or inside one of its holes
    (plan units), measured with shapely segment by segment (a path that doubles back over
    itself outside counts each time); a point within ``1e-9`` of the area's diameter of its
    boundary counts as on it. ``area`` may also be a shapely Polygon (one that
    :class:`~boustro.geometry.Region` refuses: a hole touching the shell)."""
    import shapely

    w = np.asarray(waypoints, dtype=np.float64).reshape(-1, 2)
    if len(w) < 2:
        return 0.0
    segs = np.stack([w[:-1], w[1:]], axis=1)
    lengths = np.linalg.norm(segs[:, 1] - segs[:, 0], axis=1)
    keep = lengths > 0
    if not keep.any():
        return 0.0
    if isinstance(area, shapely.Polygon):
        x0, y0, x1, y1 = area.bounds
        polygon, diameter = area, float(np.hypot(x1 - x0, y1 - y0))
    else:
        r = as_region(area)
        polygon, diameter = shapely_area(r), r.diameter
    # within 1e-9 of the diameter of the boundary counts as on it (the routing's convention)
    target = polygon.buffer(1e-9 * diameter, join_style="mitre")
    shapely.prepare(target)
    segs, lengths = segs[keep], lengths[keep]
    # a segment the (prepared) area covers is not outside at all; the others are cut where
    # they cross its boundary (_inside_lengths: an STRtree of its edges, not one overlay of
    # the whole area per segment: 20 -> 2 ms a plan on a 2000-vertex field)
    out = np.zeros(len(segs))
    cut = ~shapely.covers(target, shapely.linestrings(segs))
    if cut.any():
        out[cut] = np.maximum(lengths[cut] - _inside_lengths(segs[cut], target), 0.0)
    return float(np.sum(out))


def _inside_lengths(segs: NDArray[np.float64], target: Any) -> NDArray[np.float64]:
    """``(S,)`` the length of each segment ``segs (S, 2, 2)`` in the shapely polygon ``target``
    (its boundary counts as inside): the segments are cut at their crossings with the edges of
    the target (candidate pairs from GEOS: an STRtree of the edges, ``intersects``; a collinear
    overlap cuts at the edge's ends) and each piece is in or out as its midpoint."""
    import shapely

    coords, part = shapely.get_coordinates(
        shapely.get_parts(shapely.boundary(target)), return_index=True
    )
    same = part[1:] == part[:-1]
    q, e = coords[:-1][same], (coords[1:] - coords[:-1])[same]
    tree = shapely.STRtree(shapely.linestrings(np.stack([q, q + e], axis=1)))
    si, ei = tree.query(shapely.linestrings(segs), predicate="intersects")
    p, d = segs[si, 0], segs[si, 1] - segs[si, 0]
    qq, ee = q[ei], e[ei]

    def cross(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
        return a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]

    denom = cross(d, ee)
    dd = np.einsum("ij,ij->i", d, d)
    scale = np.sqrt(dd * np.einsum("ij,ij->i", ee, ee))
    parallel = np.abs(denom) <= 1e-12 * scale
    t_cross = cross(qq - p, ee) / np.where(parallel, 1.0, denom)
    t_a = np.einsum("ij,ij->i", qq - p, d) / dd  # a collinear overlap: the edge's ends
    t_b = np.einsum("ij,ij->i", qq + ee - p, d) / dd
    owner = np.concatenate([si, si[parallel], np.arange(len(segs)), np.arange(len(segs))])
    t = np.concatenate(
        [np.where(parallel, t_a, t_cross), t_b[parallel], np.zeros(len(segs)), np.ones(len(segs))]
    )
    t = np.clip(t, 0.0, 1.0)
    order = np.lexsort((t, owner))
    owner, t = owner[order], t[order]
    piece = owner[1:] == owner[:-1]
    o, t0, t1 = owner[:-1][piece], t[:-1][piece], t[1:][piece]
    mid = segs[o, 0] + ((t0 + t1) / 2)[:, None] * (segs[o, 1] - segs[o, 0])
    inside = shapely.intersects_xy(target, mid[:, 0], mid[:, 1])
    length = np.linalg.norm(segs[:, 1] - segs[:, 0], axis=1)
    return np.bincount(o, weights=np.where(inside, t1 - t0, 0.0), minlength=len(segs)) * length


def with_outside_length(plan: Plan, area: Region | Polygon | ArrayLike | Any) -> Plan:
    """``plan`` with its ``outside_length`` measured on its whole path (every waypoint, the
    turns' curves included) against ``area`` (plan frame; its holes count as outside), in
    ground units."""
    outside = outside_length(plan.waypoints, area) / plan.ground_scale
    stats = dataclasses.replace(plan.stats, outside_length=outside)
    return dataclasses.replace(plan, stats=stats)
