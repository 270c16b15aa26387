"""A floor of a ``keep_inside`` plan's path, from its lanes and boundary passes alone.

A search over layouts (:func:`boustro.optimize.cover.cover_optimum`) plans hundreds of
``keep_inside`` layouts of one area, most of them longer than its best plan. The lanes cut
inside the area and the boundary passes (:func:`~boustro.plan.inside.inside_layout`) are a
third of a plan's CPU; the tour, the routing and the driven path the rest. :func:`plan_floor`
lays the lanes and passes exactly as :func:`~boustro.plan.region.plan_region` does (the same
steps, the same options) and bounds every path through them from below
(:func:`tour_floor`): a layout whose floor costs more than the best plan
need not be planned (docs/keep_inside.md, "The search's screen"). ``inside_layout`` keeps its
last results, so a layout that passes the screen is not laid twice.
"""

from __future__ import annotations

import inspect
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..geometry.region import as_region
from .lanes import Lanes
from .region import _check_options, _plan_cells, _plan_lanes, plan_region

__all__ = ["plan_floor", "tour_floor"]

#: ``plan_region``'s signature, read once (``inspect.signature`` per call was 5% of a floor),
#: and its keywords' defaults (binding the arguments per call was 2% of a floor).
_SIGNATURE = inspect.signature(plan_region)
_DEFAULTS = {
    name: p.default
    for name, p in _SIGNATURE.parameters.items()
    if p.kind is inspect.Parameter.KEYWORD_ONLY
}


def plan_floor(region: Any, spacing: float, **kw: Any) -> tuple[float, int] | None:
    """A lower bound ``(path length, turns)`` (plan units) of the plan
    ``plan_region(region, spacing, **kw)``, from its cut lanes and boundary passes; ``None``
    unless it is a ``keep_inside`` plan of the guaranteed layout over one cell
    (``decompose_area=False``). Raises what ``plan_region`` raises for its lanes, not what its
    tour stage raises (``order="exact"`` over too many passes: the mission's screen never sets
    ``order``)."""
    unknown = kw.keys() - _DEFAULTS.keys()
    if unknown:  # plan_region's own error
        _SIGNATURE.bind(region, spacing, **kw)
    args = {**_DEFAULTS, **kw}
    r = as_region(region)
    del args["progress"]
    cells = args.pop("cells")
    opts = _check_options(r, spacing, cells=None if cells is None else tuple(cells), **args)
    if not opts.keep_inside or opts.layout != "guaranteed" or opts.decompose_area is not False:
        return None
    lanes = _plan_lanes(r, _plan_cells(r, opts, []), opts)
    return tour_floor(lanes.lanes, lanes.boundary or [])


def tour_floor(lanes: list[Lanes], passes: list[NDArray[np.float64]]) -> tuple[float, int]:
    """A lower bound ``(length, turns)`` of the path and turns of every tour of the cut
    ``lanes`` and boundary ``passes`` (:func:`inside_layout`), however ordered, routed and
    driven: the lanes' and passes' own length plus a floor of the moves between them, and the
    turns (one fewer than the lanes and passes: a ``keep_inside`` plan's count,
    :mod:`boustro.plan.region`).

    The path drives each *unit* (a lane, a pass) whole, from an entry to an exit: a lane or an
    open pass from one end to the other (either way), a closed pass from one of its corners
    round to it. Between consecutive units it goes from the exit of one to the entry of the
    next (a move, routed or turned: never shorter than the straight line). With ``nn(p)`` the
    distance from a unit's end ``p`` to the nearest end or corner of any *other* unit, the
    move from ``x`` to ``y`` is at least ``max(nn(x), nn(y)) >= (nn(x) + nn(y)) / 2``; summed
    over the moves, every lane's and open pass's two ends count half once each (whichever way
    it is driven) except the first unit's entry and the last one's exit (the two largest
    halves are taken off), and a closed pass counts 0. Also, every unit but the first is
    entered by a move of at least ``min(nn)`` over its ends (0 for a closed pass); the larger
    of the two floors is returned. The search's screen (:mod:`boustro.optimize.cover`) skips
    a layout whose floor is above its best plan."""
    ends, labels, rings, ring_labels = [], [], [], []
    length, units = 0.0, 0
    for ls in lanes:
        if len(ls.k):
            ends.append(ls.segments.reshape(-1, 2))
            labels.append(np.repeat(np.arange(units, units + len(ls.k)), 2))
            length += float(np.sum(ls.t1 - ls.t0))
            units += len(ls.k)
    n_lanes = units
    for p in passes:
        length += float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())
        if len(p) > 3 and bool(np.allclose(p[0], p[-1], rtol=0.0, atol=1e-12)):  # closed
            rings.append(p)
            ring_labels.append(np.full(len(p), units))
        else:
            ends.append(p[[0, -1]])
            labels.append(np.array([units, units]))
        units += 1
    if units < 2 or not ends:
        return length, max(units - 1, 0)
    xy, lab = np.concatenate(ends), np.concatenate(labels)
    every, every_lab = np.concatenate([xy, *rings]), np.concatenate([lab, *ring_labels])
    n_lane = 2 * n_lanes  # the lanes' ends come first
    nn, nn_lane = np.full(len(xy), np.inf), np.full(len(xy), np.inf)
    for lo in range(0, len(every), 512):  # the ends' nearest other unit, 512 points at a time
        d = np.hypot(every[lo : lo + 512, None, 0] - xy[None, :, 0],
                     every[lo : lo + 512, None, 1] - xy[None, :, 1])  # fmt: skip
        d[every_lab[lo : lo + 512, None] == lab[None, :]] = np.inf
        nn = np.minimum(nn, d.min(axis=0))
        if lo < n_lane:  # the nearest other lane's end
            nn_lane = np.minimum(nn_lane, d[: n_lane - lo].min(axis=0))
    nn = np.where(np.isfinite(nn), nn, 0.0)
    nn_lane = np.where(np.isfinite(nn_lane), nn_lane, nn)
    half = np.sort(nn / 2)
    by_halves = float(half[:-2].sum())
    # a move between two lanes' ends is at least half of each one's nn_lane; at most two moves
    # per pass reach a lane's end from it (in and out), each losing half of nn_lane - nn there
    charge = np.concatenate([nn_lane[:n_lane], nn[n_lane:]]) / 2
    loss = np.sort((nn_lane[:n_lane] - nn[:n_lane]) / 2)[::-1][: 2 * len(passes)]
    by_lanes = float(np.sort(charge)[:-2].sum() - loss.sum())
    entered = np.full(units, np.inf)
    np.minimum.at(entered, lab, nn)
    entered = np.where(np.isfinite(entered), entered, 0.0)  # closed passes
    by_entries = float(entered.sum() - entered.max())
    return length + max(by_halves, by_lanes, by_entries, 0.0), units - 1
