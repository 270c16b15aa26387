"""``boustro batch``: plan every feature of a vector file into a GeoPackage, resumably."""

from __future__ import annotations

import argparse

from ..batch import COLUMN_OPTIONS, PlanOptions, batch
from ..errors import InvalidParameterError
from ..io.formats import FORMATS
from ._common import positive_int, print_json, print_table
from ._sweep import check_sweep
from .plan import _add_optimiser, _add_path, _add_spacing

__all__ = ["register", "run"]

DETAILS = """\
input:
  any vector file GDAL reads through pyogrio (GeoPackage, Shapefile, GeoJSON, FlatGeobuf,
  GeoParquet if the local GDAL has the driver); every feature of --layer (needed when the file
  has several layers with geometries) is a field, named by its name/id column. A layer without
  a CRS is not taken as longitude/latitude: give --crs (EPSG:4326, or 'planar' for plain x/y), else
  each field is reported with an error. A MultiPolygon feature is planned part by part.

options:
  those of 'boustro plan' (the same definitions): spacing or sensor (--camera with
  --front-overlap, --images-in-turns; --swath), optimisation, path, the vehicle
  (--turn-radius, --reverse), --headland N, --keep-inside; not --start nor plan's flight
  options (one mission's). --OPTION-column COLUMN takes an option per field from an attribute
  column (listed below); a missing or out-of-range value is that field's error row.

output:
  PLANS.gpkg holds the layers 'lanes' (one line per lane, driving order), 'paths' (the path
  through the waypoints) and 'fields' (one row per input feature: field_id = its position in
  the layer from 1, name, status 'ok' or 'error', error (one line), lanes, turns, lengths,
  duration, covered_share, certified, gap, method, angle, bearing, the input geometry), in the
  input's CRS. Another extension (.fgb, .shp, .geojson, ...) writes PLANS.lanes.EXT,
  PLANS.paths.EXT and PLANS.fields.EXT when the run ends (the state is kept in a hidden
  .PLANS.boustro.gpkg beside them). --missions DIR also writes each field's mission file.

faults and resume:
  a field that fails (invalid, empty, not a polygon, no CRS, a bad column value, any planning
  error, a worker that died) gets an 'error' row and the run goes on (exit status 0; the
  summary counts them). Finished fields are committed a few times a second, their three
  layers together in one transaction: a crash or Ctrl-C loses only the fields being planned,
  the file is valid at every moment (readers see the last commit), and running the same
  command again plans only the fields without a row. An output made with other options is
  refused.

parallel:
  --workers N local processes (default: all cores; each imports boustro once), or
  --scheduler ADDRESS to run on a Dask distributed cluster (pip install 'boustro[dask]').
  A progress bar on stderr shows fields/s (-q silences it).
"""


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "batch",
        help="plan every field of a vector file into a GeoPackage (resumable, parallel)",
        description="Plan every feature of FIELDS as 'boustro plan' would, in parallel, and "
        "write lanes, paths and a status row per field to PLANS as they finish.",
        epilog=DETAILS,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("fields", metavar="FIELDS", help="vector file of fields (see below)")
    p.add_argument("--out", required=True, metavar="PLANS", help="output, e.g. plans.gpkg")
    p.add_argument(
        "--layer", help="the layer of FIELDS (needed when it has several with geometries)"
    )
    p.add_argument(
        "--crs",
        default=None,
        help="CRS of FIELDS' coordinates, overriding the file's: an EPSG code, 'planar', or "
        "any pyproj input",
    )
    p.add_argument(
        "--repair", action="store_true", help="make invalid fields valid (as boustro plan)"
    )
    p.add_argument(
        "--force", action="store_true", help="plan fields whose estimate is absurd (as plan)"
    )
    _add_spacing(p)
    _add_optimiser(p)
    _add_path(p)
    for action in p._actions:  # a start point is one field's: refused (see _options), unlisted
        if action.dest == "start":
            action.help = argparse.SUPPRESS
    columns = p.add_argument_group(
        "per-field values", "take an option from an attribute column of each field"
    )
    for option in COLUMN_OPTIONS:
        flag = option.replace("_", "-")
        columns.add_argument(
            f"--{flag}-column", metavar="COLUMN", dest=f"column_{option}",
            help=f"--{flag} of each field from its COLUMN",
        )  # fmt: skip
    out = p.add_argument_group("output and parallelism")
    out.add_argument(
        "--missions", metavar="DIR", help="write one mission file per field here (made if missing)"
    )
    out.add_argument(
        "--mission-format",
        choices=tuple(FORMATS),
        help="format of the --missions files (default geojson)",
    )
    out.add_argument("--workers", type=positive_int, help="local processes (default: cores)")
    out.add_argument("--scheduler", metavar="ADDRESS", help="a Dask scheduler, tcp://host:8786")
    out.add_argument(
        "--chunk-size", type=positive_int, default=8, help="fields per task (default 8)"
    )
    out.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(func=run)


def _options(args: argparse.Namespace) -> PlanOptions:
    if args.start is not None:
        raise InvalidParameterError("--start applies to one field: not offered by batch")
    if args.scheduler is not None and args.workers is not None:
        raise InvalidParameterError("give --workers or --scheduler, not both")
    check_sweep(args)  # --sweep with --no-decompose: it would change nothing
    columns = {
        o: getattr(args, f"column_{o}")
        for o in COLUMN_OPTIONS
        if getattr(args, f"column_{o}") is not None
    }
    return PlanOptions(
        spacing=args.spacing,
        camera=args.camera,
        swath=args.swath,
        gsd=args.gsd,
        overlap=args.overlap,
        front_overlap=args.front_overlap,
        images_in_turns=args.images_in_turns,
        nadir_gap=args.nadir_gap,
        method=args.method,
        objective=args.objective,
        angle=args.angle,
        bearing=args.bearing,
        turnaround=args.turnaround,
        altitude=args.altitude,
        speed=args.speed,
        turn_time=args.turn_time,
        turn_radius=args.turn_radius,
        reverse=args.reverse,
        headland=args.headland,
        keep_inside=args.keep_inside,
        layout=args.layout,
        hull_tolerance=args.hull_tolerance,
        decompose=args.decompose,
        sweep=args.sweep,
        force=args.force,
        repair=args.repair,
        columns=columns,
    )


def run(args: argparse.Namespace) -> int:
    options = _options(args)
    result = batch(
        args.fields,
        args.out,
        options,
        layer=args.layer,
        crs=args.crs,
        workers=args.workers,
        scheduler=args.scheduler,
        missions=args.missions,
        mission_format=args.mission_format,
        chunk_size=args.chunk_size,
        progress=False if args.quiet else None,
    )
    summary = {
        "fields": result.total,
        "planned": result.planned,
        "failed": result.failed,
        "skipped": result.skipped,
        "seconds": result.seconds,
        "fields_per_second": result.fields_per_second if result.seconds > 0 else None,
        "outputs": list(result.outputs),
    }
    if args.json:
        print_json(summary)
        return 0
    rate = result.fields_per_second
    print_table(
        [
            ("fields", f"{result.total} ({result.skipped} done before, skipped)"),
            ("planned", f"{result.planned} ok, {result.failed} failed (status 'error')"),
            ("time", f"{result.seconds:.1f} s, {rate:.2f} fields/s"),
            ("written", ", ".join(result.outputs)),
        ]
    )
    return 0
