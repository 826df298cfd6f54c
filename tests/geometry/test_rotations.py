"""The rotation angle (geometry/rotations.py) against scipy's Rotation and the angle a
rotation was built from, near 0, in the middle and near pi."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from ruledrobot.geometry import se3
from ruledrobot.geometry.rotations import angle_between, rotation_angle

#: an angle in [0, pi] spread over the hard ends: tiny, ordinary, within a hair of pi
ANGLES = st.one_of(
    st.floats(0.0, np.pi),
    st.floats(1e-300, 1e-6),
    st.floats(1e-12, 1e-3).map(lambda e: np.pi - e),
)
UNIT = st.tuples(*(st.floats(-1.0, 1.0) for _ in range(3))).filter(
    lambda v: 0.1 < np.linalg.norm(v)
).map(lambda v: np.asarray(v) / np.linalg.norm(v))
SEEDS = st.integers(0, 2**32 - 1)


def _close(got: np.ndarray, want: np.ndarray) -> None:
    """Within a few ulps of the angle, relative near 0, absolute elsewhere."""
    np.testing.assert_allclose(got, want, rtol=1e-13, atol=4e-16)


@settings(max_examples=300, deadline=None)
@given(ANGLES, UNIT)
def test_the_angle_a_rotation_was_built_from(theta: float, u: np.ndarray) -> None:
    """scipy builds R from the rotation vector; its magnitude and our angle agree with
    ``theta`` to rounding, at 1e-300 rad and at pi - 1e-12 too."""
    R = Rotation.from_rotvec(theta * u).as_matrix()
    _close(rotation_angle(R), theta)
    _close(Rotation.from_matrix(R).magnitude(), theta)  # the oracle itself holds there


@settings(max_examples=100, deadline=None)
@given(SEEDS)
def test_between_random_rotations_as_scipy(seed: int) -> None:
    rng = np.random.default_rng(seed)
    A = Rotation.random(50, random_state=rng)
    B = Rotation.random(50, random_state=rng)
    want = (A.inv() * B).magnitude()
    np.testing.assert_allclose(angle_between(A.as_matrix(), B.as_matrix()), want, atol=1e-14)
    # the norm of the rotation vector (quaternion route) is the same number
    rv = se3.rotvec_from_matrix(A.as_matrix().transpose(0, 2, 1) @ B.as_matrix())
    np.testing.assert_allclose(np.linalg.norm(rv, axis=-1), want, atol=1e-14)


@settings(max_examples=100, deadline=None)
@given(SEEDS, ANGLES, UNIT)
def test_invariances(seed: int, theta: float, u: np.ndarray) -> None:
    """Symmetric, the same in any world frame and for any body frame: the angle of
    ``A^T B`` where ``B = A R`` is the angle of ``R``."""
    rng = np.random.default_rng(seed)
    A, C, D = Rotation.random(3, random_state=rng).as_matrix()
    R = Rotation.from_rotvec(theta * u).as_matrix()
    B = A @ R
    _close(angle_between(A, B), theta)
    _close(angle_between(B, A), theta)
    np.testing.assert_allclose(angle_between(C @ A, C @ B), theta, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(angle_between(A @ D, B @ D), theta, rtol=1e-12, atol=1e-14)


def test_trace_arccos_is_not_enough_near_zero() -> None:
    """Why the sine part: ``arccos((trace - 1) / 2)`` reads 1e-9 rad as 0 (or 1.5e-8)."""
    R = Rotation.from_rotvec([1e-9, 0.0, 0.0]).as_matrix()
    old = np.arccos(np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0))
    assert abs(old - 1e-9) > 1e-9 * 0.5
    assert abs(rotation_angle(R) - 1e-9) < 1e-22


def test_batches_broadcast_and_poses_read_by_their_rotation(rng) -> None:
    A = Rotation.random(4, random_state=rng).as_matrix()
    B = Rotation.random(3, random_state=rng).as_matrix()
    got = angle_between(A[:, None], B[None])
    assert got.shape == (4, 3)
    for i in range(4):
        for j in range(3):
            np.testing.assert_allclose(got[i, j], angle_between(A[i], B[j]), atol=0)
    T = np.tile(np.eye(4), (3, 1, 1))
    T[:, :3, :3], T[:, :3, 3] = B, rng.normal(size=(3, 3))
    np.testing.assert_array_equal(rotation_angle(T), rotation_angle(B))
    assert rotation_angle(np.eye(3)) == 0.0


@pytest.mark.parametrize("shape", [(3,), (3, 4), (2, 2, 2)])
def test_bad_shapes_are_refused(shape: tuple[int, ...]) -> None:
    with pytest.raises(ValueError, match=r"R: expected rotation matrices"):
        rotation_angle(np.zeros(shape))
