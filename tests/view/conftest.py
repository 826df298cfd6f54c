"""Plan folders for the viewer's tests: real plans, made once per session.

``plan_folder``: the demo job made cheaper (two refinement steps, feed 40 mm/s:
a 10 s trajectory, about 2 s to plan and verify in MuJoCo).  ``failed_folder``:
the same job planned without the MuJoCo verification, so its verdict fails
(``verified``) and, like every failed plan, it holds no trajectory.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import pytest

from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.planner import plan

FAST_JOB = DEMO_JOB.replace("steps = 4", "steps = 2").replace(
    "feed_speed = 0.01 ", "feed_speed = 0.04 "
)


def _plan(tmp_path_factory, name: str, simulate: bool):
    root = tmp_path_factory.mktemp(name)
    (root / "job.toml").write_text(FAST_JOB, encoding="utf-8")
    out = root / "out"
    result = plan(load_job(root / "job.toml"), out, simulate=simulate)
    return out, result


@pytest.fixture(scope="session")
def plan_folder(tmp_path_factory):
    out, result = _plan(tmp_path_factory, "view-plan", simulate=True)
    assert result.feasible, result.report["verdict"]["summary"]
    return out


@pytest.fixture(scope="session")
def failed_folder(tmp_path_factory):
    out, result = _plan(tmp_path_factory, "view-failed", simulate=False)
    assert not result.feasible
    return out


@pytest.fixture(scope="session")
def scene(plan_folder):
    from ruledrobot.view import build_scene

    return build_scene(plan_folder)
