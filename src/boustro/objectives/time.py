"""Mission time of the flown plan (path / speed + turns x turn time), minimised."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..errors import InvalidParameterError
from .base import BaseObjective
from .registry import register_objective

__all__ = ["MissionTime"]


@register_objective("time")
@dataclass(frozen=True)
class MissionTime(BaseObjective):
    """The time to fly the whole plan: ``path_length / speed + turns * turn_time``; **minimised**.

    It scores a flown plan (coverage-guaranteed lanes, run-ins and run-outs, connecting moves,
    passes around holes), not transect lengths, so only the mission planner optimises it
    (:func:`boustro.plan_area`, ``boustro plan --objective time``: the certified search of
    :func:`boustro.optimize.cover.cover_optimum`). ``speed`` (ground units per second) and
    ``turn_time`` (seconds) default to the plan's own (``plan_area(speed=..., turn_time=...)``).

    >>> MissionTime(speed=5.0, turn_time=10.0).sense
    'min'
    """

    speed: float | None = None
    turn_time: float | None = None
    name: str = "time"
    maximise: bool = False
    needs_chords: bool = False
    needs_plan: bool = True

    def __call__(self, tl: Any) -> Any:
        raise InvalidParameterError(
            "the time objective scores flown plans, not transect lengths: plan with "
            "boustro.plan_area(..., fitness=MissionTime(...)) or 'boustro plan --objective time'"
        )
