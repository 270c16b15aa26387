"""Argument types and output helpers shared by the subcommands."""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any

from ..geometry import Polygon
from ..io import PAPER_PARALLELOGRAM, read_polygon

__all__ = [
    "add_polygon_argument",
    "finite_float",
    "load_polygon",
    "positive_float",
    "positive_int",
    "print_json",
    "print_table",
]


def finite_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def positive_float(text: str) -> float:
    value = finite_float(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}")
    return value


def positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a whole number > 0, got {text!r}")
    return value


def add_polygon_argument(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "polygon",
        nargs="?",
        metavar="POLYGON",
        help="polygon file: a JSON list of [x, y] pairs, or GeoJSON (Polygon, Feature, "
        "FeatureCollection: first polygon); coordinates taken as planar. Default: the paper's "
        "parallelogram (8,4), (8,10), (4,8), (4,2)",
    )


def load_polygon(path: str | None) -> Polygon:
    return Polygon(PAPER_PARALLELOGRAM) if path is None else read_polygon(path)


def print_json(obj: Any) -> None:
    json.dump(obj, sys.stdout, indent=2, allow_nan=False)
    sys.stdout.write("\n")


def print_table(rows: list[tuple[str, str]]) -> None:
    width = max(len(k) for k, _ in rows)
    for key, value in rows:
        print(f"{key:<{width}}  {value}")
