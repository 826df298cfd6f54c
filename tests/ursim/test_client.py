"""The real ur_rtde client (1.6.x) against the emulator: every interface, every command family."""

from __future__ import annotations

import socket
import time
from pathlib import Path

import numpy as np
import pytest

from ruledrobot.geometry.se3 import pose_from_ur_vector, ur_vector_from_pose
from ruledrobot.robot import load
from ruledrobot.robot.motion.servo import servo_time_constant
from ruledrobot.ursim import DEFAULT_Q, Emulator
from tests.support.emulators import UR, start_emulator
from tests.support.rawclient import RawRTDEClient

pytest.importorskip("rtde_control")

MODEL = load("ur5e")


def _same_pose(a, b, atol: float = 1e-6) -> bool:
    return bool(np.allclose(pose_from_ur_vector(np.asarray(a)), pose_from_ur_vector(np.asarray(b)),
                            atol=atol))  # fmt: skip


def _wait(pred, timeout: float = 3.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if pred():
            return True
        time.sleep(0.005)
    return bool(pred())


def test_connect_stream_and_moves(emulator: Emulator, ur: UR) -> None:
    r, c, io = ur.r, ur.c, ur.io
    assert r.isConnected() and c.isConnected() and io.isConnected()
    assert c.isProgramRunning()  # the uploaded control script "runs"
    np.testing.assert_allclose(r.getActualQ(), DEFAULT_Q, atol=1e-12)
    np.testing.assert_allclose(r.getTargetQ(), DEFAULT_Q, atol=1e-12)
    assert _same_pose(r.getActualTCPPose(), ur_vector_from_pose(MODEL.fk(DEFAULT_Q)), 1e-12)
    assert r.getRobotMode() == 7 and r.getSafetyMode() == 1 and r.getRuntimeState() == 2
    assert r.getJointMode() == [253] * 6
    assert not r.isProtectiveStopped() and not r.isEmergencyStopped()
    assert r.getSafetyStatusBits() == 1
    assert r.getRobotStatus() == 3  # power on, program running
    assert r.getActualToolAccelerometer() == [0.0, 0.0, 9.81]
    # 500 Hz controller clock, streamed in real time
    t0, w0 = r.getTimestamp(), time.monotonic()
    time.sleep(0.5)
    rate = (r.getTimestamp() - t0) / (time.monotonic() - w0)
    assert rate == pytest.approx(1.0, abs=0.05)
    assert emulator.stats()["rtde_protocol_errors"] == 0
    _moves(r, c)


def _moves(r, c) -> None:
    """moveJ, moveL (straight), moveJ_IK, moveL_FK with checked effects."""
    q1 = np.array(DEFAULT_Q) + np.array([0.3, -0.2, 0.25, 0.1, 0.2, -0.3])
    assert c.moveJ(q1.tolist(), 1.5, 4.0)
    np.testing.assert_allclose(r.getActualQ(), q1, atol=1e-9)
    assert max(abs(x) for x in r.getActualQd()) < 1e-9
    # moveL: the TCP goes straight to the pose
    p0 = np.array(r.getActualTCPPose())
    p1 = p0 + np.array([0.05, -0.04, -0.06, 0.0, 0.0, 0.0])
    assert c.moveL(p1.tolist(), 0.3, 2.0, True)
    path = []
    while c.getAsyncOperationProgress() >= 0:
        path.append(r.getActualTCPPose()[:3])
        time.sleep(0.01)
    assert _wait(lambda: _same_pose(r.getActualTCPPose(), p1, 1e-9))
    d = p1[:3] - p0[:3]
    rel = np.array(path) - p0[:3]
    off = rel - np.outer(rel @ d / (d @ d), d)
    assert len(path) > 5 and np.max(np.linalg.norm(off, axis=1)) < 1e-5
    # moveJ_IK and moveL_FK
    assert c.moveJ_IK(p0.tolist(), 1.5, 4.0)
    assert _same_pose(r.getActualTCPPose(), p0, 1e-9)
    assert c.moveL_FK(q1.tolist(), 0.5, 3.0)
    np.testing.assert_allclose(r.getActualQ(), q1, atol=1e-6)


def test_servo_speed_async_and_stops(emulator: Emulator, ur: UR) -> None:
    r, c = ur.r, ur.c
    q0 = np.array(r.getActualQ())
    amp = np.array([0.2, 0.0, -0.1, 0.0, 0.15, 0.2])
    n = 400
    err = []
    for k in range(n):
        t0 = c.initPeriod()
        target = q0 + amp * np.sin(np.pi * k / n) ** 2
        assert c.servoJ(target.tolist(), 0.0, 0.0, 0.002, 0.05, 500)
        if k > 150:  # past the start-up transient of the lookahead filter
            err.append(np.max(np.abs(np.array(r.getActualQ()) - target)))
        c.waitPeriod(t0)
    # the lookahead filter lags by its time constant (tau = the lookahead, 50 ms): at the
    # targets' top speed (0.2 rad x pi / 0.8 s = 0.79 rad/s) 39 mrad behind, no more
    tau = servo_time_constant(0.05, 500)
    assert max(err) < 1.1 * 0.2 * np.pi / (n * 0.002) * tau
    for _ in range(150):  # hold the last target until it settles
        t0 = c.initPeriod()
        c.servoJ(target.tolist(), 0.0, 0.0, 0.002, 0.05, 500)
        c.waitPeriod(t0)
    np.testing.assert_allclose(r.getActualQ(), target, atol=1e-4)
    assert c.servoStop(4.0)
    assert max(abs(x) for x in r.getActualQd()) < 1e-9
    # servoL to a pose
    pose = np.array(r.getActualTCPPose()) + np.array([0.0, 0.0, 0.01, 0, 0, 0])
    for _ in range(200):
        t0 = c.initPeriod()
        c.servoL(pose.tolist(), 0.0, 0.0, 0.002, 0.05, 500)
        c.waitPeriod(t0)
    assert c.servoStop(4.0)
    assert np.linalg.norm(np.array(r.getActualTCPPose())[:3] - pose[:3]) < 1e-4
    _speed_and_async(r, c)


def _speed_and_async(r, c) -> None:
    """speedJ/speedStop, async moveJ with progress, stopJ, stopL."""
    qd = [0.2, -0.1, 0.0, 0.0, 0.0, 0.3]
    assert c.speedJ(qd, 2.0, 0.002)
    assert _wait(lambda: np.allclose(r.getActualQd(), qd, atol=1e-9), 2.0)
    assert c.speedStop(5.0)
    assert max(abs(x) for x in r.getActualQd()) < 1e-9
    # async moveJ: progress >= 0 while moving, negative once done
    q = np.array(r.getActualQ())
    target = q + np.array([0.3, 0, 0, 0, 0, 0])
    assert c.moveJ(target.tolist(), 0.6, 2.0, True)
    progress = [c.getAsyncOperationProgress()]
    assert progress[0] >= 0
    while progress[-1] >= 0:
        time.sleep(0.02)
        progress.append(c.getAsyncOperationProgress())
    assert progress[-1] == -1 and min(progress[:-1]) >= 0 and len(progress) > 10
    np.testing.assert_allclose(r.getActualQ(), target, atol=1e-9)
    # async moveJ stopped half way by stopJ
    assert c.moveJ(q.tolist(), 0.6, 2.0, True)
    time.sleep(0.3)
    c.stopJ(4.0)
    qs = np.array(r.getActualQ())
    assert max(abs(x) for x in r.getActualQd()) < 1e-9
    assert 0.02 < qs[0] - q[0] < 0.28  # stopped between start and target
    time.sleep(0.1)
    np.testing.assert_allclose(r.getActualQ(), qs, atol=1e-12)  # and stays there
    assert c.getAsyncOperationProgress() < 0
    # stopL on a linear move
    p = np.array(r.getActualTCPPose())
    assert c.moveL((p + np.array([0.0, 0.0, -0.1, 0, 0, 0])).tolist(), 0.2, 1.0, True)
    time.sleep(0.2)
    c.stopL(2.0)
    assert max(abs(x) for x in r.getActualQd()) < 1e-9


def test_path_moves_and_kinematics(emulator: Emulator, ur: UR) -> None:
    r, c = ur.r, ur.c
    p0 = np.array(r.getActualTCPPose())
    corners = [p0 + np.array([0.05, 0, 0, 0, 0, 0]), p0 + np.array([0.05, 0.05, 0, 0, 0, 0]),
               p0 + np.array([0.0, 0.05, -0.03, 0, 0, 0]), p0]  # fmt: skip
    path = [[*w, 0.25, 2.0, 0.01 if k < 3 else 0.0] for k, w in enumerate(corners)]
    assert c.moveL(path, True)
    seen = set()
    tcp, speed = [], []
    while (k := c.getAsyncOperationProgress()) >= 0:
        seen.add(k)
        tcp.append(r.getActualTCPPose()[:3])
        speed.append(np.linalg.norm(r.getActualTCPSpeed()[:3]))
        time.sleep(0.005)
    assert seen >= {0, 1, 2, 3}  # progress walks through the waypoints
    assert _wait(lambda: _same_pose(r.getActualTCPPose(), p0, 2e-5))  # 6-digit text
    tcp = np.array(tcp)
    # blended: the corners are cut (by less than the radius) and the arm does not stop there
    for w in corners[:3]:
        dmin = np.min(np.linalg.norm(tcp - w[:3], axis=1))
        assert 5e-4 < dmin < 0.01
    mid = np.array(speed[len(speed) // 6 : -len(speed) // 6])
    assert mid.min() > 0.02
    # joint path
    q = np.array(r.getActualQ())
    jpath = [[*(q + np.array([0.1 * (k + 1), 0, -0.05 * (k + 1), 0, 0, 0])), 1.5, 4.0, 0.0]
             for k in range(3)]  # fmt: skip
    assert c.moveJ(jpath)
    np.testing.assert_allclose(r.getActualQ(), jpath[-1][:6], atol=2e-5)
    assert c.isProgramRunning()
    _kinematics(r, c)


def _kinematics(r, c) -> None:
    """FK/IK queries agree with ruledrobot.robot; TCP offset; safety-limit checks; poseTrans."""
    rng = np.random.default_rng(7)
    for _ in range(5):
        q = np.array(DEFAULT_Q) + rng.uniform(-0.5, 0.5, 6)
        fk = c.getForwardKinematics(q.tolist())
        assert _same_pose(fk, ur_vector_from_pose(MODEL.fk(q)), 1e-12)
        # IK: the analytic solution nearest qnear
        sols = MODEL.ik(MODEL.fk(q))
        sols = sols[~np.isnan(sols[:, 0])]
        near = q + rng.uniform(-0.05, 0.05, 6)
        ik = np.array(c.getInverseKinematics(fk, near.tolist()))
        np.testing.assert_allclose(ik, q, atol=1e-9)
        assert any(np.allclose(np.mod(ik - s + np.pi, 2 * np.pi) - np.pi, 0, atol=1e-9)
                   for s in sols)  # fmt: skip
    # defaults: current joints and TCP
    q = np.array(r.getActualQ())
    assert _same_pose(c.getForwardKinematics(), r.getActualTCPPose(), 1e-12)
    np.testing.assert_allclose(c.getInverseKinematics(r.getActualTCPPose()), q, atol=1e-9)
    assert c.getInverseKinematicsHasSolution(r.getActualTCPPose())
    assert not c.getInverseKinematicsHasSolution([2.0, 2.0, 2.0, 0, 0, 0])
    tool = [0.0, 0.0, 0.12, 0.0, 0.0, 0.0]
    fk_tool = c.getForwardKinematics(q.tolist(), tool)
    assert _same_pose(fk_tool, ur_vector_from_pose(MODEL.with_tool(tool).fk(q)), 1e-12)
    assert c.setTcp(tool)
    np.testing.assert_allclose(c.getTCPOffset(), tool, atol=1e-12)
    assert _wait(lambda: _same_pose(r.getActualTCPPose(), fk_tool, 1e-12))
    assert c.isJointsWithinSafetyLimits(q.tolist())
    assert not c.isJointsWithinSafetyLimits([7.0, 0, 0, 0, 0, 0])
    assert c.isSteady()
    pt = c.poseTrans([0.1, 0.0, 0.0, 0.0, 0.0, np.pi / 2], [0.1, 0.0, 0.0, 0.0, 0.0, 0.0])
    np.testing.assert_allclose(pt, [0.1, 0.1, 0.0, 0.0, 0.0, np.pi / 2], atol=1e-12)


def test_stop_script_reupload_and_dashboard(emulator: Emulator, ur: UR) -> None:
    import dashboard_client

    r, c = ur.r, ur.c
    d = dashboard_client.DashboardClient(emulator.host)
    d.connect()
    try:
        assert "5.11.1" in d.polyscopeVersion()
        assert d.getSerialNumber().isdigit()
        assert d.isInRemoteControl()
        assert d.getRobotModel() == "UR5"
        assert d.robotmode() == "Robotmode: RUNNING"
        assert d.safetystatus() == "Safetystatus: NORMAL"
        assert d.running()
        assert "PLAYING" in d.programState()
        c.stopScript()
        assert not c.isProgramRunning()
        assert _wait(lambda: r.getRuntimeState() == 1)
        assert not c.moveJ(list(DEFAULT_Q))  # nothing runs: refused
        assert c.reuploadScript()
        assert _wait(c.isProgramRunning)
        d.stop()
        assert _wait(lambda: not c.isProgramRunning())
        # power cycle and brake release
        d.powerOff()
        assert _wait(lambda: r.getRobotMode() == 3)
        d.powerOn()
        assert _wait(lambda: r.getRobotMode() == 5)
        d.brakeRelease()
        assert _wait(lambda: r.getRobotMode() == 7)
        # protective stop and its unlock
        emulator.protective_stop("test")
        assert _wait(r.isProtectiveStopped)
        assert d.safetystatus() == "Safetystatus: PROTECTIVE_STOP"
        d.closeSafetyPopup()
        d.unlockProtectiveStop()
        assert _wait(lambda: not r.isProtectiveStopped())
        assert c.reuploadScript() and _wait(c.isProgramRunning)
        assert c.moveJ((np.array(DEFAULT_Q) + 0.05).tolist())
        # programs
        assert d.getLoadedProgram() == "No program loaded"
        with pytest.raises(RuntimeError, match="File not found"):
            d.loadURP("/no/such/program.urp")
        urp = Path(emulator.programs_dir) / "cut.urp"  # PolyScope's /programs
        urp.write_text("placeholder")
        d.loadURP("cut.urp")
        assert d.getLoadedProgram() == f"Loaded program: {urp.resolve()}"
        d.play()
        assert _wait(lambda: r.getRuntimeState() == 2)
        d.pause()
        assert _wait(lambda: r.getRuntimeState() == 4)
        d.stop()
        assert _wait(lambda: r.getRuntimeState() == 1)
        d.addToLog("hello from the test")
    finally:
        d.disconnect()
    assert any("hello from the test" in e[2] for e in emulator.events)
    # the raw line protocol: greeting, unknown commands, quit
    with socket.create_connection((emulator.host, 29999), timeout=2.0) as s:
        f = s.makefile("rw")
        assert f.readline() == "Connected: Universal Robots Dashboard Server\n"
        for cmd, reply in (("running", "Program running: false"),
                           ("fly away", "could not understand: 'fly away'"),
                           ("quit", "Disconnected")):  # fmt: skip
            f.write(cmd + "\n")
            f.flush()
            assert f.readline().strip() == reply
        assert f.readline() == ""  # closed after quit


def test_io_interface_and_registers(emulator: Emulator, ur: UR) -> None:
    r, c, io = ur.r, ur.c, ur.io
    assert io.setStandardDigitalOut(3, True)
    assert io.setConfigurableDigitalOut(1, True)
    assert io.setToolDigitalOut(0, True)
    assert io.setSpeedSlider(0.4)
    assert io.setAnalogOutputVoltage(1, 0.25)
    assert io.setInputIntRegister(19, -42)
    assert io.setInputDoubleRegister(20, 2.5)
    assert _wait(lambda: r.getActualDigitalOutputBits() == (1 << 3) | (1 << 9) | (1 << 16))
    assert r.getDigitalOutState(3) and not r.getDigitalOutState(2)
    assert _wait(lambda: r.getTargetSpeedFraction() == pytest.approx(0.4))
    assert r.getStandardAnalogOutput1() == pytest.approx(0.25)
    assert io.setStandardDigitalOut(3, False)
    assert _wait(lambda: r.getActualDigitalOutputBits() == (1 << 9) | (1 << 16))
    # the registers written by the IO interface, read back over a raw RTDE connection
    with RawRTDEClient(emulator.host) as raw:
        assert raw.negotiate()
        raw.setup_outputs(["input_int_register_19", "input_double_register_20"], 125.0)
        assert raw.start()
        d = raw.read_data()
    assert d == {"input_int_register_19": -42, "input_double_register_20": 2.5}
    # the speed slider scales moves: 0.4 -> 2.5 times longer
    q = np.array(r.getActualQ())
    t0 = time.monotonic()
    assert c.moveJ((q + np.array([0.1, 0, 0, 0, 0, 0])).tolist(), 1.0, 4.0)
    slow = time.monotonic() - t0
    io.setSpeedSlider(1.0)
    t0 = time.monotonic()
    assert c.moveJ(q.tolist(), 1.0, 4.0)
    assert slow > 1.8 * (time.monotonic() - t0)


def test_cb3_125hz_upper_range_registers(request: pytest.FixtureRequest) -> None:
    import rtde_control

    flags = rtde_control.RTDEControlInterface
    emu = start_emulator(request.node.nodeid, model="ur10", unlock_delay=0.0)
    u = UR(emu.host, flags=flags.FLAG_UPLOAD_SCRIPT | flags.FLAG_UPPER_RANGE_REGISTERS)
    try:
        _check_cb3(emu, u)
    finally:
        u.release()
        emu.close()


def _check_cb3(emu: Emulator, u: UR) -> None:
    r, c = u.r, u.c
    t0, w0 = r.getTimestamp(), time.monotonic()
    time.sleep(0.3)
    ts = r.getTimestamp()
    assert (ts - t0) / (time.monotonic() - w0) == pytest.approx(1.0, abs=0.1)
    assert abs(ts / 0.008 - round(ts / 0.008)) < 1e-6  # 8 ms ticks (125 Hz)
    q = np.array(r.getActualQ()) + np.array([0.1, 0.1, -0.1, 0, 0, 0])
    assert c.moveJ(q.tolist(), 1.0, 2.0)
    np.testing.assert_allclose(r.getActualQ(), q, atol=1e-9)
    assert any("register offset 24" in e[2] for e in emu.events)
