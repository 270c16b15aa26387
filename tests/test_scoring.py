import math

import numpy as np
import pytest
import shapely

from boustro.errors import InvalidParameterError, NonConvexPolygonError
from boustro.models import PaperModel
from boustro.scoring import make_model, score, transect_segments


def test_segments_follow_the_documented_convention(parallelogram):
    spacing, angle, offset = 0.5, math.radians(30), 0.2
    layout = transect_segments(parallelogram, spacing, angle, offset)
    u = np.array([math.cos(angle), math.sin(angle)])
    n = np.array([-math.sin(angle), math.cos(angle)])
    centre = parallelogram.centre
    mid = layout.segments.mean(axis=1)
    pos = (mid - centre) @ n
    np.testing.assert_allclose(pos, layout.positions, atol=1e-12)
    k = (pos - offset) / spacing
    np.testing.assert_allclose(k, np.round(k), atol=1e-9)  # lines at offset + k * spacing
    np.testing.assert_allclose(np.diff(pos), spacing, atol=1e-12)  # in order, no gap
    direction = (layout.segments[:, 1] - layout.segments[:, 0]) @ u
    assert np.all(direction[0::2] > 0) and np.all(direction[1::2] < 0)  # boustrophedon
    np.testing.assert_allclose(np.abs(direction), layout.lengths, atol=1e-12)
    boundary = shapely.Polygon(parallelogram.vertices).exterior
    for p in layout.segments.reshape(-1, 2):
        assert boundary.distance(shapely.Point(p)) < 1e-12


def test_score_reports_lengths_in_user_units(parallelogram):
    result = score(parallelogram, 0.5, 0.0, 0.0)
    assert result.n_transects == 15
    assert result.total_length == pytest.approx(48.0)
    np.testing.assert_allclose(result.lengths, result.layout.lengths)
    soft = score(parallelogram, 0.5, 0.0, 0.0, model=PaperModel(1e4, 2000))
    assert soft.model == "paper"
    np.testing.assert_allclose(soft.lengths, result.lengths, atol=5e-3)
    assert soft.fitness == pytest.approx(result.fitness, abs=1e-3)


def test_paper_clip_scores_only_the_window(triangle):
    clipped = score(triangle, 0.05, math.pi / 2, 0.0, model=make_model("exact", clip=True))
    full = score(triangle, 0.05, math.pi / 2, 0.0)
    assert clipped.lengths.sum() < full.lengths.sum()


def test_concave_polygon_is_refused_by_name():
    with pytest.raises(NonConvexPolygonError, match="paper model needs a convex polygon"):
        score([(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)], 0.1, 0.0, model=PaperModel())


@pytest.mark.parametrize("bad", [{"angle": float("nan")}, {"offset": float("inf")}])
def test_non_finite_angle_or_offset(parallelogram, bad):
    kwargs = {"angle": 0.0, "offset": 0.0, **bad}
    with pytest.raises(InvalidParameterError):
        score(parallelogram, 0.5, **kwargs)


def test_unknown_model():
    with pytest.raises(InvalidParameterError, match="unknown model"):
        make_model("nope")
