"""``boustro optimize``: the best transect angle and offset for a polygon and a spacing."""

from __future__ import annotations

import argparse
import inspect
import io
import logging
import math
import os
import sys
from typing import Any

from .._files import atomic_write
from ..errors import InvalidParameterError
from ..objectives import SmithFitness
from ..optimize import GRID_200, OptimizeResult, TemperatureSchedule, optimize, resolve_method
from ..optimize import METHODS as _REGISTRY
from ..optimize.smith_bb import DEFAULT_TOL
from ..plot import plot_layout
from ..scoring import score
from ._common import (
    add_polygon_argument,
    check_plot_target,
    concave_to_plan,
    load_polygon,
    nonnegative_int,
    positive_float,
    positive_int,
    print_json,
    print_table,
)
from .score import (
    CONVENTIONS,
    add_layout_arguments,
    model_from_args,
    resolve_spacing,
    score_rows,
    score_to_json,
)

log = logging.getLogger("boustro")

#: The method names at import time (compatibility): the parser reads the registry,
#: :data:`boustro.optimize.METHODS`, when it is built, so registered methods are offered too.
METHODS = tuple(_REGISTRY)

EPILOG = (
    CONVENTIONS
    + """
methods:
  grid      exact fitness on an angles x offsets grid (default 180 x 20; --paper-grid: the
            paper's 14 x 14 over [0, 180) degrees x one spacing)
  gradient  gradient ascent through the paper's differentiable model from --starts random
            layouts (picked from 1024 by the exact fitness), then an exact zoom
  hybrid    (default) a 42 x 28 grid, gradient refinement of its --starts best local maxima,
            then an exact zoom; never worse than the grid
  global    the certified global optimum of Eq. 1: branch and bound over the angle, exact in
            the offset; prints upper_bound and gap (<= --tol)
  certified-bb  the same certificate for polygons of hundreds or thousands of vertices:
            branch and bound over (angle, offset) boxes, O(n + lines) per box; gap <= --tol
            (default 1e-4)
  learned   the shipped planner network (trained through the differentiable fitness, see
            'boustro train'); --refine adds its fast exact refinement
  Every method ranks layouts by the EXACT fitness. --model and its settings (--temperature,
  --points-per-transect, --smoothing, --clip) only choose the model that scores the answer in
  the output, as in 'boustro score'; -a and -b weigh the fitness searched and reported.
"""
)


def schedule_type(text: str) -> TemperatureSchedule:
    """``T`` (constant) or ``T0:T1`` (annealed geometrically), every temperature > 0."""
    parts = text.split(":")
    if len(parts) not in (1, 2):
        raise argparse.ArgumentTypeError(f"expected T or T0:T1, got {text!r}")
    try:
        values = [positive_float(part) for part in parts]
    except argparse.ArgumentTypeError:
        raise argparse.ArgumentTypeError(f"expected T or T0:T1 with T > 0, got {text!r}") from None
    return TemperatureSchedule(*values)


#: The paper's SGD momentum, the default of --momentum.
PAPER_MOMENTUM = 0.8


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "optimize",
        help="best transect angle and offset (global, grid, gradient, hybrid or learned search)",
        description="Find the transect angle and grid offset that maximise the fitness of Smith "
        "et al. (the paper's Eq. 1) for a convex polygon and a spacing.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_polygon_argument(p)
    add_layout_arguments(p)
    p.add_argument(
        "--method",
        choices=tuple(_REGISTRY),
        default="hybrid",
        help="search method (default: hybrid)",
    )
    grid = p.add_argument_group("grid (grid, hybrid)")
    grid.add_argument(
        "--angles", type=positive_int, default=None, help="grid angles over [0, 180) degrees"
    )
    grid.add_argument(
        "--offsets", type=positive_int, default=None, help="grid offsets over one spacing"
    )
    grid.add_argument(
        "--paper-grid",
        action="store_true",
        help="the paper's '200-sample' grid: 14 angles x 14 offsets (196)",
    )
    grad = p.add_argument_group("gradient (gradient, hybrid)")
    grad.add_argument(
        "--starts",
        type=positive_int,
        default=None,
        help="layouts descended together (gradient: 8 random; hybrid: the 3 best grid maxima)",
    )
    grad.add_argument(
        "--steps", type=nonnegative_int, default=None, help="most gradient steps (200; hybrid 30)"
    )
    grad.add_argument(
        "--optimizer", choices=("adam", "sgd"), default="adam", help="(default: adam)"
    )
    grad.add_argument(
        "--momentum",
        type=float,
        default=PAPER_MOMENTUM,
        help=f"SGD momentum (default: the paper's {PAPER_MOMENTUM:g})",
    )
    grad.add_argument(
        "--schedule",
        type=schedule_type,
        default=None,
        metavar="T|T0:T1",
        help="temperature of the guiding model: constant T, or annealed geometrically from T0 "
        "to T1 (default 50:200)",
    )
    grad.add_argument(
        "--seed",
        type=nonnegative_int,
        default=0,
        help="seed of the random starts (gradient; default 0)",
    )
    p.add_argument(
        "--refine",
        action="store_true",
        help="learned: refine the network's candidates exactly (offset sweep, vertex events, zoom)",
    )
    p.add_argument(
        "--tol",
        type=positive_float,
        default=None,
        help=(
            "global and certified-bb: the optimality gap to certify (default 1e-6 for "
            f"global, {DEFAULT_TOL:g} for certified-bb)"
        ),
    )
    p.add_argument(
        "--plot",
        metavar="FILE.png",
        default=None,
        help="also draw the polygon and the chosen transects into this image file",
    )
    p.set_defaults(func=run)


