"""A plan killed at any moment leaves its folder as the old complete set or the new one.

The planner writes into a staging folder and swaps it in at once (renameat2
RENAME_EXCHANGE); every file the manifest lists is there with its checksum.
"""

from __future__ import annotations

import hashlib
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from ruledrobot.io.outdir import read_manifest
from ruledrobot.io.trajectory import read_trajectory
from ruledrobot.wirecut.job.demo import DEMO_JOB

TRIALS = 10


def _complete(folder: Path) -> dict:
    man = read_manifest(folder)
    assert man is not None and man["complete"] is True, f"{folder}: no manifest"
    for rel, entry in man["files"].items():
        data = (folder / rel).read_bytes()
        assert hashlib.sha256(data).hexdigest() == entry["sha256"], rel
    return man


def _plan(job: Path, out: Path) -> subprocess.Popen:
    env = dict(os.environ, MUJOCO_GL=os.environ.get("MUJOCO_GL", "egl"))
    return subprocess.Popen([sys.executable, "-m", "ruledrobot.cli", "plan", str(job), "--out",
                             str(out)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            env=env)  # fmt: skip


def test_a_killed_plan_leaves_the_old_or_the_new_complete_set(tmp_path):
    old_job, new_job = tmp_path / "old.toml", tmp_path / "new.toml"
    old_job.write_text(DEMO_JOB)
    new_job.write_text(DEMO_JOB.replace("feed_speed = 0.01", "feed_speed = 0.012"))
    out = tmp_path / "cut"
    t0 = time.monotonic()
    assert _plan(old_job, out).wait(120) == 0
    full = time.monotonic() - t0
    old = _complete(out)
    rng = np.random.default_rng(1)
    outcomes = []
    for _ in range(TRIALS):
        proc = _plan(new_job, out)
        time.sleep(float(rng.uniform(0.2, 1.2 * full)))
        proc.send_signal(signal.SIGKILL)
        proc.wait(30)
        man = _complete(out)  # never a mixed or half-written folder
        outcomes.append("old" if man["files"] == old["files"] else "new")
        traj = read_trajectory(out / "trajectory.csv")  # and the pair reads back
        feed = 0.01 if outcomes[-1] == "old" else 0.012
        assert json.loads((out / "report.json").read_text())["feed_speed_mm_s"] == feed * 1e3
        assert traj.n > 0
        if outcomes[-1] == "new":  # start the next trial from the old set again
            assert _plan(old_job, out).wait(120) == 0
            old = _complete(out)
    leftovers = [p.name for p in tmp_path.iterdir() if p.name.startswith(".cut.")]
    assert all(".staging-" in n for n in leftovers)  # a killed run's staging, swept later
    assert "old" in outcomes
