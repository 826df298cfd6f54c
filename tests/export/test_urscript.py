"""URScript export and trajectory files."""

from __future__ import annotations

import json
import socket

import numpy as np
import pytest

from ruledrobot.export import export_trajectory, urscript_program
from ruledrobot.geometry.se3 import pose_from_ur_vector
from ruledrobot.io.trajectory import read_trajectory
from ruledrobot.robot import load, model_for
from ruledrobot.robot.motion.trajectory import Payload, Trajectory
from ruledrobot.ursim import Emulator
from ruledrobot.ursim.script.program import Pose, parse_call
from tests.support.emulators import smooth_trajectory


def _statements(text: str) -> list:
    lines = text.splitlines()
    assert lines[0] == "def ruledrobot_cut():"
    assert lines[-1] == "end" and text.endswith("end\n")
    body = [ln.strip() for ln in lines[1:-1]]
    assert all(ln.startswith(("#", "set_tcp(", "set_payload(", "textmsg(", "movej(", "servoj(",
                              "movel(", "movep(", "stopj(")) for ln in body if ln)  # fmt: skip
    return [parse_call(ln) for ln in body if ln and not ln.startswith("#")]


def test_servoj_program_structure_and_values() -> None:
    traj = smooth_trajectory()
    text = urscript_program(traj, lookahead=0.05, gain=500)
    sts = _statements(text)
    moves = [s for s in sts if s.name in ("movej", "movel", "movep", "servoj")]
    assert moves[0].name == "movej"  # to the start first
    np.testing.assert_allclose(moves[0].args[0], traj.q[0], rtol=1e-9, atol=1e-12)
    servo = [s for s in sts if s.name == "servoj"]
    assert len(servo) == traj.t.size
    q = np.array([s.args[0] for s in servo])
    np.testing.assert_allclose(q, traj.q, rtol=1e-9, atol=1e-12)  # 10 significant digits
    t = np.array([s.kwargs["t"] for s in servo])
    np.testing.assert_allclose(t[:-1], np.diff(traj.t), rtol=1e-9)
    assert t[-1] == pytest.approx(0.25)  # the last sample is held while the filter settles
    assert {s.kwargs["lookahead_time"] for s in servo} == {0.05}
    assert {s.kwargs["gain"] for s in servo} == {500.0}
    assert sts[-1].name == "textmsg" and any(s.name == "stopj" for s in sts)
    tcp = [s for s in sts if s.name == "set_tcp"]
    assert len(tcp) == 1 and tcp[0].args[0] == Pose((0.0,) * 6)
    pay = [s for s in sts if s.name == "set_payload"]
    assert len(pay) == 1 and pay[0].args[0] == 0.0


@pytest.mark.parametrize("mode", ["movep", "movel"])
def test_path_program_within_tolerance(mode: str) -> None:
    traj = smooth_trajectory(amplitude=(0.09, -0.07, 0.08, 0.0, 0.0, 0.0))
    text = urscript_program(traj, mode=mode, tolerance=0.0005, blend=0.002)
    sts = _statements(text)
    assert sts[3].name == "movej"
    moves = [s for s in sts if s.name == mode]
    # decimated; a speed that changes everywhere (sin^2) is split where it changes by 2 %
    assert 3 <= len(moves) < traj.t.size // 3
    poses = np.array([s.args[0].values for s in moves])
    np.testing.assert_allclose(pose_from_ur_vector(poses[-1]), traj.tcp_poses()[-1], atol=1e-9)
    # every TCP sample lies within the tolerance of the polyline
    pts = np.vstack([traj.tcp[:1, :3], poses[:, :3]])
    d = []
    for p in traj.tcp[:, :3]:
        a, b = pts[:-1], pts[1:]
        ab = b - a
        s = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab),
                                                                  1e-30), 0, 1)  # fmt: skip
        d.append(np.min(np.linalg.norm(a + s[:, None] * ab - p, axis=1)))
    assert max(d) <= 0.0005 + 1e-9
    assert all(s.kwargs["r"] <= 0.002 for s in moves) and moves[-1].kwargs["r"] == 0.0
    assert all(0 < s.kwargs["v"] <= 3.0 for s in moves)


def test_bad_parameters_are_refused() -> None:
    traj = smooth_trajectory()
    with pytest.raises(ValueError, match="mode"):
        urscript_program(traj, mode="servoc")
    with pytest.raises(ValueError, match="lookahead"):
        urscript_program(traj, lookahead=0.5)
    q = traj.q.copy()
    q[7, 2] = np.nan
    with pytest.raises(ValueError, match=r"q\[7\]: contains NaN"):
        urscript_program(Trajectory(traj.t, q, traj.tcp, traj.meta))


