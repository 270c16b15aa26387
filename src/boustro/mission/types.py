"""The mission: a plan over a real area, in the area's coordinates and in longitude/latitude."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..io.crs import Projection
from ..io.read import Area
from ..optimize import OptimizeResult
from ..plan import Coverage, Plan, PlanStats
from ..sensors import CameraTrigger
from .flight import Sortie, TerrainRoute

__all__ = ["Mission"]


def objective_name(name: Any) -> str | None:
    """An objective's name as ``boustro plan --objective`` and the web API spell it (kebab
    case: ``fewest-transects``); the optimisers' answers spell some in snake case."""
    return None if name is None else str(name).replace("_", "-")


def certificate(optimum: OptimizeResult | None) -> dict[str, Any]:
    """``objective`` (spelled as on the command line: :func:`objective_name`), ``certified``
    and ``gap`` (and ``lower_bound`` for a minimised objective) of an optimum: certified when
    the method proves its gap within its tolerance (the certified cover search; the global
    Eq. 1 search when converged); ``gap`` is ``None`` without a certificate."""
    if optimum is None:
        return {"certified": False, "gap": None}
    info = optimum.info
    if "gap" in info and "lower_bound" in info and "certified" not in info:  # exact solvers
        gap = info["gap"]
        return {
            "objective": objective_name(info.get("objective")),
            "certified": gap is not None and bool(info.get("converged", True)),
            "gap": gap,
            "lower_bound": info["lower_bound"],
        }
    if "certified" in info:
        out = {
            "objective": objective_name(info.get("objective")),
            "certified": bool(info["certified"]),
        }
        out["gap"] = info.get("gap")
        if "lower_bound" in info:
            out["lower_bound"] = info["lower_bound"]
        return out
    if optimum.upper_bound is not None:
        return {
            "objective": "smith",
            "certified": bool(info.get("converged", True)),
            "gap": optimum.gap,
        }
    return {"certified": False, "gap": None}


