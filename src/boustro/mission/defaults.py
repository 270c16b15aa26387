"""The settings of :func:`~boustro.mission.plan_area`: default optimiser and its options."""

from __future__ import annotations

import logging
from typing import Any

__all__ = [
    "DEFAULT_HULL_TOLERANCE",
    "DEFAULT_METHOD",
    "FALLBACK_METHOD",
    "METHOD_OPTIONS",
    "REGION_OPTIONS",
    "SCALE_METHOD",
    "log",
]

log = logging.getLogger("boustro")

#: The optimiser :func:`plan_area` uses unless told otherwise, and the options it passes to each
#: method. Switching the default is this one line.
DEFAULT_METHOD = "global"
#: Used instead of the default when the global optimiser would take too long (many vertices at a
#: small spacing; :data:`boustro.global_opt.WORK_LIMIT`): Eq. 1 by the certified branch and bound
#: over (angle, offset) boxes (:func:`boustro.optimize.smith_bb.smith_bb`), other objectives by
#: the hybrid search.
SCALE_METHOD = "certified-bb"
FALLBACK_METHOD = "hybrid"
METHOD_OPTIONS: dict[str, dict[str, Any]] = {"grid": {"n_angles": 360, "n_offsets": 32}}

#: Deepest pocket (metres) of a nearly convex area that is planned on its convex hull.
DEFAULT_HULL_TOLERANCE = 0.5

#: Grid of the optimiser for concave areas and areas with holes
#: (:func:`boustro.plan.optimize_region`; a cell or the whole area), overridden by
#: ``options``.
REGION_OPTIONS: dict[str, Any] = {"n_angles": 90, "n_offsets": 16}
