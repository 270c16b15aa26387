"""Issue 16 (twelfth round): :func:`boustro.plan.contour._contour_arcs` tests against the
residual (``dwithin``) only the contour samples within reach of one of its pieces' boxes
(:func:`boustro.plan.contour._box_near`); the stretches must be exactly those of testing every
sample, here on both margins' residuals of random areas with holes, near the origin and at
UTM-sized coordinates, and on a residual the lanes leave in one corner."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

from boustro.geometry.region import Region
from boustro.plan import contour, inside
from boustro.plan.lanes import region_lanes

from .conftest import random_regions
from .plan_samples import SPACING, scaled


def _moved(region: Region, by: tuple[float, float]) -> Region:
    shift = np.asarray(by, dtype=np.float64)
    return Region(region.shell.vertices + shift, [h.vertices + shift for h in region.holes])


def _areas() -> list[Region]:
    out = [scaled(r, 150.0) for r in random_regions(31, 3, n_holes=(1, 3))]
    return out + [_moved(out[0], (512_345.0, 5_412_345.0))]


def _arcs_both_ways(region: Region, residual, tol: float, monkeypatch):
    geo = inside._geometry(region, SPACING)
    got = contour._contour_arcs(residual, SPACING / 2, tol, geo.contour, SPACING / 2)
    with monkeypatch.context() as m:  # every sample tested, as before the prefilter
        m.setattr(contour, "_box_near", lambda xy, boxes, far: np.ones(len(xy), dtype=bool))
        want = contour._contour_arcs(residual, SPACING / 2, tol, geo.contour, SPACING / 2)
    return got, want


def test_contour_arcs_equal_testing_every_sample(monkeypatch):
    rng = np.random.default_rng(12)
    skipped = tested = 0
    real = contour._box_near

    def counting(xy, boxes, far):
        nonlocal skipped, tested
        out = real(xy, boxes, far)
        skipped += int((~out).sum())
        tested += int(out.sum())
        return out

    for region in _areas():
        tol = 1e-9 * region.diameter
        for _ in range(3):
            angle, offset = rng.uniform(0, math.pi), rng.uniform(0, SPACING)
            lanes = [region_lanes(region, SPACING, angle, offset, reach=SPACING / 2,
                                  holes=region.holes)]  # fmt: skip
            for margin in (0.0, SPACING / 2):
                cut = [inside.clip_lanes(ls, region, tol, margin, SPACING) for ls in lanes]
                _, residual = inside._residual(region, cut, SPACING, SPACING / 2)
                if residual is None:
                    continue
                monkeypatch.setattr(contour, "_box_near", counting)
                got, want = _arcs_both_ways(region, residual, tol, monkeypatch)
                monkeypatch.setattr(contour, "_box_near", real)
                assert len(got) == len(want)
                for a, b in zip(got, want, strict=True):
                    assert np.array_equal(a, b)
    assert skipped > 0 and tested > 0  # the boxes rule samples out, and leave others to GEOS


def test_one_corner_left(monkeypatch):
    """A residual in one corner of a square: the stretch near it, the rest ruled out by the
    box alone."""
    region = Region([(0, 0), (100, 0), (100, 100), (0, 100)])
    residual = shapely.box(0, 0, 3, 3)
    got, want = _arcs_both_ways(region, residual, 1e-7, monkeypatch)
    assert len(got) == len(want) == 1 and np.array_equal(got[0], want[0])
    assert np.linalg.norm(np.diff(got[0], axis=0), axis=1).sum() < 40


@pytest.mark.parametrize("boxes", [np.empty((0, 4)), np.full((2, 4), np.nan)])
def test_box_near_of_nothing(boxes):
    xy = np.array([[0.0, 0.0], [1.0, 2.0]])
    assert not contour._box_near(xy, boxes, 10.0).any()
    assert contour._box_near(np.empty((0, 2)), np.array([[0.0, 0.0, 1.0, 1.0]]), 1.0).shape == (0,)


def test_box_near_distance():
    """Within ``far`` of a box (inside it, beside it, at a corner), farther not."""
    boxes = np.array([[0.0, 0.0, 2.0, 1.0], [10.0, 10.0, 11.0, 11.0]])
    xy = np.array([[1.0, 0.5], [3.0, 0.5], [2.6, 1.7], [2.8, 1.8], [5.5, 5.5], [11.5, 9.5]])
    assert contour._box_near(xy, boxes, 1.0).tolist() == [True, True, True, False, False, True]

