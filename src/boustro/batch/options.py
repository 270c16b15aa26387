"""The options of every field of a batch: those of ``boustro plan``, and per-field values.

:class:`PlanOptions` holds what ``boustro plan`` takes (spacing or a sensor, optimiser,
objective, fixed angle or bearing, path and vehicle settings) as plain values, so that it
travels to worker processes and Dask workers as it is and is stored with the output (a resumed
run must use the same). ``columns`` maps an option to an attribute column of the input: each
field then takes that option from its own row (``--spacing-column sp``). :meth:`for_field`
gives one field's options, :meth:`plan_kwargs` the arguments of
:func:`boustro.mission.plan_area`.

The spacing (a number, a camera, a swath) and the vehicle are built by
:func:`boustro.mission.options.sensor_of` and :func:`~boustro.mission.options.vehicle_of`, as
``boustro plan`` builds them from its arguments.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import asdict, dataclass, field, fields, replace
from typing import Any

from ..errors import InvalidParameterError
from ..mission.defaults import DEFAULT_HULL_TOLERANCE
from ..mission.options import check_turn_time, sensor_of, vehicle_of
from ..objectives import get_objective
from ..vehicle import Vehicle

__all__ = ["COLUMN_OPTIONS", "PlanOptions"]

#: The options a field can take from an attribute column, and the range each must lie in:
#: ``">0"`` positive, ``">=0"`` non-negative, ``"%"`` a percentage in [0, 100), ``"n"`` a
#: whole number >= 0, ``""`` any finite number.
COLUMN_OPTIONS = {
    "spacing": ">0",
    "swath": ">0",
    "gsd": ">0",
    "overlap": "%",
    "altitude": "",
    "speed": ">0",
    "turn_time": ">=0",
    "turnaround": ">=0",
    "angle": "",
    "bearing": "",
    "hull_tolerance": ">=0",
    "sweep": "",
    "front_overlap": "%",
    "turn_radius": ">=0",
    "headland": "n",
}


#: Options added after outputs were first written (see :meth:`PlanOptions.settings`).
_ADDED = ("front_overlap", "images_in_turns", "turn_radius", "reverse", "headland", "keep_inside")


@dataclass(frozen=True)
class PlanOptions:
    """What ``boustro plan`` takes, for every field of a batch (angles in degrees, as on the
    command line; ``camera`` is ``(sensor mm, focal mm, image px[, image height px])``; see
    ``boustro plan --help``)."""

    spacing: float | None = None
    camera: tuple[float, ...] | None = None
    swath: float | None = None
    gsd: float | None = None
    overlap: float | None = None
    front_overlap: float | None = None
    images_in_turns: bool = False
    nadir_gap: float = 0.0
    method: str | None = None
    objective: str | None = None  # plan_area's default: mission time with a speed, else Eq. 1
    angle: float | None = None
    bearing: float | None = None
    turnaround: float = 0.0
    altitude: float | None = None
    speed: float | None = None
    turn_time: float = 0.0
    turn_radius: float | None = None
    reverse: bool = False
    headland: int = 0
    keep_inside: bool = False
    layout: str = "guaranteed"
    hull_tolerance: float = DEFAULT_HULL_TOLERANCE
    decompose: bool | None = None
    sweep: float | None = None
    force: bool = False
    repair: bool = False
    columns: dict[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        unknown = sorted(set(self.columns) - set(COLUMN_OPTIONS))
        if unknown:
            raise InvalidParameterError(
                f"no per-field column for {', '.join(unknown)}; columns can give "
                f"{', '.join(COLUMN_OPTIONS)}"
            )
        if self.objective is not None:
            get_objective(self.objective)  # an unknown objective: one error before any field
        if self.camera is not None:
            camera = tuple(self.camera)
            if len(camera) == 4 and camera[3] is None:
                camera = camera[:3]  # the command line's "no image height"
            if len(camera) not in (3, 4):
                raise InvalidParameterError(
                    "camera: expected (sensor mm, focal mm, image px[, image height px]), got "
                    f"{self.camera!r}"
                )
            object.__setattr__(self, "camera", camera)
        if isinstance(self.headland, bool) or not isinstance(self.headland, numbers.Integral):
            raise InvalidParameterError(f"headland: expected a whole number, got {self.headland!r}")
        object.__setattr__(self, "headland", int(self.headland))
        if self.headland < 0:
            raise InvalidParameterError(f"headland must be >= 0, got {self.headland}")

    def check(self) -> None:
        """Raise the error that every field would have for the options as a whole (no
        spacing, ``--reverse`` without a radius, ...), before any field is planned; per-field
        columns are checked with a placeholder value."""
        one = self.for_field({c: 1.0 for c in self.columns.values()})
        one.spacing_arg()
        one.vehicle()
        check_turn_time(one.speed, one.turn_time)  # a speed column gives every field a speed

    def settings(self) -> dict[str, Any]:
        """Plain JSON of the options (stored with the output). The options added since the
        first version are left out at their defaults, so that an output of that version is
        resumed by this one (the same settings)."""
        out = asdict(self)
        out["camera"] = None if self.camera is None else list(self.camera)
        for name in _ADDED:
            if out[name] == _DEFAULTS[name]:
                del out[name]
        return out

    def for_field(self, values: dict[str, Any]) -> PlanOptions:
        """These options with the values of this field's columns (``{column: value}``).

        Raises:
            InvalidParameterError: a column's value is missing or out of its option's range.
        """
        changes: dict[str, Any] = {}
        for option, column in self.columns.items():
            changes[option] = _column_value(option, column, values.get(column))
        return replace(self, columns={}, **changes) if changes else self

    def spacing_arg(self) -> Any:
        """The spacing of :func:`~boustro.mission.plan_area`: metres, a Camera or a Swath."""
        return sensor_of(self)

    def vehicle(self) -> Vehicle | None:
        """The vehicle of :func:`~boustro.mission.plan_area` (``None`` without a radius)."""
        return vehicle_of(self)

    def plan_kwargs(self) -> dict[str, Any]:
        """The keyword arguments of :func:`boustro.mission.plan_area` besides the spacing."""
        return dict(
            method=self.method,
            fitness=None if self.objective is None else get_objective(self.objective),
            turnaround=self.turnaround,
            speed=self.speed,
            turn_time=self.turn_time,
            altitude=self.altitude,
            hull_tolerance=self.hull_tolerance,
            layout=self.layout,
            decompose=self.decompose,
            sweep=self.sweep,
            angle=None if self.angle is None else math.radians(self.angle),
            bearing=self.bearing,
            force=self.force,
            keep_inside=self.keep_inside,
            vehicle=self.vehicle(),
            headland=self.headland,
            progress=False,
        )


def _column_value(option: str, column: str, value: Any) -> float | int:
    where = f"column {column!r} ({option})"
    if value is None or (isinstance(value, str) and not value.strip()):
        raise InvalidParameterError(f"{where} is empty for this field")
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{where}: expected a number, got {value!r}") from None
    rule = COLUMN_OPTIONS[option]
    bad = (
        not math.isfinite(number)
        or (rule == ">0" and number <= 0)
        or (rule == ">=0" and number < 0)
        or (rule == "%" and not 0 <= number < 100)
        or (rule == "n" and not (number >= 0 and number.is_integer()))
    )
    if bad or isinstance(value, bool):
        wanted = {">0": "> 0", ">=0": ">= 0", "%": "in [0, 100)", "n": "a whole number >= 0",
                  "": "finite"}[rule]  # fmt: skip
        what = wanted if rule == "n" else f"a number {wanted}"
        raise InvalidParameterError(f"{where}: expected {what}, got {value!r}")
    return int(number) if rule == "n" else number


_DEFAULTS = {f.name: f.default for f in fields(PlanOptions)}
