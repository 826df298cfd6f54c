"""The ruledrobot command line: refine, errors, help texts."""

from __future__ import annotations

import numpy as np
from typer.testing import CliRunner

import ruledrobot as rr
from ruledrobot.cli import app

runner = CliRunner()


def test_help_lists_commands_with_examples():
    result = runner.invoke(app, ["--help"])
    assert result.exit_code == 0
    for name in ("refine", "gallery"):
        assert name in result.output
        sub = runner.invoke(app, [name, "--help"])
        assert sub.exit_code == 0 and "Example:" in sub.output


def test_refine_writes_lines_frames_and_mesh(tmp_path, rng):
    lines = rr.Lines.from_point_direction(rng.normal(size=(6, 3)), rng.normal(size=(6, 3)))
    src = rr.save_lines(tmp_path / "in.csv", lines)
    out = tmp_path / "out" / "refined.json"
    mesh = tmp_path / "out" / "refined.stl"
    result = runner.invoke(
        app,
        [
            "refine",
            str(src),
            "--out",
            str(out),
            "--algorithm",
            "dh",
            "--steps",
            "2",
            "--mesh",
            str(mesh),
            "--half-width",
            "0.2",
        ],
    )
    assert result.exit_code == 0, result.output
    assert f"wrote {out}" in result.output.replace("\n", "")
    doc = rr.read_lines_document(out)
    expected = rr.refine(lines, "dh", "four_point", 2)
    np.testing.assert_allclose(doc.lines.plucker, expected.lines.plucker, atol=1e-12)
    np.testing.assert_allclose(doc.frames, expected.frames, atol=1e-12)
    assert mesh.stat().st_size > 84


def test_refine_reports_bad_input_without_traceback(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"lines": [[1, 0, 0, 0, 1, 0], [3, 0, 0, 0, 1, 0]]}')
    result = runner.invoke(app, ["refine", str(bad), "--out", str(tmp_path / "o.json")])
    assert result.exit_code == 2
    assert "lines[1]: direction must be a unit vector" in result.output
    assert "Traceback" not in result.output
    assert not (tmp_path / "o.json").exists()
    few = rr.save_lines(
        tmp_path / "few.json", rr.Lines.from_point_direction(np.eye(3), np.ones((3, 3)))
    )
    result = runner.invoke(app, ["refine", str(few), "--scheme", "six_point"])
    assert result.exit_code == 2 and "needs at least 6" in result.output


def test_chain_command_writes_mjcf_whose_axes_are_the_lines(tmp_path, rng):
    import os

    os.environ.setdefault("MUJOCO_GL", "egl")
    import mujoco

    lines = rr.Lines.from_point_direction(rng.normal(size=(5, 3)), rng.normal(size=(5, 3)))
    src = rr.save_lines(tmp_path / "lines.json", lines)
    out = tmp_path / "chain.xml"
    result = runner.invoke(app, ["chain", str(src), "--out", str(out)])
    assert result.exit_code == 0, result.output
    model = mujoco.MjModel.from_xml_string(out.read_text())
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    axes, anchors = data.xaxis[: len(lines)], data.xanchor[: len(lines)]
    np.testing.assert_allclose(np.abs((axes * lines.direction).sum(1)), 1.0, atol=1e-9)
    np.testing.assert_allclose(
        np.cross(anchors, lines.direction),
        lines.moment * np.sign((axes * lines.direction).sum(1))[:, None],
        atol=1e-9,
    )
    bad = runner.invoke(app, ["chain", str(tmp_path / "missing.json")])
    assert bad.exit_code == 2 and "no such file" in bad.output


def test_simulate_command_reports_tracking(tmp_path):
    from ruledrobot.io.trajectory import write_trajectory
    from ruledrobot.robot.motion.trajectory import Trajectory

    model = rr.robot.load("ur5e")
    t = np.arange(0, 1.0, 0.002)
    q = np.array([3.0, -1.2, 1.4, -1.8, -1.57, 0.0]) + 0.05 * np.sin(2 * np.pi * t)[:, None]
    traj = write_trajectory(tmp_path / "t.csv", Trajectory.from_joints(t, q, model))
    result = runner.invoke(app, ["simulate", str(traj), "--out", str(tmp_path / "sim")])
    assert result.exit_code == 0, result.output
    assert "TCP position error" in result.output
    assert (tmp_path / "sim" / "report.json").exists()


def _small_trajectory(tmp_path):
    from ruledrobot.io.trajectory import write_trajectory
    from ruledrobot.robot.motion.trajectory import Trajectory

    model = rr.robot.load("ur5e").with_tool([0, 0, 0.1, 0, 0, 0])
    t = np.arange(0, 0.6, 0.002)
    q = np.array([3.0, -1.2, 1.4, -1.8, -1.57, 0.0]) + 0.02 * (1 - np.cos(np.pi * t / 0.6))[:, None]
    return write_trajectory(tmp_path / "t.csv", Trajectory.from_joints(t, q, model))


def test_export_urscript_and_dry_run(tmp_path):
    traj = _small_trajectory(tmp_path)
    out = tmp_path / "cut.script"
    result = runner.invoke(app, ["export", str(traj), "--out", str(out)])
    assert result.exit_code == 0, result.output
    text = out.read_text()
    assert "movej(" in text and text.count("servoj(") >= 299
    result = runner.invoke(app, ["run", str(traj), "--dry-run"])
    assert result.exit_code == 0, result.output
    bad = runner.invoke(app, ["export", str(traj), "--out", str(tmp_path / "x.txt")])
    assert bad.exit_code == 2


def test_run_streams_to_the_embedded_emulator(tmp_path):
    traj = _small_trajectory(tmp_path)
    result = runner.invoke(app, ["run", str(traj), "--yes"])
    assert result.exit_code == 0, result.output
    assert "completed" in result.output
    assert (tmp_path / "t.run-001.csv").exists()
