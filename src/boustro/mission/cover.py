"""Step 2 for plan-level objectives (mission time, fewest turns): the certified cover search
with the real planner as its upper bound (:func:`boustro.optimize.cover.cover_optimum`)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import Any

from ..errors import InvalidParameterError
from ..geometry import Polygon
from ..geometry.region import Region
from ..objectives import FewestTransects, MissionTime
from ..optimize import OptimizeResult
from ..optimize.cover import CoverCost, cover_optimum
from ..optimize.cover.plans import rules_out
from ..optimize.cover.u_turns import CONVEX_MAX_LINES, UTurns
from ..plan import Plan, build_plan, coverage
from ..plan.region import BLOCKED_NOTE, OUTSIDE_NOTE, plan_region
from ..plan.region_floor import screen_floor
from ..plan.types import Layout
from .project import Frame
from .steps import Planned, _path_options

__all__ = ["cover_cost", "flown_cost", "plan_cover"]


def cover_cost(
    fitness: Any, frame: Frame, speed: float | None, turn_time: float, turnaround: float
) -> CoverCost | None:
    """The :class:`CoverCost` of a plan-level objective, or ``None`` for the others: mission
    time (:class:`MissionTime`, its speed and turn time default to the plan's), and fewest
    transects on a concave area or one with holes (fewest lanes and hole passes)."""
    scale = frame.proj.scale_max
    if isinstance(fitness, MissionTime):
        v = fitness.speed if fitness.speed is not None else speed
        if v is None:
            raise InvalidParameterError(
                "the time objective needs a speed (--speed M/S, or plan_area(speed=...))"
            )
        tt = fitness.turn_time if fitness.turn_time is not None else turn_time
        return CoverCost.time(
            float(v), float(tt), turnaround=turnaround * scale, ground_scale=frame.proj.scale
        )
    if isinstance(fitness, FewestTransects) and frame.region is not None:
        return CoverCost.fewest_turns(turnaround=turnaround * scale)
    return None


def _planner(
    frame: Frame, layout: str, options: dict[str, Any], keep_inside: bool = False
) -> Callable[..., Plan]:
    """The plan of one layout, as the final plan is built (convex or region planner; with
    ``keep_inside`` the region planner over the area itself, not its hull)."""
    s_plan = frame.sensor.spacing * frame.proj.scale_min
    lay: Layout = "chords" if layout == "chords" else "guaranteed"

    if frame.region is None and not keep_inside:

        def convex(angle: float, offset: float) -> Plan:
            plan = build_plan(
                frame.poly, s_plan, angle, offset, layout=lay, start=frame.start, **options
            )
            if frame.given_start:
                return plan
            # no start given: the corner of the first lane's other end flips the turns' sides
            other = build_plan(
                frame.poly, s_plan, angle, offset, layout=lay,
                start=plan.waypoints[_first_end(plan)], **options,
            )  # fmt: skip
            return other if _cost_key(other) < _cost_key(plan) else plan

        return convex

    area, kw = _region_call(frame, layout, options, keep_inside)

    def region(angle: float, offset: float) -> Plan:
        return plan_region(area, s_plan, angle=angle, offset=offset, **kw)

    return region


def _region_call(
    frame: Frame, layout: str, options: dict[str, Any], keep_inside: bool
) -> tuple[Polygon | Region, dict[str, Any]]:
    """The area and the keywords (but the angle and offset) of a layout's region plan."""
    lay: Layout = "chords" if layout == "chords" else "guaranteed"
    start = frame.start if frame.given_start else None
    kw = dict(decompose_area=False, layout=lay, start=start, keep_inside=keep_inside, **options)
    return _area(frame, keep_inside), kw


def _screen(
    frame: Frame, layout: str, options: dict[str, Any], keep_inside: bool, cost: CoverCost
) -> Callable[..., float] | None:
    """A floor of :func:`flown_cost` of a ``keep_inside`` layout's plan (not finished),
    cheaper than the plan (:func:`~boustro.plan.region_floor.screen_floor`: its lanes and
    passes, a floor of its moves; the lanes alone where that already rules it out against
    ``best``), for the search's screen; ``None`` without ``keep_inside`` or with the chords
    layout."""
    if not keep_inside or layout == "chords":
        return None
    s_plan = frame.sensor.spacing * frame.proj.scale_min
    area, kw = _region_call(frame, layout, options, keep_inside)

    def screen(angle: float, offset: float, best: float = math.inf) -> float:
        beyond = lambda floor: rules_out(floor, best)  # noqa: E731
        return screen_floor(area, s_plan, cost.of, beyond, angle=angle, offset=offset, **kw)

    return screen


def _area(frame: Frame, keep_inside: bool) -> Polygon | Region:
    """What the plans cover: the area (a region), or the convex polygon planned (the hull of a
    nearly convex area, unless ``keep_inside``)."""
    if frame.region is not None:
        return frame.region
    return Region(frame.surveyed) if keep_inside else frame.poly


def flown_cost(
    cost: CoverCost, plan: Plan, frame: Frame, finish: Callable[[Plan], Plan] | None = None
) -> float:
    """``cost`` of what is flown: ``finish(plan)`` (headland passes, the vehicle's turns) where
    given; its statistics are in ground units, the cost in the plan frame's."""
    st = (plan if finish is None else finish(plan)).stats
    return cost.of(st.path_length * frame.proj.scale, st.n_turns)


def _first_end(plan: Plan) -> int:
    kinds = list(plan.kinds)
    return kinds.index("end") if "end" in kinds else len(kinds) - 1


def _cost_key(plan: Plan) -> tuple[float, int]:
    return (plan.stats.path_length, plan.stats.n_turns)


#: A plan's notes that void its certificate: a move flown straight through a hole or out of the
#: area (the bound's premise), or a keep-inside path that leaves the area (never seen).
LEFT_NOTES = (BLOCKED_NOTE, OUTSIDE_NOTE)


#: How far from the area a plan's path may lie, in lanes' reach plus run-ins (a factor above
#: 1): a lane within ``reach`` of the area (it spans its band's projection), a run-in
#: ``turnaround`` beyond its lane, a straight connecting move within ``max(reach, turnaround)``
#: at points ``1/16`` of that apart (:meth:`~boustro.plan.routing.Router.path`: within
#: ``1 + 1/32`` of it between them), a routed one inside the area or, where shorter, through
#: the shell grown by that allowance with every segment passing the same straight test
#: (:mod:`boustro.plan.route_grown`); a move the router found no way for voids the
#: certificate (:data:`LEFT_NOTES`).
OUTSIDE_FACTOR = 1.0 + 1.0 / 16


def _outside(options: dict[str, Any], keep_inside: bool, finish: Any) -> float | None:
    """How far from the area any point of a plan lies (:data:`OUTSIDE_FACTOR`), for the
    search's walls outside the shell; ``None`` with ``finish`` (a vehicle's turns may reach
    farther) or ``keep_inside`` (no 1-tree)."""
    if finish is not None or keep_inside:
        return None
    return OUTSIDE_FACTOR * (float(options["reach"]) + float(options["turnaround"]))


def _uncertified(optimum: OptimizeResult, why: str) -> OptimizeResult:
    """The search's result without its certificate, saying ``why``: the chords layout's
    bound counts coverage-guaranteed lanes, which its lanes (shorter, sometimes fewer) can
    undercut; a plan with a move the router found no way for inside the area flies straight
    through a hole, which the bound's walls (and its premise) rule out."""
    info = {k: v for k, v in optimum.info.items() if k != "lower_bound"}
    info.update(certified=False, gap=None, uncertified=why)
    return dataclasses.replace(optimum, info=info)


def plan_cover(
    frame: Frame,
    cost: CoverCost,
    *,
    layout: str,
    turnaround: float,
    speed: float | None,
    turn_time: float,
    check_coverage: bool,
    angle: float | None = None,
    finish: Callable[[Plan], Plan] | None = None,
    boustrophedon: bool | None = None,
    keep_inside: bool = False,
    u_turns: UTurns | None = None,
) -> Planned:
    """The plan of the layout with the least ``cost``, certified by
    :func:`~boustro.optimize.cover.cover_optimum` (over every angle, or at ``angle``).

    ``finish`` turns a plan into what is flown (headland passes, the vehicle's turns): the
    costs are of its result; the bound stays valid, since it adds to the path (a turn is never
    shorter than the straight move it replaces) and no turns; the headland passes' length, the
    same for every layout, joins the bound as a fixed cost. ``boustrophedon=False`` drops the
    bound's boustrophedon moves (a vehicle may fly every other lane); the plan returned is not
    finished. ``u_turns`` (ground units): ``finish`` flies every move of the convex planner's
    plans as the vehicle's U-turn (no headland passes, no field the turns must keep inside); the
    bound then charges those turns' floors (:mod:`~boustro.optimize.cover.u_turns`), for the
    convex planner only (a region plan's moves are not all U-turns)."""
    options = _path_options(frame, turnaround, speed, turn_time)
    planner = _planner(frame, layout, options, keep_inside)

    def evaluate(a: float, d: float) -> float:
        return flown_cost(cost, planner(a, d), frame, finish)

    s_plan = frame.sensor.spacing * frame.proj.scale_min
    target = _area(frame, keep_inside)
    bound_cost = cost  # what the lower bounds count: the headland passes as a fixed length
    if finish is not None:
        passes = finish(planner(0.0, 0.0)).stats.headland_length * frame.proj.scale
        bound_cost = dataclasses.replace(cost, fixed=cost.fixed + cost.per_length * passes)
    if u_turns is not None and frame.region is None and not keep_inside:
        turns = dataclasses.replace(
            u_turns, radius=u_turns.radius * frame.proj.scale, max_lines=CONVEX_MAX_LINES
        )
        bound_cost = dataclasses.replace(bound_cost, u_turns=turns)
    if boustrophedon is None:
        boustrophedon = frame.region is None
    optimum = cover_optimum(
        target,
        s_plan,
        bound_cost,
        evaluate,
        reach=frame.sensor.reach * frame.proj.scale_min,
        angle=angle,
        boustrophedon=boustrophedon,
        keep_inside=keep_inside,
        screen=None if finish is not None else _screen(frame, layout, options, keep_inside, cost),
        outside=_outside(options, keep_inside, finish),
    )
    if layout == "chords":
        optimum = _uncertified(optimum, "the chords layout has no certificate")
    plan = planner(optimum.angle, optimum.offset)
    if optimum.info.get("certified") and any(n.startswith(LEFT_NOTES) for n in plan.notes):
        optimum = _uncertified(optimum, "a move of the plan crosses a hole or leaves the area")
    if plan.cells:  # the one cell carries the certificate
        cells = tuple(
            dataclasses.replace(c, fitness=optimum.fitness, optimum=optimum) for c in plan.cells
        )
        plan = dataclasses.replace(plan, cells=cells)
    surveyed = frame.surveyed if frame.region is None else frame.region  # not the hull
    cov = coverage(plan, surveyed) if check_coverage else None
    return Planned(plan, optimum, cov)
