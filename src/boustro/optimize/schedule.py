"""Temperature schedules of the guiding model, and a model at another temperature."""

from __future__ import annotations

import dataclasses
import inspect
from dataclasses import dataclass

from ..errors import InvalidParameterError
from ..models import (
    TransectModel,
)
from .problem import _check_positive

__all__ = ["DEFAULT_SCHEDULE", "TemperatureSchedule"]


@dataclass(frozen=True)
class TemperatureSchedule:
    """The guiding model's temperature at each step of gradient descent.

    Constant (``end is None``) or annealed geometrically from ``start`` at the first step to
    ``end`` at the last: ``T_i = start * (end / start) ** (i / (steps - 1))``. The paper
    (Sec. VI) suggests starting low, where the surface is smooth, and raising the temperature
    to refine; ``end < start`` is allowed too.
    """

    start: float
    end: float | None = None

    def __post_init__(self) -> None:
        _check_positive("temperature", self.start)
        if self.end is not None:
            _check_positive("temperature", self.end)

    @classmethod
    def constant(cls, temperature: float) -> TemperatureSchedule:
        return cls(float(temperature))

    @classmethod
    def anneal(cls, start: float, end: float) -> TemperatureSchedule:
        return cls(float(start), float(end))

    def __call__(self, step: int, steps: int) -> float:
        if self.end is None or steps <= 1:
            return self.start
        return self.start * (self.end / self.start) ** (min(step, steps - 1) / (steps - 1))

    def __str__(self) -> str:
        return f"{self.start:g}" if self.end is None else f"{self.start:g}:{self.end:g}"


#: Default schedule of the gradient methods: annealed from 50 to 200 (normalised frame). Below
#: about 30 the double sigmoid of Eq. 4-5 melts the polygon into a nearly flat surface (every
#: fitness near ``b``: no gradient to follow); above about 200, 64 points per transect no longer
#: resolve the transition (see :data:`DEFAULT_GUIDE`).
DEFAULT_SCHEDULE = TemperatureSchedule(50.0, 200.0)


def _as_schedule(
    temperature: float | tuple[float, float] | TemperatureSchedule | None,
) -> TemperatureSchedule | None:
    if temperature is None or isinstance(temperature, TemperatureSchedule):
        return temperature
    if isinstance(temperature, (tuple, list)):
        if len(temperature) != 2:
            raise InvalidParameterError(
                f"a temperature schedule is T or (T0, T1), got {temperature!r}"
            )
        return TemperatureSchedule.anneal(*temperature)
    return TemperatureSchedule.constant(_check_positive("temperature", temperature))


def _with_temperature(model: TransectModel, temperature: float) -> TransectModel:
    """``model`` at another temperature.

    Asks the model, in this order: a ``with_temperature(T)`` method; a dataclass field
    ``temperature`` (:class:`~boustro.models.PaperModel`); a ``from_temperature(T, **settings)``
    class method, given those of its keyword arguments that the model has as attributes
    (e.g. ``clip`` of the smooth closed form, whose smoothing length is ``1 / T``).
    """
    if hasattr(model, "with_temperature"):
        return model.with_temperature(temperature)
    if dataclasses.is_dataclass(model) and any(
        f.name == "temperature" for f in dataclasses.fields(model)
    ):
        return dataclasses.replace(model, temperature=temperature)
    factory = getattr(type(model), "from_temperature", None)
    if callable(factory):
        params = list(inspect.signature(factory).parameters.values())[1:]
        settings = {
            q.name: getattr(model, q.name)
            for q in params
            if q.kind is inspect.Parameter.KEYWORD_ONLY and hasattr(model, q.name)
        }
        return factory(temperature, **settings)
    raise InvalidParameterError(
        f"the {getattr(model, 'name', type(model).__name__)} model has no temperature to "
        "schedule; pass temperature=None"
    )