@dataclass(frozen=True)
class Mission:
    """A plan over a real area: the plan frame's :class:`~boustro.plan.Plan` and its coordinates.

    Attributes:
        name: the area's name.
        area: the area as read (source coordinates).
        projection: source CRS <-> plan frame.
        plan: the plan in the plan frame (its statistics in metres, or planar units).
        optimum: the optimiser's answer, in the plan frame.
        spacing: the spacing asked for, ground metres (planar units for planar input).
        reach, nadir_gap: the band half-width each transect covers and the sensor's blind strip,
            ground metres.
        turnaround: run-in / run-out distance asked for, metres.
        hull_depth: for a nearly convex area planned on its convex hull, the depth of the deepest
            pocket (how far transects may leave the area), metres; 0 for a convex area.
        altitude: mission altitude above the take-off point, metres, if known.
        coverage: coverage of the area (not the hull) by the plan's footprints, or ``None``.
        sensor: description of the sensor the spacing came from, if any.
        waypoints: ``(W, 2)`` in the area's coordinates; ``kinds`` as in the plan.
        transects: ``(T, 2, 2)`` in the area's coordinates, driving order.
        waypoints_lonlat, transects_lonlat, area_lonlat: the same in WGS 84 longitude/latitude,
            ``None`` for planar input.
        bearing: direction of the transects, degrees clockwise from true north in ``[0, 180)``
            (from grid north +y for planar input).
        home, home_lonlat: the take-off / home position: the ``start`` point if given, else the
            first waypoint (area coordinates; WGS 84, ``None`` for planar input).
        camera: distance triggering of a camera along the lanes (``--front-overlap``), if any;
            ``photos``: the number of photos it takes.
        terrain: the waypoints at a constant height above ground from a DEM, if any.
        sortie: this mission's place among the sorties of a split mission, if any.
        passes: a crosshatch mission's two passes, as planned (this mission flies both).
    """

    name: str
    area: Area
    projection: Projection
    plan: Plan
    optimum: OptimizeResult
    spacing: float
    reach: float
    nadir_gap: float
    turnaround: float
    hull_depth: float
    altitude: float | None
    coverage: Coverage | None
    sensor: str | None
    waypoints: NDArray[np.float64]
    transects: NDArray[np.float64]
    waypoints_lonlat: NDArray[np.float64] | None
    transects_lonlat: NDArray[np.float64] | None
    area_lonlat: NDArray[np.float64] | None
    bearing: float
    home: NDArray[np.float64]
    home_lonlat: NDArray[np.float64] | None
    holes_lonlat: tuple[NDArray[np.float64], ...] = ()
    camera: CameraTrigger | None = None
    photos: int | None = None
    terrain: TerrainRoute | None = None
    sortie: Sortie | None = None
    passes: tuple[Mission, ...] = ()

    @property
    def crs(self) -> str | None:
        return self.area.crs

    @property
    def decomposed(self) -> bool:
        """True for a plan over several cells."""
        return len(self.plan.cells) > 1

    def cell_rings(self) -> list[list[NDArray[np.float64]]]:
        """Each cell's rings (outer boundary, then holes) in the area's coordinates."""
        out = []
        for cell in self.plan.cells:
            region = cell.region
            out.append(
                [self.projection.to_source(region.shell.vertices)]
                + [self.projection.to_source(h.vertices) for h in region.holes]
            )
        return out

    @property
    def kinds(self) -> tuple[str, ...]:
        return self.plan.kinds

    @property
    def stats(self) -> PlanStats:
        return self.plan.stats

    def summary(self) -> dict[str, Any]:
        """Plain-JSON summary of the mission (no waypoints), for files and ``--json``."""
        s = self.stats
        out: dict[str, Any] = {
            "name": self.name,
            "crs": self.crs,
            "plan_crs": self.projection.plan_crs,
            "spacing_m": self.spacing,
            "bearing_deg": self.bearing,
            "angle_deg": math.degrees(self.plan.angle),
            "offset": self.plan.offset,
            "method": self.optimum.method,
            **certificate(self.optimum),
            # undefined (None) for a single lane: Eq. 1 needs two transects (region_opt)
            "fitness": None if math.isnan(self.optimum.fitness) else self.optimum.fitness,
            "layout": self.plan.layout,
            "n_transects": s.n_transects,
            "n_turns": s.n_turns,
            "transect_length_m": s.transect_length,
            "path_length_m": s.path_length,
            "area_m2": s.area,
            "turnaround_m": self.turnaround,
            "hull_depth_m": self.hull_depth,
        }
        out["outside_length_m"] = s.outside_length
        if self.plan.keep_inside:
            out["keep_inside"] = True
            out["boundary_pass_length_m"] = s.boundary_pass_length
        if s.duration is not None:
            out.update(speed_m_s=s.speed, turn_time_s=s.turn_time, duration_s=s.duration)
        if self.altitude is not None:
            out["altitude_m"] = self.altitude
        if self.coverage is not None:
            out["covered_share"] = self.coverage.covered_share
            out["overlap_share"] = self.coverage.overlap_share
        if self.nadir_gap:
            out["nadir_gap_m"] = self.nadir_gap
            out["reach_m"] = self.reach
        if self.sensor:
            out["sensor"] = self.sensor
        vehicle = self.plan.vehicle
        if vehicle is not None:
            out["vehicle"] = {
                "turns": vehicle.kind,
                "turn_radius_m": vehicle.turn_radius,
                "reverse": vehicle.reverse,
                # moves kept straight or routed: the turn would leave the field or a hole
                "routed_moves": self.plan.routed_moves,
            }
            out["turn_length_m"] = s.turn_length
        if self.plan.headland:
            out["headland_passes"] = self.plan.headland
            out["headland_length_m"] = s.headland_length
        if self.plan.region is not None:
            out["holes"] = self.plan.region.n_holes
            out["n_cells"] = s.n_cells
            out["cells"] = [
                {
                    "angle_deg": math.degrees(c.angle),
                    "offset": c.offset,
                    "fitness": None if math.isnan(c.fitness) else c.fitness,
                    "n_transects": c.n_transects,
                    **certificate(c.optimum),
                    "area_m2": c.region.area / self.plan.ground_scale**2,
                }
                for c in self.plan.cells
            ]
            out["hole_pass_length_m"] = s.hole_pass_length
            if self.plan.order_solver is not None:
                out["cell_order"] = self.plan.order_solver
            info = self.optimum.info
            if "one_grid" in info:  # the time objective compared one grid and the cells
                out["compared"] = {"one_grid": info["one_grid"], "decomposed": info["decomposed"]}
            if "decomposition" in info:  # which candidate decomposition was kept
                out["decomposition"] = info["decomposition"]
            if self.plan.notes:
                out["notes"] = list(self.plan.notes)
        out.update(self._flight_summary())
        return out

    def _flight_summary(self) -> dict[str, Any]:
        """The camera, terrain, sortie and crosshatch entries of :meth:`summary`."""
        out: dict[str, Any] = {}
        if self.camera is not None:
            c = self.camera
            out["camera"] = {
                "trigger_distance_m": c.distance,
                "front_overlap": c.front_overlap,
                "footprint_along_m": c.footprint_along,
                "footprint_across_m": c.footprint_across,
                "gsd_cm_px": c.gsd,
                "height_m": c.altitude,
                "images_in_turns": c.images_in_turns,
                "photos": self.photos,
            }
        if self.terrain is not None:
            out["terrain"] = self.terrain.summary()
        if self.sortie is not None:
            out["sortie"] = self.sortie.summary()
        if self.passes:
            out["crosshatch"] = [
                {
                    "angle_deg": math.degrees(p.plan.angle),
                    "bearing_deg": p.bearing,
                    "n_transects": p.stats.n_transects,
                    "covered_share": None if p.coverage is None else p.coverage.covered_share,
                }
                for p in self.passes
            ]
        return out
