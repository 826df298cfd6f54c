"""An honest emulator (issue 8): what it cannot do, it refuses, visibly, before any motion.

* a URScript program with a line the emulator cannot run is refused whole, with
  the line number and text (a compile error), runtime state STOPPED;
* I/O setters are run and recorded (RTDE outputs), their arguments checked as
  the controller checks them;
* ur_rtde commands the emulator does not emulate (force mode, contact detection,
  teach/freedrive) fail in the client instead of "succeeding" with no effect;
* the RTDE outputs of UR's table that were missing exist with UR's types;
* decimated streams start on the decimation grid.
"""

from __future__ import annotations

import socket
import time

import numpy as np
import pytest

from ruledrobot.export import urscript_program
from ruledrobot.robot import load
from ruledrobot.robot.motion.trajectory import Payload, Trajectory
from ruledrobot.ursim import DEFAULT_Q, Emulator
from ruledrobot.ursim.controller.machine import Controller
from tests.support.emulators import UR, smooth_trajectory
from tests.support.rawclient import RawRTDEClient

MODEL = load("ur5e")


def _run(ctrl: Controller, ticks: int = 20000) -> None:
    """Tick until the program has ended (runtime state STOPPED)."""
    for _ in range(ticks):
        ctrl.tick()
        if ctrl.runtime_state == 1 and ctrl.runner is None:
            return
    raise AssertionError("the program did not end")


def _errors(ctrl: Controller) -> list[str]:
    return [m for _, level, m in ctrl.events if level <= 1]


# ---------------------------------------------------------------- programs: refused whole


def test_program_with_an_unsupported_line_is_refused_before_any_motion() -> None:
    ctrl = Controller(MODEL)
    q = np.round(np.array(DEFAULT_Q) + 0.2, 6).tolist()
    text = (
        "def cut():\n"
        "  set_standard_digital_out(2, True)\n"
        f"  movej({q}, a=1.4, v=1.05)\n"
        "  while True:\n"
        "    force_mode(p[0, 0, 0, 0, 0, 0], [0, 0, 1, 0, 0, 0], [0, 0, 5, 0, 0, 0], 2,\n"
        "               [0.1, 0.1, 0.1, 0.1, 0.1, 0.1])\n"
        "  end\n"
        "end\n"
    )
    assert not ctrl.load_script(text)
    for _ in range(50):
        ctrl.tick()
    assert ctrl.runtime_state == 1  # STOPPED: nothing ran
    assert ctrl.values["actual_digital_output_bits"] == 0  # not even the first line
    np.testing.assert_allclose(ctrl.values["actual_q"], DEFAULT_Q, atol=0)
    errs = _errors(ctrl)
    assert len(errs) == 1
    assert "compile error" in errs[0] and "line 5" in errs[0] and "force_mode(" in errs[0]
    assert "not emulated" in errs[0]
    assert ctrl.popup is not None and "line 5" in ctrl.popup  # what the pendant would show


