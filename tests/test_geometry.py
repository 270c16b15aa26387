import math

import numpy as np
import pytest
import torch

from boustro.errors import InvalidPolygonError, NonConvexPolygonError
from boustro.geometry import (
    PAD_OFFSET,
    Polygon,
    halfplanes,
    paper_eq2_halfplanes,
    random_convex_polygon,
    rotation_matrix,
)

from .conftest import random_polygons

L_SHAPE = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]


def signed_area(v):
    return 0.5 * np.sum(v[:, 0] * np.roll(v[:, 1], -1) - np.roll(v[:, 0], -1) * v[:, 1])


def test_clockwise_input_is_reoriented():
    ccw = Polygon([(0, 0), (2, 0), (2, 1), (0, 1)])
    cw = Polygon([(0, 0), (0, 1), (2, 1), (2, 0)])
    assert signed_area(cw.vertices) > 0 and signed_area(ccw.vertices) > 0
    assert cw.area == pytest.approx(2.0)
    assert {tuple(v) for v in cw.vertices} == {tuple(v) for v in ccw.vertices}


def test_closing_duplicate_and_collinear_vertices_removed():
    p = Polygon([(0, 0), (1, 0), (1, 0), (2, 0), (2, 1), (0, 1), (0, 0.5), (0, 0)])
    assert len(p) == 4
    assert p.area == pytest.approx(2.0)


@pytest.mark.parametrize(
    "vertices, message",
    [
        ([(0, 0), (1, 0)], "at least 3"),
        ([(0, 0), (1, 1), (0, 0), (1, 1)], "at least 3 distinct"),
        ([(0, 0), (1, 1), (2, 2)], "zero area"),
        ([(0, 0), (1, 0), (0, 1), (1, 1)], "self-intersecting"),
        ([(0, 0), (2, 0), (2, 2), (1, 2), (1, -1), (0, -1)], "self-intersecting"),
        ([(0, 0), (2, 0), (1, 0), (1, 1)], "turns back"),
        ([(0, 0), (1, float("nan")), (0, 1)], "finite"),
        ([(0, 0, 0), (1, 0, 0)], "shape"),
        ([("a", 0), (1, 0), (0, 1)], "non-numeric"),
    ],
)
def test_invalid_polygons_are_refused(vertices, message):
    with pytest.raises(InvalidPolygonError, match=message):
        Polygon(vertices)


def test_errors_are_value_errors():
    with pytest.raises(ValueError):
        Polygon([(0, 0), (1, 0)])


def test_convexity_and_require_convex():
    assert Polygon([(0, 0), (1, 0), (0, 1)]).is_convex
    concave = Polygon(L_SHAPE)
    assert not concave.is_convex
    with pytest.raises(NonConvexPolygonError, match="paper model needs a convex polygon"):
        concave.require_convex("the paper model")
    assert concave.convex_hull_area() == pytest.approx(3.5)
    with pytest.raises(NonConvexPolygonError):
        halfplanes(concave)


def test_normalised_frame_and_round_trip(parallelogram):
    p = parallelogram
    assert p.diameter == pytest.approx(math.hypot(4, 8))
    n = p.normalised()
    assert n.diameter == pytest.approx(1.0)
    np.testing.assert_allclose(n.centre, 0.0, atol=1e-15)
    frame = p.frame
    pts = np.array([[1.5, -2.0], [8.0, 10.0]])
    np.testing.assert_allclose(frame.to_user(frame.to_normalised(pts)), pts, rtol=0, atol=1e-13)
    np.testing.assert_allclose(frame.to_normalised(p.vertices), n.vertices, atol=1e-15)


def test_rotation_translation_scale():
    p = Polygon([(0, 0), (2, 0), (2, 1), (0, 1)])
    r = p.rotated(math.pi / 2, origin=(0, 0))
    expected = p.vertices @ rotation_matrix(math.pi / 2).T
    assert {tuple(np.round(v, 12)) for v in r.vertices} == {
        tuple(np.round(v, 12)) for v in expected
    }
    assert p.translated(3, 4).area == pytest.approx(2.0)
    assert p.scaled(3).area == pytest.approx(18.0)


@pytest.mark.parametrize("seed", range(5))
def test_halfplanes_are_unit_inward(seed):
    poly = random_polygons(seed, 1)[0]
    n, b = poly.halfplanes()
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0)
    values = poly.vertices @ n.T + b  # (vertex, edge)
    assert np.all(values >= -1e-12)
    # each edge passes through its own two vertices
    idx = np.arange(len(poly))
    np.testing.assert_allclose(values[idx, idx], 0.0, atol=1e-12)
    np.testing.assert_allclose(values[(idx + 1) % len(poly), idx], 0.0, atol=1e-12)
    assert np.all(poly.centre @ n.T + b > 0)


def test_paper_eq2_describes_polygon_rotated_by_90_degrees(rng):
    poly = random_convex_polygon(rng, 6)
    w, b = paper_eq2_halfplanes(poly)
    inside = poly.vertices.mean(axis=0) * 0.3 + poly.vertices[0] * 0.7  # a point inside
    rotated = rotation_matrix(math.pi / 2) @ inside
    assert np.all(w @ rotated + b > 0)  # inside the rotated polygon per printed Eq. 2
    n, b_true = poly.halfplanes()
    # W is the inward normal rotated by +90 degrees (up to the edge length)
    lengths = np.linalg.norm(w, axis=1)
    np.testing.assert_allclose(w / lengths[:, None], n @ rotation_matrix(math.pi / 2).T)
    np.testing.assert_allclose(b / lengths, b_true)


def test_batched_halfplanes_are_padded():
    polys = [Polygon([(0, 0), (1, 0), (0, 1)]), Polygon([(0, 0), (1, 0), (1, 1), (0, 1)])]
    hp = halfplanes(polys)
    assert hp.normals.shape == (2, 4, 2) and hp.offsets.shape == (2, 4)
    assert hp.normals.dtype == torch.float64
    assert torch.all(hp.normals[0, 3] == 0) and hp.offsets[0, 3] == PAD_OFFSET
    with pytest.raises(InvalidPolygonError):
        halfplanes([])


def test_random_convex_polygon_factory():
    rng = np.random.default_rng(3)
    for n in range(3, 10):
        p = random_convex_polygon(rng, n)
        assert len(p) == n and p.is_convex
        assert p.diameter == pytest.approx(1.0)
    with pytest.raises(InvalidPolygonError):
        random_convex_polygon(rng, 2)
