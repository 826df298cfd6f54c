"""The MuJoCo-backed controller emulator, driven by the real ur_rtde client through the runner."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from ruledrobot.export import run_trajectory
from ruledrobot.io.trajectory import read_trajectory, write_trajectory
from ruledrobot.robot import load
from ruledrobot.robot.motion.trajectory import Trajectory
from ruledrobot.ursim.arm.physics import MujocoBackend
from tests.support.emulators import start_emulator

MODEL = "ur5e"


def test_backend_tracks_with_dynamics() -> None:
    b = MujocoBackend(load(MODEL))
    q0 = np.array([3.0, -1.2, 1.4, -1.8, -1.57, 0.0])
    b.reset(q0)
    for k in range(500):
        t = k * 0.002
        b.track(q0 + 0.05 * np.sin(t), np.full(6, 0.05 * np.cos(t)), np.zeros(6))
        b.step(0.002)
    s = b.state()
    assert 0.0 < np.abs(s.q - s.target_q).max() < 1e-3  # real tracking: small, not zero
    assert abs(s.current[1]) > 5.0  # the shoulder carries the arm against gravity (N m)


def test_runner_streams_to_the_mujoco_backed_emulator(request, tmp_path: Path) -> None:
    model = load(MODEL)
    t = np.arange(0.0, 1.5, 0.002)
    q0 = np.array([3.0, -1.2, 1.4, -1.8, -1.57, 0.0])
    q = q0 + 0.1 * (1 - np.cos(np.pi * t / 1.5))[:, None] * np.array([1, -0.5, 0.5, 1, 0, 1])
    src = write_trajectory(tmp_path / "cut.csv", Trajectory.from_joints(t, q, model))
    emu = start_emulator(request.node.nodeid, model=MODEL, unlock_delay=0.0, q0=q0,
                         backend=MujocoBackend)  # fmt: skip
    try:
        res = run_trajectory(src, emu.host, MODEL)
        assert res.status == "completed", res
        rec = read_trajectory(res.actual_path)
        np.testing.assert_allclose(rec.q[-1], q[-1], atol=2e-3)
        assert res.max_deviation < 0.02
        np.testing.assert_allclose(emu.actual_q, q[-1], atol=2e-3)
    finally:
        emu.close()


@pytest.mark.parametrize("physics", ["bogus"])
def test_cli_rejects_unknown_physics(physics: str) -> None:
    from typer.testing import CliRunner

    from ruledrobot.cli import app

    result = CliRunner().invoke(app, ["ursim", "--physics", physics])
    assert result.exit_code == 2 and "--physics" in result.output
