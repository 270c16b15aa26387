"""Compatibility path: the concave-area planner now lives in :mod:`boustro.plan`."""

from __future__ import annotations

from .plan.cell_trace import _interval_minus
from .plan.cells import (
    _TOL,
    Decomposition,
    Trapezoids,
    _check_float,
    _crossings,
    _frame,
    _links,
    _ring_area,
    _straighten,
    _UnionFind,
    decompose,
    trace_region,
    trapezoids,
)
from .plan.lanes import Lanes, _intervals_on_lines, _merge_intervals, _subtract, region_lanes
from .plan.region import plan_region
from .plan.region_opt import (
    SWEEP_SEARCH,
    _angle_gap,
    _cells_for_sweep,
    _estimate,
    _merge_by_angle,
    choose_sweep,
    optimize_region,
)
from .plan.tour import (
    ORDER_BUDGET,
    _chain_pass,
    _chains,
    _extension_end,
    _hole_pass,
    _orders,
    _Pass,
)
from .plan.types import Layout

__all__ = [
    "ORDER_BUDGET",
    "SWEEP_SEARCH",
    "_TOL",
    "Decomposition",
    "Lanes",
    "Layout",
    "Trapezoids",
    "_Pass",
    "_UnionFind",
    "_angle_gap",
    "_cells_for_sweep",
    "_chain_pass",
    "_chains",
    "_check_float",
    "_crossings",
    "_estimate",
    "_extension_end",
    "_frame",
    "_hole_pass",
    "_interval_minus",
    "_intervals_on_lines",
    "_links",
    "_merge_by_angle",
    "_merge_intervals",
    "_orders",
    "_ring_area",
    "_straighten",
    "_subtract",
    "choose_sweep",
    "decompose",
    "optimize_region",
    "plan_region",
    "region_lanes",
    "trace_region",
    "trapezoids",
]