@pytest.mark.parametrize(
    ("line", "reason"),
    [
        ("set_standard_digital_out(8, True)", "0..7"),
        ("set_standard_digital_out(64, True)", "0..7"),
        ("set_standard_digital_out(1e7, True)", "0..7"),
        ("set_standard_digital_out(1.5, True)", "integer"),
        ("set_standard_digital_out(-1, True)", "0..7"),
        ("set_standard_digital_out(1, 3)", "True or False"),
        ("set_standard_digital_out(1)", "missing"),
        ("set_configurable_digital_out(100, True)", "0..7"),
        ("set_tool_digital_out(2, True)", "0..1"),
        ("set_standard_analog_out(2, 0.5)", "0..1"),
        ("set_standard_analog_out(0, 1.5)", "[0, 1]"),
        ("set_standard_analog_out(0, -0.1)", "[0, 1]"),
        ("set_payload(-1, [0, 0, 0])", "mass"),
        ("set_payload(100, [0, 0, 0])", "mass"),
        ("set_payload(1, [0, 0])", "3 numbers"),
        ("set_target_payload(1)", "missing"),
        ("set_tcp(p[0, 0, 0.1])", "6 numbers"),
        ("servoj([0, 0, 0, 0, 0, 0], t=0.002, lookahead_time=0.5, gain=300)", "lookahead_time"),
        ("servoj([0, 0, 0, 0, 0, 0], t=0.002, lookahead_time=0.1, gain=5000)", "gain"),
        ("movej([0, 0, 0, 0, 0, 0], a=1.4, v=1.05, t=2)", "t"),
        ("movej([0, 0, 0, 0, 0, 0], speed=1)", "speed"),
        (
            "force_mode(p[0,0,0,0,0,0], [0,0,1,0,0,0], [0,0,10,0,0,0], 2, [1,1,1,1,1,1])",
            "force_mode",
        ),
        ("x = y + 1", "unknown variable 'y'"),
        ("movej(q_start)", "unknown variable 'q_start'"),
        ("set_standard_digital_out(1, True) set_standard_digital_out(2, True)", "syntax error"),
        ("x = p[0, 0, 0.1]", "6 values"),
        ("write_output_integer_register(48, 1)", "0..47"),
        ("write_output_integer_register(1, 3000000000)", "int32"),
        ("movej([1e999, 0, 0, 0, 0, 0])", "finite"),
    ],
)
def test_bad_arguments_and_unknown_functions_refuse_the_program(line: str, reason: str) -> None:
    ctrl = Controller(MODEL)
    text = f"def p():\n  set_standard_digital_out(0, True)\n  {line}\nend\n"
    assert not ctrl.load_script(text)
    ctrl.tick()
    assert ctrl.runtime_state == 1 and ctrl.values["actual_digital_output_bits"] == 0
    errs = _errors(ctrl)
    assert len(errs) == 1 and "line 3" in errs[0] and reason in errs[0], errs


def test_a_block_without_its_end_is_refused_at_the_programs_end() -> None:
    ctrl = Controller(MODEL)
    assert not ctrl.load_script("def p():\n  if True:\n    sync()\nend\n")
    errs = _errors(ctrl)
    assert len(errs) == 1 and "line 4" in errs[0] and "missing 'end'" in errs[0], errs


def test_a_bare_bad_line_is_refused_too() -> None:
    ctrl = Controller(MODEL)
    assert not ctrl.load_script("set_standard_digital_out(64, True)\n")
    for _ in range(20):
        ctrl.tick()
    assert ctrl.runtime_state == 1 and ctrl.values["actual_digital_output_bits"] == 0
    assert "line 1" in _errors(ctrl)[0]


def test_a_refused_program_stops_the_running_one() -> None:
    ctrl = Controller(MODEL)
    assert ctrl.load_script("def rtde_control():\n  sync()\nend\n")
    assert ctrl.runtime_state == 2
    assert not ctrl.load_script("def p():\n  if True:\n    sync()\n  end\n  undefined_fn()\nend\n")
    assert ctrl.runtime_state == 1


def test_io_setters_run_and_appear_in_the_rtde_outputs() -> None:
    ctrl = Controller(MODEL)
    text = (
        "def heat():\n"
        "  set_standard_digital_out(3, True)\n"
        "  set_standard_digital_out(7, True)\n"
        "  set_standard_digital_out(7, False)\n"
        "  set_configurable_digital_out(1, True)\n"
        "  set_tool_digital_out(1, True)\n"
        "  set_standard_analog_out(0, 0.25)\n"
        "  set_standard_analog_out(1, 1)\n"
        "  set_digital_out(9, True)  # deprecated name: 8, 9 are the tool outputs\n"
        "  write_output_integer_register(5, -7)\n"
        "  write_output_float_register(6, 2.5)\n"
        "  write_output_boolean_register(3, True)\n"
        "  set_payload(1.5, [0, 0, 0.05])\n"
        "  set_target_payload(1.25, [0.01, 0, 0.04], [0, 0, 0, 0, 0, 0])\n"
        "end\n"
    )
    assert ctrl.load_script(text)
    _run(ctrl)
    v = ctrl.values
    assert v["actual_digital_output_bits"] == (1 << 3) | (1 << 9) | (1 << 17)
    assert v["actual_configurable_digital_output_bits"] == 1 << 1
    assert v["standard_analog_output0"] == 0.25 and v["standard_analog_output1"] == 1.0
    assert v["output_int_register_5"] == -7 and v["output_double_register_6"] == 2.5
    assert v["output_bit_registers0_to_31"] == 1 << 3
    assert v["payload"] == 1.25 and v["payload_cog"] == (0.01, 0.0, 0.04)
    assert not _errors(ctrl)


