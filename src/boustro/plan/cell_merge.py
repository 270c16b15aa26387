"""Merging the narrow cells of a decomposition into their neighbours, incrementally."""

from __future__ import annotations

import heapq
from collections.abc import Callable
from typing import Any

__all__: list[str] = []


def _merge_narrow(
    links: list[tuple[float, int, int, bool]],
    uf: Any,
    q: int,
    width: Callable[[int], float],
    join: Callable[[int, int], None],
    min_width: float,
) -> None:
    """Merge the narrowest cell (width under ``min_width``) that has a neighbour into the one
    it shares the longest boundary with (ties: the larger root pair), until none is left.

    Incremental: the links of each cell are kept, and after a merge only the merged cell's
    shared lengths are summed again (in link order, as a full recount would, so the same
    floating-point sums and the same choices), instead of recounting every link per merge.
    """
    by_root: dict[int, list[int]] = {}
    for k, (_, i, j, _) in enumerate(links):
        ri, rj = uf.find(i), uf.find(j)
        if ri != rj:
            by_root.setdefault(ri, []).append(k)
            by_root.setdefault(rj, []).append(k)

    def shared_of(rt: int) -> dict[int, float]:
        out: dict[int, float] = {}
        for k in by_root.get(rt, []):
            overlap, i, j, _ = links[k]
            ri, rj = uf.find(i), uf.find(j)
            if ri != rj:
                other = rj if ri == rt else ri
                out[other] = out.get(other, 0.0) + overlap
        return out

    roots = {uf.find(i) for i in range(q)}
    heap = [(width(rt), rt) for rt in roots if width(rt) < min_width]
    heapq.heapify(heap)
    while heap:
        w, rt = heapq.heappop(heap)
        if uf.find(rt) != rt or width(rt) != w:
            continue  # stale: merged, or widened by a merge (pushed again then)
        nbrs = shared_of(rt)
        if not nbrs:
            continue  # no neighbour now, none later (merges add no links)
        _, key = max((length, (min(rt, o), max(rt, o))) for o, length in nbrs.items())
        a, b = key
        join(a, b)
        new = uf.find(a)
        merged = sorted(set(by_root.pop(a, [])) | set(by_root.pop(b, [])))
        by_root[new] = merged
        if width(new) < min_width:
            heapq.heappush(heap, (width(new), new))
