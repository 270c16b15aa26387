"""outside_length cuts segments at the area's edges (STRtree) instead of one GEOS overlay of the
whole area per segment: the same lengths as the overlay, to 1e-9 relative."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from boustro.geometry.traced import traced_field
from boustro.plan.outside import outside_length, shapely_area
from boustro.plan.region import plan_region


def _overlay(w, r):
    """The length outside by GEOS overlays, segment by segment (the code it replaced)."""
    segs = np.stack([w[:-1], w[1:]], axis=1)
    lengths = np.linalg.norm(segs[:, 1] - segs[:, 0], axis=1)
    keep = lengths > 0
    target = shapely_area(r).buffer(1e-9 * r.diameter, join_style="mitre")
    inside = shapely.length(shapely.intersection(shapely.linestrings(segs[keep]), target))
    return float(np.sum(np.maximum(lengths[keep] - inside, 0.0)))


@pytest.mark.parametrize("kw", [{}, {"turnaround": 15.0}, {"angle": 1.1, "offset": 3.0}])
def test_plans_outside_length_as_overlay(kw):
    r = traced_field(400, 5)
    kw = {"decompose_area": False, "angle": 0.3, "offset": 1.0, **kw}
    w = plan_region(r, 10.0, **kw).waypoints
    want = _overlay(w, r)
    assert want > 100.0  # guaranteed lanes reach out of the area: something to measure
    assert outside_length(w, r) == pytest.approx(want, rel=1e-9)


def test_paths_along_and_across_the_boundary():
    r = traced_field(300, 4)
    rng = np.random.default_rng(0)
    paths = [
        np.r_[r.shell.vertices[:40], r.holes[0].vertices],  # along edges, then into a hole
        r.shell.vertices[rng.integers(0, 300, 12)],  # vertex to vertex, in and out
        np.array([[0.0, 0.0], [1.0, 0.0]]),  # inside
        np.array([[-1000.0, 0.0], [1000.0, 0.0]]),  # across the field and its holes
    ] + [rng.uniform(-400, 400, (int(rng.integers(2, 20)), 2)) for _ in range(40)]
    for w in paths:
        want = _overlay(w, r)
        assert outside_length(w, r) == pytest.approx(want, rel=1e-9, abs=1e-9)
    assert outside_length(paths[2], r) == 0.0
