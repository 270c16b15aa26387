"""``boustro plan``: from a survey area to a mission file (and a plot)."""

from __future__ import annotations

import argparse
import io
import math
import os
import sys
from typing import Any

from .. import objectives
from .._files import atomic_write_all
from ..errors import InvalidParameterError
from ..io import Area, embedded_field, read_areas
from ..io.formats import FORMATS, format_for
from ..io.formats._common import ALTITUDE_FORMATS, check_altitude
from ..io.repair import check_area, detach_holes, repair_area
from ..mission import DEFAULT_HULL_TOLERANCE, DEFAULT_METHOD, Mission
from ..mission.camera import camera_presets
from ..mission.options import check_turn_time, sensor_of, vehicle_of
from ..plot.plan import plot_plan
from ..vehicle import Vehicle
from ._camera import add_trigger_options, camera_arg
from ._common import (
    check_not_input,
    check_output_path,
    check_plot_target,
    finite_float,
    positive_float,
    print_json,
    print_table,
)
from ._fields import mission_files, output_files, pick_fields, plan_fields, read_picked
from ._flight import add_flight_options, check_flight, fly, plan_mission
from ._plan_rows import rows as _rows
from ._sweep import check_sweep, sweep_noted


#: Objectives by name on the command line: the library's registry
#: (:data:`boustro.objectives.OBJECTIVES`) in kebab case. Objectives that score the chords' ends
#: (``needs_chords``, e.g. ShortestPath) are not offered: the coverage-guaranteed lanes that a
#: plan flies can add a lane and length, so their optimum is not the shortest flown path (see
#: README, "Known limitations", and docs/limitations.md).
def cli_objectives() -> dict[str, Any]:
    """The objectives ``--objective`` offers, read from the registry when called."""
    return {
        name.replace("_", "-"): factory
        for name, factory in objectives.OBJECTIVES.items()
        if not getattr(factory, "needs_chords", False)
    }


def _kebab(name: str) -> str:
    """An objective's name in kebab case, as ``--objective`` offers it and ``--json`` spells
    it (``fewest_transects`` -> ``fewest-transects``)."""
    return name.replace("_", "-")


#: The objectives at import time (compatibility; the parser reads :func:`cli_objectives`).
OBJECTIVES: dict[str, Any] = cli_objectives()


#: Spacing used for the embedded field when none is given, metres.
EMBEDDED_SPACING = 10.0

