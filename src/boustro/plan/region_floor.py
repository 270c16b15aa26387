"""A floor of a ``keep_inside`` plan's path, from its lanes and boundary passes alone.

A search over layouts (:func:`boustro.optimize.cover.cover_optimum`) plans hundreds of
``keep_inside`` layouts of one area, most of them longer than its best plan. The lanes cut
inside the area and the boundary passes (:func:`~boustro.plan.inside.inside_layout`) are a
third of a plan's CPU; the tour, the routing and the driven path the rest. :func:`plan_floor`
lays the lanes and passes exactly as :func:`~boustro.plan.region.plan_region` does (the same
steps, the same options) and bounds every path through them from below
(:func:`~boustro.plan.inside.path_floor`): a layout whose floor costs more than the best plan
need not be planned (docs/keep_inside.md, "The search's screen"). ``inside_layout`` keeps its
last results, so a layout that passes the screen is not laid twice.
"""

from __future__ import annotations

import inspect
from typing import Any

from ..geometry.region import as_region
from .inside import path_floor
from .region import _check_options, _plan_cells, _plan_lanes, plan_region

__all__ = ["plan_floor"]


def plan_floor(region: Any, spacing: float, **kw: Any) -> tuple[float, int] | None:
    """A lower bound ``(path length, turns)`` (plan units) of the plan
    ``plan_region(region, spacing, **kw)``, from its cut lanes and boundary passes; ``None``
    unless it is a ``keep_inside`` plan of the guaranteed layout over one cell
    (``decompose_area=False``). Raises what ``plan_region`` raises for its lanes."""
    bound = inspect.signature(plan_region).bind(region, spacing, **kw)
    bound.apply_defaults()
    args = dict(bound.arguments)
    r = as_region(args.pop("region"))
    del args["spacing"], args["progress"]
    cells = args.pop("cells")
    opts = _check_options(r, spacing, cells=None if cells is None else tuple(cells), **args)
    if not opts.keep_inside or opts.layout != "guaranteed" or opts.decompose_area is not False:
        return None
    lanes = _plan_lanes(r, _plan_cells(r, opts, []), opts)
    return path_floor(lanes.lanes, lanes.boundary or [])
