"""A job on a calibrated robot plans with, and records, that robot's kinematics."""

from __future__ import annotations

import numpy as np
import pytest

from ruledrobot.io.calibration import save_calibration
from ruledrobot.robot import load, model_for, random_calibration
from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.planner import plan


def _job(tmp_path, cal_text: str):
    (tmp_path / "job.toml").write_text(
        DEMO_JOB.replace("speed_scale = 1.0", f"speed_scale = 1.0\n{cal_text}")
    )
    return load_job(tmp_path / "job.toml")


def test_the_trajectory_carries_the_calibration_it_was_planned_with(tmp_path):
    cal = random_calibration("ur5e", seed=3)
    save_calibration(tmp_path / "robot.calib.json", cal)
    job = _job(tmp_path, 'calibration = "robot.calib.json"')
    assert job.robot_model().calibration is not None
    res = plan(job, None, simulate=False)
    traj = res.trajectory
    kin = traj.meta.kinematics
    assert kin.source == cal.source and kin.controller_checksum == cal.checksum
    np.testing.assert_array_equal(kin.dh, cal.dh())
    robot = model_for(traj.meta)
    assert robot.calibration is not None
    # the TCP column is the calibrated FK of the joints, not the nominal one
    assert traj.tcp_error(robot)[0] < 1e-9
    nominal = load("ur5e").with_tool(traj.meta.tcp_offset)
    assert traj.tcp_error(nominal)[0] > 1e-4


def test_a_calibration_of_another_robot_is_refused_naming_the_field(tmp_path):
    save_calibration(tmp_path / "ur10e.calib.json", random_calibration("ur10e", seed=1))
    with pytest.raises(ValueError, match=r"\[robot\] calibration: .*a ur10e, the job's robot is"):
        _job(tmp_path, 'calibration = "ur10e.calib.json"')
    with pytest.raises(ValueError, match=r"\[robot\] calibration"):
        _job(tmp_path, 'calibration = "missing.json"')
