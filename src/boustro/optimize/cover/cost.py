"""The cost of a flown plan that the certified cover search minimises: length and turns."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ...errors import InvalidParameterError
from .u_turns import UTurns

__all__ = ["COVER_OBJECTIVES", "CoverCost"]

#: Objectives the certified cover search minimises (names as on the command line).
COVER_OBJECTIVES = ("time", "fewest-transects", "shortest-path")


@dataclass(frozen=True)
class CoverCost:
    """``per_length * path + per_turn * turns`` of a flown plan, minimised.

    ``path`` is the length of the whole path in plan units (lanes, run-ins and run-outs,
    connecting moves, passes around holes) and ``turns`` the moves between consecutive passes
    (lanes or hole passes): ``passes - 1``. Mission time is ``per_length = 1 / (speed *
    ground_scale)`` seconds per plan unit and ``per_turn`` = the time of a turn;
    ``turnaround`` is the run-in and run-out beyond each lane end (plan units); ``fixed`` a cost
    every plan pays whatever its layout (e.g. headland passes), part of the lower bounds;
    ``u_turns`` (a vehicle's turn radius, plan units) where every move of every plan is a
    vehicle's U-turn between lanes on distinct lines (the convex planner's plans with a vehicle,
    :mod:`~.u_turns`): the bounds' moves are then at least those turns' floors.

    >>> c = CoverCost.time(speed=5.0, turn_time=10.0)
    >>> c.per_length, c.per_turn, c.name
    (0.2, 10.0, 'time')
    """

    per_length: float
    per_turn: float
    turnaround: float = 0.0
    name: str = "time"
    fixed: float = 0.0
    u_turns: UTurns | None = None

    def __post_init__(self) -> None:
        for label, value in (
            ("per_length", self.per_length),
            ("per_turn", self.per_turn),
            ("turnaround", self.turnaround),
            ("fixed", self.fixed),
        ):
            if not (math.isfinite(value) and value >= 0):
                raise InvalidParameterError(f"{label} must be a finite number >= 0, got {value}")
        if self.per_length == 0 and self.per_turn == 0:
            raise InvalidParameterError("a cost needs per_length > 0 or per_turn > 0")

    @classmethod
    def time(
        cls,
        speed: float,
        turn_time: float = 0.0,
        *,
        turnaround: float = 0.0,
        ground_scale: float = 1.0,
    ) -> CoverCost:
        """Mission time in seconds: ``path / speed + turns * turn_time`` (``speed`` in ground
        units per second, ``ground_scale`` plan units per ground unit)."""
        if not (math.isfinite(speed) and speed > 0):
            raise InvalidParameterError(f"the time objective needs a speed > 0, got {speed}")
        return cls(1.0 / (speed * ground_scale), float(turn_time), float(turnaround), "time")

    @classmethod
    def fewest_turns(cls, *, turnaround: float = 0.0) -> CoverCost:
        """The number of turns (passes - 1): fewest lanes and hole passes."""
        return cls(0.0, 1.0, float(turnaround), "fewest-transects")

    @classmethod
    def path_length(cls, *, turnaround: float = 0.0, ground_scale: float = 1.0) -> CoverCost:
        """The length of the path in ground units."""
        return cls(1.0 / ground_scale, 0.0, float(turnaround), "shortest-path")

    def of(self, path_length: float, turns: int) -> float:
        """The cost of a plan of ``path_length`` (plan units) and ``turns``."""
        return self.per_length * float(path_length) + self.per_turn * int(turns)
