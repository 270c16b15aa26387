"""Issue 21's traced field end to end: the same plans as before the vectorised decomposition
(numbers stored from commit 8882b43), full coverage measured with shapely, and the peak memory
of a 2000-vertex ``plan_area`` in a subprocess."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
import shapely

from boustro.geometry.traced import traced_field
from boustro.mission import plan_area
from boustro.plan.coverage import coverage
from boustro.plan.region import plan_region

SRC = Path(__file__).resolve().parents[1] / "src"

#: (waypoints, path length, sum |waypoints|, sum x_i * i) of plan_region at spacing 10,
#: computed by the code at 8882b43 (before cell_trace.py and the links sweep).
STORED = {
    "t300": (214, 28640.119300527127, 65573.73109412749, -1844755.1352081713),
    # t150d: (179, 28398.40543207045 m) at 8882b43 until moves that are not straight were
    # routed in the shell grown by the reach where shorter (plan/route_grown.py, fourteenth
    # round): 43 m shorter, coverage still 1
    "t150d": (172, 28355.331334322553, 56813.68184717682, -1578546.522189826),
    # keep-inside: a pass's swath is the union of its pieces split at its spurs' tips (one GEOS
    # buffer of a line turning back on itself was most of the plan's time), whose noding moves
    # a patch by micrometres: 30275.394908338647 m at 8882b43 (+5.0e-5 m, 1352 waypoints both);
    # then 30275.394958414592 m, 1352 waypoints until the tour was refined lane by lane
    # (plan/lane_tour.py, issue 16): the same lanes and boundary passes in a shorter order
    # (1349, 29290.67154001922 m); then 29416.52894364059 m since a lane end whose nearest
    # domain point is hidden walks along the boundary when that is shorter than the leg to a
    # visible domain vertex (plan/domain_moves.py, thirteenth round): 126 m longer here, 4-24%
    # shorter on 2000-5000-vertex traced keep-inside fields (docs/scale.md); then
    # 29294.2575448493 m (1360 waypoints; 122 m shorter, coverage 1) since the lane tour's
    # iterated local search and its closed boundary passes entered where their moves are
    # shortest (plan/lane_tour.py, seventeenth round)
    "t400in": (1360, 29294.2575448493, 461480.0708403765, -63026327.33837047),
}
CASES = {
    "t300": (traced_field(300, 4), {}),
    "t150d": (traced_field(150, 2, seed=3), {"decompose_area": True}),
    "t400in": (traced_field(400, 3, seed=2), {"keep_inside": True}),
}


@pytest.mark.parametrize("name", sorted(STORED))
def test_same_plans_as_before(name):
    region, kw = CASES[name]
    p = plan_region(region, 10.0, **kw)
    w = p.waypoints
    n, length, total, moment = STORED[name]
    assert len(w) == n
    assert p.stats.path_length == pytest.approx(length, rel=1e-12)
    assert float(np.abs(w).sum()) == pytest.approx(total, rel=1e-12)
    assert float((w[:, 0] * np.arange(len(w))).sum()) == pytest.approx(moment, rel=1e-12)
    assert coverage(p).covered_share == pytest.approx(1.0, abs=1e-9)


def test_plan_area_same_plan_and_full_coverage_on_the_original_boundary():
    r = traced_field(300, 4)
    m = plan_area(r.shell.vertices, 10.0, crs=None, holes=[h.vertices for h in r.holes])
    w = m.plan.waypoints
    assert len(w) == 207
    assert m.plan.stats.path_length == pytest.approx(28528.180033002012, rel=1e-12)
    assert m.optimum.fitness == pytest.approx(0.6550450578903096, rel=1e-12)
    # coverage with shapely on the original boundary: every lane's band, every hole pass's
    area = shapely.Polygon(r.shell.vertices, [h.vertices for h in r.holes])
    p = m.plan
    bands = []
    for (a, b), role in zip(p.transects, p.roles, strict=True):
        line = shapely.LineString([a, b])
        bands.append(
            line.buffer(p.reach, cap_style="flat") if role == "lane" else line.buffer(p.reach)
        )
    covered = shapely.union_all(bands).intersection(area).area / area.area
    assert covered >= 1 - 1e-6
    assert m.coverage is not None and m.coverage.covered_share >= 1 - 1e-9


def test_plan_area_of_2000_vertices_and_10_holes_under_1_gb():
    """Peak RSS (VmHWM) of a process that runs ``plan_area`` (certified region search,
    coverage measured) on issue 21's field; a first process compiles numba's kernels."""
    code = textwrap.dedent(
        """
        import json, sys, time
        from boustro.geometry.traced import traced_field
        from boustro.mission import plan_area
        n, holes = int(sys.argv[1]), int(sys.argv[2])
        r = traced_field(n, holes)
        t = time.process_time()
        m = plan_area(r.shell.vertices, 10.0, crs=None, holes=[h.vertices for h in r.holes])
        cpu = time.process_time() - t
        hwm = [l for l in open("/proc/self/status") if l.startswith("VmHWM:")]
        print(json.dumps({"rss_mb": int(hwm[0].split()[1]) / 1024, "cpu": cpu,
                          "covered": m.coverage.covered_share, "lanes": m.plan.stats.n_transects}))
        """
    )
    env = {"PYTHONPATH": str(SRC), "PATH": "/usr/bin:/bin"}
    subprocess.run([sys.executable, "-c", code, "60", "1"], env=env, capture_output=True,
                   timeout=900, check=True)  # fmt: skip
    out = subprocess.run([sys.executable, "-c", code, "2000", "10"], env=env,
                         capture_output=True, text=True, timeout=600, check=True)  # fmt: skip
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert got["lanes"] > 50
    assert got["covered"] >= 1 - 1e-9
    assert got["rss_mb"] < 1024, got
