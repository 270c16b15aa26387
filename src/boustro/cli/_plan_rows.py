"""The table ``boustro plan`` prints for one mission (without ``--json``)."""

from __future__ import annotations

import math

from ..mission import Mission

__all__ = ["rows"]


def _fitness(value: float) -> str:
    return "undefined (one lane)" if math.isnan(value) else f"{value:.6f}"


def rows(mission: Mission, written: list[str]) -> list[tuple[str, str]]:
    s, opt = mission.stats, mission.optimum
    proj = mission.projection
    where = mission.area.source
    crs = "planar coordinates" if proj.planar else f"{mission.crs}"
    if proj.geographic:
        crs += f", planned in {proj.plan_crs}"
    rows = [
        ("area", f"{mission.name or '(unnamed)'} ({where}), {crs}"),
        ("area size", f"{s.area:.1f} m2 ({s.area / 1e4:.4g} ha)"),
        (
            "spacing",
            f"{mission.spacing:.4g} m" + (f" ({mission.sensor})" if mission.sensor else ""),
        ),
        (
            "transects",
            f"angle {math.degrees(mission.plan.angle):.4f} deg (bearing {mission.bearing:.2f} "
            f"deg from north), offset {mission.plan.offset:.4g} m",
        ),
        (
            "optimiser",
            f"{opt.method}, fitness {_fitness(opt.fitness)} ({opt.evaluations} evaluations)",
        ),
        ("count", f"{s.n_transects} transects, {s.n_turns} turns ({mission.plan.layout} layout)"),
        ("transect length", f"{s.transect_length:.1f} m"),
        ("path length", f"{s.path_length:.1f} m"),
    ]
    if mission.plan.keep_inside:
        rows.append(
            (
                "inside",
                f"the whole path (--keep-inside), boundary passes {s.boundary_pass_length:.1f} m",
            )
        )
    elif s.outside_length > 0:
        rows.append(
            ("outside", f"{s.outside_length:.1f} m of the path (--keep-inside keeps it inside)")
        )
    if mission.coverage is not None:
        rows.append(
            (
                "covered",
                f"{100 * mission.coverage.covered_share:.4f}% of the area "
                f"(overlap {100 * mission.coverage.overlap_share:.2f}%)",
            )
        )
    if s.duration is not None:
        rows.append(
            (
                "duration",
                f"{s.duration:.0f} s ({s.duration / 60:.1f} min) at {s.speed:g} m/s, "
                f"{s.turn_time:g} s per turn",
            )
        )
    region = mission.plan.region
    if region is not None:
        shape = "concave" if not region.shell.is_convex else "convex"
        rows.append(
            (
                "area shape",
                f"{shape}, {region.n_holes} hole(s), "
                + (
                    f"{s.n_cells} cells (boustrophedon decomposition)"
                    if s.n_cells > 1
                    else "one angle, lines cut at the boundary"
                ),
            )
        )
        if s.n_cells > 1:
            angles = ", ".join(f"{math.degrees(c.angle):.1f}" for c in mission.plan.cells)
            rows.append(("cell angles", f"{angles} deg"))
        if s.hole_pass_length > 0:
            rows.append(("hole passes", f"{s.hole_pass_length:.1f} m around holes that cut lanes"))
        rows += [("note", note) for note in mission.plan.notes]
    if mission.hull_depth > 0:
        rows.append(
            (
                "note",
                f"the area is not convex; its convex hull, planned instead, reaches at most "
                f"{mission.hull_depth:.2f} m beyond it",
            )
        )
    if mission.altitude is not None:
        rows.append(("altitude", f"{mission.altitude:g} m above take-off"))
    rows += [("written", name) for name in written]
    return rows
