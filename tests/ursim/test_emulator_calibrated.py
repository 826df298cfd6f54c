"""The calibrated emulator: a robot with its own factory calibration.

It serves the calibration's KinematicsInfo (bit for bit) on the primary interface and
uses the calibrated arm for everything it reports and does: actual and target TCP
pose, getForwardKinematics / getInverseKinematics, moveL / moveJ_IK / servoL targets,
path moves.  Without a calibration it is the nominal arm; another model's calibration
is refused before anything starts.
"""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from ruledrobot.geometry.se3 import pose_from_ur_vector, ur_vector_from_pose
from ruledrobot.io.calibration import save_calibration
from ruledrobot.protocol.primary import PRIMARY_PORT, SECONDARY_PORT, read_kinematics_info
from ruledrobot.robot import load, random_calibration
from ruledrobot.robot.motion.servo import servo_time_constant
from ruledrobot.ursim import DEFAULT_Q, Emulator, ThreadedEmulator
from tests.support.emulators import UR, _address, start_emulator
from tests.support.processes import popen_as_from_a_terminal

pytest.importorskip("rtde_control")

CAL = random_calibration("ur5e", 11)
ARM = load("ur5e", calibration=CAL)
NOM = load("ur5e")
TOOL = [0.0, 0.01, 0.15, 0.0, 0.0, 0.2]


def _pose_err(a, b) -> float:
    """Largest entry of the difference of two UR pose vectors as 4x4 matrices."""
    A, B = pose_from_ur_vector(np.asarray(a, float)), pose_from_ur_vector(np.asarray(b, float))
    return float(np.max(np.abs(A - B)))


def _same_bits(info, cal) -> bool:
    cols = (("theta", "theta_offset"), ("a", "a"), ("d", "d"), ("alpha", "alpha"))
    return all(np.asarray(getattr(info, k)).tobytes() == np.asarray(getattr(cal, j)).tobytes()
               for k, j in cols) and tuple(info.checksum) == tuple(cal.checksum) and (
        info.calibration_status == cal.status)  # fmt: skip


