"""The library's error hierarchy: every error bad input can cause derives from BoustroError.

Each also derives from the built-in exception a caller would naturally catch (``ValueError``
for bad values), so both ``except boustro.BoustroError`` and ``except ValueError`` work.
Messages say what was expected and what came.
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
    "as_number",  # noqa: F822 (served lazily by __getattr__)
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


class NoTransectError(BoustroError, ValueError):
    """No transect of the grid crosses the polygon, so the fitness is undefined."""


class PolygonFileError(BoustroError, ValueError):
    """A polygon file is missing, unreadable, or holds no usable polygon."""


class MissingDependencyError(BoustroError, ImportError):
    """An optional dependency that this operation needs is not installed."""


def __getattr__(name: str) -> object:
    """Lazy compatibility entry: ``as_number`` lives in :mod:`boustro._validate` (which imports
    this module, so importing it here at load time would make a cycle)."""
    if name == "as_number":
        from ._validate import as_number  # declared lazy entry (no cycle at load)

        return as_number
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
