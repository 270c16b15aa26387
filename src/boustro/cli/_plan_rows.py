"""The table ``boustro plan`` prints for one mission (without ``--json``)."""

from __future__ import annotations

import math

from ..mission import Mission

__all__ = ["flight_rows", "rows"]


def flight_rows(mission: Mission) -> list[tuple[str, str]]:
    """The camera, terrain, sortie and crosshatch rows."""
    out = []
    c = mission.camera
    if c is not None:
        turns = "through the turns" if c.images_in_turns else "along the lanes only"
        out.append(
            (
                "camera",
                f"{mission.photos} photos, one every {c.distance:.2f} m {turns} (front overlap "
                f"{100 * c.front_overlap:g}%, footprint {c.footprint_along:.1f} m along track), "
                f"GSD {c.gsd:.2f} cm/px",
            )
        )
    t = mission.terrain
    if t is not None:
        out.append(
            (
                "terrain",
                f"{t.height:g} m above ground from {t.dem}: {len(t.points)} waypoints "
                f"({sum(k == 'terrain' for k in t.kinds)} added, tolerance {t.tolerance:g} m), "
                f"{t.amsl.min():.1f} to {t.amsl.max():.1f} m AMSL",
            )
        )
    so = mission.sortie
    if so is not None:
        time = "" if so.duration is None else f", {so.duration:.0f} s"
        out.append(
            (
                "sortie",
                f"{so.index} of {so.count}: lanes {so.lanes[0] + 1}-{so.lanes[1] + 1}, "
                f"{so.length:.1f} m from home and back{time} ({so.limit})",
            )
        )
    for k, p in enumerate(mission.passes, start=1):
        cov = "" if p.coverage is None else f", covered {100 * p.coverage.covered_share:.4f}%"
        out.append(
            (
                f"crosshatch {k}",
                f"angle {math.degrees(p.plan.angle):.2f} deg, {p.stats.n_transects} transects{cov}",
            )
        )
    return out


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
    vehicle = mission.plan.vehicle
    if vehicle is not None:
        back = ", may reverse" if vehicle.reverse else ""
        rows.append(
            (
                "turns",
                f"{vehicle.kind}, radius {vehicle.turn_radius:g} m{back}: "
                f"{s.turn_length:.1f} m of curves in the path",
            )
        )
    if mission.plan.headland:
        rows.append(("headland", f"{mission.plan.headland} pass(es), {s.headland_length:.1f} m"))
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
    rows += flight_rows(mission)
    rows += [("written", name) for name in written]
    return rows
