"""The library's error hierarchy: every error bad input can cause derives from BoustroError.

Each also derives from the built-in exception a caller would naturally catch (``ValueError``
for bad values), so both ``except boustro.BoustroError`` and ``except ValueError`` work.
Messages say what was expected and what came; :func:`as_number`, the one conversion of a
parameter to a number, raises them (the other checks are in :mod:`boustro._validate`).
"""

from __future__ import annotations

__all__ = [
    "BoustroError",
    "InvalidParameterError",
    "InvalidPolygonError",
    "MissingDependencyError",
    "NoTransectError",
    "NonConvexPolygonError",
    "PolygonFileError",
    "ProblemTooLargeError",
    "TooMuchWorkError",
    "as_number",
]


class BoustroError(Exception):
    """Base class of every error raised by boustro for bad input."""


class InvalidPolygonError(BoustroError, ValueError):
    """The vertices do not describe a valid simple polygon."""


class NonConvexPolygonError(InvalidPolygonError):
    """A convex polygon was required (e.g. by the paper's sigmoid model) and a concave one came."""


class InvalidParameterError(BoustroError, ValueError):
    """A numeric parameter (spacing, temperature, angle, ...) is out of its valid range."""


class ProblemTooLargeError(InvalidParameterError):
    """The exact global optimiser would need more work than :data:`boustro.global_opt.WORK_LIMIT`
    (many vertices at a small spacing); another method can take the problem."""


class TooMuchWorkError(InvalidParameterError):
    """The estimate before planning (:func:`boustro.mission.estimate_work`) is absurd: too many
    lanes, too large an area or too long a time; ``force=True`` (``--force``) plans anyway."""


class NoTransectError(BoustroError, ValueError):
    """No transect of the grid crosses the polygon, so the fitness is undefined."""


class PolygonFileError(BoustroError, ValueError):
    """A polygon file is missing, unreadable, or holds no usable polygon."""


class MissingDependencyError(BoustroError, ImportError):
    """An optional dependency that this operation needs is not installed."""


def as_number(name: str, value: object) -> float:
    """``float(value)``, or :class:`InvalidParameterError` ``"<name> must be a number, got ..."``.

    Callers check the range themselves, with a message that states it.
    """
    if isinstance(value, bool):  # float(True) == 1.0: a flag is not a number
        raise InvalidParameterError(f"{name} must be a number, got {value!r}")
    try:
        detach = getattr(value, "detach", None)  # a tensor (a gradient may flow through it)
        return float(detach() if callable(detach) else value)  # type: ignore[arg-type]
    except (TypeError, ValueError, RuntimeError):
        raise InvalidParameterError(f"{name} must be a number, got {value!r}") from None