@pytest.mark.parametrize("mode", ["servoj", "movep", "movel"])
def test_the_programs_ruledrobot_exports_still_run(mode: str) -> None:
    """urscript_program writes set_tcp and set_payload (mass, centre of gravity) too."""
    base = smooth_trajectory()  # within the UR5e limits the export now checks
    traj = Trajectory.from_joints(base.t, base.q, MODEL, payload=Payload(0.8, [0, 0, 0.06]))
    text = urscript_program(traj, mode=mode, approach_speed=1.0, approach_acceleration=4.0)
    assert "set_payload(0.8, [0, 0, 0.06])" in text
    ctrl = Controller(MODEL)
    assert ctrl.load_script(text)
    _run(ctrl)
    assert not _errors(ctrl)
    assert ctrl.values["payload"] == 0.8 and ctrl.values["payload_cog"] == (0.0, 0.0, 0.06)
    tol = 1e-3 if mode == "servoj" else 1e-5  # servoj: the lookahead filter's tail
    np.testing.assert_allclose(ctrl.values["actual_q"], traj.q[-1], atol=tol)


def test_refusal_seen_by_clients(emulator: Emulator, ur: UR) -> None:
    """Through the script port: the program does not run, the client sees STOPPED and
    the outputs unchanged; the controller log and the popup name the line."""
    import dashboard_client

    r = ur.r
    d = dashboard_client.DashboardClient(emulator.host)
    d.connect()
    try:
        with socket.create_connection((emulator.host, emulator.ports["script"])) as s:
            s.sendall(
                b"def bad():\n  set_standard_digital_out(1, True)\n"
                b"  set_configurable_digital_out(100, True)\nend\n"
            )
            assert emulator.wait_for(lambda: emulator.popup is not None, 3.0)
            time.sleep(0.05)
            assert r.getRuntimeState() == 1 and r.getActualDigitalOutputBits() == 0
            assert d.programState().startswith("STOPPED")
            assert "line 3" in emulator.popup and "set_configurable_digital_out" in emulator.popup
            errs = [m for _, lv, m in emulator.events if lv <= 1]
            assert any("compile error" in m and "line 3" in m for m in errs)
            d.closePopup()
            assert emulator.wait_for(lambda: emulator.popup is None, 2.0)
            # a good program runs, and its outputs reach the RTDE stream
            s.sendall(
                b"def heat():\n  set_standard_digital_out(1, True)\n"
                b"  set_standard_analog_out(0, 0.5)\nend\n"
            )
            assert emulator.wait_for(
                lambda: any("heat finished" in e[2] for e in emulator.events), 3.0
            )
        assert emulator.wait_for(lambda: r.getActualDigitalOutputBits() == 2, 2.0)
        assert r.getStandardAnalogOutput0() == 0.5
    finally:
        d.disconnect()


# ---------------------------------------------------------------- ur_rtde: not emulated = failure


def _running(c) -> bool:
    deadline = time.monotonic() + 2.0
    while time.monotonic() < deadline:
        if c.isProgramRunning():
            return True
        time.sleep(0.005)
    return False


def _not_running(c) -> bool:
    deadline = time.monotonic() + 2.0
    while time.monotonic() < deadline:
        if not c.isProgramRunning():
            return True
        time.sleep(0.005)
    return False


