"""Unit tests of the emulator's pieces: packets, recipes, programs, motion, kinematics."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from ruledrobot.geometry.se3 import pose_from_ur_vector, ur_vector_from_pose
from ruledrobot.protocol.rtde import (
    DATA_PACKAGE,
    InputRecipe,
    OutputRecipe,
    PacketFramer,
    ProtocolError,
    pack_packet,
    parse_output_setup,
)
from ruledrobot.protocol.rtde_types import TYPE_SIZES, input_type, output_type
from ruledrobot.robot import load
from ruledrobot.robot.motion.arm_kinematics import ArmKinematics
from ruledrobot.robot.motion.ur_motion import (
    PathMotion,
    Profile,
    StopMotion,
    joint_segment,
    linear_segment,
)
from ruledrobot.ursim import DEFAULT_Q, KinematicBackend
from ruledrobot.ursim.controller.machine import Controller
from ruledrobot.ursim.script.program import ProgramSplitter, parse_call, parse_program
from tests.support.rawclient import UR_RTDE_RECEIVE_RECIPE


def test_official_types() -> None:
    assert output_type("actual_q") == "VECTOR6D"
    assert output_type("joint_mode") == "VECTOR6INT32"
    assert output_type("actual_tool_accelerometer") == "VECTOR3D"
    assert output_type("runtime_state") == "UINT32"
    assert output_type("robot_mode") == "INT32"
    assert output_type("actual_digital_output_bits") == "UINT64"
    assert output_type("output_int_register_47") == "INT32"
    assert output_type("output_double_register_0") == "DOUBLE"
    assert output_type("input_int_register_3") == "INT32"  # inputs can be read back
    assert output_type("output_int_register_48") is None
    assert output_type("no_such_variable") is None
    assert input_type("standard_digital_output_mask") == "UINT8"
    assert input_type("speed_slider_mask") == "UINT32"
    assert input_type("external_force_torque") == "VECTOR6D"
    assert input_type("output_int_register_0") is None


def test_ur_rtde_receive_recipe_is_1180_bytes() -> None:
    rec = OutputRecipe(1, list(UR_RTDE_RECEIVE_RECIPE), 500.0)
    assert rec.ok
    assert len(UR_RTDE_RECEIVE_RECIPE) == 58
    assert rec.size == 1180  # what the probe of the real 5.11 controller recipe measured
    pkt = rec.pack({"timestamp": 1.5, "actual_q": (1, 2, 3, 4, 5, 6)})
    assert len(pkt) == 1180
    size, kind, rid, ts = struct.unpack_from(">HBBd", pkt)
    assert (size, kind, rid, ts) == (1180, DATA_PACKAGE, 1, 1.5)


def test_unknown_output_is_not_found() -> None:
    rec = OutputRecipe(1, ["timestamp", "bogus", "actual_q"], 125.0)
    assert not rec.ok
    assert rec.reply() == b"\x00DOUBLE,NOT_FOUND,VECTOR6D"


def test_framer_handles_fragments_and_rejects_garbage() -> None:
    data = pack_packet(ord("V"), b"\x00\x02") + pack_packet(ord("v")) + pack_packet(ord("S"))
    f = PacketFramer()
    got = []
    for b in data:  # one byte at a time
        f.feed(bytes([b]))
        got.extend(f.packets())
    assert got == [(ord("V"), b"\x00\x02"), (ord("v"), b""), (ord("S"), b"")]
    f = PacketFramer()
    f.feed(b"\x00\x01V")
    with pytest.raises(ProtocolError, match="size 1"):
        list(f.packets())
    f = PacketFramer()
    f.feed(b"\x00\x05Zab")
    with pytest.raises(ProtocolError, match="unknown packet type"):
        list(f.packets())


def test_input_recipe_unpack_and_size_check() -> None:
    rec = InputRecipe(
        2, ["input_int_register_0", "input_double_register_0", "external_force_torque"]
    )
    assert rec.ok and rec.reply().startswith(b"\x02INT32,DOUBLE,VECTOR6D")
    fields = struct.pack(">id6d", 11, 0.5, *range(6))
    vals = rec.unpack(fields)
    assert vals["input_int_register_0"] == 11
    assert vals["external_force_torque"] == (0, 1, 2, 3, 4, 5)
    with pytest.raises(ProtocolError, match="needs"):
        rec.unpack(fields[:-1])
    with pytest.raises(ProtocolError, match="not finite"):
        rec.unpack(struct.pack(">id6d", 1, float("nan"), *range(6)))


def test_output_setup_frequency() -> None:
    freq, names = parse_output_setup(struct.pack(">d", 125.0) + b"timestamp,actual_q,", 2)
    assert freq == 125.0 and names == ["timestamp", "actual_q"]
    with pytest.raises(ProtocolError):
        parse_output_setup(struct.pack(">d", float("inf")) + b"timestamp", 2)


def test_type_sizes() -> None:
    assert TYPE_SIZES == {
        "BOOL": 1, "UINT8": 1, "UINT32": 4, "UINT64": 8, "INT32": 4, "DOUBLE": 8,
        "VECTOR3D": 24, "VECTOR6D": 48, "VECTOR6INT32": 24, "VECTOR6UINT32": 24,
    }  # fmt: skip


# ---------------------------------------------------------------- programs


def test_parse_call_literals() -> None:
    st = parse_call("movel(p[0.1,-2e-3,0.3,0,3.14,0],a=1.2,v=0.25,r=0.001)")
    assert st.name == "movel"
    assert st.args[0].values == (0.1, -0.002, 0.3, 0.0, 3.14, 0.0)
    assert st.kwargs == {"a": 1.2, "v": 0.25, "r": 0.001}
    st = parse_call('textmsg("hello, world")')
    assert st.args == ["hello, world"]


def test_rtde_control_program_path_and_offset() -> None:
    text = (
        "def rtde_control():\n"
        "    global reg_offset_float = # float register offset\n24    global x = 1\n"
        "    def exec_move_path():\n"
        "        # inject move path\n"
        "\tsignal_async_progress(0)\n"
        "\tmovel(p[0.1,0.2,0.3,0,3.14159,0],a=1.2,v=0.25,r=0.01)\n"
        "\tsignal_async_progress(1)\n"
        "\tmovej([0,-1.57,1.57,-1.57,-1.57,0],a=1.4,v=1.05,r=0)\n"
        "    end\n"
        "end\n"
    )
    prog = parse_program(text)
    assert prog.kind == "rtde_control" and prog.register_offset == 24
    assert [w.kind for w in prog.path] == ["movel", "movej"]
    assert prog.path[0].pose and not prog.path[1].pose
    assert prog.path[0].r == 0.01 and prog.path[1].v == 1.05


def test_splitter_cuts_programs_at_top_level_end() -> None:
    sp = ProgramSplitter()
    a = "def a():\n  if True:\n    sleep(1)\n  end\nend\n"
    b = "def b():\n  sync()\nend\n"
    text = a + b + "textmsg(1)\n"
    got = []
    for i in range(0, len(text), 7):
        got.extend(sp.feed(text[i : i + 7]))
    assert got == [a, b, "textmsg(1)\n"]


# ---------------------------------------------------------------- kinematics and motion


def test_fast_kinematics_match_the_model(rng: np.random.Generator) -> None:
    model = load("ur10e").with_tool([0.01, 0.02, 0.15, 0.1, -0.2, 0.3])
    kin = ArmKinematics(model)
    for _ in range(20):
        q = rng.uniform(-3, 3, 6)
        qd = rng.uniform(-1, 1, 6)
        pose, speed, _ = kin.state(q.tolist(), qd.tolist())
        np.testing.assert_allclose(pose, ur_vector_from_pose(model.fk(q)), atol=1e-12)
        np.testing.assert_allclose(speed, model.jacobian(q) @ qd, atol=1e-12)
        sol = kin.ik_nearest(pose, q + 0.01)
        np.testing.assert_allclose(sol, q, atol=1e-9)


def test_trapezoid_profile() -> None:
    p = Profile.trapezoid(1.0, 0.5, 1.0)
    assert p.duration == pytest.approx(0.5 + 1.5 + 0.5)
    assert p.position(p.duration) == 1.0
    ts = np.linspace(0, p.duration, 301)
    s = np.array([p.position(t) for t in ts])
    assert np.all(np.diff(s) >= -1e-15) and np.max(np.diff(s) / np.diff(ts)) <= 0.5 + 1e-9
    tri = Profile.trapezoid(0.1, 1.0, 1.0)  # too short to reach v: triangular
    assert tri.v == pytest.approx(np.sqrt(0.1)) and tri.t_cruise == 0.0


def test_joint_and_linear_moves_reach_their_targets() -> None:
    kin = ArmKinematics(load("ur5e"))
    q0 = np.array(DEFAULT_Q)
    q1 = q0 + np.array([0.3, -0.2, 0.1, 0.0, 0.2, -0.4])
    m = PathMotion(q0, [joint_segment(q0, q1, 1.0, 2.0, 0.0, kin)])
    qs = _run(m)
    np.testing.assert_allclose(qs[-1], q1, atol=1e-12)
    dq = np.diff(qs, axis=0) / 0.002
    assert np.max(np.abs(dq)) <= 1.0 + 1e-9  # leading-axis speed
    pose = np.array(kin.tcp_vector(q0.tolist()))
    target = pose + np.array([0.05, -0.1, -0.05, 0, 0, 0])
    m = PathMotion(q0, [linear_segment(q0, target, 0.25, 1.2, 0.0, kin)])
    qs = _run(m)
    tcp = np.array([kin.tcp_vector(q.tolist()) for q in qs[::25]])
    np.testing.assert_allclose(
        pose_from_ur_vector(kin.tcp_vector(qs[-1].tolist())), pose_from_ur_vector(target), atol=1e-9
    )
    # straight line: the TCP stays on the segment
    d = target[:3] - pose[:3]
    rel = tcp[:, :3] - pose[:3]
    off = rel - np.outer(rel @ d / (d @ d), d)
    assert np.max(np.linalg.norm(off, axis=1)) < 1e-6


def test_blended_path_does_not_stop_at_waypoints() -> None:
    kin = ArmKinematics(load("ur5e"))
    q0 = np.array(DEFAULT_Q)
    p0 = np.array(kin.tcp_vector(q0.tolist()))
    wps = [
        p0 + np.array([0.1, 0, 0, 0, 0, 0]),
        p0 + np.array([0.1, 0.1, 0, 0, 0, 0]),
        p0 + np.array([0.2, 0.1, 0, 0, 0, 0]),
    ]
    segs = []
    q = q0
    for k, w in enumerate(wps):
        seg = linear_segment(q, w, 0.2, 2.0, 0.02 if k < 2 else 0.0, kin)
        segs.append(seg)
        q = seg.q_end
    m = PathMotion(q0, segs)
    qs = _run(m)
    tcp = np.array([kin.tcp_vector(x.tolist())[:3] for x in qs])
    speed = np.linalg.norm(np.diff(tcp, axis=0), axis=1) / 0.002
    mid = speed[len(speed) // 5 : -len(speed) // 5]
    assert mid.min() > 0.1  # no stop at the corners
    np.testing.assert_allclose(tcp[-1], wps[-1][:3], atol=1e-9)
    # the corner is cut by about the blend radius, not more
    corner = wps[0][:3]
    assert 0.001 < np.min(np.linalg.norm(tcp - corner, axis=1)) < 0.02


def test_stop_motion_decelerates_to_rest() -> None:
    q0 = np.zeros(6)
    qd0 = np.array([1.0, -0.5, 0, 0, 0, 0.2])
    m = StopMotion(q0, qd0, 4.0)
    assert m.duration == pytest.approx(0.25)
    qs = _run(m)
    np.testing.assert_allclose(qs[-1], q0 + 0.5 * qd0 * 0.25, atol=1e-12)


def test_kinematic_backend_limits_and_servo_lag() -> None:
    model = load("ur5e")
    be = KinematicBackend(model, max_acceleration=10.0)
    be.reset(np.zeros(6))
    target = np.full(6, 0.1)
    for _ in range(500):
        be.servo(target, 0.1, 300)
        be.step(0.002)
    st = be.state()
    np.testing.assert_allclose(st.q, target, atol=1e-3)  # 1 s = 10 time constants
    be.reset(np.zeros(6))
    be.track(np.full(6, 1.0), np.zeros(6), np.zeros(6))  # an impossible jump
    be.step(0.002)
    assert be.state().limited
    assert np.all(np.abs(be.state().qd) <= 10.0 * 0.002 + 1e-12)


def test_controller_handshake_moves_and_signals_done() -> None:
    """The register handshake without sockets: moveJ through the input registers."""
    ctrl = Controller(load("ur5e"))
    ctrl.load_script("def rtde_control():\n  sync()\nend\n")
    assert ctrl.runtime_state == 2
    ctrl.tick()
    assert ctrl.values["output_int_register_0"] == 1  # ready
    target = np.array(DEFAULT_Q) + 0.1
    regs = {f"input_double_register_{i}": float(x) for i, x in enumerate(target)}
    regs.update({"input_int_register_0": 1, "input_double_register_6": 1.0,
                 "input_double_register_7": 2.0, "input_int_register_1": 0})  # fmt: skip
    ctrl.apply_inputs(regs, list(regs))
    for _ in range(2000):
        ctrl.tick()
        if ctrl.values["output_int_register_0"] == 2:
            break
    assert ctrl.values["output_int_register_0"] == 2
    np.testing.assert_allclose(ctrl.values["actual_q"], target, atol=1e-12)
    ctrl.apply_inputs({"input_int_register_0": 0}, ["input_int_register_0"])
    ctrl.tick()
    assert ctrl.values["output_int_register_0"] == 1


def _run(m) -> np.ndarray:
    out = []
    while (sp := m.next(0.002)) is not None:
        out.append(sp[0])
    return np.array(out)
