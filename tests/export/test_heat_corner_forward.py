"""A corner stop forwarded to the emulator (issue 33): a 40 degree corner in the block cut
with ``constant_kerf``, planned, then run on the embedded emulator by the forwarded
program.  The arm under servoj trails its command by the servo's time constant; the plan
waits at the corner until it settles (``CORNER_DWELL``) and the run sets the heat as the
arm reaches each sample (``export.heat.servo_levels``), so the run's verdict, computed
from the recorded motion and the recorded analog output, finds the face as the plan did.
(Before both: the arm rounded the corner by 0.50 mm and face_error was 0.32 mm.)"""

from __future__ import annotations

import numpy as np
import pytest

from ruledrobot.export import run_trajectory
from ruledrobot.robot.motion.servo import servo_settle_time
from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.plan import make_plan
from tests.support.emulators import start_emulator
from tests.wirecut.kerf.panel import write_corner

pytest.importorskip("rtde_control")

HEAT = ('heat = { output = "analog:0", mode = "constant_kerf", full_scale = 100.0, '
        "preheat = 0.5 }")


def test_a_forwarded_corner_stop_cuts_the_face_the_plan_predicts(request, tmp_path):
    plan = make_plan(load_job(write_corner(tmp_path, HEAT)))
    traj = plan.trajectory
    assert traj is not None, plan.reasons
    stop = np.flatnonzero(plan.motion.corner_stop)
    assert traj.t[stop[-1]] - traj.t[stop[0]] >= servo_settle_time()  # the plan waits
    planned = traj.face_errors()["cut"]
    # the heated part only (pre-heat to the lead-out's end): 5.6 s of motion
    heated = [p for p in traj.meta.phases if p.name in ("preheat", "lead_out")]
    part = traj.sliced(heated[0].start, heated[-1].stop)
    emu = start_emulator(request.node.nodeid, model="ur5e", unlock_delay=0.0, q0=part.q[0])
    try:
        res = run_trajectory(part, emu.host, actual_path=tmp_path / "actual.csv")
    finally:
        emu.close()
    assert res.status == "completed", res.message
    checks = {c.name: c for c in res.run_verdict.checks}
    face, wire = checks["face_error"], checks["wire_deviation"]
    print(f"plan face_error {1e3 * planned.worst:.3f} mm; run face_error {face.value:.3f} mm "
          f"({face.detail}); wire deviation {wire.value:.3f} mm; hot dwell "
          f"{checks['hot_dwell'].value:.3f} s")  # fmt: skip
    assert face.gating and face.ok, face.detail
    assert face.value < 0.06  # within the tolerance with room: the plan's 0.023 mm and the servo
    assert wire.ok and wire.value < 0.1
    assert checks["hot_dwell"].ok
    assert res.run_verdict.ok, [c.name for c in res.run_verdict.checks if not c.ok]
