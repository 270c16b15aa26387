"""The layouts of a 1-degree brute force of the lane angle (each angle's lanes laid from the
area's extreme, the first half a spacing inside it) in the certified cover search: planned as
seeds before it and, where their bound could beat its best plan, after it, so that its plan is
never longer than that brute force's best (issue 16; docs/mission_time.md, "Never longer than
the 1-degree brute force")."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...geometry.region import Region
from .boxes import Boxes
from .plans import centred_offsets, try_plans

__all__ = [
    "CENTRED_ANGLES",
    "CENTRED_MAX_PLANS",
    "CENTRED_SEEDS",
    "centred_boxes",
    "try_centred",
]

#: Whole degrees of angle whose lanes laid from the area's extreme (the first half a spacing
#: inside it: the layouts of a 1-degree brute force) are seeds and a final sweep of a search
#: over every angle (:func:`try_centred`); 0: none.
CENTRED_ANGLES = 180
#: Those layouts planned before the search (the lowest models): a good first incumbent.
CENTRED_SEEDS = 4
#: Plans of the final sweep at most (``info["centred_complete"]``: whether it planned every
#: layout whose bound is below the best plan; a loose bound, as a vehicle's or headlands',
#: would plan most of the 180). Not with keep-inside (its bound at a layout is 5-20% below its
#: plans: 148 plans a search, 18-24 s a field; and its brute force is not issue 16's).
CENTRED_MAX_PLANS = 24


def centred_boxes(region: Region, spacing: float, reach: float) -> Boxes:
    """The layouts of a brute force over :data:`CENTRED_ANGLES` whole angles: each with its
    first line ``reach`` inside the area's lowest extreme (:func:`centred_offsets`)."""
    angles = np.arange(CENTRED_ANGLES, dtype=np.float64) * (math.pi / CENTRED_ANGLES)
    d = centred_offsets(region, angles, spacing, reach)
    zeros = np.zeros(len(angles))
    return Boxes(angles, zeros, d, zeros)


def try_centred(search: Any, seeds: int | None = None) -> None:
    """Plan the brute force's layouts (:func:`centred_boxes`) that could beat ``search``'s
    (a :class:`~.search.CoverSearch`) best plan: ``seeds`` of them, those of the lowest
    models, before the search (a first incumbent); without ``seeds``, after it, every one whose
    lower bound at the layout itself (the exact area, with the 1-tree) is below the best plan,
    lowest first, at most :data:`CENTRED_MAX_PLANS`: where that planned them all
    (``search.centred_complete``) the plan is never longer than the best of that brute force
    (as far as the bound at a layout holds, which the tests check against the plans)."""
    if CENTRED_ANGLES <= 0:
        return
    boxes = centred_boxes(search.region, search.s, search.reach)
    if seeds is not None:
        bounds = search.point_values(boxes)
        try_plans(search, boxes, search.ranks, limit=seeds, bounds=bounds)
        return
    before = search.plans
    values: NDArray[np.float64] = search.point_values(boxes, exact=True)
    try_plans(search, boxes, values, limit=CENTRED_MAX_PLANS)
    search.centred_plans = search.plans - before
    unseen = np.array([boxes.centre_key(i) not in search.seen for i in range(len(boxes.d))])
    search.centred_complete = not bool((unseen & (values < search.best[0])).any())