def _settle(r, timeout: float = 3.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if max(abs(v) for v in r.getActualQd()) < 1e-9:
            return
        time.sleep(0.01)


@pytest.fixture
def calibrated(request: pytest.FixtureRequest):
    emu = start_emulator(request.node.nodeid, model="ur5e", calibration=CAL, unlock_delay=0.0)
    try:
        yield emu
    finally:
        emu.close()


@pytest.fixture
def cur(calibrated: Emulator):
    u = UR(calibrated.host)
    try:
        yield u
    finally:
        u.release()


def test_random_calibration_is_of_realistic_size() -> None:
    q = np.array(DEFAULT_Q)
    gap = np.linalg.norm(ARM.fk(q)[:3, 3] - NOM.fk(q)[:3, 3])
    assert 5e-4 < gap < 0.03, gap  # millimetres: what the tests below must see


def test_kinematics_info_is_the_calibration_bit_for_bit(calibrated: Emulator, tmp_path) -> None:
    for port in (PRIMARY_PORT, SECONDARY_PORT):
        info, version = read_kinematics_info(calibrated.host, port)
        assert _same_bits(info, CAL)
        assert version is not None and version.text == "5.11.1.108318"
    assert _same_bits(calibrated.kinematics_info, CAL)
    assert calibrated.calibration is not None and calibrated.calibration.source == CAL.source
    # from a ruledrobot.calibration/1 file: the same bits (17 significant digits)
    path = save_calibration(tmp_path / "cal.json", CAL)
    emu = Emulator(_address("cal-file", 0), "ur5e", calibration=str(path), in_process=True)
    with emu:
        info, _ = read_kinematics_info(emu.host, PRIMARY_PORT)
    assert _same_bits(info, CAL)


def test_everything_reported_uses_the_calibrated_arm(calibrated: Emulator, cur: UR) -> None:
    r, c = cur.r, cur.c
    # actual / target TCP pose = calibrated FK(q) . TCP
    q = np.array(r.getActualQ())
    assert _pose_err(r.getActualTCPPose(), ur_vector_from_pose(ARM.fk(q))) < 1e-9
    assert _pose_err(r.getActualTCPPose(), ur_vector_from_pose(NOM.fk(q))) > 5e-4
    assert c.setTcp(TOOL)
    arm = ARM.with_tool(TOOL)
    time.sleep(0.05)
    q = np.array(r.getActualQ())
    assert _pose_err(r.getActualTCPPose(), ur_vector_from_pose(arm.fk(q))) < 1e-9
    assert _pose_err(r.getTargetTCPPose(), ur_vector_from_pose(arm.fk(r.getTargetQ()))) < 1e-9
    # getForwardKinematics / getInverseKinematics agree with the calibrated model
    rng = np.random.default_rng(5)
    for _ in range(5):
        qk = np.array(DEFAULT_Q) + rng.uniform(-0.5, 0.5, 6)
        fk = c.getForwardKinematics(qk.tolist(), TOOL)
        assert _pose_err(fk, ur_vector_from_pose(arm.fk(qk))) < 1e-12
        assert _pose_err(c.getForwardKinematics(qk.tolist()), fk) < 1e-12  # the TCP set
        ik = np.array(c.getInverseKinematics(fk, (qk + rng.uniform(-0.05, 0.05, 6)).tolist()))
        np.testing.assert_allclose(ik, qk, atol=1e-9)  # the solution nearest qnear
        assert _pose_err(ur_vector_from_pose(arm.fk(ik)), fk) < 1e-9
    np.testing.assert_allclose(c.getInverseKinematics(r.getActualTCPPose()), q, atol=1e-9)
    # moveL: a straight line of the calibrated TCP, ending on the target
    p0 = np.array(r.getActualTCPPose())
    target = p0 + np.array([0.08, -0.05, 0.04, 0.0, 0.0, 0.0])
    assert c.moveL(target.tolist(), 0.25, 1.5, True)
    seen = []
    while c.getAsyncOperationProgress() >= 0:
        seen.append(arm.fk(np.array(r.getActualQ()))[:3, 3])
        time.sleep(0.01)
    _settle(r)
    assert _pose_err(r.getActualTCPPose(), target) < 1e-8
    assert _pose_err(ur_vector_from_pose(arm.fk(r.getActualQ())), target) < 1e-8
    u = (target[:3] - p0[:3]) / np.linalg.norm(target[:3] - p0[:3])
    off = [np.linalg.norm((p - p0[:3]) - ((p - p0[:3]) @ u) * u) for p in seen]
    assert len(off) > 20 and max(off) < 1e-6, max(off)  # nominal IK would be mm off the line
    # moveJ_IK
    back = p0 + np.array([0.0, 0.03, -0.02, 0.0, 0.05, 0.0])
    assert c.moveJ_IK(back.tolist(), 1.0, 2.0)
    _settle(r)
    assert _pose_err(r.getActualTCPPose(), back) < 1e-8
    # servoL at 125 Hz towards a target, then held: the calibrated TCP gets there
    start = np.array(r.getActualTCPPose())
    goal = start + np.array([0.03, 0.02, 0.0, 0.0, 0.0, 0.0])
    for k in range(1, 126):
        t0 = c.initPeriod()
        x = start + (goal - start) * min(1.0, k / 100)
        assert c.servoL(x.tolist(), 0.5, 0.5, 0.008, 0.03, 2000)  # filter: tau 30 ms
        c.waitPeriod(t0)
    time.sleep(25 * servo_time_constant(0.03, 2000))  # settled: e^-25 of 36 mm, 5e-13 m
    assert _pose_err(r.getActualTCPPose(), goal) < 1e-9
    assert c.servoStop()
    # a path move: through the waypoints (6-digit text in the re-uploaded script)
    p1 = np.array(r.getActualTCPPose())
    corners = [p1 + np.array([0.04, 0, 0, 0, 0, 0]), p1 + np.array([0.04, 0.04, 0, 0, 0, 0]), p1]
    assert c.moveL([[*w, 0.25, 1.5, 0.0] for w in corners])
    _settle(r)
    assert _pose_err(r.getActualTCPPose(), p1) < 2e-5
    assert c.isProgramRunning()
    stats = calibrated.stats()
    assert stats["tick_errors"] == 0 and stats["resyncs"] == 0, stats


def test_nominal_without_a_calibration(emulator: Emulator, ur: UR) -> None:
    info, _ = read_kinematics_info(emulator.host, PRIMARY_PORT)
    for k, j in (("theta", "theta_offset"), ("a", "a"), ("d", "d"), ("alpha", "alpha")):
        assert getattr(info, k).tobytes() == np.asarray(getattr(NOM, j)).tobytes()
    assert info.checksum == (0,) * 6 and info.calibration_status == 2
    assert emulator.calibration is None
    q = np.array(ur.r.getActualQ())
    assert _pose_err(ur.r.getActualTCPPose(), ur_vector_from_pose(NOM.fk(q))) < 1e-12
    fk = ur.c.getForwardKinematics(q.tolist())
    assert _pose_err(fk, ur_vector_from_pose(NOM.fk(q))) < 1e-12


def test_the_elbow_is_the_arm_s_not_the_dh_frame_s(request: pytest.FixtureRequest) -> None:
    emu = ThreadedEmulator(_address(request.node.nodeid, 0), "ur5e", calibration=CAL,
                           realtime=False)  # fmt: skip
    elbow = np.array(emu.controller.values["elbow_position"])
    nominal = NOM.link_points(np.array(DEFAULT_Q))  # the nominal skeleton
    assert np.min(np.linalg.norm(nominal - elbow, axis=1)) < 0.03  # the real elbow, not 100 m off
    assert abs(np.linalg.norm(elbow)) < 1.0


def test_another_model_s_calibration_is_refused(tmp_path: Path) -> None:
    other = random_calibration("ur10e", 1)
    with pytest.raises(ValueError, match=r"calibration of a ur10e.*the emulator is a ur5e"):
        Emulator(_address("refused", 0), "ur5e", calibration=other)  # before any child starts
    with pytest.raises(ValueError, match=r"calibration of a ur10e.*the emulator is a ur5e"):
        ThreadedEmulator(_address("refused", 1), "ur5e", calibration=other)
    path = save_calibration(tmp_path / "ur10e.json", other)
    with pytest.raises(ValueError, match=r"ur10e\.json: a calibration of a ur10e"):
        Emulator(_address("refused", 2), "ur5e", calibration=path)

    from typer.testing import CliRunner

    from ruledrobot.cli import app

    host = _address("refused-cli", 0)
    runner = CliRunner()
    for arg, message in ((str(path), "ur10e.json: a calibration of a ur10e"),
                         ("random:x", "random:SEED needs a seed"),
                         (str(tmp_path / "missing.json"), "no such calibration file")):  # fmt: skip
        res = runner.invoke(app, ["ursim", "--host", host, "--calibration", arg,
                                  "--duration", "0.5"])  # fmt: skip
        assert res.exit_code == 2, res.output
        assert message in res.output and "listening" not in res.output, res.output


def test_ursim_serves_a_seeded_random_calibration() -> None:
    host = _address("test_ursim_serves_a_seeded_random_calibration", 0)
    cmd = [sys.executable, "-c", "from ruledrobot.cli import app; app()", "ursim",
           "--host", host, "--duration", "20", "--calibration", "random:7"]  # fmt: skip
    proc = popen_as_from_a_terminal(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                    text=True)  # stopped by SIGINT below
    try:
        assert proc.stdout is not None
        for line in proc.stdout:
            if "listening on" in line:
                break
        assert "calibrated kinematics (seeded random (seed 7))" in line, line
        assert "primary 30001, secondary 30002" in line
        info, _ = read_kinematics_info(host, PRIMARY_PORT)
        assert _same_bits(info, random_calibration("ur5e", 7))
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.communicate(timeout=10.0)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.communicate()
