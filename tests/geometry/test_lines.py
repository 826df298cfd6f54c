"""Plücker lines: construction, validation, projections onto M^4, common normals."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import ruledrobot as rr
from ruledrobot.geometry import lines as L

from ..conftest import random_poses

r6 = arrays(np.float64, (5, 6), elements=st.floats(-10, 10)).filter(
    lambda x: np.all(np.linalg.norm(x[:, :3], axis=1) > 1e-3)
)


def manifold_residual(x: np.ndarray) -> float:
    l, m = x[..., :3], x[..., 3:]
    return float(max(np.abs(np.linalg.norm(l, axis=-1) - 1).max(), np.abs((l * m).sum(-1)).max()))


def test_from_point_direction_moment_is_p_cross_l():
    lines = rr.Lines.from_point_direction([[1, 2, 3]], [[0, 0, 2]])
    np.testing.assert_allclose(lines.direction, [[0, 0, 1]])
    np.testing.assert_allclose(lines.moment, [np.cross([1, 2, 3], [0, 0, 1])])
    np.testing.assert_allclose(lines.point, [[1, 2, 0]])
    two = rr.Lines.from_two_points([[1, 2, 3]], [[1, 2, 5]])
    np.testing.assert_allclose(two.plucker, lines.plucker)


def test_bad_input_names_the_index():
    with pytest.raises(ValueError, match=r"directions\[2\]: zero direction"):
        rr.Lines.from_point_direction(np.zeros((3, 3)), [[1, 0, 0], [0, 1, 0], [0, 0, 0]])
    with pytest.raises(ValueError, match=r"points\[1\].*NaN"):
        rr.Lines.from_point_direction([[0, 0, 0], [np.nan, 0, 0]], [[1, 0, 0], [1, 0, 0]])
    with pytest.raises(ValueError, match=r"lines\[1\]: direction must be a unit vector"):
        rr.Lines.from_plucker([[1, 0, 0, 0, 1, 0], [2, 0, 0, 0, 1, 0]])
    with pytest.raises(ValueError, match=r"lines\[0\]: l \. m"):
        rr.Lines.from_plucker([[1, 0, 0, 1, 1, 0]])
    with pytest.raises(ValueError, match=r"points\[0\]: the two points coincide"):
        rr.Lines.from_two_points([[1, 1, 1]], [[1, 1, 1]])
    with pytest.raises(ValueError, match=r"shape \(N, 6\)"):
        rr.Lines(np.zeros((3, 5)))


def test_lines_are_immutable():
    lines = rr.Lines.from_point_direction([[0, 0, 0]], [[1, 0, 0]])
    with pytest.raises(ValueError):
        lines.plucker[0, 0] = 3.0


@given(x=r6)
def test_eq4_projection_lands_on_manifold(x):
    y = L.plucker_project(x)
    assert manifold_residual(y) < 1e-12 * max(1.0, np.abs(y).max())


def test_eq4_is_identity_on_lines_and_similarity_equivariant(rng):
    lines = rr.Lines.from_point_direction(rng.normal(size=(50, 3)), rng.normal(size=(50, 3)))
    np.testing.assert_allclose(L.plucker_project(lines.plucker), lines.plucker, atol=1e-15)
    x = rng.normal(size=(50, 6))
    g = random_poses(rng, 1)[0]
    # rigid motions act linearly on R^6: (l, m) -> (R l, R m + t x R l); scaling m by s
    for s in (1.0, 2.5):
        gx = L.plucker_transform(g, x * np.r_[1, 1, 1, s, s, s])
        expected = L.plucker_transform(g, L.plucker_project(x) * np.r_[1, 1, 1, s, s, s])
        np.testing.assert_allclose(L.plucker_project(gx), expected, atol=1e-12)


def test_exact_nearest_point_against_quartic_roots(rng):
    x = rng.normal(size=(300, 6)) * 2
    near = L.plucker_nearest(x)
    assert manifold_residual(near) < 1e-12
    for i in range(300):
        p, pb = x[i, :3], x[i, 3:]
        a, b, c = p @ p, p @ pb, pb @ pb
        best = np.inf
        for mu in np.roots([c, -2 * b, a - c * c, 2 * b * c, -b * b]):
            if abs(mu.imag) > 1e-9:
                continue
            d = p - mu.real * pb
            for s in (1, -1):
                l = s * d / np.linalg.norm(d)
                y = np.r_[l, pb - (l @ pb) * l]
                best = min(best, ((y - x[i]) ** 2).sum())
        assert ((near[i] - x[i]) ** 2).sum() == pytest.approx(best, rel=1e-9, abs=1e-12)
    gs = L.plucker_project(x)
    assert np.all(((near - x) ** 2).sum(1) <= ((gs - x) ** 2).sum(1) + 1e-12)


def test_common_normal_closed_form_skew():
    x_axis = rr.Lines.from_point_direction([[0, 0, 0]], [[1, 0, 0]]).plucker
    y_up = rr.Lines.from_point_direction([[5, 0, 1]], [[0, 1, 0]]).plucker
    cn = L.common_normal(x_axis, y_up)
    np.testing.assert_allclose(cn.foot1, [[5, 0, 0]], atol=1e-15)
    np.testing.assert_allclose(cn.foot2, [[5, 0, 1]], atol=1e-15)
    np.testing.assert_allclose(cn.direction, [[0, 0, 1]], atol=1e-15)
    np.testing.assert_allclose(cn.distance, [1.0])
    np.testing.assert_allclose(cn.angle, [np.pi / 2])
    assert not cn.parallel[0] and not cn.intersecting[0]


def test_common_normal_intersecting_parallel_identical():
    a = rr.Lines.from_point_direction([[1, 1, 1]], [[1, 0, 0]]).plucker
    b = rr.Lines.from_point_direction([[1, 1, 1]], [[0, 1, 0]]).plucker
    cn = L.common_normal(a, b)
    assert cn.intersecting[0] and cn.distance[0] == 0.0
    np.testing.assert_allclose(cn.foot1, [[1, 1, 1]], atol=1e-15)
    np.testing.assert_allclose(cn.direction, [[0, 0, 1]], atol=1e-15)  # l1 x l2
    p = rr.Lines.from_point_direction([[0, 2, 0]], [[1, 0, 0]]).plucker
    cn = L.common_normal(a, p, reference=[[7, 0, 0]])
    assert cn.parallel[0]
    np.testing.assert_allclose(cn.foot1, [[7, 1, 1]], atol=1e-15)
    np.testing.assert_allclose(cn.foot2, [[7, 2, 0]], atol=1e-15)
    np.testing.assert_allclose(cn.distance, [np.sqrt(2)])
    np.testing.assert_allclose(cn.angle, [0.0], atol=1e-15)
    cn = L.common_normal(a, -a)  # identical, opposite orientation
    assert cn.parallel[0] and cn.distance[0] == 0.0
    assert abs(cn.direction[0] @ a[0, :3]) < 1e-15
    assert abs(abs(cn.angle[0]) - np.pi) < 1e-15


def test_common_normal_random_is_shortest_and_perpendicular(rng):
    a = rr.Lines.from_point_direction(rng.normal(size=(1000, 3)), rng.normal(size=(1000, 3)))
    b = rr.Lines.from_point_direction(rng.normal(size=(1000, 3)), rng.normal(size=(1000, 3)))
    cn = L.common_normal(a.plucker, b.plucker)
    gap = cn.foot2 - cn.foot1
    assert np.abs((gap * a.direction).sum(1)).max() < 1e-9
    assert np.abs((gap * b.direction).sum(1)).max() < 1e-9
    # the feet lie on their lines
    assert np.abs(np.cross(cn.foot1, a.direction) - a.moment).max() < 1e-9
    assert np.abs(np.cross(cn.foot2, b.direction) - b.moment).max() < 1e-9
    # no pair of points on the lines is closer
    s = rng.normal(size=(1000, 2))
    pa = a.points_at(s[:, 0])
    pb = b.points_at(s[:, 1])
    assert np.all(np.linalg.norm(pa - pb, axis=1) >= cn.distance - 1e-12)
    # twist: rotating l1 by angle about the normal direction gives l2
    from ruledrobot.geometry.se3 import rotation_about_axis

    R = rotation_about_axis(cn.direction, cn.angle)
    np.testing.assert_allclose(np.einsum("nij,nj->ni", R, a.direction), b.direction, atol=1e-12)


def test_transform_moves_points_and_directions(rng):
    lines = rr.Lines.from_point_direction(rng.normal(size=(10, 3)), rng.normal(size=(10, 3)))
    g = random_poses(rng, 1)[0]
    moved = lines.transform(g)
    pts = lines.points_at(np.linspace(-1, 1, 10))
    gp = pts @ g[:3, :3].T + g[:3, 3]
    expected = rr.Lines.from_point_direction(gp, lines.direction @ g[:3, :3].T)
    np.testing.assert_allclose(moved.plucker, expected.plucker, atol=1e-12)
