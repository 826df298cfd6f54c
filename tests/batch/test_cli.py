"""``ruledrobot batch`` on the command line: bad input to the batch (exit 2), and the real
command on its own local cluster stopped by Ctrl-C and run again (exit 130, then 0)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from typer.testing import CliRunner

from ruledrobot.cli import app
from tests.architecture.imports import graph
from tests.support.processes import popen_as_from_a_terminal

from .conftest import FAST_JOB, deadline

runner = CliRunner()


def _text(result) -> str:
    return " ".join(result.output.split())  # rich wraps long lines


def test_only_the_cli_imports_batch_and_batch_does_not_import_the_layers_above():
    for mod, deps in graph().items():
        if mod.startswith("ruledrobot.batch"):
            assert not any(d.startswith(("ruledrobot.cli", "ruledrobot.view")) for d in deps)
        elif not mod.startswith("ruledrobot.cli"):
            assert not any(d.startswith("ruledrobot.batch") for d in deps), mod


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["nothing-*.toml"], "matches no file"),
        (["list.toml"], "list.toml: not valid TOML"),
        (["job.toml", "--workers", "2", "--scheduler", "tcp://127.0.0.1:1"],
         "--workers sizes the local cluster"),
        (["job.toml"], "batch.json: not a batch manifest of ruledrobot"),
    ],
)
def test_bad_input_to_the_batch_exits_2_and_plans_nothing(tmp_path, monkeypatch, args,
                                                          message):  # fmt: skip
    monkeypatch.chdir(tmp_path)
    (tmp_path / "job.toml").write_text(FAST_JOB)
    (tmp_path / "list.toml").write_text("[[jobs]]\njob = \n")
    out = tmp_path / "out"
    if "batch.json: not" in message:
        out.mkdir()
        (out / "batch.json").write_text("[1, 2]")
    res = runner.invoke(app, ["batch", *args, "--out", str(out)])
    assert res.exit_code == 2, res.output
    assert message in _text(res)
    assert not out.exists() or sorted(p.name for p in out.iterdir()) == ["batch.json"]
    if out.exists():
        assert (out / "batch.json").read_text() == "[1, 2]"  # not ours: left alone


def test_an_unreachable_scheduler_is_bad_input_and_nothing_is_written(tmp_path):
    from ruledrobot.batch import EngineUnavailable, run_batch

    (tmp_path / "job.toml").write_text(FAST_JOB)
    with deadline(60), pytest.raises(EngineUnavailable, match="cannot reach the Dask scheduler"):
        run_batch([tmp_path / "job.toml"], tmp_path / "out", scheduler="tcp://127.0.0.1:9",
                  timeout=2)  # fmt: skip
    assert not (tmp_path / "out").exists()


def _children(pid: int) -> list[int]:
    import psutil

    return [p.pid for p in psutil.Process(pid).children(recursive=True)]


def _alive(pids: list[int]) -> list[int]:
    import psutil

    alive = []
    for pid in pids:
        try:
            if psutil.Process(pid).status() != psutil.STATUS_ZOMBIE:
                alive.append(pid)
        except psutil.NoSuchProcess:
            pass
    return alive


def test_ctrl_c_stops_cleanly_and_the_same_command_resumes(tmp_path):
    pytest.importorskip("distributed")
    jobs = tmp_path / "jobs"
    jobs.mkdir()
    n = 3  # three jobs on two workers: the first result comes with two to go (one running,
    # one sent in its place); a fourth cost the resume a second round of plans
    for k in range(n):
        (jobs / f"p{k}.toml").write_text(FAST_JOB.replace("feed_speed = 0.04 ",
                                                          f"feed_speed = 0.04{k} "))
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "ruledrobot.cli", "batch", str(jobs / "*.toml"), "--out",
           str(out), "--workers", "2"]  # fmt: skip
    env = dict(os.environ, MUJOCO_GL=os.environ.get("MUJOCO_GL", "egl"), COLUMNS="200")
    with deadline(240):
        proc = popen_as_from_a_terminal(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                        env=env, start_new_session=True, text=True)
        t0 = time.monotonic()
        while time.monotonic() - t0 < 150:
            try:
                doc = json.loads((out / "batch.json").read_text())
                if doc["counts"]["feasible"]:
                    break
            except (OSError, ValueError, KeyError):
                pass
            time.sleep(0.2)
        workers = _children(proc.pid)
        os.killpg(proc.pid, signal.SIGINT)  # as a terminal's Ctrl-C: the whole group
        t_int = time.monotonic()
        output, _ = proc.communicate(timeout=60)
        stop_s = time.monotonic() - t_int
        assert proc.returncode == 130, output
        assert stop_s < 30, f"took {stop_s:.1f} s to stop"
        assert "Traceback" not in output and "KeyboardInterrupt" not in output, output
        time.sleep(1.0)
        assert not _alive(workers), "worker processes left behind"
        doc = json.loads((out / "batch.json").read_text())
        assert doc["run"]["interrupted"] is True and doc["complete"] is False
        statuses = [j["status"] for j in doc["jobs"]]
        assert set(statuses) == {"feasible", "pending"}, statuses
        done = [j["name"] for j in doc["jobs"] if j["status"] == "feasible"]
        assert all((out / n / "trajectory.csv").is_file() for n in done)
        assert not list(out.glob(".*staging*"))  # nothing half-written left

        again = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=150)
    assert again.returncode == 0, again.stdout + again.stderr
    doc = json.loads((out / "batch.json").read_text())
    assert [j["status"] for j in doc["jobs"]] == ["feasible"] * n
    assert doc["run"]["kept"] == len(done) and doc["run"]["planned"] == n - len(done)
    assert f"kept {len(done)}" in " ".join(again.stdout.split())
    assert Path(out / "batch.csv").read_text().count("feasible") == n
