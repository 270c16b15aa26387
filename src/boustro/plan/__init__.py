"""Coverage plans: from an optimum to transects, cells, a tour and waypoints (plan frame)."""

from __future__ import annotations

from .cells import Decomposition, Trapezoids, decompose, trace_region, trapezoids
from .convex import build_plan, edge_offset, guaranteed_segments
from .coverage import Coverage, coverage, footprint, swath_polygons
from .hull import convex_hull, hull_depth, nearly_convex
from .lanes import Lanes, region_lanes
from .region import PlanOptions, plan_region
from .region_opt import SWEEP_SEARCH, choose_sweep, optimize_region
from .routing import Route, Router
from .types import KINDS, Layout, Plan, PlanCell, PlanStats

__all__ = [
    "KINDS",
    "SWEEP_SEARCH",
    "Coverage",
    "Decomposition",
    "Lanes",
    "Layout",
    "Plan",
    "PlanCell",
    "PlanOptions",
    "PlanStats",
    "Route",
    "Router",
    "Trapezoids",
    "build_plan",
    "choose_sweep",
    "convex_hull",
    "coverage",
    "decompose",
    "edge_offset",
    "footprint",
    "guaranteed_segments",
    "hull_depth",
    "nearly_convex",
    "optimize_region",
    "plan_region",
    "region_lanes",
    "swath_polygons",
    "trace_region",
    "trapezoids",
]
