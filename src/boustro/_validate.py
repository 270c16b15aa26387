"""Small parameter validators shared by the library: numbers, spacings, finite and positive."""

from __future__ import annotations

import math

from .errors import InvalidParameterError, as_number

__all__ = ["MAX_TRANSECTS", "as_number", "check_finite", "check_positive", "check_spacing"]

#: Most transects across one area that boustro plans or scores (a 10 km field at 1 cm): a
#: smaller spacing is refused with a clear error instead of exhausting memory.
MAX_TRANSECTS = 1_000_000


def check_spacing(spacing: float, extent: float | None = None) -> float:
    """Return ``spacing`` as a float, or raise if it is not a finite positive number, or (with
    ``extent``, the width to cover in the same units) if more than :data:`MAX_TRANSECTS`
    transects would be needed.

    Example:
        >>> check_spacing(0.5)
        0.5
    """
    s = as_number("spacing", spacing)
    if not math.isfinite(s) or s <= 0:
        raise InvalidParameterError(f"spacing must be a finite number > 0, got {spacing!r}")
    if extent is not None and extent / s > MAX_TRANSECTS:
        raise InvalidParameterError(
            f"spacing {s:.6g} is too small for an area {extent:.6g} across: about "
            f"{extent / s:.3g} transects, more than the {MAX_TRANSECTS} boustro handles"
        )
    return s


def check_finite(name: str, value: float) -> float:
    """Return ``value`` as a float, or raise if it is not a finite number."""
    v = as_number(name, value)
    if not math.isfinite(v):
        raise InvalidParameterError(f"{name} must be a finite number, got {value!r}")
    return v


def check_positive(name: str, value: float) -> float:
    """Return ``value`` as a float, or raise ``"<name> must be finite and > 0, got ..."``."""
    v = as_number(name, value)
    if not (math.isfinite(v) and v > 0):
        raise InvalidParameterError(f"{name} must be finite and > 0, got {value!r}")
    return v
