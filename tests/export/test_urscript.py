"""URScript export and trajectory files."""

from __future__ import annotations

import json
import socket

import numpy as np
import pytest

from ruledrobot.export import export_trajectory, urscript_program
from ruledrobot.export.emulator import Emulator
from ruledrobot.export.emulator.program import Pose, parse_call
from ruledrobot.geometry.se3 import pose_from_ur_vector
from ruledrobot.io.trajectory import Trajectory, read_trajectory
from ruledrobot.robot import load

from .conftest import smooth_trajectory


def _statements(text: str) -> list:
    lines = text.splitlines()
    assert lines[0] == "def ruledrobot_cut():"
    assert lines[-1] == "end" and text.endswith("end\n")
    body = [ln.strip() for ln in lines[1:-1]]
    assert all(ln.startswith(("#", "set_tcp(", "textmsg(", "movej(", "servoj(", "movel(",
                              "movep(", "stopj(")) for ln in body if ln)  # fmt: skip
    return [parse_call(ln) for ln in body if ln and not ln.startswith("#")]


def test_servoj_program_structure_and_values() -> None:
    traj = smooth_trajectory()
    text = urscript_program(traj, "ur5e", lookahead=0.05, gain=500)
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


@pytest.mark.parametrize("mode", ["movep", "movel"])
def test_path_program_within_tolerance(mode: str) -> None:
    traj = smooth_trajectory(amplitude=(0.09, -0.07, 0.08, 0.0, 0.0, 0.0))
    text = urscript_program(traj, "ur5e", mode=mode, tolerance=0.0005, blend=0.002)
    sts = _statements(text)
    assert sts[2].name == "movej"
    moves = [s for s in sts if s.name == mode]
    assert 3 <= len(moves) < traj.t.size // 10  # decimated
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
    with pytest.raises(ValueError, match="sample 7"):
        urscript_program(Trajectory(traj.t, q, traj.tcp))


def test_export_formats(tmp_path) -> None:
    traj = smooth_trajectory()
    p = export_trajectory(traj, tmp_path / "cut.csv")
    back = read_trajectory(p)
    np.testing.assert_allclose(back.q, traj.q, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(back.t, traj.t, atol=1e-12)
    doc = json.loads(export_trajectory(traj, tmp_path / "cut.json").read_text())
    assert doc["format"] == "ruledrobot.trajectory/1" and doc["header"][0] == "t"
    np.testing.assert_array_equal(doc["q"], traj.q)
    npz = np.load(export_trajectory(traj, tmp_path / "cut.npz"))
    np.testing.assert_array_equal(npz["tcp"], traj.tcp)
    assert list(npz["comments"]) == list(traj.comments)
    script = export_trajectory(traj, tmp_path / "cut.script", lookahead=0.1)
    assert script.read_text() == urscript_program(traj, "ur5e", lookahead=0.1)
    export_trajectory(traj, tmp_path / "cut.txt", fmt="urscript", mode="movep")
    with pytest.raises(ValueError, match=r"cut\.xyz.*suffix"):
        export_trajectory(traj, tmp_path / "cut.xyz")
    assert sorted(f.name for f in tmp_path.iterdir()) == [
        "cut.csv",
        "cut.json",
        "cut.npz",
        "cut.script",
        "cut.txt",
    ]  # no temporary files left


@pytest.mark.parametrize("mode", ["servoj", "movep"])
def test_emulator_runs_the_exported_program(mode: str, host: str) -> None:
    """The program, sent to the script port as a robot would receive it, ends on the last sample."""
    traj = smooth_trajectory()
    text = urscript_program(traj, load("ur5e"), mode=mode, approach_speed=1.0,
                            approach_acceleration=4.0)  # fmt: skip
    with Emulator(host, "ur5e", in_process=True) as emu:
        with socket.create_connection((host, emu.ports["script"])) as s:
            s.sendall(text.encode())
            assert emu.wait_for(lambda: any("ruledrobot: cut" in e[2] for e in emu.events), 5)
            assert emu.wait_for(lambda: emu.runtime_state == 1, 10)
        assert any("finished" in e[2] for e in emu.events)
        np.testing.assert_allclose(
            emu.actual_q, traj.q[-1], atol=1e-4 if mode == "servoj" else 1e-6
        )
