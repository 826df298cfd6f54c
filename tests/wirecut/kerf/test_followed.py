"""The face as servoj follows the plan (``face_followed``), against the emulator's own arm.

The plan judges the part's face twice: on its motion (``face_error``) and on the motion
as the controller's servo follows it (``faces_followed``: the joints through
:func:`~ruledrobot.robot.motion.servo.servo_track`).  The independent truth here is the
emulator's arm (:class:`~ruledrobot.ursim.arm.backend.KinematicBackend`), which steps its
own first-order tracker once per control period under servoj, as a run streams the
samples: the wire it puts in the foam must be judged the same.
"""

from __future__ import annotations

import numpy as np
import pytest

from ruledrobot.robot.motion.servo import SERVO_GAIN, SERVO_LOOKAHEAD
from ruledrobot.robot.motion.trajectory import model_for
from ruledrobot.ursim.arm.backend import KinematicBackend
from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.plan import make_plan
from ruledrobot.wirecut.report.outcome import plan_outcome

from .panel import write_corner, write_panel


def _emulated_arm(traj) -> np.ndarray:
    """(M, 6) the joints of the emulator's arm when each sample is streamed with servoj."""
    arm = KinematicBackend(model_for(traj.meta), max_acceleration=1e6)  # the law, no limits
    arm.reset(traj.q[0])
    out = np.empty_like(traj.q)
    for k, q in enumerate(traj.q):
        arm.servo(q, SERVO_LOOKAHEAD, SERVO_GAIN)
        arm.step(traj.meta.control_period)
        out[k] = arm.state().q
    return out


@pytest.mark.parametrize("shape", ["panel", "corner"])
def test_the_followed_face_is_the_emulated_arms(tmp_path, shape):
    heat = 'heat = { output = "analog:0", mode = "constant_kerf", full_scale = 200.0 }'
    path = write_panel(tmp_path) if shape == "panel" else write_corner(tmp_path, heat)
    plan = make_plan(load_job(path))
    traj = plan.trajectory
    assert traj is not None, plan.reasons
    followed = plan.measured.faces_followed["cut"]
    q = _emulated_arm(traj)
    wis = traj.meta.cut.measure(traj.t, model_for(traj.meta).fk(q))
    truth = traj.face_errors(wis)["cut"]
    np.testing.assert_allclose(followed.error, truth.error, rtol=0, atol=1e-6)
    # the verdict judges its finite part (a burn is face_error's) against the tolerance
    finite = truth.error[np.isfinite(truth.error)]
    _, verdict = plan_outcome(plan, None)
    check = verdict["face_followed"]
    assert check.gating and check.value == pytest.approx(finite.max() * 1e3, abs=1e-6)
    assert check.ok is bool(finite.max() <= truth.tolerance)


def test_a_failing_followed_face_says_where_and_what_to_change():
    from ruledrobot.wirecut.report.outcome import _followed_detail

    ok = _followed_detail((0.05, 10), 0.1, 1.234, "cut")
    bad = _followed_detail((0.2, 10), 0.1, 1.234, "cut")
    assert ok == "worst at t = 1.234 s (cut)"
    assert bad.startswith(ok) and "feed_speed" in bad and "0.03 s" in bad  # the lag said
