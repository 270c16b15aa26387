"""Certified maximum of Eq. 1 at scale (``method="certified-bb"``): a branch and bound over
boxes of (angle, offset) with sandwich bounds, ``O(n + lines)`` per box (:func:`smith_bb`)."""

from .kernel import box_bounds, eq1_values
from .search import DEFAULT_TOL, smith_bb

__all__ = ["DEFAULT_TOL", "box_bounds", "eq1_values", "smith_bb"]