DETAILS = """\
area files:
  GeoJSON (RFC 7946: Polygon, MultiPolygon, Feature, FeatureCollection), a JSON list of [x, y]
  pairs, KML, KMZ, GML, WKT/EWKT (POLYGON, MULTIPOLYGON, GEOMETRYCOLLECTION), QGroundControl
  .plan (survey polygons and inclusion geofences, [lat, lon] read as lon/lat; exclusion fences
  and circles are not obstacles: each is named in a warning); with pyogrio (pip install
  'boustro[geo]'): Shapefile (.shp, .shp.zip, .zip), GeoPackage, FlatGeobuf, GeoParquet, each
  recognised by its signature (no other GDAL format). Chosen by extension, else by content.
  Coordinates are longitude, latitude (WGS 84) unless the file or --crs says otherwise; lon/lat
  areas are planned in the UTM zone of the area and written back in lon/lat. Without AREA, an
  embedded 3.6 ha field in the Netherlands (Fields2Cover, BSD-3-Clause) is planned at 10 m.

several fields in one file:
  every polygon is a field (each feature, placemark or GML parcel; each part of a multi-part
  geometry), named by its feature's name or id, its placemark's <name>, else 'field N'. Every
  field is planned (--field NAME|INDEX picks one; INDEX counts from 1): --json prints a list,
  one object per field; a GeoJSON mission holds every field (a 'field' property on each
  feature), KML a Folder per field, GPX a route and a track per field, CSV a 'field' column;
  other formats (.plan, .waypoints) and --plot write one file per field, FILE-<name>.ext (the
  name made filesystem-safe: runs of characters other than letters, digits, '.', '_', '-'
  become '_'; over 100 bytes cut, with 8 hex digits of its SHA-1). All fields are planned
  before anything is written; if any fails, nothing is written and one line names each
  failed field (exit status 2).

concave areas and holes:
  holes (GeoJSON interior rings, KML innerBoundaryIs, WKT inner rings) are obstacles: no path
  enters them. A concave area (unless nearly convex, see --hull-tolerance) or one with holes is
  decomposed into cells, each with its own angle and offset, when that promises fewer turns
  (with --speed, the time objective: when the decomposed plan is faster than one grid, its
  cells each searched by the certified search and carrying its certificate (certified, gap),
  the order of their lanes solved exactly for up to 12 passes, by
  OR-Tools beyond if installed; --json says "cell_order" and "compared");
  --decompose always decomposes, --no-decompose plans one angle with the lines cut at the
  boundary and the holes. Connecting moves go around holes; a hole that cuts lanes gets one
  pass around it so that the area along its edge is covered too.

keeping inside (--keep-inside):
  by default lanes run up to half a spacing past the boundary (their strip must cover the area
  up to it) and moves between lanes may cut across outside; outside_length_m in --json says
  how much of the path is outside the area or in a hole. --keep-inside keeps all of it inside:
  lanes are cut at the boundary (or half a spacing inside it, whichever needs less driving),
  moves follow the inside, and boundary passes along the contour half a spacing inside the edge
  (plus short patches over corners and parts narrower than a spacing) cover what the cut lanes
  leave; coverage is still checked with shapely on the area itself. With --turn-radius a turn
  whose shortest path would leave the area takes the shortest other one that stays inside (the
  loop the other way, or with --reverse a manoeuvre with reversing), else the move stays the
  routed one inside the area; --json counts those (vehicle.routed_moves) and notes say it.

coverage:
  every transect covers the strip of width SPACING centred on it, and its segment spans the
  whole part of the area inside that strip, so no part of the area is left outside every swath
  ("covered" is computed exactly with shapely). Such a plan can have one transect more than the
  layout the optimiser scores; --layout chords flies the lines' chords instead (no guarantee).

output formats (--out, by extension or --format):
  .geojson/.json  area, path, transects (property 'pass': lane, hole, boundary) and waypoints
                  (property 'kind') (area coordinates)
  .kml            area, path, transects named 'Transect N', 'Hole pass N', 'Boundary pass N'
                  (WGS 84)
  .gpx            route of waypoints (<type> their kind) + transects as track segments, the
                  boundary passes as a track of <type>boundary</type> (WGS 84); <ele>: the
                  altitude above take-off (with --dem: the route's, above mean sea level)
  .csv            one row per waypoint (with its kind; 'contour': a boundary pass)
  .plan           QGroundControl plan, MAV_CMD_NAV_WAYPOINT items (needs --altitude)
  .waypoints/.txt MAVLink 'QGC WPL 110' (needs --altitude)
  Files are written atomically: an error never leaves a half-written file, and AREA itself is
  never overwritten (an output of the same name is refused).
"""


#: The formats :data:`DETAILS` describes; the help lists any other registered format after them.
_DESCRIBED_FORMATS = ("geojson", "kml", "gpx", "csv", "plan", "wpl")


