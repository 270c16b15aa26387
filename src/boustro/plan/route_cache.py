"""What a :class:`~boustro.plan.routing.Router` remembers between queries, bounded.

A router is shared by every plan of an area (``router_for``), and the plans of nearby layouts
(and a plan's two distance matrices: the order of its chains, then the lane-by-lane
refinement) share most of their points: the lane ends, the hole passes' ends, the start.
Answers that depend on one point only (its *rows*: the leg to an inner domain, the visible
nodes, the shortest lengths through them to every node) are remembered by the point's bytes,
so a plan never depends on what was asked before (every answer equals the one computed from
scratch, bit for bit). A store is emptied all at once when it would pass its limit; a batch
keeps its own answers meanwhile.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["remembered_rows"]


def remembered_rows(
    cache: dict[bytes, tuple[Any, ...]],
    p: NDArray[np.float64],
    compute: Callable[[NDArray[np.float64]], tuple[NDArray[Any], ...]],
    limit: int,
) -> tuple[NDArray[Any], ...]:
    """``compute(p)`` for a computation whose answer for each point depends on that point only
    (its rows), each point's rows remembered in ``cache`` by the point's bytes (at most
    ``limit`` points)."""
    p = np.ascontiguousarray(p, dtype=np.float64).reshape(-1, 2)
    keys = [x.tobytes() for x in p]
    # the batch's rows kept here: the cache may be emptied below
    known = {k: cache[k] for k in keys if k in cache}
    new: dict[bytes, int] = {}
    for i, k in enumerate(keys):
        if k not in known and k not in new:
            new[k] = i
    if new:
        if len(cache) + len(new) > limit:
            cache.clear()
        idx = np.fromiter(new.values(), dtype=np.int64, count=len(new))
        got = compute(p[idx])
        for j, k in enumerate(new):
            known[k] = cache[k] = tuple(g[j] for g in got)
    rows = [known[k] for k in keys]
    if not rows:
        return compute(p)
    return tuple(np.array([r[c] for r in rows]) for c in range(len(rows[0])))
