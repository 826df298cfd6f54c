"""The cell a trajectory was planned in (wirecut.job.scene): the job file the trajectory
names, or the plan folder's copy, rebuilt when its SHA-256 matches; else the robot alone."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from ruledrobot.io.trajectory import write_trajectory
from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.job.scene import scene_of_trajectory
from ruledrobot.wirecut.plan import make_plan

#: the demo on a base turned and raised: the scene must carry the job's base
BASED = DEMO_JOB.replace("base = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]",
                         "base = [0.1, 0.2, 0.05, 0.0, 0.0, 0.5]")


@pytest.fixture(scope="module")
def planned(tmp_path_factory):
    root = tmp_path_factory.mktemp("scene")
    job_file = root / "job_src" / "based.toml"
    job_file.parent.mkdir()
    job_file.write_text(BASED)
    job = load_job(job_file)
    plan = make_plan(job)
    assert plan.trajectory.meta.job["path"] == str(job_file)
    out = root / "plan"
    out.mkdir()
    traj = write_trajectory(out / "trajectory.csv", plan.trajectory)
    return job_file, job, traj


def test_the_named_job_file_gives_its_cell(planned):
    job_file, job, traj = planned
    scene, words = scene_of_trajectory(traj)
    assert scene is not None
    assert words == f"the cell of {job_file} (arm, bow, stock, table)"
    np.testing.assert_array_equal(scene.stock.centre, job.stock.centre)
    np.testing.assert_array_equal(scene.stock.size, job.stock.size)
    np.testing.assert_allclose(scene.robot.base, job.robot.base, atol=1e-12)
    assert scene.tool is not None


def test_the_plan_folders_copy_serves_when_the_file_is_gone_or_changed(planned):
    job_file, _, traj = planned
    copy = traj.parent / "job.toml"
    shutil.copy(job_file, copy)
    saved = job_file.read_text()
    try:
        job_file.write_text(saved.replace("feed_speed = 0.01", "feed_speed = 0.02"))
        scene, words = scene_of_trajectory(traj)
        assert scene is not None and words.startswith(f"the cell of {copy} ")
        copy.write_text(saved + "# edited\n")  # neither matches the trajectory's SHA-256
        scene, words = scene_of_trajectory(traj)
        assert scene is None
        assert words == ("the robot on a table (the trajectory names no job file that is at "
                         "hand)")  # fmt: skip
    finally:
        job_file.write_text(saved)
        copy.unlink(missing_ok=True)