def test_export_formats(tmp_path) -> None:
    traj = smooth_trajectory()
    p = export_trajectory(traj, tmp_path / "cut.csv")
    back = read_trajectory(p)
    np.testing.assert_allclose(back.q, traj.q, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(back.t, traj.t, atol=1e-12)
    (tmp_path / "cut.csv").rename(tmp_path / "kept.csv")
    (tmp_path / "cut.json").rename(tmp_path / "kept.json")
    doc = json.loads(export_trajectory(traj, tmp_path / "cut.json").read_text())
    assert doc["format"] == "ruledrobot.trajectory/1" and doc["header"][0] == "t"
    np.testing.assert_array_equal(doc["q"], traj.q)
    npz = np.load(export_trajectory(traj, tmp_path / "cut.npz"))
    np.testing.assert_array_equal(npz["tcp"], traj.tcp)
    assert json.loads(str(npz["meta"]))["robot"] == "ur5e"
    script = export_trajectory(traj, tmp_path / "cut.script", lookahead=0.1)
    assert script.read_text() == urscript_program(traj, lookahead=0.1)
    export_trajectory(traj, tmp_path / "cut.txt", fmt="urscript", mode="movep")
    with pytest.raises(ValueError, match=r"cut\.xyz.*suffix"):
        export_trajectory(traj, tmp_path / "cut.xyz")
    assert sorted(f.name for f in tmp_path.iterdir()) == [
        "cut.json",
        "cut.npz",
        "cut.script",
        "cut.txt",
        "kept.csv",
        "kept.json",
    ]  # no temporary files left


@pytest.mark.parametrize("mode", ["servoj", "movep"])
def test_emulator_runs_the_exported_program(mode: str, host: str) -> None:
    """The program, sent to the script port as a robot would receive it, ends on the last sample."""
    traj = smooth_trajectory()
    text = urscript_program(traj, mode=mode, approach_speed=1.0, approach_acceleration=4.0)
    with Emulator(host, "ur5e", in_process=True) as emu:
        with socket.create_connection((host, emu.ports["script"])) as s:
            s.sendall(text.encode())
            assert emu.wait_for(lambda: any("ruledrobot: cut" in e[2] for e in emu.events), 5)
            assert emu.wait_for(lambda: emu.runtime_state == 1, 10)
        assert any("finished" in e[2] for e in emu.events)
        np.testing.assert_allclose(
            emu.actual_q, traj.q[-1], atol=1e-4 if mode == "servoj" else 1e-6
        )


def _wire_trajectory() -> Trajectory:
    """A trajectory whose TCP is a wire frame 0.25 m out with a tilted z, and a payload."""
    base = smooth_trajectory(amplitude=(0.09, -0.07, 0.08, 0.05, 0.06, 0.0))
    tool = [0.01, 0.0, 0.25, 1.2, 0.0, 1.2]
    return Trajectory.from_joints(base.t, base.q, load("ur5e").with_tool(tool),
                                  payload=Payload(1.3, [0.0, 0.0, 0.07]))  # fmt: skip


@pytest.mark.parametrize("mode", ["servoj", "movep", "movel"])
def test_every_mode_sets_the_tcp_and_payload_and_commands_fk_times_tcp(mode: str) -> None:
    """Each program sets TCP and payload from the metadata; the commanded poses (movel/movep)
    or the commanded joints through FK times that TCP (servoj) are the trajectory's TCP."""
    traj = _wire_trajectory()
    sts = _statements(urscript_program(traj, mode=mode))
    tcp = [s for s in sts if s.name == "set_tcp"]
    pay = [s for s in sts if s.name == "set_payload"]
    assert len(tcp) == 1 and len(pay) == 1
    set_tcp = pose_from_ur_vector(np.array(tcp[0].args[0].values))
    np.testing.assert_allclose(set_tcp, traj.meta.tcp_offset, atol=1e-9)
    assert pay[0].args[0] == 1.3
    np.testing.assert_allclose(pay[0].args[1], [0.0, 0.0, 0.07])
    flange_model = load("ur5e")  # independent of the metadata: nominal flange FK
    if mode == "servoj":
        q = np.array([s.args[0] for s in sts if s.name == "servoj"])
        np.testing.assert_allclose(flange_model.fk(q) @ set_tcp, traj.tcp_poses(), atol=1e-8)
    else:
        cmd = np.array([s.args[0].values for s in sts if s.name == mode])
        poses = pose_from_ur_vector(cmd)
        # every commanded pose is FK(q_k) . TCP of some sample k of the plan
        fk = flange_model.fk(traj.q) @ set_tcp
        d = np.linalg.norm(poses[:, None, :3, 3] - fk[None, :, :3, 3], axis=-1).min(axis=1)
        assert d.max() < 1e-8
        # and not the flange: the mix-up of the old export put the flange 0.25 m away
        flange = flange_model.fk(traj.q)
        assert np.linalg.norm(poses[-1, :3, 3] - flange[-1, :3, 3]) > 0.2


def test_long_programs_warn_and_beyond_the_limit_are_refused() -> None:
    from ruledrobot.export.urscript import MAX_MOTION_LINES, WARN_MOTION_LINES

    long = smooth_trajectory(duration=(WARN_MOTION_LINES + 100) * 0.002)
    text = urscript_program(long)
    assert "long program" in text and "prefer streaming" in text
    assert "long program" not in urscript_program(smooth_trajectory())
    huge = smooth_trajectory(duration=(MAX_MOTION_LINES + 10) * 0.002)
    with pytest.raises(ValueError, match=r"beyond the safe size.*ruledrobot run"):
        urscript_program(huge)
    assert urscript_program(huge, allow_long=True).count("servoj(") == huge.n


def test_programs_of_any_mode_say_which_kinematics_they_need() -> None:
    traj = _wire_trajectory()
    text = urscript_program(traj, mode="movel")
    assert traj.meta.kinematics.checksum in text
    assert model_for(traj.meta).name == "ur5e"


def test_a_program_is_never_written_for_motion_beyond_the_limits(tmp_path) -> None:
    traj = smooth_trajectory()
    q = traj.q.copy()
    q[300:, 2] += 0.05  # a 25 rad/s step on the elbow
    with pytest.raises(ValueError, match=r"sample 300 .*joint q3 speed"):
        export_trajectory(Trajectory(traj.t, q, traj.tcp, traj.meta), tmp_path / "x.script")
    assert not (tmp_path / "x.script").exists()
