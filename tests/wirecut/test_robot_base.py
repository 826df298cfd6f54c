"""``[robot] base`` places the whole cell in the world: it never changes the plan.

Every pose of a job is in the robot base frame; the MuJoCo scene puts the arm at
``base`` and the stock at ``base @ stock``.  A job on a turned, raised base must plan
the same joints as on the identity and verify in MuJoCo with the same result.
"""

from __future__ import annotations

import numpy as np
import pytest

from ruledrobot.geometry import se3
from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.plan import make_plan
from ruledrobot.wirecut.report.outcome import plan_outcome
from ruledrobot.wirecut.verify import verify_plan

BASE = [0.3, 0.2, 0.1, 0.0, 0.0, 0.7]  # UR pose vector: metres, rotation vector


@pytest.fixture(scope="module")
def plans(tmp_path_factory):
    d = tmp_path_factory.mktemp("base")
    out = []
    for name, base in (("identity", "[0.0, 0.0, 0.0, 0.0, 0.0, 0.0]"), ("moved", str(BASE))):
        p = d / f"{name}.toml"
        p.write_text(DEMO_JOB.replace("base = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]", f"base = {base}"))
        job = load_job(p)
        planned = make_plan(job)
        out.append((job, planned, verify_plan(planned)))
    return out


def test_the_base_does_not_change_the_planned_joints(plans):
    (_, a, _), (job, b, _) = plans
    np.testing.assert_allclose(job.robot.base, se3.pose_from_ur_vector(BASE))
    np.testing.assert_array_equal(a.motion.timed.q, b.motion.timed.q)
    np.testing.assert_allclose(b.trajectory.meta.base, job.robot.base)
    assert np.allclose(b.model.base, np.eye(4))


def test_the_moved_cell_verifies_like_the_original(plans):
    (_, a, va), (_, b, vb) = plans
    _, verdict_a = plan_outcome(a, va)
    _, verdict_b = plan_outcome(b, vb)
    assert verdict_a.ok and verdict_b.ok, verdict_b.summary()
    assert not vb.collisions
    # the simulated wire follows the rulings as closely in the moved cell
    np.testing.assert_allclose(vb.deviation, va.deviation, atol=2e-5)


def test_the_scene_puts_the_stock_at_base_times_stock(plans):
    import mujoco

    from ruledrobot.sim import Scene

    job, _, _ = plans[1]
    m = mujoco.MjModel.from_xml_string(Scene.from_job(job).mjcf())
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    stock = d.geom("stock")
    want = job.robot.base[:3, :3] @ job.stock.centre + job.robot.base[:3, 3]
    np.testing.assert_allclose(stock.xpos, want, atol=1e-9)
    base = d.body("base")
    np.testing.assert_allclose(base.xpos, job.robot.base[:3, 3], atol=1e-9)
