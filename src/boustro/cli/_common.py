"""Argument types and output helpers shared by the subcommands."""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from ..errors import InvalidParameterError, NonConvexPolygonError
from ..geometry import Polygon
from ..io import PAPER_PARALLELOGRAM, read_polygon

__all__ = [
    "add_polygon_argument",
    "check_not_input",
    "check_output_path",
    "check_plot_target",
    "concave_to_plan",
    "finite_float",
    "load_polygon",
    "nonnegative_int",
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


def nonnegative_int(text: str) -> int:
    """A whole number >= 0 (a random seed, a count that may be 0)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 0, got {text!r}")
    return value


def check_plot_target(path: str | os.PathLike[str], option: str = "--plot") -> None:
    """Fail before any work if the plot cannot be written: no matplotlib, an unknown image
    format, a missing folder, or a folder in the file's place."""
    try:
        from matplotlib.figure import Figure
    except ImportError:
        raise InvalidParameterError(
            f"{option} needs matplotlib: pip install 'boustro[plot]'"
        ) from None
    name = os.fspath(path)
    suffix = name.rsplit(".", 1)[-1].lower() if "." in os.path.basename(name) else ""
    supported = Figure().canvas.get_supported_filetypes()
    if suffix not in supported:
        raise InvalidParameterError(
            f"{option} {name}: unknown image format {suffix!r}; expected a file name ending in "
            f"one of {', '.join('.' + k for k in sorted(supported))}"
        )
    check_output_path(name, option)


def check_output_path(path: str | os.PathLike[str], option: str) -> None:
    """Fail before any work if ``path`` cannot be a file: its folder is missing, or it is a
    folder itself."""
    name = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(name))
    if os.path.isdir(name):
        raise InvalidParameterError(f"{option} {name}: is a folder; give a file name")
    if not os.path.isdir(folder):
        raise InvalidParameterError(f"{option} {name}: no such folder {folder}")


def check_not_input(path: str | os.PathLike[str], option: str, area: str | None) -> None:
    """Fail before anything is written if ``path`` is the input file ``area`` itself (the
    file's field boundaries would be replaced by the mission: ``plan f.geojson --out
    f.geojson``)."""
    if area is None or not os.path.exists(area):
        return
    name = os.fspath(path)
    same = os.path.samefile(name, area) if os.path.exists(name) else False
    if same or os.path.realpath(name) == os.path.realpath(area):
        raise InvalidParameterError(
            f"{option} {name}: is the area file itself; writing it would replace the area: "
            "give another file name"
        )


def add_polygon_argument(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "polygon",
        nargs="?",
        metavar="POLYGON",
        help="polygon file: a JSON list of [x, y] pairs, or GeoJSON (Polygon, Feature, "
        "FeatureCollection: first polygon); coordinates taken as planar. Default: the paper's "
        "parallelogram (8,4), (8,10), (4,8), (4,2)",
    )


@contextmanager
def concave_to_plan(path: str | None, spacing: float | None) -> Iterator[None]:
    """Add to a concave polygon's refusal (the models of ``score`` and ``optimize`` need a
    convex one) the command that plans it: ``boustro plan``, with the file's coordinates kept
    planar."""
    try:
        yield
    except NonConvexPolygonError as exc:
        raise NonConvexPolygonError(
            f"{exc}; concave areas are planned by boustro plan: "
            f"boustro plan {path or 'FILE'} --crs planar --spacing "
            f"{'S' if spacing is None else format(spacing, 'g')}"
        ) from None


def load_polygon(path: str | None) -> Polygon:
    return Polygon(PAPER_PARALLELOGRAM) if path is None else read_polygon(path)


def print_json(obj: Any) -> None:
    """Print ``obj`` as strict JSON, all at once: a result that is not a finite number (an
    overflow) is an error, never half a document or a bare ``NaN``."""
    try:
        text = json.dumps(obj, indent=2, allow_nan=False)
    except ValueError:
        raise InvalidParameterError(
            "a result is not a finite number (inf or nan: an overflow in the inputs' range?); "
            "no JSON written"
        ) from None
    sys.stdout.write(text + "\n")


def print_table(rows: list[tuple[str, str]]) -> None:
    width = max(len(k) for k, _ in rows)
    for key, value in rows:
        print(f"{key:<{width}}  {value}")
