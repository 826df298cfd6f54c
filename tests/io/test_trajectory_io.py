"""Trajectory files: a plain CSV and its sidecar; round trips; errors naming file and line."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

import ruledrobot as rr
from ruledrobot.export import export_trajectory
from ruledrobot.io.trajectory import read_trajectory, sidecar_path, write_trajectory
from ruledrobot.robot.motion.trajectory import Payload, Phase, Trajectory


def _traj(tool=(0.0, 0.0, 0.25, 0.0, 0.3, 0.0), n: int = 50) -> Trajectory:
    model = rr.robot.load("ur5e").with_tool(tool)
    t = np.arange(n) * 0.002
    q = np.array([0.3, -1.2, 1.4, -1.8, -1.57, 0.2]) + 0.3 * np.sin(np.outer(t, np.arange(1, 7)))
    return Trajectory.from_joints(
        t, q, model, payload=Payload(1.2, [0.0, 0.01, 0.07]),
        phases=(Phase("approach", 0, 10), Phase("cut", 10, n)), in_stock=((12, 40),),
        source="test",
    )  # fmt: skip


def test_round_trip_keeps_samples_and_metadata(tmp_path):
    traj = _traj()
    p = write_trajectory(tmp_path / "traj.csv", traj)
    back = read_trajectory(p)
    np.testing.assert_allclose(back.t, traj.t, atol=1e-12)
    np.testing.assert_allclose(back.q, traj.q, atol=1e-9)
    np.testing.assert_allclose(back.tcp_poses(), traj.tcp_poses(), atol=1e-8)
    assert back.meta.robot == "ur5e" and back.meta.control_period == 0.002
    np.testing.assert_allclose(back.meta.tcp_offset, traj.meta.tcp_offset, atol=1e-12)
    assert back.meta.payload.mass == 1.2
    np.testing.assert_allclose(back.meta.payload.cog, [0.0, 0.01, 0.07])
    assert back.meta.kinematics.checksum == traj.meta.kinematics.checksum
    assert back.meta.phases == traj.meta.phases and back.meta.in_stock == ((12, 40),)
    assert back.phase_at(5) == "approach" and back.inside_stock().sum() == 28


def test_csv_is_plain_csv(tmp_path):
    """Header on the first line, numbers only: csv.reader (and pandas) read it as it is."""
    p = write_trajectory(tmp_path / "traj.csv", _traj())
    rows = list(csv.reader(p.open()))
    assert rows[0] == ["t", "q1", "q2", "q3", "q4", "q5", "q6", "x", "y", "z", "rx", "ry", "rz"]
    assert len(rows) == 51 and all(len(r) == 13 for r in rows)
    float(rows[1][0])
    assert not any(r[0].startswith("#") for r in rows)


def test_the_tcp_column_is_fk_times_the_tcp_offset(tmp_path):
    traj = _traj()
    model = rr.robot.model_for(traj.meta)
    np.testing.assert_allclose(model.fk(traj.q), traj.tcp_poses(), atol=1e-12)
    assert traj.tcp_error()[0] < 1e-12


def test_missing_sidecar_is_refused_with_an_example(tmp_path):
    p = write_trajectory(tmp_path / "traj.csv", _traj())
    sidecar_path(p).unlink()
    with pytest.raises(ValueError, match=r"traj\.json is missing.*tcp_offset"):
        read_trajectory(p)


def test_csv_from_another_plan_is_refused(tmp_path):
    a = write_trajectory(tmp_path / "a.csv", _traj())
    b = write_trajectory(tmp_path / "b.csv", _traj(n=60))
    a.write_text(b.read_text())
    with pytest.raises(ValueError, match="checksum differs"):
        read_trajectory(a)


def test_a_tcp_column_of_another_frame_is_refused(tmp_path):
    """The flange poses under a wire-frame sidecar: the mix-up of the old movel export."""
    traj = _traj()
    flange = Trajectory(traj.t, traj.q, rr.robot.load("ur5e").fk(traj.q), traj.meta)
    p = write_trajectory(tmp_path / "t.csv", flange)
    with pytest.raises(ValueError, match=r"line \d+: the TCP columns differ.*250 mm"):
        read_trajectory(p)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"robot": "ur99"}, r"field 'robot': expected one of"),
        ({"format": "x"}, r"field 'format'"),
        ({"tcp_offset": [0, 0]}, r"field 'tcp_offset': expected 6 finite numbers"),
        ({"payload": {"mass_kg": -1}}, r"payload.mass: expected a mass >= 0"),
        ({"control_period_s": 0.008}, r"control_period_s': 0.008 s, but a ur5e runs at 0.002"),
        ({"phases": [{"name": "cut", "start": 10, "stop": 5}]}, r"phase cut: expected 0 <= start"),
    ],
)
def test_bad_sidecar_fields_are_named(tmp_path, change, message):
    p = write_trajectory(tmp_path / "traj.csv", _traj())
    side = sidecar_path(p)
    doc = json.loads(side.read_text())
    doc.update(change)
    side.write_text(json.dumps(doc))
    with pytest.raises(ValueError, match=message) as info:
        read_trajectory(p)
    assert "traj" in str(info.value)


def test_minimal_sidecar_of_a_foreign_csv(tmp_path):
    """A CSV from another tool needs only robot, TCP offset and payload beside it."""
    traj = _traj(tool=(0, 0, 0, 0, 0, 0))
    p = write_trajectory(tmp_path / "x.csv", traj)
    sidecar_path(p).write_text(json.dumps({
        "format": "ruledrobot.trajectory-meta/1", "robot": "ur5e",
        "tcp_offset": [0, 0, 0, 0, 0, 0], "payload": {"mass_kg": 0}}))  # fmt: skip
    back = read_trajectory(p)
    assert back.meta.kinematics.source == "nominal" and back.meta.phases == ()


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("t,q1\n", r"line 1: expected the header"),
        ("# robot: ur5e\nt,q1,q2,q3,q4,q5,q6,x,y,z,rx,ry,rz\n", r"line 1: expected the header"),
        ("t,q1,q2,q3,q4,q5,q6,x,y,z,rx,ry,rz\n0,0,0,0,0,0,0,0,0,0,0,0\n", r"line 2: expected 13"),
        (
            "t,q1,q2,q3,q4,q5,q6,x,y,z,rx,ry,rz\n0" + ",0" * 12 + "\n0" + ",0" * 12 + "\n",
            r"line 3: time 0.0 does not increase",
        ),
        ("t,q1,q2,q3,q4,q5,q6,x,y,z,rx,ry,rz\n0,nan" + ",0" * 11 + "\n", r"line 2: contains NaN"),
        ("t,q1,q2,q3,q4,q5,q6,x,y,z,rx,ry,rz\n0,a" + ",0" * 11 + "\n", r"line 2: not a number"),
        ("t,q1,q2,q3,q4,q5,q6,x,y,z,rx,ry,rz\n", r"no samples"),
    ],
)
def test_bad_csv_files(tmp_path, content, message):
    p = write_trajectory(tmp_path / "bad.csv", _traj())
    doc = json.loads(sidecar_path(p).read_text())
    doc.pop("csv_sha256")
    sidecar_path(p).write_text(json.dumps(doc))
    p.write_text(content)
    with pytest.raises(ValueError, match=message):
        read_trajectory(p)


def test_bad_arrays_are_refused():
    traj = _traj()
    with pytest.raises(ValueError, match=r"t\[2\]: times must increase"):
        Trajectory(np.array([0.0, 1.0, 1.0]), np.zeros((3, 6)), np.zeros((3, 6)), traj.meta)
    with pytest.raises(ValueError, match="same"):
        Trajectory(np.array([0.0, 1.0]), np.zeros((3, 6)), np.zeros((3, 6)), traj.meta)
    with pytest.raises(ValueError, match="beyond the 2 samples"):
        Trajectory(np.array([0.0, 1.0]), np.zeros((2, 6)), np.zeros((2, 6)), traj.meta)


@pytest.mark.parametrize("suffix", [".json", ".npz"])
def test_json_and_npz_exports_carry_the_metadata(tmp_path, suffix):
    traj = _traj()
    p = export_trajectory(traj, tmp_path / f"cut{suffix}")
    back = read_trajectory(p)
    np.testing.assert_allclose(back.q, traj.q, atol=1e-12)
    assert back.meta.payload.mass == traj.meta.payload.mass and back.meta.phases == traj.meta.phases
    assert back.meta.kinematics.checksum == traj.meta.kinematics.checksum
    np.testing.assert_allclose(back.meta.tcp_offset, traj.meta.tcp_offset, atol=1e-12)


def test_sliced_keeps_phases_in_range():
    part = _traj().sliced(5, 20)
    assert part.t[0] == 0.0 and part.n == 15
    assert part.meta.phases == (Phase("approach", 0, 5), Phase("cut", 5, 15))
    assert part.meta.in_stock == ((7, 15),)


def test_a_bad_feed_window_is_named_with_the_file_once(tmp_path):
    p = write_trajectory(tmp_path / "traj.csv", _traj())
    side = sidecar_path(p)
    doc = json.loads(side.read_text())
    doc["cut"] = {"stock": {"centre": [0.5, 0, 0.3], "size": [0.2, 0.2, 0.2],
                           "rotvec": [0, 0, 0]},
                  "wire_length_m": 0.4, "feeds": [{"name": "a", "start": "x"}]}  # fmt: skip
    side.write_text(json.dumps(doc))
    with pytest.raises(ValueError, match=r"field 'cut.feeds\[0\]': expected \{name") as info:
        read_trajectory(p)
    assert str(info.value).count(str(side)) == 1, str(info.value)
