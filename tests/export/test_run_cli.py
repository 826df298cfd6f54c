"""``ruledrobot run`` on the command line: confirmation policy, --mode choice, dry run,
refusal, where a stopped run stopped and the resume command, numbered recordings."""

from __future__ import annotations

import functools
import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

from ruledrobot.cli import app
from ruledrobot.io.trajectory import write_trajectory
from ruledrobot.ursim import Emulator, KinematicBackend
from tests.support.emulators import smooth_trajectory, start_emulator

from .test_run_plan import cut_trajectory

pytest.importorskip("rtde_control")


def _invoke(*args: str):
    return CliRunner().invoke(app, ["run", *args])


def test_without_a_terminal_and_without_yes_it_refuses(tmp_path: Path) -> None:
    src = write_trajectory(tmp_path / "cut.csv", smooth_trajectory())
    res = _invoke(str(src), "--host", "127.0.0.1")  # CliRunner's stdin is no terminal
    assert res.exit_code == 2 and "pass --yes" in res.output


def test_mode_is_a_choice(tmp_path: Path) -> None:
    src = write_trajectory(tmp_path / "cut.csv", smooth_trajectory())
    res = _invoke(str(src), "--mode", "movej", "--yes")
    assert res.exit_code == 2 and "servoj" in res.output and "path" in res.output


def test_dry_run_prints_the_checks_and_the_approach_not_a_deviation(
    emulator: Emulator, tmp_path: Path
) -> None:
    src = write_trajectory(tmp_path / "cut.csv", cut_trajectory())
    res = _invoke(str(src), "--host", emulator.host, "--dry-run")
    assert res.exit_code == 0, res.output
    out = res.output
    assert "checks before motion" in out and "robot model" in out
    assert "kinematics" in out  # the nominal plan on a nominal controller: checked
    assert "approach move:" in out and "dry run: nothing moved" in out
    assert "deviation" not in out
    assert not list(tmp_path.glob("*.run-*"))
    # a trajectory for another robot: refused, exit 1, the failing check in the table
    other = write_trajectory(tmp_path / "ur10e.csv", smooth_trajectory(model="ur10e"))
    res = _invoke(str(other), "--host", emulator.host, "--dry-run")
    assert res.exit_code == 1 and "FAIL" in res.output and "planned for a ur10e" in res.output


def test_a_stopped_run_says_where_and_how_to_resume(request, tmp_path: Path) -> None:
    # joint 1 of this arm cannot follow: the run stops on the deviation, inside the stock
    slow = functools.partial(KinematicBackend, max_velocity=[0.1, 3.0, 3.0, 3.0, 3.0, 3.0])
    traj = cut_trajectory()
    emu = start_emulator(request.node.nodeid, model="ur5e", backend=slow, unlock_delay=0.0,
                         q0=traj.q[0])  # fmt: skip
    try:
        src = write_trajectory(tmp_path / "cut.csv", traj)
        outs = []
        for _ in range(2):  # servoj: its stop leaves the arm where the second run may enter
            res = _invoke(str(src), "--host", emu.host, "--yes", "--mode", "servoj")
            assert res.exit_code == 1, res.output
            outs.append(res.output)
    finally:
        emu.close()
    out = outs[0]
    assert "deviation:" in out
    m = re.search(r"stopped at sample (\d+) \(t = [\d.]+ s\), phase (\w+), wire (\w+) the stock",
                  out)  # fmt: skip
    assert m, out
    k = int(m.group(1))
    assert m.group(2) == traj.phase_at(k)
    assert m.group(3) == ("inside" if traj.inside_stock()[k] else "outside")
    assert (f"resume with: ruledrobot run {src} --host {emu.host} --mode servoj --resume {k}"
            in out)
    assert "cut.run-001.csv" in outs[0] and "cut.run-002.csv" in outs[1]
    assert (tmp_path / "cut.run-001.csv").exists() and (tmp_path / "cut.run-002.json").exists()
