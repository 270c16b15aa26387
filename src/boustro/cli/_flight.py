"""``boustro plan``'s flight options: sorties (home, limits), terrain (a DEM), crosshatch."""

from __future__ import annotations

import argparse
from typing import Any

from ..errors import InvalidParameterError
from ..mission import Mission, plan_area
from ..mission.crosshatch import plan_crosshatch
from ..mission.project import START_NAME
from ..mission.sorties import check_speed, split_mission
from ..mission.terrain import DEFAULT_TOLERANCE, check_height, follow_terrain, open_dem
from ._common import positive_float

__all__ = ["add_flight_options", "check_flight", "fly", "plan_mission"]


def add_flight_options(p: argparse.ArgumentParser, point: Any) -> None:
    """The options of this module; ``point`` parses ``X,Y``."""
    g = p.add_argument_group("flight: sorties, terrain, crosshatch")
    g.add_argument(
        "--home",
        type=point,
        metavar="X,Y",
        help="home (take-off and landing) position in AREA's coordinates (LON,LAT for lon/lat); "
        "the path starts at the lane end nearest it unless --start is given. Default: the "
        "mission's home (--start, else the first waypoint)",
    )
    g.add_argument(
        "--max-flight-time",
        type=positive_float,
        metavar="S",
        help="split the mission into sorties of at most S seconds each, from home and back "
        "(needs --speed; --turn-time counts): whole lanes in the mission's order, the cut "
        "points chosen for the fewest sorties, then the least total time. .plan and "
        ".waypoints: one file per sortie (FILE-<name>_sortie_N.ext), each ending with a return "
        "to launch; GeoJSON, KML, GPX, CSV: one file with every sortie",
    )
    g.add_argument(
        "--max-distance",
        type=positive_float,
        metavar="M",
        help="as --max-flight-time, sorties of at most M metres each (home and back included)",
    )
    g.add_argument(
        "--dem",
        metavar="FILE.tif",
        help="keep a constant height above ground (--altitude, or the camera's) over the "
        "terrain of this GeoTIFF DEM (rasterio: pip install 'boustro[terrain]'): waypoint "
        "altitudes above mean sea level, points added where the terrain bends; .plan and "
        ".waypoints in MAV_FRAME_GLOBAL (AMSL), GPX's route with <ele> AMSL",
    )
    g.add_argument(
        "--terrain-tolerance",
        type=positive_float,
        default=DEFAULT_TOLERANCE,
        metavar="M",
        help="with --dem: largest vertical error between two waypoints, metres (default "
        f"{DEFAULT_TOLERANCE:g})",
    )
    g.add_argument(
        "--crosshatch",
        action="store_true",
        help="fly a second pass at 90 degrees to the first (3D mapping); the angle is chosen "
        "for the pair (the objective summed over both passes)",
    )


def plan_mission(args: argparse.Namespace, area: Any, spacing: Any, **kwargs: Any) -> Mission:
    """The mission of one area: :func:`plan_area`, or a crosshatch pair."""
    name = None
    if args.home is not None and kwargs.get("start") is None:
        kwargs["start"] = args.home
        name = START_NAME.set("home")  # a far home is warned about as home, not "the start"
    try:
        if args.crosshatch:
            return plan_crosshatch(area, spacing, **kwargs)
        return plan_area(area, spacing, **kwargs)
    finally:
        if name is not None:
            START_NAME.reset(name)


def check_flight(args: argparse.Namespace) -> None:
    """The flight options' errors that need no plan, raised before any work: a tolerance
    without a DEM, a flight time without a speed, a DEM without a height or that cannot be
    read (read here, once: ``args.dem`` becomes the :class:`~boustro.mission.terrain.Dem`)."""
    if args.terrain_tolerance != DEFAULT_TOLERANCE and args.dem is None:
        raise InvalidParameterError("--terrain-tolerance needs --dem")
    check_speed(args.max_flight_time, args.speed)
    if args.dem is not None:
        if args.camera is None:  # a camera always has its flying height
            check_height(args.altitude)
        args.dem = open_dem(args.dem)


def fly(args: argparse.Namespace, mission: Mission) -> list[Mission]:
    """The mission's sorties (or the mission), each over the terrain with ``--dem``
    (:func:`check_flight` first)."""
    missions = split_mission(
        mission,
        home=args.home,
        max_time=args.max_flight_time,
        max_distance=args.max_distance,
    )
    if args.dem is not None:
        missions = [follow_terrain(m, args.dem, tolerance=args.terrain_tolerance) for m in missions]
    return missions