def _details() -> str:
    """:data:`DETAILS`, with a line for each format registered beyond those it describes."""
    extra = []
    for name, (exts, renderer) in FORMATS.items():
        if name not in _DESCRIBED_FORMATS:
            doc = (renderer.__doc__ or "").strip().splitlines()
            extra.append(f"  {'/'.join(exts):<15} {doc[0] if doc else f'format {name!r}'}")
    if not extra:
        return DETAILS
    marker = "  Files are written atomically"
    head, _, tail = DETAILS.partition(marker)
    return head + "\n".join(extra) + "\n" + marker + tail


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "plan",
        help="plan a survey area: optimised, coverage-guaranteed waypoints and mission files",
        description="Plan a boustrophedon survey of an area given in real coordinates: choose "
        "the transect angle and offset with an optimiser, place coverage-guaranteed transects, "
        "order them from the start corner, report statistics, write a mission file and a plot.",
        epilog=_details(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument(
        "area",
        nargs="?",
        metavar="AREA",
        help="area file (GeoJSON, JSON list, KML, KMZ, GML, WKT, QGroundControl .plan; with "
        "'boustro[geo]': Shapefile, GeoPackage, FlatGeobuf, GeoParquet); every field in it is "
        "planned; default: the embedded example field",
    )
    p.add_argument(
        "--field",
        metavar="NAME|INDEX",
        help="plan only this field of AREA: its name, else its index in the file (from 1)",
    )
    p.add_argument(
        "--crs",
        default=None,
        help="CRS of AREA's coordinates: an EPSG code (e.g. EPSG:28992), 'planar', or any "
        "pyproj input (WKT, PROJ string) (default: the file's, else EPSG:4326 longitude/"
        "latitude; a CRS read from a file must be an authority code or a WKT naming no file "
        "or grid)",
    )
    p.add_argument(
        "--repair",
        action="store_true",
        help="make an invalid AREA valid (shapely.make_valid: e.g. a self-touching ring or a "
        "spike) and say on stderr what changed; a repair that splits the area into several "
        "polygons is refused. Without it an invalid AREA is refused with GEOS's reason",
    )
    p.add_argument(
        "--force",
        action="store_true",
        help="plan even when the estimate before planning is absurd (more than 100000 lanes, "
        "an area over 10000 km^2, or an estimated time over 10 minutes for an area over 100 "
        "km^2: usually a planar file read as longitude/latitude, or longitude and latitude "
        "swapped); the hard limit (a million lanes) still holds. A plan estimated over 3 s "
        "says so on stderr first and shows progress bars (-q silences both)",
    )
    _add_spacing(p)
    _add_optimiser(p)
    _add_path(p)
    add_flight_options(p, _point)
    _add_output(p)
    p.set_defaults(func=run)


def _add_spacing(p: argparse.ArgumentParser) -> None:
    """The spacing options: a spacing, a camera or a swath sensor."""
    sensor = p.add_argument_group("spacing (one of)")
    which = sensor.add_mutually_exclusive_group()
    which.add_argument("--spacing", type=positive_float, help="transect spacing, metres")
    which.add_argument(
        "--camera",
        type=camera_arg,
        metavar="SENSOR_MM,FOCAL_MM,IMAGE_PX[,IMAGE_H_PX]|NAME",
        help="camera: sensor width (mm), focal length (mm), image width (px) and, for "
        "--front-overlap, image height (px), e.g. 13.2,8.8,5472,3648; or a preset: "
        f"{', '.join(sorted(camera_presets()))}; with --altitude or --gsd",
    )
    which.add_argument(
        "--swath", type=positive_float, metavar="WIDTH_M", help="swath sensor width, metres"
    )
    sensor.add_argument(
        "--gsd", type=positive_float, metavar="CM", help="camera ground sample distance, cm/px"
    )
    sensor.add_argument(
        "--overlap",
        type=_percent,
        metavar="PCT",
        help="side overlap between neighbouring swaths, percent (camera default 70, swath 0)",
    )
    add_trigger_options(sensor, _percent)
    sensor.add_argument(
        "--nadir-gap",
        type=_non_negative,
        default=0.0,
        metavar="M",
        help="swath sensor's blind strip under the vehicle (side-scan sonar), metres",
    )


def _add_optimiser(p: argparse.ArgumentParser) -> None:
    """The optimiser options: method and objective."""
    opt = p.add_argument_group("optimisation")
    opt.add_argument(
        "--method",
        default=None,
        help=f"optimiser (default: {DEFAULT_METHOD}; a concave area or one with holes: the "
        "certified optimum of Eq. 1 over its segments, 'grid' for the grid search)",
    )
    opt.add_argument(
        "--objective",
        choices=sorted(cli_objectives()),
        type=_kebab,  # --json's spelling before this round (fewest_transects) still accepted
        default=None,
        help="what the optimiser seeks: time (the mission time of the flown plan: path / "
        "--speed + turns x --turn-time, minimised over every angle and offset by a certified "
        "search; the DEFAULT whenever --speed is given), smith (Eq. 1 of the paper, "
        "maximised; the default without --speed), or fewest-transects (fewest lanes, i.e. "
        "turns, for full coverage: the minimum-width direction on a convex area, the "
        "certified search on a concave one); --json says certified and gap",
    )
    fixed = opt.add_mutually_exclusive_group()
    fixed.add_argument(
        "--angle",
        type=finite_float,
        metavar="DEG",
        help="plan at this fixed transect angle, degrees counter-clockwise from east (+x) in the "
        "plan frame, modulo 180 (as angle_deg in --json); only the offset is optimised for the "
        "objective (exactly for a convex area, by a dense offset scan otherwise; --json's "
        "method says which) and a concave area is planned as one grid. Not with --method, "
        "--decompose or --sweep",
    )
    fixed.add_argument(
        "--bearing",
        type=finite_float,
        metavar="DEG",
        help="as --angle, the direction given as a bearing: degrees clockwise from true north "
        "(grid north for planar input), modulo 180, as bearing_deg in --json; in the plan "
        "frame angle = 90 - bearing + the azimuth of grid north at the area's centre",
    )


def _add_path(p: argparse.ArgumentParser) -> None:
    """The path options: start, turns, speed, altitude, layout, decomposition."""
    path = p.add_argument_group("path")
    path.add_argument(
        "--start",
        type=_point,
        metavar="X,Y",
        help="start at the lane end nearest this point, in AREA's coordinates (LON,LAT for "
        "lon/lat); also the mission's home. Default: a convex area starts at the corner nearest "
        "AREA's first vertex, a concave one where the tour is shortest; the home is then the "
        "first waypoint",
    )
    path.add_argument(
        "--turnaround",
        type=_non_negative,
        default=0.0,
        metavar="M",
        help="run-in / run-out distance beyond each transect end, metres (default 0)",
    )
    path.add_argument(
        "--altitude",
        type=finite_float,
        metavar="M",
        help="mission altitude above take-off, metres (with --camera: its flying height)",
    )
    path.add_argument("--speed", type=positive_float, metavar="M/S", help="ground speed, m/s")
    path.add_argument(
        "--turn-time",
        type=_non_negative,
        default=0.0,
        metavar="S",
        help="seconds per turn (with --speed)",
    )
    path.add_argument(
        "--turn-radius",
        type=_non_negative,
        default=None,
        metavar="M",
        help="the vehicle's smallest turning radius, metres: the moves between lanes become "
        "Dubins turns (forward only: fixed-wing, boats, tractors), their waypoints along the "
        "curves in every export (no chord more than 5 cm off the curve: the waypoints fly a "
        "U-turn about 5 cm shorter than the curve), the curves' length in the path length and "
        "duration; a convex area's lanes are flown every other one and back when that turns "
        "less (2R > spacing)",
    )
    path.add_argument(
        "--reverse",
        action="store_true",
        help="with --turn-radius: the vehicle may reverse (Reeds-Shepp turns)",
    )
    path.add_argument(
        "--headland",
        type=_count,
        default=0,
        metavar="N",
        help="N headland passes around the boundary and around the holes, at the spacing; lanes "
        "clipped to the inner field, turns inside the field, coverage measured on the whole "
        "field (convex corners are reached by a short pass into the corner and back)",
    )
    path.add_argument(
        "--layout",
        choices=("guaranteed", "chords"),
        default="guaranteed",
        help=(
            "transect segments: coverage-guaranteed (default) or the lines' chords (chords "
            "leave the area's edges partly uncovered; a time plan of chords carries no "
            "certificate)"
        ),
    )
    path.add_argument(
        "--hull-tolerance",
        type=_non_negative,
        default=DEFAULT_HULL_TOLERANCE,
        metavar="M",
        help="plan a nearly convex area on its convex hull if the hull reaches at most this far "
        f"beyond it, metres (default {DEFAULT_HULL_TOLERANCE:g}; 0 plans every concave area as "
        "such)",
    )
    path.add_argument(
        "--decompose",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="concave areas and holes: always decompose into cells (--decompose), or plan one "
        "angle with lines cut at the boundary (--no-decompose); default: decompose when it "
        "promises fewer turns (the time objective: when the decomposed plan is faster). "
        "Either also turns off the hull rule of --hull-tolerance",
    )
    path.add_argument(
        "--keep-inside",
        action="store_true",
        help="no part of the path leaves the area or enters a hole (a boat on a lake, a "
        "tractor at a fence): lanes end at the boundary, moves between them follow the inside, "
        "and boundary passes (the contour half a spacing inside the edge, short patches over "
        "corners and thin parts) cover what the lane ends leave, so coverage stays 100%%; "
        "exported as transects of pass 'boundary', waypoints of kind 'contour'. Without it, "
        "outside_length_m (--json) is the length of the path flown (turn curves and headland "
        "passes included) outside the area or in a hole. Run-ins and run-outs (--turnaround) "
        "end at the boundary. With --turn-radius a turn that would leave takes the shortest "
        "other turn that stays inside, else the routed move (vehicle.routed_moves in --json). "
        "Not with --nadir-gap",
    )
    path.add_argument(
        "--sweep",
        type=finite_float,
        metavar="DEG",
        help="sweep direction of the decomposition, degrees counter-clockwise from east in the "
        "plan frame (default: chosen for few turns). Without --decompose the cells along it "
        "are kept only if they promise fewer turns than one grid (boustro plan notes a plan "
        "of one grid: the sweep changed nothing). Not with --no-decompose",
    )


def _add_output(p: argparse.ArgumentParser) -> None:
    """The output options: the mission file (formats read from FORMATS), plot, JSON."""
    out = p.add_argument_group("output")
    out.add_argument("--out", metavar="FILE", help="write the mission to FILE")
    out.add_argument(
        "--format", choices=tuple(FORMATS), help="format of --out (default: from its extension)"
    )
    out.add_argument("--plot", metavar="FILE", help="draw the plan to an image (e.g. plan.png)")
    out.add_argument(
        "--json",
        action="store_true",
        help="print one JSON object (a list of them, one per field, for several fields)",
    )


# -- argument types ----------------------------------------------------------------------------
def _numbers(text: str, count: int, what: str) -> list[float]:
    parts = text.replace(" ", "").split(",")
    if len(parts) != count:
        raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}")
    try:
        values = [float(x) for x in parts]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {what} (numbers), got {text!r}") from None
    if not all(math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"expected finite numbers, got {text!r}")
    return values


