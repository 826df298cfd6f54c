"""nearest_ik: the closed-form solution of a pose nearest given joints (robot.arm.nearest)."""

from __future__ import annotations

import numpy as np

from ruledrobot.robot import load
from ruledrobot.robot.arm.nearest import nearest_ik


def test_the_joints_of_a_pose_come_back_from_near_them(rng):
    m = load("ur5e")
    for _ in range(20):
        q = rng.uniform(-2.5, 2.5, 6)
        q[4] = rng.uniform(0.3, 2.5)  # away from the wrist singularity
        got = nearest_ik(m, m.fk(q), q + rng.uniform(-0.05, 0.05, 6))
        assert got is not None
        np.testing.assert_allclose(got, q, atol=1e-9)


def test_the_2pi_representative_nearest_the_given_joints():
    m = load("ur5e")
    q = np.array([0.3, -1.2, 1.1, -1.4, 1.2, -0.4])
    near = q.copy()
    near[5] += 2.0 * np.pi  # inside the +-2 pi limits of the wrist
    got = nearest_ik(m, m.fk(q), near)
    assert got is not None
    np.testing.assert_allclose(got, near, atol=1e-9)
    near[5] += 2.0 * np.pi  # nearest beyond the limits: none
    assert nearest_ik(m, m.fk(q), near) is None


def test_none_out_of_reach():
    m = load("ur5e")
    q = np.array([0.3, -1.2, 1.1, -1.4, 1.2, 0.4])
    P = m.fk(q)
    P[:3, 3] += [5.0, 0.0, 0.0]
    assert nearest_ik(m, P, q) is None
