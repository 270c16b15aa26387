"""The cache of :func:`~boustro.plan.lanes.region_lanes` results of keep-inside plans
(``boustro.plan.region._region_lanes``): every number ``region_lanes`` reads is in its key, so
a hit gives the same lanes as a fresh call, and it holds at most
:data:`~boustro.plan.region.LANES_CACHE` entries."""

from __future__ import annotations

import numpy as np

from boustro.geometry.polygon import Polygon
from boustro.geometry.region import Region
from boustro.plan import region
from boustro.plan.lanes import region_lanes
from boustro.plan.region import PlanOptions

SPACING = 9.0
#: An L with a hole, and a cell of it with a hole of its own.
AREA_HOLES = (Polygon([(80, 10), (95, 12), (88, 30)]),)
MOVED_HOLES = (Polygon([(70, 10), (95, 12), (88, 30)]),)
CELLS = (
    Region([(0, 0), (120, 0), (120, 40), (0, 40)], [[(20, 10), (35, 10), (28, 25)]]),
    Region([(0, 0), (120, 0), (120, 40), (0, 40)]),
    Region([(0, 0), (120, 0), (120, 40), (0, 40)], [[(40, 10), (55, 10), (48, 25)]]),
)


def _same(a, b) -> bool:
    cols = ("k", "c", "t0", "t1", "origin")
    return (
        a.angle == b.angle
        and a.cut == b.cut
        and all(np.array_equal(getattr(a, x), getattr(b, x)) for x in cols)
    )


def _call(cell, angle, offset, holes, spacing, reach, layout):
    opts = PlanOptions(spacing, reach, layout=layout, keep_inside=True)
    got = region._region_lanes(cell, angle, offset, holes, opts)
    want = region_lanes(cell, spacing, angle, offset, reach=reach, holes=holes, layout=layout)
    assert _same(got, want), (angle, offset, len(holes), spacing, reach, layout)
    assert len(region._LANES) <= region.LANES_CACHE


def test_a_hit_is_the_lanes_of_a_fresh_call():
    region._LANES.clear()
    base = dict(
        cell=CELLS[0],
        angle=0.3,
        offset=1.0,
        holes=AREA_HOLES,
        spacing=SPACING,
        reach=SPACING / 2,
        layout="guaranteed",
    )
    changes = [
        ("cell", CELLS[1]),  # the cell's own hole gone
        ("cell", CELLS[2]),  # the cell's hole moved
        ("angle", 0.3 + 1e-3),
        ("offset", 4.0),
        ("holes", ()),
        ("holes", MOVED_HOLES),
        ("spacing", SPACING * 1.25),
        ("reach", SPACING * 0.7),
        ("layout", "chords"),
    ]
    # the base laid, then each number changed alone: a key without it returns the base's lanes
    for name, value in changes:
        _call(**base)
        _call(**{**base, name: value})
    # the cell's hole made the area's (the same rings, in the same order): it cuts the lanes now
    _call(**base)
    cell_hole = Polygon(CELLS[0].holes[0].vertices)
    _call(**{**base, "cell": CELLS[1], "holes": (cell_hole, *AREA_HOLES)})
    # more calls than the cache holds, then all again
    grids = [(a, d) for a in (0.2, 0.9, 1.6) for d in (0.5, 3.0, 6.0)]
    for angle, offset in grids + grids:
        _call(**{**base, "angle": angle, "offset": offset})


def test_the_cache_is_only_for_keep_inside():
    region._LANES.clear()
    opts = PlanOptions(SPACING, SPACING / 2)
    a = region._region_lanes(CELLS[1], 0.3, 1.0, (), opts)
    assert not region._LANES and _same(a, region_lanes(CELLS[1], SPACING, 0.3, 1.0))
    inside = PlanOptions(SPACING, SPACING / 2, keep_inside=True)
    b = region._region_lanes(CELLS[1], 0.3, 1.0, (), inside)
    assert region._region_lanes(CELLS[1], 0.3, 1.0, (), inside) is b  # a hit
