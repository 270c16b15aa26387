"""Transect spacing from a sensor: a camera or a swath sensor (sonar, lidar, sprayer boom).

Lengths are metres, the camera's sensor size and focal length millimetres, GSD centimetres per
pixel, overlaps fractions in ``[0, 1)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ._validate import as_number
from .errors import InvalidParameterError

__all__ = ["Camera", "CameraTrigger", "SensorSpacing", "Swath"]


def _positive(name: str, value: float) -> float:
    v = as_number(name, value)
    if not math.isfinite(v) or v <= 0:
        raise InvalidParameterError(f"{name} must be a finite number > 0, got {value!r}")
    return v


def _fraction(name: str, value: float) -> float:
    v = as_number(name, value)
    if not (0 <= v < 1):
        raise InvalidParameterError(f"{name} must be a fraction in [0, 1), got {value!r}")
    return v


@dataclass(frozen=True)
class SensorSpacing:
    """What a sensor implies for the plan.

    Attributes:
        spacing: distance between neighbouring transects, metres.
        reach: half-width of the band each transect must cover, metres (``spacing / 2`` unless
            there is a nadir gap).
        nadir_gap: blind strip under the vehicle, metres (0 for a camera).
        footprint: the sensor's full width across track, metres.
        altitude: flying height above ground, metres, when the sensor fixes it (camera).
        description: one line for the user, e.g. the footprint and GSD.
    """

    spacing: float
    reach: float
    nadir_gap: float
    footprint: float
    altitude: float | None
    description: str
    trigger: CameraTrigger | None = None


@dataclass(frozen=True)
class CameraTrigger:
    """Distance-based camera triggering along the lanes (``MAV_CMD_DO_SET_CAM_TRIGG_DIST``).

    Attributes:
        distance: metres flown between two photos: the footprint along track times
            ``1 - front_overlap``.
        front_overlap: forward overlap between consecutive photos, a fraction in ``[0, 1)``.
        footprint_along, footprint_across: the photo's footprint on the ground, metres (the
            image's height along track, its width across).
        gsd: ground sample distance, centimetres per pixel.
        altitude: flying height above ground, metres.
        images_in_turns: keep triggering through the turns (default: only along the lanes).
    """

    distance: float
    front_overlap: float
    footprint_along: float
    footprint_across: float
    gsd: float
    altitude: float
    images_in_turns: bool = False


@dataclass(frozen=True)
class Camera:
    """A frame camera looking straight down.

    Give exactly one of ``altitude`` (m) and ``gsd`` (cm/px); the other follows. The image's
    width lies across track. With ``front_overlap`` (and the image's height ``image_height``,
    px, square pixels) the camera is triggered by distance along the lanes
    (:class:`CameraTrigger`, in :attr:`SensorSpacing.trigger`).

    Example (a 1-inch 20 MP camera, 13.2 mm wide sensor, 8.8 mm lens, 5472 px wide images):
        >>> round(Camera(13.2, 8.8, 5472, altitude=80, side_overlap=0.7).spacing().spacing, 6)
        36.0

    Example:
        >>> s = Camera(13.2, 8.8, 5472, altitude=100.0).spacing()
        >>> round(s.spacing, 3), round(s.footprint, 3)
        (45.0, 150.0)
    """

    sensor_width: float  # mm
    focal_length: float  # mm
    image_width: int  # px
    altitude: float | None = None  # m above ground
    gsd: float | None = None  # cm / px
    side_overlap: float = 0.7
    image_height: int | None = None  # px, along track
    front_overlap: float | None = None
    images_in_turns: bool = False

    def spacing(self) -> SensorSpacing:
        sw = _positive("sensor width (mm)", self.sensor_width)
        f = _positive("focal length (mm)", self.focal_length)
        px = _positive("image width (px)", self.image_width)
        overlap = _fraction("side overlap", self.side_overlap)
        if (self.altitude is None) == (self.gsd is None):
            raise InvalidParameterError(
                "a camera needs exactly one of altitude (m) and ground sample distance (cm/px), "
                f"got altitude={self.altitude!r}, gsd={self.gsd!r}"
            )
        if self.altitude is not None:
            altitude = _positive("altitude (m)", self.altitude)
        else:
            gsd_m = _positive("ground sample distance (cm/px)", self.gsd) / 100  # type: ignore[arg-type]
            altitude = gsd_m * px * f / sw
        footprint = sw * altitude / f
        gsd_cm = footprint / px * 100
        spacing = footprint * (1 - overlap)
        text = (
            f"camera footprint {footprint:.2f} m across track at {altitude:.1f} m, "
            f"GSD {gsd_cm:.2f} cm/px, side overlap {overlap * 100:g}%: spacing {spacing:.2f} m"
        )
        trigger = self._trigger(footprint, gsd_cm, altitude)
        if trigger is not None:
            text += (
                f"; front overlap {trigger.front_overlap * 100:g}%: a photo every "
                f"{trigger.distance:.2f} m"
            )
        return SensorSpacing(spacing, spacing / 2, 0.0, footprint, altitude, text, trigger)

    def _trigger(self, footprint: float, gsd_cm: float, altitude: float) -> CameraTrigger | None:
        """The trigger distance for ``front_overlap``: footprint along track x (1 - overlap)."""
        if self.front_overlap is None:
            return None
        front = _fraction("front overlap", self.front_overlap)
        if self.image_height is None:
            raise InvalidParameterError(
                "a front overlap needs the image's height in pixels (along track): give the "
                "camera as SENSOR_MM,FOCAL_MM,IMAGE_W_PX,IMAGE_H_PX or a preset name"
            )
        along = gsd_cm / 100 * _positive("image height (px)", self.image_height)
        return CameraTrigger(
            along * (1 - front), front, along, footprint, gsd_cm, altitude, self.images_in_turns
        )


@dataclass(frozen=True)
class Swath:
    """A sensor that sees a strip of ``width`` metres across track (sonar, lidar, boom).

    ``nadir_gap`` (m): a blind strip of that width centred under the vehicle (side-scan sonar).

    Example:
        >>> s = Swath(20.0, overlap=0.1, nadir_gap=2.0).spacing()
        >>> round(s.spacing, 3), round(s.reach, 3)
        (8.1, 9.1)
    """

    width: float
    overlap: float = 0.0
    nadir_gap: float = 0.0

    def spacing(self) -> SensorSpacing:
        w = _positive("swath width (m)", self.width)
        overlap = _fraction("swath overlap", self.overlap)
        gap = as_number("nadir gap", self.nadir_gap)
        if not (math.isfinite(gap) and 0 <= gap < w):
            raise InvalidParameterError(
                f"nadir gap must be >= 0 and smaller than the swath width {w:g} m, got "
                f"{self.nadir_gap!r}"
            )
        if gap == 0:
            spacing = w * (1 - overlap)
            text = f"swath {w:g} m, overlap {overlap * 100:g}%: spacing {spacing:.2f} m"
            return SensorSpacing(spacing, spacing / 2, 0.0, w, None, text)
        spacing = (w - gap) / 2 * (1 - overlap)
        reach = spacing + gap / 2
        text = (
            f"swath {w:g} m with a {gap:g} m nadir gap, overlap {overlap * 100:g}%: spacing "
            f"{spacing:.2f} m (each gap seen by a neighbouring line)"
        )
        return SensorSpacing(spacing, reach, gap, w, None, text)
