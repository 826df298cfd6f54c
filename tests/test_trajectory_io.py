"""Trajectory CSV: round trip, header and errors naming file and line."""

from __future__ import annotations

import numpy as np
import pytest

import ruledrobot as rr
from ruledrobot.io.trajectory import read_trajectory, write_trajectory


def test_round_trip_with_poses(tmp_path):
    model = rr.robot.load("ur5e")
    t = np.arange(50) * 0.002
    q = np.sin(np.outer(t, np.arange(1, 7))) * 0.5
    T = model.fk(q)
    p = write_trajectory(tmp_path / "traj.csv", t, q, T, comments=["robot: ur5e"])
    lines = p.read_text().splitlines()
    assert lines[0] == "# robot: ur5e"
    assert lines[1] == "t,q1,q2,q3,q4,q5,q6,x,y,z,rx,ry,rz"
    traj = read_trajectory(p)
    np.testing.assert_allclose(traj.t, t, atol=1e-12)
    np.testing.assert_allclose(traj.q, q, atol=1e-9)
    np.testing.assert_allclose(traj.tcp_poses(), T, atol=1e-8)
    assert traj.period == pytest.approx(0.002) and traj.comments == ("robot: ur5e",)


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("t,q1\n", r"line 1: expected the header"),
        ("t,q1,q2,q3,q4,q5,q6,x,y,z,rx,ry,rz\n0,0,0,0,0,0,0,0,0,0,0,0\n", r"line 2: expected 13"),
        (
            "t,q1,q2,q3,q4,q5,q6,x,y,z,rx,ry,rz\n0" + ",0" * 12 + "\n0" + ",0" * 12 + "\n",
            r"line 3: time 0.0 does not increase",
        ),
        ("t,q1,q2,q3,q4,q5,q6,x,y,z,rx,ry,rz\n0,nan" + ",0" * 11 + "\n", r"line 2: contains NaN"),
        ("t,q1,q2,q3,q4,q5,q6,x,y,z,rx,ry,rz\n", r"no samples"),
    ],
)
def test_bad_files(tmp_path, content, message):
    p = tmp_path / "bad.csv"
    p.write_text(content)
    with pytest.raises(ValueError, match=message):
        read_trajectory(p)


def test_writer_rejects_bad_arrays(tmp_path):
    with pytest.raises(ValueError, match=r"t\[2\]: times must increase"):
        write_trajectory(tmp_path / "x.csv", [0.0, 1.0, 1.0], np.zeros((3, 6)), np.zeros((3, 6)))
    with pytest.raises(ValueError, match="same length"):
        write_trajectory(tmp_path / "x.csv", [0.0, 1.0], np.zeros((3, 6)), np.zeros((3, 6)))
    assert not (tmp_path / "x.csv").exists()
