"""The options of every field of a batch: those of ``boustro plan``, and per-field values.

:class:`PlanOptions` holds what ``boustro plan`` takes (spacing or a sensor, optimiser,
objective, fixed angle or bearing, path and vehicle settings) as plain values, so that it
travels to worker processes and Dask workers as it is and is stored with the output (a resumed
run must use the same). ``columns`` maps an option to an attribute column of the input: each
field then takes that option from its own row (``--spacing-column sp``). :meth:`for_field`
gives one field's options, :meth:`plan_kwargs` the arguments of
:func:`boustro.mission.plan_area`.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace
from typing import Any

from ..errors import InvalidParameterError
from ..mission.defaults import DEFAULT_HULL_TOLERANCE
from ..objectives import get_objective
from ..sensors import Camera, Swath

__all__ = ["COLUMN_OPTIONS", "PlanOptions"]

#: The options a field can take from an attribute column, and the range each must lie in:
#: ``">0"`` positive, ``">=0"`` non-negative, ``"%"`` a percentage in [0, 100), ``""`` any
#: finite number.
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
}


@dataclass(frozen=True)
class PlanOptions:
    """What ``boustro plan`` takes, for every field of a batch (angles in degrees, as on the
    command line; ``camera`` is ``(sensor mm, focal mm, image px)``; see ``boustro plan
    --help``)."""

    spacing: float | None = None
    camera: tuple[float, float, float] | None = None
    swath: float | None = None
    gsd: float | None = None
    overlap: float | None = None
    nadir_gap: float = 0.0
    method: str | None = None
    objective: str | None = None  # plan_area's default: mission time with a speed, else Eq. 1
    angle: float | None = None
    bearing: float | None = None
    turnaround: float = 0.0
    altitude: float | None = None
    speed: float | None = None
    turn_time: float = 0.0
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

    def settings(self) -> dict[str, Any]:
        """Plain JSON of the options (stored with the output)."""
        out = asdict(self)
        out["camera"] = None if self.camera is None else list(self.camera)
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
        if self.gsd is not None and self.camera is None:
            raise InvalidParameterError("--gsd needs --camera")
        if self.nadir_gap and self.swath is None:
            raise InvalidParameterError("--nadir-gap needs --swath")
        if self.camera is not None:
            if self.gsd is not None and self.altitude is not None:
                raise InvalidParameterError("give the camera's --altitude or its --gsd, not both")
            overlap = 70.0 if self.overlap is None else self.overlap
            sw, f, px = self.camera
            camera = dict(altitude=self.altitude, gsd=self.gsd, side_overlap=overlap / 100)
            return Camera(sw, f, px, **camera)  # type: ignore[arg-type]  # as boustro plan does
        if self.swath is not None:
            overlap = 0.0 if self.overlap is None else self.overlap
            return Swath(self.swath, overlap / 100, self.nadir_gap)
        if self.overlap is not None:
            raise InvalidParameterError("--overlap needs --camera or --swath")
        if self.spacing is not None:
            return self.spacing
        raise InvalidParameterError(
            "give the spacing: --spacing METRES, --camera ... or --swath ..."
        )

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
            progress=False,
        )


def _column_value(option: str, column: str, value: Any) -> float:
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
    )
    if bad or isinstance(value, bool):
        wanted = {">0": "> 0", ">=0": ">= 0", "%": "in [0, 100)", "": "finite"}[rule]
        raise InvalidParameterError(f"{where}: expected a number {wanted}, got {value!r}")
    return number