def _point(text: str) -> tuple[float, float]:
    x, y = _numbers(text, 2, "X,Y")
    return x, y


def _percent(text: str) -> float:
    value = finite_float(text.rstrip("%"))
    if not 0 <= value < 100:
        raise argparse.ArgumentTypeError(f"expected a percentage in [0, 100), got {text!r}")
    return value


def _count(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 0, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 0, got {text!r}")
    return value


def _non_negative(text: str) -> float:
    value = finite_float(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text!r}")
    return value


# -- the command ---------------------------------------------------------------------------
def _spacing(args: argparse.Namespace, embedded: bool) -> Any:
    """The spacing, camera or swath (as ``boustro batch``: one definition)."""
    return sensor_of(args, default=EMBEDDED_SPACING if embedded else None)


def _load(args: argparse.Namespace) -> list[Area]:
    if args.area is None:
        areas = [embedded_field()]
        if args.crs is not None:
            raise InvalidParameterError(
                "--crs applies to an AREA file; the embedded field is lon/lat"
            )
        return pick_fields(areas, args.field)
    return read_picked(lambda: read_areas(args.area, crs=args.crs), args.field)


def _validated(args: argparse.Namespace, area: Area) -> Area:
    """``area`` checked by GEOS (refused with its reason), or made valid with ``--repair``;
    a hole that touches the shell (valid for GEOS) cut back from it (:func:`detach_holes`)."""
    note = None
    if args.repair:
        area, note = repair_area(area)
    if note is not None:
        print(f"boustro: {note}", file=sys.stderr)
    area, note = detach_holes(area)
    if not args.repair:
        check_area(area)  # before the note: a refused area is not said to be planned
    if note is not None:
        print(f"boustro: {note}", file=sys.stderr)
    return area


def _plot_bytes(mission: Mission, path: str) -> bytes:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise InvalidParameterError(
            "--plot needs matplotlib: pip install 'boustro[plot]'"
        ) from None
    ext = os.path.splitext(path)[1].lstrip(".").lower() or "png"
    fig, ax = plt.subplots(figsize=(8, 8))
    try:
        plot_plan(mission, ax=ax)
        buf = io.BytesIO()
        try:
            fig.savefig(buf, format=ext, dpi=150, bbox_inches="tight")
        except ValueError as exc:
            raise InvalidParameterError(f"--plot {path}: {exc}") from None
        return buf.getvalue()
    finally:
        plt.close(fig)


def _vehicle(args: argparse.Namespace) -> Vehicle | None:
    """``--turn-radius`` and ``--reverse`` (as ``boustro batch``: one definition)."""
    return vehicle_of(args)


def _plan_one(args: argparse.Namespace, area: Area) -> list[Mission]:
    spacing = _spacing(args, embedded=args.area is None)
    # no --objective: plan_area's default (mission time with a speed, else Eq. 1)
    fitness = None if args.objective is None else cli_objectives()[args.objective]()
    mission = plan_mission(
        args,
        area,
        spacing,
        method=args.method,
        fitness=fitness,
        start=args.start,
        turnaround=args.turnaround,
        speed=args.speed,
        turn_time=args.turn_time,
        altitude=args.altitude,
        hull_tolerance=args.hull_tolerance,
        layout=args.layout,
        decompose=args.decompose,
        sweep=args.sweep,
        angle=None if args.angle is None else math.radians(args.angle),
        bearing=args.bearing,
        force=args.force,
        keep_inside=args.keep_inside,
        progress=False if args.quiet else None,
        vehicle=_vehicle(args),
        headland=args.headland,
    )
    return fly(args, sweep_noted(args, mission))


def run(args: argparse.Namespace) -> int:
    # Refuse unwritable outputs before any work (an error writes nothing): a missing folder,
    # an unknown format, a MAVLink mission without an altitude.
    fmt = None
    if args.out is not None:
        check_output_path(args.out, "--out")
        check_not_input(args.out, "--out", args.area)
        fmt = format_for(args.out, args.format)
        if fmt in ALTITUDE_FORMATS and args.camera is None:
            check_altitude(args.altitude, ALTITUDE_FORMATS[fmt])
    if args.plot is not None:
        check_plot_target(args.plot)
    if args.format is not None and args.out is None:
        raise InvalidParameterError("--format needs --out FILE")
    check_flight(args)
    check_turn_time(args.speed, args.turn_time)
    areas = _load(args)
    _vehicle(args)  # --reverse without --turn-radius: one error before any work
    check_sweep(args)
    _spacing(args, embedded=args.area is None)  # a missing spacing: one error, not one per field
    planned = plan_fields(areas, lambda area: _plan_one(args, _validated(args, area)))
    missions = [m for ms in planned for m in ms]  # a field's sorties follow one another
    # Render everything before touching any file, so that an error writes nothing.
    outputs: list[tuple[str, bytes | str, str, int | None]] = []
    if fmt is not None:
        outputs += [(p, d, fmt, i) for p, d, i in mission_files(missions, args.out, fmt)]
    if args.plot is not None:
        plots = output_files(
            missions,
            [m.name for m in missions],
            args.plot,
            lambda ms: None,  # one image per field
            lambda m: _plot_bytes(m, args.plot),
        )
        outputs += [(p, d, "plot", i) for p, d, i in plots]
    for path, _, fmt_or_plot, _ in outputs:  # a field's own file name too
        check_not_input(path, "--plot" if fmt_or_plot == "plot" else "--out", args.area)
    atomic_write_all((path, data) for path, data, _, _ in outputs)  # all files or none
    results = []
    for k, mission in enumerate(missions):
        mine = [(path, fmt) for path, _, fmt, i in outputs if i is None or i == k]
        if args.json:
            out = mission.summary()
            out["written"] = [path for path, _ in mine]
            results.append(out)
        else:
            if k:
                print()
            print_table(_rows(mission, [f"{path} ({fmt})" for path, fmt in mine]))
    if args.json:
        print_json(results[0] if len(results) == 1 else results)
    return 0
