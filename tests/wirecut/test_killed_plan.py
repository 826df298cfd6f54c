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

#: where the kills fall (fractions): one while the command starts (before its staging
#: folder exists), one while it plans (the staging folder empty), and four in quarters of
#: the time it writes its files (from the staging folder's first file to the command's
#: exit, the last quarter past it), each at a random moment in its stratum
STRATA = ((None, 0.0, 1.0), ("planning", 0.0, 1.0),
          ("writing", 0.0, 0.25), ("writing", 0.25, 0.5), ("writing", 0.5, 0.75),
          ("writing", 0.75, 1.05))  # fmt: skip
#: the two jobs planned over each other: the demo job made cheap (two refinement steps, a
#: feed of 40 and 45 mm/s: a 10 s cut, each plan about a third of the demo's), what is
#: tested being the folder's swap, not the cut
OLD, NEW = 0.04, 0.045


def _job(feed: float) -> str:
    return DEMO_JOB.replace("steps = 4", "steps = 2").replace("feed_speed = 0.01 ",
                                                              f"feed_speed = {feed} ")


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


def _phases(proc: subprocess.Popen, out: Path, seen: set[Path]) -> dict[str, float]:
    """Poll a running plan's staging folder: the moments (s after now) its folder appears
    (``planning``) and receives its first file (``writing``), and its exit (``end``)."""
    t0, marks = time.monotonic(), {}
    while proc.poll() is None:
        for phase in ("planning", "writing"):
            if phase not in marks and _entered(out, seen, phase):
                marks[phase] = time.monotonic() - t0
        time.sleep(0.01)
    marks["end"] = time.monotonic() - t0
    return marks


def _staging(out: Path) -> set[Path]:
    return set(out.parent.glob(f".{out.name}.staging-*"))


def test_a_killed_plan_leaves_the_old_or_the_new_complete_set(tmp_path):
    """SIGKILL at a random moment in each stratum of :data:`STRATA`; after each kill the
    folder is the previous complete set or the incoming one (then the next trial plans the
    other job over it)."""
    jobs = {OLD: tmp_path / "old.toml", NEW: tmp_path / "new.toml"}
    for feed, path in jobs.items():
        path.write_text(_job(feed))
        assert f"feed_speed = {feed} " in path.read_text()
    out = tmp_path / "cut"
    proc = _plan(jobs[OLD], out)
    marks = _phases(proc, out, _staging(out))
    assert proc.wait() == 0 and "writing" in marks, marks
    window = marks["end"] - marks["writing"]
    feed, current = OLD, _complete(out)
    rng = np.random.default_rng(1)
    outcomes = []
    for phase, lo, hi in STRATA:
        incoming = NEW if feed == OLD else OLD
        seen = _staging(out)
        proc = _plan(jobs[incoming], out)
        if phase is None:  # before the staging folder: the command starting
            time.sleep(float(rng.uniform(0.2, marks["planning"])))
        else:  # wait for the phase in this run, then a random moment in the stratum
            length = window if phase == "writing" else marks["writing"] - marks["planning"]
            while proc.poll() is None and not _entered(out, seen, phase):
                time.sleep(0.01)
            time.sleep(float(rng.uniform(lo, hi)) * length)
        proc.send_signal(signal.SIGKILL)
        proc.wait(30)
        man = _complete(out)  # never a mixed or half-written folder
        outcomes.append("old" if man["files"] == current["files"] else "new")
        traj = read_trajectory(out / "trajectory.csv")  # and the pair reads back
        if outcomes[-1] == "new":  # the incoming set, whole: the next trial replaces it
            feed, current = incoming, man
        assert json.loads((out / "report.json").read_text())["feed_speed_mm_s"] == feed * 1e3
        assert traj.n > 0
    leftovers = [p.name for p in tmp_path.iterdir() if p.name.startswith(".cut.")]
    assert all(".staging-" in n for n in leftovers)  # a killed run's staging, swept later
    assert "old" in outcomes


def _entered(out: Path, seen: set[Path], phase: str) -> bool:
    """Whether a plan started after ``seen`` was taken has entered ``phase``: its staging
    folder exists (``planning``) or holds a file (``writing``)."""
    new = _staging(out) - seen
    return bool(new) and (phase == "planning" or any(
        q.is_file() for p in new for q in p.rglob("*")))
