"""The vehicle: speed, turn radius, time per turn, whether it may reverse (:class:`Vehicle`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from .._validate import as_number
from ..errors import InvalidParameterError

__all__ = ["Vehicle"]


def _nonnegative(name: str, value: float) -> float:
    v = as_number(name, value)
    if not math.isfinite(v) or v < 0:
        raise InvalidParameterError(f"{name} must be a finite number >= 0, got {value!r}")
    return v


@dataclass(frozen=True)
class Vehicle:
    """What the vehicle can execute.

    Attributes:
        speed: ground speed, m/s, for the duration (``None``: no duration).
        turn_radius: the smallest turning radius, metres (0: turns on the spot, the straight
            connecting moves of a plan without a vehicle).
        turn_time: seconds added per turn (on top of the time to drive the turn's curve).
        reverse: whether it may drive backwards (Reeds-Shepp turns, e.g. a tractor that
            reverses) or not (Dubins turns: fixed-wing drones, boats).

    Example:
        >>> Vehicle(speed=3.0, turn_radius=6.0).reverse
        False
    """

    speed: float | None = None
    turn_radius: float = 0.0
    turn_time: float = 0.0
    reverse: bool = False

    def __post_init__(self) -> None:
        if self.speed is not None:
            speed = as_number("speed", self.speed)
            if not math.isfinite(speed) or speed <= 0:
                raise InvalidParameterError(f"speed must be a finite number > 0, got {speed!r}")
            object.__setattr__(self, "speed", speed)
        object.__setattr__(self, "turn_radius", _nonnegative("turn radius", self.turn_radius))
        object.__setattr__(self, "turn_time", _nonnegative("turn time", self.turn_time))
        if not isinstance(self.reverse, bool):
            raise InvalidParameterError(f"reverse must be True or False, got {self.reverse!r}")

    @property
    def kind(self) -> str:
        """The turns it drives: ``"straight"`` (no radius), ``"dubins"`` or ``"reeds-shepp"``."""
        if self.turn_radius == 0:
            return "straight"
        return "reeds-shepp" if self.reverse else "dubins"
