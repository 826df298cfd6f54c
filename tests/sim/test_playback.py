"""Playback: tracking error bounds, torques within limits, report, collisions, files."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from ruledrobot.io.trajectory import read_trajectory, write_trajectory
from ruledrobot.robot import load
from ruledrobot.sim import PlaybackResult, Scene, play, play_file, simulate
from ruledrobot.sim.scene import example_scene

from .helpers import cartesian_move, smooth_trajectory, wire_pose

#: Documented report keys (docs/sim.md).
REPORT_KEYS = {
    "format", "robot", "duration_s", "samples", "timestep_s", "control_period_s", "servo",
    "joint_error_rad", "tcp_position_error_mm", "tcp_orientation_error_deg", "joint_speed",
    "joint_torque", "joint_position", "joint_acceleration", "collisions", "collision_count", "wire",
    "realtime_factor", "physics_realtime_factor", "wall_time_s", "ok",
}  # fmt: skip

#: Cutting cell with the TCP in the middle of the wire (0.25 m along the flange z axis).
CELL = example_scene()
CELL = dataclasses.replace(CELL, robot=CELL.robot.with_tool([0.0, 0.0, 0.25, 0.0, 0.0, 0.0]))
ELBOW_UP = [np.pi, -1.2, 1.6, -1.97, -1.57, 0.0]


@pytest.fixture(scope="module")
def smooth_run() -> PlaybackResult:
    t, q, qd = smooth_trajectory(3.0)
    return play(CELL, t, q, qd)


def test_tracking_error_bounds(smooth_run):
    """A smooth trajectory (peak speed 0.15 of the limit, accelerations <= 0.6 rad/s^2).

    Bound: with position + velocity servo and gravity compensation the error is
    the uncompensated torque over the position gain, ``(M qdd + b qd) / kp``: at most
    ~4 N m / 15000 N m/rad = 0.3 mrad on a shoulder joint, ~0.3 mm at the TCP 1 m away;
    the 0.5 mm bound is the design target of the servo model (measured: ~0.1 mm).
    """
    rep = smooth_run.report()
    assert rep["tcp_position_error_mm"]["max"] < 0.5
    assert rep["tcp_position_error_mm"]["rms"] < 0.25
    assert rep["tcp_orientation_error_deg"]["max"] < 0.05
    assert rep["joint_error_rad"]["max"] < 5e-4
    assert rep["joint_torque"]["max_ratio"] < 1.0
    assert rep["joint_speed"]["max_ratio"] < 1.0
    assert rep["joint_position"]["within_limits"]
    assert rep["joint_position"]["reference_within_limits"]
    assert rep["joint_acceleration"]["max_ratio"] < 1.0  # 1.4 rad/s^2 catalogue default
    assert rep["collisions"] == [] and rep["ok"]
    assert rep["wire"]["in_stock_s"] == 0.0
    # the robot starts on the trajectory and the first sample is exact
    np.testing.assert_allclose(smooth_run.q[0], smooth_run.q_ref[0])


def test_torque_feedforward_is_ten_times_better(smooth_run):
    """Computed-torque feed-forward (inverse dynamics of the reference): the error left
    is the one-step discretisation of the servo, bound 0.05 mm (measured ~0.016 mm)."""
    t, q, qd = smooth_trajectory(3.0)
    res = play(CELL, t, q, qd, feedforward="torque", collisions=False)
    err = res.report()["tcp_position_error_mm"]["max"]
    assert err < 0.05
    assert err < 0.3 * smooth_run.report()["tcp_position_error_mm"]["max"]
    # the same torques do the work: within a few percent of the PD-only run
    np.testing.assert_allclose(res.torque, smooth_run.torque, atol=0.02 * 150)


def test_torques_hold_gravity(smooth_run):
    """Joint 2 and 3 torques are mostly the gravity load: compare with the static holding
    torque of the reference posture computed by MuJoCo (zero speed)."""
    import mujoco

    m = mujoco.MjModel.from_xml_string(CELL.mjcf())
    d = mujoco.MjData(m)
    k = smooth_run.t.size // 2
    d.qpos[:] = smooth_run.q_ref[k]
    mujoco.mj_forward(m, d)
    np.testing.assert_allclose(smooth_run.torque[k, 1:3], d.qfrc_gravcomp[1:3], rtol=0.15)


def test_report_keys_and_files(smooth_run, tmp_path):
    rep = smooth_run.report()
    assert set(rep) == REPORT_KEYS
    assert rep["format"] == "ruledrobot.playback/1" and rep["robot"] == "ur5e"
    assert rep["samples"] == smooth_run.t.size == 1501
    assert rep["realtime_factor"] > 1.0
    paths = smooth_run.write(tmp_path / "out")
    assert set(paths) == {"report", "tracking_plot", "limits_plot", "simulated"}
    loaded = json.loads(paths["report"].read_text())
    assert loaded["tcp_position_error_mm"] == rep["tcp_position_error_mm"]
    for key in ("tracking_plot", "limits_plot"):
        assert paths[key].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    actual = read_trajectory(paths["simulated"])
    np.testing.assert_allclose(actual.q, smooth_run.q, atol=1e-9)
    assert actual.meta.robot == "ur5e" and "MuJoCo" in actual.meta.source


def test_wire_in_stock_is_reported_not_a_collision():
    t, q = cartesian_move(
        CELL.robot,
        wire_pose(CELL.stock.centre, height=0.3),
        wire_pose(CELL.stock.centre),
        q_start=ELBOW_UP,
    )
    res = play(CELL, t, q)
    rep = res.report()
    assert rep["collisions"] == []
    assert rep["wire"]["in_stock_s"] > 0.5
    assert rep["wire"]["max_length_in_stock_mm"] == pytest.approx(200.0, abs=0.1)
    assert rep["wire"]["last_in_stock_s"] == pytest.approx(t[-1])


def test_bow_driven_into_the_stock_collides():
    _, q0 = cartesian_move(
        CELL.robot,
        wire_pose(CELL.stock.centre, height=0.3),
        wire_pose(CELL.stock.centre),
        q_start=ELBOW_UP,
    )
    t, q = cartesian_move(
        CELL.robot,
        wire_pose(CELL.stock.centre),
        wire_pose(CELL.stock.centre, shift_along_wire=0.15),
        q_start=q0[-1],
    )
    res = play(CELL, t, q)
    rep = res.report()
    assert not rep["ok"] and rep["collision_count"] >= 1
    hit = rep["collisions"][0]
    assert {hit["geom1"], hit["geom2"]} == {"stock", "bow_arm0"}
    assert {hit["body1"], hit["body2"]} == {"world", "bow"}
    # the arm enters at 0.05 m of the 0.15 m shift: s(t) = 1/3 of the quintic law
    assert 0.8 < hit["start_s"] < 1.3 and hit["end_s"] == pytest.approx(t[-1])
    assert hit["max_depth_mm"] > 10.0
    # the coarse-then-exact search finds what a check of every sample finds
    exact = play(CELL, t, q, collision_stride=1)
    assert [c.as_dict() for c in exact.collisions] == rep["collisions"]


def test_table_collision_and_clear_run_without_scene():
    """The bow swung down through the table top is caught; the arm alone has no table."""
    t, q, _ = smooth_trajectory(2.0)
    q = q.copy()
    q[:, 1] += np.linspace(0.0, 0.9, q.shape[0])  # shoulder down: the bow dips into the table
    rep = play(CELL, t, q).report()
    assert any("table" in (c["geom1"], c["geom2"]) for c in rep["collisions"])
    rep_arm = play(CELL.robot, t, q).report()
    assert rep_arm["collisions"] == [] and rep_arm["wire"] is None


def test_resampled_cb3_trajectory():
    """A CB3 arm at 125 Hz: the physics runs at 2 ms, the reference is interpolated."""
    robot = load("ur5")
    t, q, _ = smooth_trajectory(2.0, dt=0.008)
    res = play(robot, t, q)  # velocities from finite differences
    assert res.timestep == pytest.approx(0.002)
    assert res.t.size == 1001
    np.testing.assert_allclose(res.q_ref[::4], q, atol=1e-12)
    assert res.report()["tcp_position_error_mm"]["max"] < 0.5


def test_progress_and_errors():
    t, q, _ = smooth_trajectory(1.0)
    seen: list[tuple[float, str]] = []
    play(load("ur5e"), t, q, progress=lambda f, stage: seen.append((f, stage)))
    assert seen[-1] == (1.0, "done")
    fractions = [f for f, _ in seen]
    assert fractions == sorted(fractions) and {s for _, s in seen} >= {"dynamics", "done"}
    robot = load("ur5e")
    with pytest.raises(ValueError, match=r"q: expected shape \(501, 6\)"):
        play(robot, t, q[:, :5])
    with pytest.raises(ValueError, match=r"t\[3\]"):
        play(robot, np.r_[t[:3], t[2], t[4:]], q)
    with pytest.raises(ValueError, match="qd"):
        play(robot, t, q, q[:-1])
    with pytest.raises(ValueError, match="feedforward"):
        play(robot, t, q, feedforward="magic")
    with pytest.raises(ValueError, match="model_or_scene"):
        play("ur5e", t, q)


def test_trajectory_file_and_simulate(tmp_path):
    """A trajectory file of a robot with a TCP: the robot and TCP come from its metadata,
    and simulate() writes the report and plots (the CLI's `ruledrobot simulate`)."""
    from ruledrobot.robot.motion.trajectory import Trajectory

    robot = load("ur10e").with_tool([0.02, 0.0, 0.2, 0.0, 0.3, 0.0])
    t, q, _ = smooth_trajectory(1.0, q0=(0.0, -1.4, 1.2, -1.4, -1.57, 0.0))
    path = write_trajectory(tmp_path / "traj.csv", Trajectory.from_joints(t, q, robot))
    res = play_file(path)
    assert res.robot.name == "ur10e"
    np.testing.assert_allclose(res.robot.tool, robot.tool, atol=1e-9)
    assert res.report()["tcp_position_error_mm"]["max"] < 0.5
    paths = simulate(path, tmp_path / "sim")
    assert {"report", "tracking_plot", "limits_plot", "simulated"} <= set(paths)
    assert json.loads(paths["report"].read_text())["robot"] == "ur10e"
    with pytest.raises(ValueError, match=r"planned for a ur10e.*not for the ur5e"):
        play_file(path, load("ur5e"))


def test_scene_gains_override():
    from ruledrobot.sim import ServoGains

    t, q, _ = smooth_trajectory(1.0)
    soft = ServoGains.default(CELL.robot)
    soft = ServoGains(0.1 * soft.kp, 0.1 * soft.kv)
    res = play(Scene(CELL.robot), t, q, gains=soft, collisions=False)
    stiff = play(Scene(CELL.robot), t, q, collisions=False)
    assert res.report()["servo"]["kp"] == pytest.approx(soft.kp.tolist())
    assert res.report()["joint_error_rad"]["max"] > 3 * stiff.report()["joint_error_rad"]["max"]
