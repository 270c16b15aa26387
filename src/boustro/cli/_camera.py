"""``boustro plan``'s camera: ``--camera`` numbers or a preset, and distance triggering (the
:class:`~boustro.sensors.Camera` is built by :func:`boustro.mission.options.sensor_of`)."""

from __future__ import annotations

import argparse
from collections.abc import Callable

from ..errors import InvalidParameterError
from ..mission.camera import camera_preset

__all__ = ["add_trigger_options", "camera_arg"]


def add_trigger_options(group: argparse._ArgumentGroup, percent: Callable[[str], float]) -> None:
    """``--front-overlap`` and ``--images-in-turns``; ``percent`` parses a percentage."""
    group.add_argument(
        "--front-overlap",
        type=percent,
        metavar="PCT",
        help="camera: forward overlap between consecutive photos, percent; triggers the camera "
        "by distance (MAV_CMD_DO_SET_CAM_TRIGG_DIST at each lane's start, 0 at its end, in "
        ".plan and .waypoints): footprint along track x (1 - PCT/100)",
    )
    group.add_argument(
        "--images-in-turns",
        action="store_true",
        help="with --front-overlap: keep taking photos through the turns (default: only along "
        "the lanes)",
    )


def _numbers(text: str) -> list[float] | None:
    try:
        return [float(x) for x in text.replace(" ", "").split(",")]
    except ValueError:
        return None


def camera_arg(text: str) -> tuple[float, float, float, float | None]:
    """``--camera``: three or four positive numbers, or a preset's name (its four numbers)."""
    values = _numbers(text)
    if values is None:
        try:
            cam = camera_preset(text)
        except InvalidParameterError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
        return cam.sensor_width, cam.focal_length, cam.image_width, cam.image_height
    if len(values) not in (3, 4):
        raise argparse.ArgumentTypeError(
            f"expected SENSOR_MM,FOCAL_MM,IMAGE_PX[,IMAGE_H_PX] or a preset name, got {text!r}"
        )
    if not all(0 < v < float("inf") for v in values):
        raise argparse.ArgumentTypeError(f"camera values must be finite and > 0, got {text!r}")
    return values[0], values[1], values[2], values[3] if len(values) == 4 else None
