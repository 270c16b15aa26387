"""A mapping camera on the mission: presets of common cameras, the photos a plan takes.

The trigger distance itself is the camera's (:meth:`boustro.sensors.Camera.spacing`: the
footprint along track times ``1 - front_overlap``); the MAVLink formats write it as
``MAV_CMD_DO_SET_CAM_TRIGG_DIST`` at each lane's start and 0 at its end.
"""

from __future__ import annotations

import dataclasses
import json
import math
from functools import cache
from importlib import resources
from typing import Any

import numpy as np

from ..errors import InvalidParameterError
from ..sensors import Camera, CameraTrigger, SensorSpacing
from .types import Mission

__all__ = [
    "CAMERA_FILE",
    "camera_preset",
    "camera_presets",
    "camera_trigger",
    "count_photos",
    "with_camera",
]

#: The presets' data file in ``boustro/data``.
CAMERA_FILE = "cameras.json"


@cache
def camera_presets() -> dict[str, dict[str, Any]]:
    """The camera presets by name (``boustro/data/cameras.json``): label, sensor size (mm),
    focal length (mm), image size (px).

    >>> camera_presets()["dji-phantom-4-pro"]["image_width_px"]
    5472
    """
    text = (resources.files("boustro") / "data" / CAMERA_FILE).read_text(encoding="utf-8")
    return dict(json.loads(text)["cameras"])


def camera_preset(name: str, **settings: Any) -> Camera:
    """The :class:`~boustro.sensors.Camera` of preset ``name`` (case and ``_``/`` `` ignored),
    with ``settings`` (``altitude`` or ``gsd``, ``side_overlap``, ``front_overlap``...).

    >>> s = camera_preset("DJI Phantom 4 Pro", altitude=80, front_overlap=0.75).spacing()
    >>> round(s.trigger.distance, 3)
    20.0
    """
    key = "-".join(str(name).strip().lower().replace("_", " ").split())
    presets = camera_presets()
    if key not in presets:
        raise InvalidParameterError(
            f"unknown camera {name!r}; the presets: {', '.join(sorted(presets))} (or give "
            "SENSOR_MM,FOCAL_MM,IMAGE_W_PX[,IMAGE_H_PX])"
        )
    p = presets[key]
    return Camera(
        p["sensor_width_mm"],
        p["focal_length_mm"],
        p["image_width_px"],
        image_height=p["image_height_px"],
        **settings,
    )


def _triggered_stretches(mission: Mission) -> list[float]:
    """Ground length of each stretch of the path flown with the camera on: from each lane's
    ``start`` waypoint to the next ``end`` (around a hole too), or with ``images_in_turns``
    from the first start to the last end."""
    plan = mission.plan
    points = plan.waypoints / plan.ground_scale
    legs = np.hypot(*np.diff(points, axis=0).T)
    along = np.concatenate([[0.0], np.cumsum(legs)])
    starts = [i for i, k in enumerate(plan.kinds) if k == "start"]
    ends = [i for i, k in enumerate(plan.kinds) if k == "end"]
    if not starts or not ends:
        return []
    assert mission.camera is not None
    if mission.camera.images_in_turns:
        return [float(along[ends[-1]] - along[starts[0]])]
    out = []
    for s in starts:
        e = next(i for i in ends if i > s)
        out.append(float(along[e] - along[s]))
    return out


def count_photos(mission: Mission) -> int:
    """The photos taken: in each triggered stretch one at its start (the command's "trigger
    once now") and one every trigger distance after it."""
    if mission.camera is None:
        return 0
    d = mission.camera.distance
    return sum(math.floor(length / d + 1e-9) + 1 for length in _triggered_stretches(mission))


def camera_trigger(spacing: Any) -> CameraTrigger | None:
    """The trigger of a camera given as the spacing (a :class:`~boustro.sensors.Camera` or its
    :class:`~boustro.sensors.SensorSpacing`), else ``None``."""
    if callable(getattr(spacing, "spacing", None)):
        spacing = spacing.spacing()
    return spacing.trigger if isinstance(spacing, SensorSpacing) else None


def with_camera(mission: Mission, trigger: CameraTrigger | None) -> Mission:
    """``mission`` with the camera's trigger and the number of photos (unchanged without one)."""
    if trigger is None:
        return mission
    out = dataclasses.replace(mission, camera=trigger)
    return dataclasses.replace(out, photos=count_photos(out))