def test_commands_the_emulator_cannot_do_fail_in_the_client(emulator: Emulator, ur: UR) -> None:
    r, c = ur.r, ur.c
    frame = [0.0] * 6
    pose = r.getActualTCPPose()
    blocking = {
        "forceModeStop": lambda: c.forceModeStop(),
        "zeroFtSensor": lambda: c.zeroFtSensor(),
        "moveUntilContact": lambda: c.moveUntilContact([0, 0, -0.05, 0, 0, 0]),
        "startContactDetection": lambda: c.startContactDetection(),
        "teachMode": lambda: c.teachMode(),
        "endTeachMode": lambda: c.endTeachMode(),
        "freedriveMode": lambda: c.freedriveMode(),
        "endFreedriveMode": lambda: c.endFreedriveMode(),
        "forceModeSetDamping": lambda: c.forceModeSetDamping(0.1),
    }
    for name, call in blocking.items():
        assert _running(c), name
        assert call() is False, f"{name} returned success"
        assert _not_running(c), name
        assert any(lv <= 1 and "not emulated" in m for _, lv, m in emulator.events[-5:]), name
        assert c.reuploadScript()
    # getFreedriveStatus raises when its command fails
    assert _running(c)
    with pytest.raises(RuntimeError):
        c.getFreedriveStatus()
    assert c.reuploadScript()
    # real-time commands: ur_rtde never waits for them (True on a robot too), but the
    # program stops at once, so the next command fails and the arm has not moved
    q0 = r.getActualQ()
    for name, call in {
        "forceMode": lambda: c.forceMode(
            frame, [0, 0, 1, 0, 0, 0], [0, 0, 10, 0, 0, 0], 2, [2, 2, 1.5, 1, 1, 1]
        ),
        "toolContact": lambda: c.toolContact([0, 0, 0, 0, 0, 0]),
    }.items():
        assert _running(c), name
        call()
        assert _not_running(c), name
        assert c.moveL(pose, 0.1, 0.5) is False, name
        assert r.getActualQ() == q0
        assert c.reuploadScript()
    # and everything that is emulated still works afterwards
    assert _running(c)
    assert c.moveJ((np.array(q0) + 0.02).tolist(), 1.0, 4.0)


# ---------------------------------------------------------------- RTDE outputs of UR's table


def test_outputs_missing_before_exist_with_urs_types(emulator: Emulator) -> None:
    names = {
        "tool_output_mode": "UINT8",
        "tool_digital_output0_mode": "UINT8",
        "tool_digital_output1_mode": "UINT8",
        "actual_configurable_digital_input_bits": "UINT64",
        "actual_configurable_digital_output_bits": "UINT64",
        "encoder0_raw": "INT32",
        "encoder1_raw": "INT32",
    }
    with RawRTDEClient(emulator.host) as cli:
        assert cli.negotiate()
        types = cli.setup_outputs(["timestamp", *names], 125.0)
        assert types == ["DOUBLE", *names.values()]
        assert cli.start()
        d = cli.read_data()
    # no encoders, no configurable inputs; the tool I/O set-up of a default installation
    # (set_tool_output_mode(0), set_tool_digital_output_mode(n, 1))
    assert {n: d[n] for n in names} == {
        **dict.fromkeys(names, 0),
        "tool_digital_output0_mode": 1,
        "tool_digital_output1_mode": 1,
    }


def test_ur_rtde_asks_for_them(emulator: Emulator) -> None:
    import rtde_receive

    r = rtde_receive.RTDEReceiveInterface(
        emulator.host,
        125.0,
        [
            "timestamp",
            "tool_output_mode",
            "encoder0_raw",
            "actual_configurable_digital_output_bits",
        ],
    )
    try:
        assert r.isConnected() and r.getTimestamp() > 0.0
    finally:
        del r


# ---------------------------------------------------------------- decimation grid


@pytest.mark.parametrize(("frequency", "step"), [(125.0, 0.008), (100.0, 0.01), (250.0, 0.004)])
def test_decimated_streams_start_on_the_grid(
    emulator: Emulator, frequency: float, step: float
) -> None:
    """Eight connections, each started at an arbitrary controller tick: every package,
    the first included, carries a timestamp on the decimation grid."""
    firsts = []
    for k in range(8):
        time.sleep(0.0013 * k)  # start at different ticks
        with RawRTDEClient(emulator.host) as cli:
            assert cli.negotiate()
            cli.setup_outputs(["timestamp"], frequency)
            assert cli.start()
            ts = [cli.read_data()["timestamp"] for _ in range(5)]
        firsts.append(ts[0])
        k_ts = np.asarray(ts) / step
        np.testing.assert_allclose(k_ts, np.round(k_ts), atol=1e-6)
    assert len(firsts) == 8
