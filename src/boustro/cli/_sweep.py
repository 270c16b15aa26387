"""``--sweep`` where it can change nothing: one error with ``--no-decompose``, a note on a plan
of one grid (``boustro plan``; ``boustro batch`` takes the error)."""

from __future__ import annotations

import argparse
import dataclasses
import sys

from ..errors import InvalidParameterError
from ..mission import Mission

__all__ = ["check_sweep", "sweep_noted"]


def check_sweep(args: argparse.Namespace) -> None:
    """``--sweep`` with ``--no-decompose`` (which plans one grid: the sweep could change
    nothing): one error before any work."""
    if args.sweep is not None and args.decompose is False:
        raise InvalidParameterError(
            "--sweep sets the decomposition's direction; --no-decompose plans one grid, so it "
            "would change nothing: leave one of them out"
        )


def sweep_noted(args: argparse.Namespace, mission: Mission) -> Mission:
    """With ``--sweep``, a plan of one cell (a convex area; the decomposition along the sweep
    promised no fewer turns than one grid, and ``--decompose`` was not given) says that the
    sweep changed nothing: a note (``notes`` in ``--json`` for a concave area, the table's
    notes) and one line on stderr."""
    if args.sweep is None or mission.plan.stats.n_cells > 1:
        return mission
    why = (
        "the area is convex or planned on its convex hull, see --hull-tolerance"
        if mission.plan.region is None or mission.plan.region.is_convex
        else "the decomposition along it promised no fewer turns than one grid; --decompose "
        "plans its cells"
        if args.decompose is None
        else "the decomposition along it gave one cell"
    )
    note = f"--sweep {args.sweep:g} changed nothing: the area is planned as one grid ({why})"
    print(f"boustro: {note}", file=sys.stderr)
    plan = dataclasses.replace(mission.plan, notes=(*mission.plan.notes, note))
    return dataclasses.replace(mission, plan=plan)