def _parameters(method: str) -> set[str]:
    """The keyword parameters of the registered method (``"**"`` if it takes any)."""
    try:
        params = inspect.signature(resolve_method(method)).parameters.values()
    except (TypeError, ValueError):
        return {"**"}
    return {"**" if p.kind is p.VAR_KEYWORD else p.name for p in params}


def _options(args: argparse.Namespace) -> dict[str, Any]:
    """The keyword arguments of the chosen method; warn about options it does not use."""
    method = args.method
    takes = _parameters(method)
    options: dict[str, Any] = {}
    if "progress" in takes or "**" in takes:
        options["progress"] = False if args.quiet else None
    ignored = []
    if args.paper_grid and (args.angles is not None or args.offsets is not None):
        raise InvalidParameterError("--paper-grid fixes the grid: drop --angles and --offsets")
    if method in ("grid", "hybrid"):
        if args.paper_grid:
            options.update(GRID_200)
        if args.angles is not None:
            options["n_angles"] = args.angles
        if args.offsets is not None:
            options["n_offsets"] = args.offsets
    elif args.paper_grid or args.angles is not None or args.offsets is not None:
        ignored.append("--angles/--offsets/--paper-grid")
    if method in ("gradient", "hybrid"):
        if args.starts is not None:
            options["starts" if method == "gradient" else "top_k"] = args.starts
        if args.steps is not None:
            options["steps"] = args.steps
        if args.schedule is not None:
            options["temperature"] = args.schedule
        options["optimizer"] = args.optimizer
        options["momentum"] = args.momentum
        if args.optimizer == "adam" and args.momentum != PAPER_MOMENTUM:
            ignored.append("--momentum (SGD only)")
    else:
        for flag, value, default in (
            ("--starts", args.starts, None),
            ("--steps", args.steps, None),
            ("--schedule", args.schedule, None),
            ("--optimizer", args.optimizer, "adam"),
            ("--momentum", args.momentum, PAPER_MOMENTUM),
        ):
            if value != default:
                ignored.append(flag)
    if "seed" in takes:
        options["seed"] = args.seed
    elif args.seed != 0:
        ignored.append("--seed")
    if method == "global":
        options["tol"] = 1e-6 if args.tol is None else args.tol
    elif method == "certified-bb":
        options["tol"] = DEFAULT_TOL if args.tol is None else args.tol
    elif args.tol is not None:
        ignored.append("--tol")
    if method == "learned":
        options["refine"] = args.refine
    elif args.refine:
        ignored.append("--refine")
    for flag in ignored:
        log.warning("%s is not used by --method %s; ignored", flag, method)
    return options


def _save_plot(path: str, polygon, result, found: OptimizeResult) -> None:
    from matplotlib.figure import Figure  # lazy: matplotlib only when a plot is asked for

    fig = Figure(figsize=(6, 6))
    ax = fig.add_subplot()
    plot_layout(
        polygon,
        result.layout,
        ax=ax,
        title=f"{found.method}: {math.degrees(found.angle):.2f} deg, offset "
        f"{found.offset:.4g}, fitness {found.fitness:.4f}",
    )
    buf = io.BytesIO()  # rendered whole, then written atomically: a failure writes nothing
    ext = os.path.splitext(path)[1].lstrip(".").lower() or "png"
    fig.savefig(buf, format=ext, dpi=150, bbox_inches="tight")
    atomic_write(path, buf.getvalue())


def run(args: argparse.Namespace) -> int:
    polygon = load_polygon(args.polygon)
    spacing = resolve_spacing(args)
    if args.plot is not None:
        check_plot_target(args.plot)
    fitness = SmithFitness(a=args.a, b=args.b)
    model = model_from_args(args)  # validates the scoring model's settings before the search
    with concave_to_plan(args.polygon, args.spacing):
        found = optimize(polygon, spacing, method=args.method, fitness=fitness, **_options(args))
        result = score(polygon, spacing, found.angle, found.offset, model=model, fitness=fitness)
    if args.plot is not None:
        _save_plot(args.plot, polygon, result, found)
    if args.json:
        out = score_to_json(result, args)
        out.update(method=found.method, evaluations=found.evaluations, seconds=found.seconds)
        if found.upper_bound is not None:
            out.update(upper_bound=found.upper_bound, gap=found.gap, bound_model="exact")
            out["certified"] = bool(found.info.get("converged", False))
            if "note" in found.info:
                out["note"] = found.info["note"]
        print_json(out)
    else:
        rows = score_rows(result)
        rows += [
            ("method", found.method),
            ("evaluations", f"{found.evaluations}"),
            ("time", f"{found.seconds:.3f} s"),
        ]
        if found.upper_bound is not None:
            rows += [
                ("upper bound", f"{found.upper_bound:.9f} (exact model, whole polygon)"),
                ("gap", f"{found.gap:.2e} (exact fitness {found.fitness:.9f})"),
            ]
            if not found.info.get("converged", False):
                rows.append(("certified", "no: " + str(found.info.get("note", "not converged"))))
        print_table(rows)
        if args.plot is not None:
            print(f"plot written to {args.plot}", file=sys.stderr)
    return 0
