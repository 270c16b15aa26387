"""A mission split into sorties: each from home, over whole lanes, and back to home.

The lanes keep the mission's order and direction; only the cut points are chosen. A lane
(with its run-in and run-out, and a pass around a hole from its lane's start to its end) is
never cut. Sortie ``i..j`` flies from home straight to lane ``i``'s first waypoint, along the
mission's path to lane ``j``'s last one, and straight back home. Its length is
``|home - first(i)| + path(i..j) + |last(j) - home|`` and its time ``length / speed`` plus the
turn time of each turn between its lanes. An exact dynamic programme over the cut points
(``O(n^2)`` for ``n`` lanes) finds, among the splits with every sortie within the limits, those
of the fewest sorties and of them the one of least total time (of least total length without a
speed).

Fewest sorties first: each sortie is a landing, a battery swap and a take-off, which the time
model does not count, and a sortie's legs from and to home carry no turns, so with a turn time
splitting a mission further can be "faster" on paper (a turn between two lanes replaced by a
flight home and back): four 100 m lanes 10 m apart, home 52 m from their ends, 10 m/s, 30 s a
turn, fly in one sortie of 143.4 s or in four of 81.8 s in all (tested). The lexicographic
order (count, time) is added sortie by sortie, so the programme stays exact: a best split of
lanes ``0..j`` ends with a best split of ``0..i-1`` for its last cut ``i``.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validate import as_number
from ..errors import InvalidParameterError
from .camera import with_camera
from .flight import Sortie
from .types import Mission

__all__ = ["check_speed", "lane_units", "plan_sorties", "split_mission", "with_home"]


def lane_units(kinds: tuple[str, ...] | list[str]) -> list[tuple[int, int]]:
    """``(first, last)`` waypoint index of each lane: its start (or run-in) to its end (or
    run-out); the waypoints between two lanes are the move that connects them.

    >>> lane_units(("run_in", "start", "end", "run_out", "via", "start", "end"))
    [(0, 3), (5, 6)]
    """
    units = []
    i, n = 0, len(kinds)
    while i < n:
        if kinds[i] != "start":
            i += 1
            continue
        first = i - 1 if i > 0 and kinds[i - 1] == "run_in" else i
        last = next(k for k in range(i + 1, n) if kinds[k] == "end")
        if last + 1 < n and kinds[last + 1] == "run_out":
            last += 1
        units.append((first, last))
        i = last + 1
    return units


def _positive(name: str, value: Any) -> float | None:
    if value is None:
        return None
    v = as_number(name, value)
    if not (math.isfinite(v) and v > 0):
        raise InvalidParameterError(f"{name} must be a finite number > 0, got {value!r}")
    return v


def plan_sorties(
    path: NDArray[np.float64],
    units: list[tuple[int, int]],
    home: NDArray[np.float64],
    *,
    max_time: float | None = None,
    max_distance: float | None = None,
    speed: float | None = None,
    turn_time: float = 0.0,
) -> list[tuple[int, int, float, float | None]]:
    """The split of the fewest sorties, then of least total time (least total length without a
    speed): ``(first lane, last lane, length, time)`` per sortie.

    ``path``: the waypoints in ground metres; ``units``: :func:`lane_units`; ``home``: ground
    metres, same frame. Raises :class:`InvalidParameterError` when a lane alone (home, the lane,
    home) exceeds a limit.
    """
    along = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(path, axis=0).T))])
    first = np.array([a for a, _ in units])
    last = np.array([b for _, b in units])
    out_leg = np.hypot(*(path[first] - home).T)  # home to each lane's first waypoint
    back_leg = np.hypot(*(path[last] - home).T)
    n = len(units)
    best = np.full(n + 1, np.inf)  # least total cost of lanes 0..j-1 in fewest[j] sorties
    best[0] = 0.0
    fewest = np.full(n + 1, np.inf)  # fewest sorties that fly lanes 0..j-1
    fewest[0] = 0.0
    cut = np.zeros(n + 1, dtype=np.int64)
    for j in range(n):
        ii = np.arange(j + 1)  # sorties i..j
        length = out_leg[ii] + (along[last[j]] - along[first[ii]]) + back_leg[j]
        time = None if speed is None else length / speed + (j - ii) * turn_time
        ok = np.ones(j + 1, dtype=bool)
        if max_distance is not None:
            ok &= length <= max_distance
        if max_time is not None and time is not None:
            ok &= time <= max_time
        if not ok[j]:
            what = f"{length[j]:.0f} m" if time is None else f"{time[j]:.0f} s ({length[j]:.0f} m)"
            raise InvalidParameterError(
                f"lane {j + 1} alone takes {what} from home and back, over the sortie limit; "
                "raise the limit or move --home nearer"
            )
        count = np.where(ok, fewest[ii] + 1, np.inf)
        cost = best[ii] + (length if time is None else time)
        cost[count > count.min()] = np.inf  # fewest sorties first, then the cost
        k = int(np.argmin(cost))
        best[j + 1], fewest[j + 1], cut[j + 1] = cost[k], count[k], k
    sorties = []
    j = n
    while j > 0:
        i = int(cut[j])
        total = float(out_leg[i] + along[last[j - 1]] - along[first[i]] + back_leg[j - 1])
        sorties.append(
            (i, j - 1, total, None if speed is None else total / speed + (j - 1 - i) * turn_time)
        )
        j = i
    return sorties[::-1]


def with_home(mission: Mission, home: ArrayLike) -> Mission:
    """``mission`` with its home at ``home`` (the area's coordinates)."""
    proj = mission.projection
    plan_home = proj.point_to_plan(home, "home")  # checked before it is reshaped
    h = np.asarray(home, dtype=np.float64).reshape(2)
    lonlat = None if proj.planar else proj.to_lonlat(plan_home)
    return dataclasses.replace(mission, home=h, home_lonlat=lonlat)


def check_speed(max_time: float | None, speed: float | None) -> None:
    """Raise :class:`InvalidParameterError` for a maximum flight time without a speed."""
    if max_time is not None and speed is None:
        raise InvalidParameterError("a maximum flight time needs the speed (--speed M/S)")


def split_mission(
    mission: Mission,
    *,
    home: ArrayLike | None = None,
    max_time: float | None = None,
    max_distance: float | None = None,
) -> list[Mission]:
    """The mission's sorties (see the module docstring), each a :class:`Mission` named
    ``"<name> sortie k"`` with its :class:`~boustro.mission.flight.Sortie`; ``home`` in the
    area's coordinates (default: the mission's home). ``max_time`` (s) needs the mission's
    speed. Without a limit: the mission, with its home moved."""
    max_time = _positive("max flight time (s)", max_time)
    max_distance = _positive("max distance (m)", max_distance)
    if home is not None:
        mission = with_home(mission, home)
    if max_time is None and max_distance is None:
        return [mission]
    s = mission.stats
    check_speed(max_time, s.speed)
    plan = mission.plan
    path = plan.waypoints / plan.ground_scale
    home_ground = mission.projection.to_plan(mission.home) / plan.ground_scale
    units = lane_units(plan.kinds)
    limits = [f"max flight time {max_time:g} s"] if max_time is not None else []
    limits += [f"max distance {max_distance:g} m"] if max_distance is not None else []
    split = plan_sorties(
        path,
        units,
        home_ground,
        max_time=max_time,
        max_distance=max_distance,
        speed=s.speed,
        turn_time=s.turn_time,
    )
    return [
        _sortie(mission, units, Sortie(k, len(split), (i, j), length, time, ", ".join(limits)))
        for k, (i, j, length, time) in enumerate(split, start=1)
    ]


def _sortie(mission: Mission, units: list[tuple[int, int]], sortie: Sortie) -> Mission:
    """The part of ``mission`` that ``sortie`` flies, as a mission of its own."""
    plan = mission.plan
    a, b = units[sortie.lanes[0]][0], units[sortie.lanes[1]][1] + 1
    lanes = plan.lane[a:b]
    t0, t1 = int(lanes.min()), int(lanes.max()) + 1
    transects = plan.transects[t0:t1]
    path = plan.waypoints[a:b] / plan.ground_scale
    n = sortie.lanes[1] - sortie.lanes[0] + 1
    length = float(np.hypot(*np.diff(path, axis=0).T).sum())
    s = plan.stats
    stats = dataclasses.replace(
        s,
        n_transects=plan.role()[t0:t1].count("lane"),  # lane segments, as the plan's
        n_turns=n - 1,
        transect_length=float(np.hypot(*(transects[:, 1] - transects[:, 0]).T).sum())
        / plan.ground_scale,
        path_length=length,
        duration=None if s.speed is None else length / s.speed + (n - 1) * s.turn_time,
    )

    def cut(x: Any) -> Any:
        return None if x is None else x[t0:t1]

    sub_plan = dataclasses.replace(
        plan,
        positions=plan.positions[t0:t1],
        transects=transects,
        waypoints=plan.waypoints[a:b],
        kinds=plan.kinds[a:b],
        lane=lanes - t0,
        stats=stats,
        transect_angles=cut(plan.transect_angles),
        roles=plan.roles[t0:t1],
        transect_cells=cut(plan.transect_cells),
    )
    out = dataclasses.replace(
        mission,
        name=f"{mission.name} sortie {sortie.index}" if mission.name else f"sortie {sortie.index}",
        plan=sub_plan,
        coverage=None,
        waypoints=mission.waypoints[a:b],
        transects=mission.transects[t0:t1],
        waypoints_lonlat=None
        if mission.waypoints_lonlat is None
        else mission.waypoints_lonlat[a:b],
        transects_lonlat=cut(mission.transects_lonlat),
        sortie=sortie,
    )
    return with_camera(out, mission.camera)
