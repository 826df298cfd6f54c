"""How far a pose misses a UR arm's reach (robot.ik.workspace), checked against the IK."""

from __future__ import annotations

import numpy as np
import pytest

from ruledrobot.robot import load
from ruledrobot.robot.ik.workspace import elbow_distance, reach_excess, reach_margin


@pytest.mark.parametrize("name", ["ur3e", "ur5e", "ur10e"])
def test_excess_is_minus_the_margin_where_a_branch_reaches(name):
    model = load(name).with_base([0.1, -0.2, 0.0, 0.0, 0.0, 0.4])
    rng = np.random.default_rng(3)
    T = model.fk(rng.uniform(-np.pi, np.pi, (3000, 6)))
    T[1000:, :3, 3] *= rng.uniform(0.2, 3.0, (2000, 1))  # many poses out of reach
    sols = model.ik(T)
    ok = ~np.isnan(sols[..., 0])
    excess, kind = reach_excess(model, T)
    np.testing.assert_allclose(excess[ok], -reach_margin(model, sols)[ok], atol=1e-9)
    assert (kind[ok] == 0).all()
    # a branch without a solution misses by a positive distance, and says which way
    assert (excess[~ok] > -1e-9).all() and (kind[~ok] > 0).mean() > 0.99


def test_excess_is_the_distance_a_pose_must_come_closer():
    """A pose 50 mm further out than the stretched arm: the excess says about 50 mm, and
    moving the pose back by a little more makes it reachable, by a little less not."""
    model = load("ur5e")
    q = np.array([0.0, -0.3, 0.0, -1.0, 1.2, 0.4])  # the elbow stretched
    T = model.fk(q)
    assert elbow_distance(model, q) == pytest.approx(0.425 + 0.3922)
    shoulder = np.array([0.0, 0.0, model.d[0]])
    out = T.copy()
    u = T[:3, 3] - shoulder
    u /= np.linalg.norm(u)
    out[:3, 3] += 0.05 * u
    e, kind = reach_excess(model, out)
    b = int(np.argmin(e))
    assert kind[b] == 1 and abs(e[b] - 0.05) < 0.002
    for f, reaches in ((1.05, True), (0.95, False)):
        back = out.copy()
        back[:3, 3] -= f * e[b] * u
        assert np.isnan(model.ik(back)[b, 0]) != reaches
