"""The core packages (geometry/, models/): old import paths, and the one chord kernel serving
the copies in the learned planner and the experiments."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from boustro import io
from boustro.geometry import (
    PAD_OFFSET,
    PAPER_PARALLELOGRAM,
    PAPER_SPACING,
    HalfPlanes,
    Polygon,
    halfplanes,
    random_convex_polygon,
)
from boustro.models import (
    chord_bounds,
    chords_at,
    exact_chords,
)


def _batch(seed: int = 0, counts: tuple[int, ...] = (3, 5, 8, 4)) -> HalfPlanes:
    """Half-planes of polygons with different vertex counts, padded to the largest."""
    rng = np.random.default_rng(seed)
    return halfplanes([random_convex_polygon(rng, n) for n in counts])


# -- old import paths -----------------------------------------------------------------------------
def test_alias_shims_are_the_moved_modules_and_forward_monkeypatching(monkeypatch):
    import boustro._compiled
    import boustro.models._kernels
    import boustro.models.smooth
    import boustro.smooth

    assert boustro.smooth is boustro.models.smooth
    assert boustro._compiled is boustro.models._kernels
    monkeypatch.setattr(boustro.smooth, "COMPILED", False)
    assert boustro.models.smooth.COMPILED is False


def test_moved_names_stay_importable_from_their_old_paths():
    import boustro.errors
    import boustro.geometry
    import boustro.models
    import boustro.regions
    import boustro.scoring
    from boustro._validate import as_number
    from boustro.errors import MissingDependencyError
    from boustro.regions import _point_segment_distance, evaluate_region_grid, random_region

    assert boustro.errors.as_number is as_number
    assert issubclass(MissingDependencyError, ImportError)
    assert boustro.scoring.as_polygon is boustro.geometry.as_polygon
    assert callable(_point_segment_distance) and callable(evaluate_region_grid)
    assert callable(random_region)
    for name in ("_prepare", "_components", "_grid", "_window_mask", "_SigmoidIntegral"):
        assert hasattr(boustro.models, name), name
    for name in ("PAD_OFFSET", "random_convex_polygon", "paper_eq2_halfplanes", "_cross"):
        assert hasattr(boustro.geometry, name), name
    with pytest.raises(AttributeError):
        boustro.errors.no_such_name  # noqa: B018


def test_paper_shapes_equal_the_io_copies():
    assert PAPER_PARALLELOGRAM == io.PAPER_PARALLELOGRAM
    assert PAPER_SPACING == io.PAPER_SPACING


def test_check_positive_message():
    from boustro._validate import check_positive
    from boustro.errors import InvalidParameterError

    assert check_positive("smoothing", 2) == 2.0
    with pytest.raises(InvalidParameterError, match="smoothing must be finite and > 0"):
        check_positive("smoothing", 0.0)


# -- the one chord kernel -------------------------------------------------------------------------
def test_padded_batch_equals_each_polygon_alone():
    hp = _batch()
    theta, offset = torch.tensor([0.3, -1.1, 2.0, 0.7]), torch.tensor([0.01, 0.02, -0.03, 0.0])
    batched = exact_chords(hp, theta, offset, 0.05)
    for row, n in enumerate((3, 5, 8, 4)):
        one = HalfPlanes(hp.normals[row, :n], hp.offsets[row, :n], hp.radius)
        alone = exact_chords(one, theta[row], offset[row], 0.05)
        torch.testing.assert_close(batched.lengths[row], alone.lengths, rtol=0, atol=0)


@pytest.mark.parametrize("clip", [False, True])
def test_fused_and_divided_chords_agree_and_differentiate_alike(clip):
    hp = _batch(5, (3, 4, 9, 6, 5, 12))
    g = torch.Generator().manual_seed(3)
    theta = (torch.rand(6, 20, generator=g, dtype=torch.float64) * 7 - 3.5).requires_grad_()
    offset = torch.rand(6, 20, generator=g, dtype=torch.float64) * 0.03
    hp = HalfPlanes(hp.normals[:, None], hp.offsets[:, None], hp.radius)
    results = []
    for fused in (False, True):
        ch = exact_chords(hp, theta, offset, 0.03, clip=clip, fused=fused)
        (grad,) = torch.autograd.grad(ch.lengths.pow(2).sum(), theta)
        results.append((ch.lengths.detach(), grad))
    (a, ga), (b, gb) = results
    torch.testing.assert_close(a, b, rtol=1e-12, atol=1e-13)
    torch.testing.assert_close(ga, gb, rtol=1e-9, atol=1e-11)


def test_axis_parallel_edges_block_the_same_lines_in_both_forms():
    square = halfplanes(Polygon([(0, 0), (1, 0), (1, 1), (0, 1)]), normalise=False)
    c = torch.tensor([-0.5, 0.0, 0.5, 1.0, 1.5], dtype=torch.float64)
    for fused in (False, True):
        out = chords_at(square, 0.0, c, fused=fused).lengths
        assert out.tolist() == [0.0, 1.0, 1.0, 1.0, 0.0]


def test_padding_half_planes_never_bound_a_chord():
    hp = halfplanes([Polygon([(0, 0), (1, 0), (0, 1)]), Polygon([(0, 0), (2, 0), (2, 1), (0, 1)])])
    assert float(hp.offsets[0, 3]) == PAD_OFFSET
    lhs = torch.tensor([[PAD_OFFSET, 1.0, 1.0]], dtype=torch.float64)
    out = chord_bounds(lhs, torch.tensor([[0.0, 1.0, -1.0]], dtype=torch.float64))
    assert (out.lower.item(), out.upper.item(), out.blocked.item()) == (-1.0, 1.0, False)
