"""The spacing and the vehicle of ``boustro plan``'s options, built one way for every caller.

:func:`sensor_of` and :func:`vehicle_of` take any object with the attributes of those options
(``boustro plan``'s argparse namespace, or a :class:`boustro.batch.PlanOptions`), check that
they go together, and build the spacing (metres, a :class:`~boustro.sensors.Camera` or a
:class:`~boustro.sensors.Swath`) and the :class:`~boustro.vehicle.Vehicle` that
:func:`boustro.mission.plan_area` takes: ``boustro plan`` and ``boustro batch`` share them, so
the two commands accept the same combinations with the same messages. :func:`check_turn_time`
is the rule of a turn time without a speed for ``plan``, ``batch`` and the page's API alike.
"""

from __future__ import annotations

from typing import Any

from ..errors import InvalidParameterError
from ..sensors import Camera, Swath
from ..vehicle import Vehicle

__all__ = ["check_turn_time", "sensor_of", "vehicle_of"]


def sensor_of(o: Any, default: float | None = None) -> Any:
    """The spacing ``o`` gives (``o.spacing``, ``o.camera``, ``o.swath`` with ``o.gsd``,
    ``o.altitude``, ``o.overlap``, ``o.front_overlap``, ``o.images_in_turns``,
    ``o.nadir_gap``): metres, a :class:`Camera` or a :class:`Swath`; ``default`` metres when
    none is given.

    Raises:
        InvalidParameterError: no spacing, or options that do not go together.
    """
    if o.gsd is not None and o.camera is None:
        raise InvalidParameterError("--gsd needs --camera")
    if o.nadir_gap and o.swath is None:
        raise InvalidParameterError("--nadir-gap needs --swath")
    if o.camera is not None or o.front_overlap is not None or o.images_in_turns:
        return _camera(o)
    if o.swath is not None:
        overlap = 0.0 if o.overlap is None else o.overlap
        return Swath(o.swath, overlap / 100, o.nadir_gap)
    if o.overlap is not None:
        raise InvalidParameterError("--overlap needs --camera or --swath")
    if o.spacing is not None:
        return o.spacing
    if default is not None:
        return default
    raise InvalidParameterError("give the spacing: --spacing METRES, --camera ... or --swath ...")


def _camera(o: Any) -> Camera:
    """The :class:`Camera` of ``o.camera`` (3 or 4 numbers) with its altitude or GSD and the
    overlaps."""
    if o.camera is None:
        raise InvalidParameterError("--front-overlap and --images-in-turns need --camera")
    if o.images_in_turns and o.front_overlap is None:
        raise InvalidParameterError("--images-in-turns needs --front-overlap")
    if o.gsd is not None and o.altitude is not None:
        raise InvalidParameterError(
            "give the camera's --altitude or its --gsd, not both (one follows from the other)"
        )
    sw, f, px, *rest = o.camera
    height = rest[0] if rest else None
    overlap = 70.0 if o.overlap is None else o.overlap
    return Camera(
        sw,
        f,
        px,
        altitude=o.altitude,
        gsd=o.gsd,
        side_overlap=overlap / 100,
        image_height=None if height is None else round(height),
        front_overlap=None if o.front_overlap is None else o.front_overlap / 100,
        images_in_turns=o.images_in_turns,
    )


def vehicle_of(o: Any) -> Vehicle | None:
    """The :class:`Vehicle` of ``o.turn_radius`` and ``o.reverse`` (``None`` without a radius).

    Raises:
        InvalidParameterError: ``reverse`` without a turn radius, or a bad radius.
    """
    if o.turn_radius is None:
        if o.reverse:
            raise InvalidParameterError("--reverse needs --turn-radius")
        return None
    return Vehicle(turn_radius=o.turn_radius, reverse=o.reverse)


def _dashed(option: str) -> str:
    """``turn_time`` -> ``--turn-time``: an option as the command line spells it."""
    return "--" + option.replace("_", "-")


def check_turn_time(speed: float | None, turn_time: float, spell: Any = _dashed) -> None:
    """Refuse a turn time without a speed: the turn time counts only in the mission's duration
    (path / speed + turns x turn time) and in the time objective, which both need the speed,
    so without one it would be ignored silently. ``spell`` names an option in the messages
    (``--turn-time`` on the command line, ``options.turn_time`` in the page's API).

    Example:
        >>> check_turn_time(None, 0.0)
        >>> check_turn_time(None, 5.0, lambda name: name)
        Traceback (most recent call last):
        ...
        boustro.errors.InvalidParameterError: turn_time needs speed (the duration is ...)
    """
    if turn_time and speed is None:
        raise InvalidParameterError(
            f"{spell('turn_time')} needs {spell('speed')} (the duration is path / speed + "
            "turns x turn time)"
        )
