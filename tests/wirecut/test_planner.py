"""The cut planner end to end, checked on the written files independently of the planner."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from ruledrobot.cli import app
from ruledrobot.geometry.surfaces import hyperbolic_paraboloid_residual
from ruledrobot.io.trajectory import read_trajectory
from ruledrobot.robot import load
from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.planner import plan

runner = CliRunner()


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo")
    (out / "job.toml").write_text(DEMO_JOB)
    job = load_job(out / "job.toml")
    return job, plan(job, out), out


def test_demo_plan_writes_every_file(demo):
    job, res, out = demo
    assert res.feasible
    for name in ("trajectory.csv", "refined.json", "surface.stl", "report.json", "plots.png"):
        assert (out / name).stat().st_size > 0
    report = json.loads((out / "report.json").read_text())
    for key in (
        "duration_s",
        "max_wire_deviation_mm",
        "max_feed_speed_mm_s",
        "max_joint_speed_ratio",
        "max_joint_accel_ratio",
        "min_singularity_measure",
        "collisions",
        "verdict",
        "max_tcp_tracking_error_mm",
    ):
        assert key in report
    assert report["collisions"] == [] and report["verdict"]["ok"] is True
    assert report["verdict"]["failed"] == [] and len(report["verdict"]["checks"]) >= 11
    # verified in MuJoCo: the simulated wire stays on the target rulings inside the stock
    assert report["max_wire_deviation_mm"] <= 0.5
    assert report["max_tcp_tracking_error_mm"] <= 0.5
    assert report["max_feed_speed_mm_s"] <= 1.01 * job.cut.feed_speed * 1e3
    assert report["max_joint_speed_ratio"] <= 1.0 and report["max_joint_accel_ratio"] <= 1.0
    assert (out / "simulation" / "report.json").exists()


def test_trajectory_respects_limits_and_period(demo):
    job, _, out = demo
    traj = read_trajectory(out / "trajectory.csv")
    model = load(job.robot.model)
    np.testing.assert_allclose(np.diff(traj.t), model.control_period, atol=1e-9)
    qd = np.diff(traj.q, axis=0) / np.diff(traj.t)[:, None]
    qdd = np.diff(qd, axis=0) / model.control_period
    assert (np.abs(qd) / model.max_velocity).max() <= 1.0
    assert (np.abs(qdd) / model.max_acceleration).max() <= 1.01  # CSV rounding: 10 digits
    assert model.within_limits(traj.q).all()
    # the TCP columns are the forward kinematics of the joint columns (wire frame)
    from ruledrobot.wirecut.cut.wire_geometry import wire_frame

    np.testing.assert_allclose(model.fk(traj.q) @ wire_frame(job.tool), traj.tcp_poses(), atol=1e-7)
    np.testing.assert_allclose(traj.meta.tcp_offset, wire_frame(job.tool), atol=1e-12)
    assert traj.meta.payload.mass == job.tool.mass and traj.meta.robot == "ur5e"


def test_wire_lies_on_the_surface_and_moves_at_the_feed_speed(demo):
    """Independent of the planner: the wire line from the CSV, clipped to the stock, lies
    on the exact hyperbolic paraboloid, and its points inside move at the feed speed."""
    job, _, out = demo
    traj = read_trajectory(out / "trajectory.csv")
    G = traj.tcp_poses()
    o, z = G[:, :3, 3], G[:, :3, 2]
    t0, t1, hit = job.stock.clip_lines(o, z)
    k = np.flatnonzero(hit)
    assert k.size > 1000
    inv = np.linalg.inv(job.surface.pose)  # into the surface frame
    for t in (t0, t1, 0.5 * (t0 + t1)):
        p = o[k] + t[k, None] * z[k]
        local = p @ inv[:3, :3].T + inv[:3, 3]
        assert np.abs(hyperbolic_paraboloid_residual(local, c=0.4)).max() < 1e-4  # 0.1 mm
    # feed: speed of the chord end points (as points of the wire) between samples
    inside = k[(k > 0) & (k < len(G) - 1)]
    inside = inside[hit[inside - 1] & hit[inside + 1]]
    speeds = []
    for t in (t0, t1):
        local_z = t[inside]  # material point: the same wire coordinate at the neighbours
        a = o[inside + 1] + local_z[:, None] * z[inside + 1]
        b = o[inside - 1] + local_z[:, None] * z[inside - 1]
        speeds.append(np.linalg.norm(a - b, axis=1) / (traj.t[inside + 1] - traj.t[inside - 1]))
    feed = np.maximum(*speeds)
    assert feed.max() <= job.cut.feed_speed * 1.01
    steady = np.abs(feed / job.cut.feed_speed - 1.0) <= 0.01
    assert steady.mean() > 0.95


def test_cli_plan_and_infeasible_job(tmp_path):
    job = tmp_path / "job.toml"
    job.write_text(DEMO_JOB)
    result = runner.invoke(app, ["plan", str(job), "--out", str(tmp_path / "ok")])
    assert result.exit_code == 0, result.output
    assert "trajectory.csv" in result.output
    far = DEMO_JOB.replace("pose = [0.5, 0.0, 0.3,", "pose = [2.5, 0.0, 0.3,").replace(
        "centre = [0.5, 0.0, 0.3]", "centre = [2.5, 0.0, 0.3]"
    )
    job.write_text(far)
    result = runner.invoke(app, ["plan", str(job), "--out", str(tmp_path / "far")])
    assert result.exit_code == 1
    text = " ".join(result.output.split())  # rich wraps long lines
    assert "verdict: FAIL" in text and "no continuous IK" in text
    report = json.loads((tmp_path / "far" / "report.json").read_text())
    assert report["feasible"] is False and report["reasons"]
    assert not (tmp_path / "far" / "trajectory.csv").exists()
