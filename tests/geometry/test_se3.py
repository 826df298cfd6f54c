"""SE(3): exp/log, screw geodesic, conversions — against scipy and pytransform3d."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.linalg import expm, logm

from ruledrobot.geometry import se3

from ..conftest import random_poses


def hat(xi: np.ndarray) -> np.ndarray:
    w, v = xi[:3], xi[3:]
    X = np.zeros((4, 4))
    X[:3, :3] = [[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]]
    X[:3, 3] = v
    return X


def test_exp_matches_matrix_exponential(rng):
    for xi in rng.normal(size=(20, 6)):
        np.testing.assert_allclose(se3.exp(xi), expm(hat(xi)), atol=1e-12)


def test_geodesic_matches_expm_logm(rng):
    A, B = random_poses(rng, 30), random_poses(rng, 30)
    for a, b in zip(A, B, strict=True):
        D = np.real(logm(np.linalg.inv(a) @ b))
        for t in (-0.7, 0.25, 0.5, 1.0, 1.9):
            np.testing.assert_allclose(se3.geodesic(a, b, t), a @ expm(t * D), atol=1e-10)


def test_geodesic_equals_pytransform3d_sclerp(rng):
    ptr = pytest.importorskip("pytransform3d.trajectories")
    n = 2000
    A, B = random_poses(rng, n), random_poses(rng, n)
    t = rng.uniform(-0.5, 1.5, size=n)
    dqa = ptr.dual_quaternions_from_transforms(A)
    dqb = ptr.dual_quaternions_from_transforms(B)
    ref = ptr.transforms_from_dual_quaternions(ptr.dual_quaternions_sclerp(dqa, dqb, t))
    np.testing.assert_allclose(se3.geodesic(A, B, t), ref, atol=1e-9)


def test_geodesic_endpoints_symmetry_and_invariance(rng):
    A, B = random_poses(rng, 200), random_poses(rng, 200)
    np.testing.assert_allclose(se3.geodesic(A, B, 0.0), A, atol=1e-12)
    np.testing.assert_allclose(se3.geodesic(A, B, 1.0), B, atol=1e-12)
    t = 0.3
    np.testing.assert_allclose(se3.geodesic(B, A, 1 - t), se3.geodesic(A, B, t), atol=1e-10)
    g, h = random_poses(rng, 2)
    np.testing.assert_allclose(se3.geodesic(g @ A, g @ B, t), g @ se3.geodesic(A, B, t), atol=1e-10)
    np.testing.assert_allclose(se3.geodesic(A @ h, B @ h, t), se3.geodesic(A, B, t) @ h, atol=1e-10)


def test_geodesic_broadcasts_and_many_agrees(rng):
    A = random_poses(rng, 5)
    B = random_poses(rng, 1)[0]
    t = np.linspace(0, 1, 5)
    out = se3.geodesic(A, B, t)
    assert out.shape == (5, 4, 4)
    for i in range(5):
        np.testing.assert_allclose(out[i], se3.geodesic(A[i], B, t[i]), atol=1e-14)
    many = se3.geodesic_many(A, np.broadcast_to(B, A.shape), [0.2, 1.5])
    np.testing.assert_allclose(many[1], se3.geodesic(A, B, 1.5), atol=1e-14)


def test_geodesic_is_shortest_screw(rng):
    """The rotation angle of every step of the geodesic is at most pi."""
    A, B = random_poses(rng, 500), random_poses(rng, 500)
    mid = se3.geodesic(A, B, 0.5)
    half = se3.log(se3.inverse(A) @ mid)
    full = se3.log(se3.inverse(A) @ B)
    np.testing.assert_allclose(2 * half, full, atol=1e-9)
    assert np.all(np.linalg.norm(full[:, :3], axis=1) <= np.pi + 1e-12)


angles = st.floats(0.0, np.pi - 1e-7)
unit = arrays(np.float64, 3, elements=st.floats(-1, 1)).filter(lambda v: np.linalg.norm(v) > 0.1)
trans = arrays(np.float64, 3, elements=st.floats(-5, 5))


@given(axis=unit, angle=angles, v=trans)
def test_log_exp_round_trip(axis, angle, v):
    w = axis / np.linalg.norm(axis) * angle
    xi = np.concatenate([w, v])
    np.testing.assert_allclose(se3.log(se3.exp(xi)), xi, atol=1e-9)


@given(axis=unit, eps=st.floats(0.0, 1e-6), v=trans)
def test_log_exp_near_pi(axis, eps, v):
    """Near pi the logarithm is continuous up to the axis sign; exp(log) is exact."""
    w = axis / np.linalg.norm(axis) * (np.pi - eps)
    T = se3.exp(np.concatenate([w, v]))
    np.testing.assert_allclose(se3.exp(se3.log(T)), T, atol=1e-9)
    assert np.linalg.norm(se3.log(T)[:3]) == pytest.approx(np.pi - eps, abs=1e-9)


@given(axis=unit, angle=st.floats(0.0, 1e-9), v=trans)
def test_tiny_rotations(axis, angle, v):
    w = axis / np.linalg.norm(axis) * angle
    xi = np.concatenate([w, v])
    T = se3.exp(xi)
    np.testing.assert_allclose(se3.log(T), xi, atol=1e-12)
    A = np.eye(4)
    np.testing.assert_allclose(se3.geodesic(A, T, 0.5)[:3, 3], 0.5 * T[:3, 3], atol=1e-9)


@given(p=trans, q=trans, t=st.floats(-3, 3))
def test_pure_translations(p, q, t):
    A, B = np.eye(4), np.eye(4)
    A[:3, 3], B[:3, 3] = p, q
    G = se3.geodesic(A, B, t)
    np.testing.assert_allclose(G[:3, :3], np.eye(3), atol=1e-15)
    np.testing.assert_allclose(G[:3, 3], p + t * (q - p), atol=1e-12)


def test_exactly_pi_rotation():
    T = se3.exp(np.array([np.pi, 0, 0, 0.1, 0.2, 0.3]))
    np.testing.assert_allclose(se3.exp(se3.log(T)), T, atol=1e-12)
    G = se3.geodesic(np.eye(4), T, 0.5)
    assert abs(abs(se3.log(G)[0]) - np.pi / 2) < 1e-12


def test_conversions_round_trip(rng):
    T = random_poses(rng, 100)
    np.testing.assert_allclose(se3.pose_from_ur_vector(se3.ur_vector_from_pose(T)), T, atol=1e-12)
    q, p = se3.quaternion_from_pose(T)
    assert np.all(q[:, 0] >= 0)
    np.testing.assert_allclose(se3.pose_from_quaternion(q, p), T, atol=1e-12)
    rv = se3.rotvec_from_matrix(T[:, :3, :3])
    assert np.all(np.linalg.norm(rv, axis=1) <= np.pi + 1e-12)
    np.testing.assert_allclose(se3.pose_from_rotvec(rv, p), T, atol=1e-12)
    np.testing.assert_allclose(se3.inverse(T) @ T, np.broadcast_to(np.eye(4), T.shape), atol=1e-12)
    np.testing.assert_allclose(se3.matrix_from_qt(se3.qt_from_matrix(T)), T, atol=1e-12)


def test_rotvec_near_pi_is_stable():
    for eps in (0.0, 1e-12, 1e-8):
        axis = np.array([1.0, -2.0, 0.5]) / np.linalg.norm([1.0, -2.0, 0.5])
        R = se3.rotation_about_axis(axis, np.pi - eps)
        rv = se3.rotvec_from_matrix(R)
        np.testing.assert_allclose(
            se3.rotation_about_axis(rv / np.linalg.norm(rv), np.linalg.norm(rv)), R, atol=1e-12
        )


def test_validate_poses_names_the_item():
    T = np.broadcast_to(np.eye(4), (3, 4, 4)).copy()
    T[1, 0, 0] = 2.0
    with pytest.raises(ValueError, match=r"poses\[1\].*orthonormal"):
        se3.validate_poses(T)
    T = np.broadcast_to(np.eye(4), (3, 4, 4)).copy()
    T[2, 0, 3] = np.nan
    with pytest.raises(ValueError, match=r"poses\[2\].*NaN"):
        se3.validate_poses(T)
    T = np.broadcast_to(np.eye(4), (3, 4, 4)).copy()
    T[0, :3, :3] = np.diag([1.0, 1.0, -1.0])
    with pytest.raises(ValueError, match=r"poses\[0\].*reflection"):
        se3.validate_poses(T)
    with pytest.raises(ValueError, match=r"expected an array of shape"):
        se3.validate_poses(np.eye(3))
