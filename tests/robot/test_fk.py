"""Forward kinematics and the Jacobian against independent implementations."""

from __future__ import annotations

import numpy as np
import pytest

from ruledrobot.geometry import se3
from ruledrobot.robot import MODEL_NAMES, RobotModel, load

from .helpers import dh_fk_reference


@pytest.mark.parametrize("name", MODEL_NAMES)
def test_fk_matches_product_of_dh_matrices(name: str, rng: np.random.Generator) -> None:
    m = load(name)
    q = rng.uniform(-2 * np.pi, 2 * np.pi, size=(4, 5, 6))
    T = m.fk(q)
    assert T.shape == (4, 5, 4, 4) and T.dtype == np.float64
    np.testing.assert_allclose(T, dh_fk_reference(q, m.d, m.a, m.alpha), atol=1e-14)
    # a single configuration gives a single pose
    assert m.fk(q[0, 0]).shape == (4, 4)


def test_ur5e_zero_configuration() -> None:
    """At q = 0 the UR5e flange sits at (a2 + a3, -(d4 + d6), d1 - d5), tool z along -y."""
    T = load("ur5e").fk(np.zeros(6))
    np.testing.assert_allclose(T[:3, 3], [-0.8172, -0.2329, 0.0628], atol=1e-12)
    np.testing.assert_allclose(T[:3, 2], [0, -1, 0], atol=1e-15)


def test_fk_with_base_and_tool(rng: np.random.Generator) -> None:
    m = load("ur10e")
    base = se3.pose_from_ur_vector([0.5, -0.2, 0.8, 0.1, 0.2, 2.0])
    tool = se3.pose_from_ur_vector([0.01, 0.02, 0.25, 0.3, -0.1, 0.0])
    mt = m.with_base(base).with_tool(tool)
    q = rng.uniform(-np.pi, np.pi, size=(50, 6))
    ref = base @ dh_fk_reference(q, m.d, m.a, m.alpha) @ tool
    np.testing.assert_allclose(mt.fk(q), ref, atol=1e-14)


def test_fk_with_theta_offsets_and_long_batches(rng: np.random.Generator) -> None:
    m = load("ur5e")
    off = rng.uniform(-1, 1, 6)
    mo = RobotModel.from_dh(m.d, m.a, m.alpha, theta_offset=off)
    q = rng.uniform(-np.pi, np.pi, size=(20000, 6))  # several chunks
    T = mo.fk(q)
    sel = rng.choice(20000, 40, replace=False)
    np.testing.assert_allclose(T[sel], dh_fk_reference(q[sel], m.d, m.a, m.alpha, off), atol=1e-14)
    np.testing.assert_allclose(T, m.fk(q + off), atol=1e-14)


def test_fk_general_twist_angles(rng: np.random.Generator) -> None:
    d, a, alpha = rng.normal(size=(3, 7))
    m = RobotModel.from_dh(d, a, alpha)
    q = rng.normal(size=(30, 7))
    np.testing.assert_allclose(m.fk(q), dh_fk_reference(q, d, a, alpha), atol=1e-13)


def test_fk_rejects_bad_joints() -> None:
    m = load("ur5e")
    with pytest.raises(ValueError, match=r"q: expected an array of shape \(\.\.\., 6\)"):
        m.fk(np.zeros((3, 5)))
    q = np.zeros((3, 6))
    q[2, 4] = np.nan
    with pytest.raises(ValueError, match=r"q\[2\]"):
        m.fk(q)


def _twist_fd(m: RobotModel, q: np.ndarray, h: float = 1e-6) -> np.ndarray:
    """Central finite-difference Jacobian [v; omega] of the TCP pose."""
    J = np.empty((6, 6))
    for i in range(6):
        dq = np.zeros(6)
        dq[i] = h
        Tp, Tm = m.fk(q + dq), m.fk(q - dq)
        J[:3, i] = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
        # angular velocity in the world frame: log(R+ R-^T) / 2h
        J[3:, i] = se3.rotvec_from_matrix(Tp[:3, :3] @ Tm[:3, :3].T) / (2 * h)
    return J


def test_jacobian_matches_finite_differences(rng: np.random.Generator) -> None:
    m = load("ur5e").with_base([0.2, 0.1, 0.5, 0.3, 0, 1.0]).with_tool([0, 0.05, 0.2, 0.2, 0, 0])
    q = rng.uniform(-np.pi, np.pi, size=(5, 6))
    J = m.jacobian(q)
    assert J.shape == (5, 6, 6)
    for k in range(5):
        np.testing.assert_allclose(J[k], _twist_fd(m, q[k]), atol=1e-8)


@pytest.mark.parametrize("name", MODEL_NAMES)
def test_det_jacobian_is_the_product_of_the_singularity_factors(
    name: str, rng: np.random.Generator
) -> None:
    """det J = a2 a3 sin q3 sin q5 (a2 c2 + a3 c23 + d5 s234): the documented measure."""
    m = load(name).with_tool([0.1, 0, 0.3, 0, 0.5, 0])  # det J does not depend on the TCP
    q = rng.uniform(-np.pi, np.pi, size=(200, 6))
    det = np.linalg.det(m.jacobian(q))
    g = m.ur_geometry
    s = g.a2 * np.cos(q[:, 1]) + g.a3 * np.cos(q[:, 1] + q[:, 2]) + g.d5 * np.sin(q[:, 1:4].sum(1))
    np.testing.assert_allclose(det, g.a2 * g.a3 * np.sin(q[:, 2]) * np.sin(q[:, 4]) * s, atol=1e-12)
    f = m.singularity_factors(q)
    np.testing.assert_allclose(f[:, 0] * f[:, 1] * f[:, 2], np.abs(det / (g.a2 * g.a3)), atol=1e-12)
    meas = m.singularity_measure(q)
    assert np.all((meas >= 0) & (meas <= 1))
    scale = abs(g.a2 * g.a3) * (abs(g.a2) + abs(g.a3) + g.d5)
    np.testing.assert_allclose(meas, np.abs(det) / scale)


def test_within_limits() -> None:
    m = load("ur5e").with_limits(lower=-np.pi, upper=np.pi)
    q = np.zeros((3, 6))
    q[1, 2] = 3.5
    assert m.within_limits(q).tolist() == [True, False, True]


def test_link_points_are_the_dh_skeleton(rng) -> None:
    from ruledrobot.geometry import se3
    from ruledrobot.robot import load

    from .helpers import dh_matrix

    model = load("ur10e").with_base(se3.pose_from_ur_vector([0.1, 0.2, 0.3, 0.1, -0.2, 0.3]))
    q = rng.uniform(-3.0, 3.0, size=(20, 6))
    pts = model.link_points(q)
    assert pts.shape == (20, 13, 3)
    for n in range(20):
        T = model.base.copy()
        expected = [T[:3, 3]]
        for j in range(6):
            expected.append(T[:3, 3] + model.d[j] * T[:3, 2])  # along the previous z by d
            T = T @ dh_matrix(q[n, j] + model.theta_offset[j], model.d[j], model.a[j],
                              model.alpha[j])  # fmt: skip
            expected.append(T[:3, 3])
        np.testing.assert_allclose(pts[n], expected, atol=1e-12)
    np.testing.assert_allclose(pts[:, -1], model.fk(q)[:, :3, 3], atol=1e-12)
