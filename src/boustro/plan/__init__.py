"""Coverage plans: from an optimum to transects, cells, a tour and waypoints (plan frame)."""

from __future__ import annotations

from .cells import Decomposition, Trapezoids, decompose, trace_region, trapezoids
from .convex import build_plan, edge_offset, guaranteed_segments
from .coverage import Coverage, coverage, footprint, swath_polygons
from .headland import add_headland, check_headland, headland_rings, inner_field
from .hull import convex_hull, hull_depth, nearly_convex
from .lanes import Lanes, region_lanes
from .region import PlanOptions, plan_region
from .region_opt import SWEEP_SEARCH, choose_sweep, optimize_region
from .routing import Route, Router
from .types import KINDS, Layout, Plan, PlanCell, PlanStats
from .vehicle_path import drive_vehicle, order_lanes, vehicle_stats

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
    "add_headland",
    "build_plan",
    "check_headland",
    "choose_sweep",
    "convex_hull",
    "coverage",
    "decompose",
    "drive_vehicle",
    "edge_offset",
    "footprint",
    "guaranteed_segments",
    "headland_rings",
    "hull_depth",
    "inner_field",
    "nearly_convex",
    "optimize_region",
    "order_lanes",
    "plan_region",
    "region_lanes",
    "swath_polygons",
    "trace_region",
    "trapezoids",
    "vehicle_stats",
]
