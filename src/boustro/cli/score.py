"""``boustro score``: the fitness of one transect layout."""

from __future__ import annotations

import argparse
import math
from typing import Any

from ..errors import InvalidParameterError
from ..io import PAPER_SPACING
from ..models.smooth import DEFAULT_SMOOTHING
from ..objectives import SmithFitness
from ..scoring import Score, make_model, score
from ._common import (
    add_polygon_argument,
    concave_to_plan,
    finite_float,
    load_polygon,
    positive_float,
    positive_int,
    print_json,
    print_table,
)

CONVENTIONS = """\
conventions:
  angle   transect direction, degrees counter-clockwise from +x
  offset  signed distance of the transect grid from the polygon's vertex mean, along the
          transects' left normal (-sin angle, cos angle), in the polygon's units; the grid is
          periodic in the spacing, and (angle + 180, -offset) is the same grid as (angle, offset)
  fitness Eq. 1 of the paper, a*mean + b*(1 - std) of the transect lengths in the normalised
          frame (polygon centred on its vertex mean, diameter 1); maximised
"""


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "score",
        help="fitness of one transect layout (angle, offset, spacing)",
        description="Score one boustrophedon layout of a convex polygon with the fitness of "
        "Smith et al. (the paper's Eq. 1), exactly or with the paper's differentiable model.",
        epilog=CONVENTIONS,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_polygon_argument(p)
    add_layout_arguments(p)
    p.add_argument("--angle", type=finite_float, default=0.0, help="transect angle, degrees (0)")
    p.add_argument(
        "--offset", type=finite_float, default=0.0, help="grid offset, polygon units (0)"
    )
    p.set_defaults(func=run)


def add_layout_arguments(p: argparse.ArgumentParser) -> None:
    """Options shared by every command that scores layouts: spacing, model, fitness, output."""
    p.add_argument(
        "--spacing",
        type=positive_float,
        default=None,
        help="transect spacing in the polygon's units (default: 0.5 for the embedded "
        "parallelogram; required with POLYGON)",
    )
    p.add_argument(
        "--model",
        choices=("exact", "paper", "soft"),
        default="exact",
        help="transect-length model: exact chords, the paper's sigmoid integral, or the smooth "
        "closed form (default: exact)",
    )
    p.add_argument(
        "--smoothing",
        type=positive_float,
        default=DEFAULT_SMOOTHING,
        help="soft model smoothing length, a fraction of the polygon's diameter "
        "(default: 1e-4, the softness of the paper's temperature 10000)",
    )
    p.add_argument(
        "--temperature",
        type=positive_float,
        default=1000.0,
        help="paper model temperature (default: 1000)",
    )
    p.add_argument(
        "--points-per-transect",
        type=positive_int,
        default=1000,
        help="paper model trapezoid points per transect (default: 1000)",
    )
    p.add_argument(
        "--clip",
        action="store_true",
        help="the paper's transect window: |position| <= 0.5 and along-transect "
        "range [-0.5, 0.5] of the normalised frame (reproduction only)",
    )
    p.add_argument("-a", type=positive_or_zero, default=0.5, help="weight of the mean (0.5)")
    p.add_argument("-b", type=positive_or_zero, default=0.5, help="weight of 1 - std (0.5)")
    p.add_argument("--json", action="store_true", help="print one JSON object")


def positive_or_zero(text: str) -> float:
    value = finite_float(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text!r}")
    return value


def resolve_spacing(args: argparse.Namespace) -> float:
    if args.spacing is not None:
        return float(args.spacing)
    if args.polygon is None:
        return PAPER_SPACING
    raise InvalidParameterError("--spacing is required with a POLYGON file")


def model_from_args(args: argparse.Namespace):
    return make_model(
        args.model,
        temperature=args.temperature,
        smoothing=args.smoothing,
        points_per_transect=args.points_per_transect,
        clip=args.clip,
    )


def score_to_json(result: Score, args: argparse.Namespace) -> dict[str, Any]:
    out: dict[str, Any] = {
        "fitness": result.fitness,
        "angle_deg": math.degrees(result.angle),
        "offset": result.offset,
        "spacing": result.spacing,
        "model": result.model,
        "n_transects": result.n_transects,
        "total_length": result.total_length,
        "lengths": result.lengths.tolist(),
        "transects": result.layout.segments.tolist(),
        "a": args.a,
        "b": args.b,
    }
    if result.model == "soft":
        out["smoothing"] = args.smoothing
    if result.model == "paper":
        out["temperature"] = args.temperature
        out["points_per_transect"] = args.points_per_transect
    out["clip"] = bool(args.clip)
    return out


def score_rows(result: Score) -> list[tuple[str, str]]:
    return [
        ("angle", f"{math.degrees(result.angle)!r} deg"),
        ("offset", f"{result.offset!r}"),
        ("spacing", f"{result.spacing:.6g}"),
        ("fitness", f"{result.fitness:.6f} ({result.model} model)"),
        ("transects", f"{result.n_transects}"),
        ("total length", f"{result.total_length:.6g}"),
    ]


def run(args: argparse.Namespace) -> int:
    polygon = load_polygon(args.polygon)
    spacing = resolve_spacing(args)
    with concave_to_plan(args.polygon, args.spacing):
        result = score(
            polygon,
            spacing,
            math.radians(args.angle),
            args.offset,
            model=model_from_args(args),
            fitness=SmithFitness(a=args.a, b=args.b),
        )
    if args.json:
        print_json(score_to_json(result, args))
    else:
        print_table(score_rows(result))
    return 0
