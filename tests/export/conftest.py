"""Tests of the runner and the URScript export, against the emulator.

The fixtures (emulators on distinct loopback addresses, hard time limits, ur_rtde
interfaces) live in :mod:`tests.support.emulators`.
"""

from __future__ import annotations

import pytest

from ruledrobot.robot.motion.trajectory import Trajectory
from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.planner import plan
from tests.support.emulators import _deadline, emulator, host, ur  # noqa: F401  (fixtures)

#: the demo job at 25 mm/s (its own 10 mm/s is planned and verified in tests/wirecut)
FAST_DEMO_JOB = DEMO_JOB.replace("feed_speed = 0.01 ", "feed_speed = 0.025 ")


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """These tests run real-time servers (500 Hz streams, timed faults) on whatever else
    the machine is doing: a failure is rerun once, and the run says so ("1 rerun")."""
    for item in items:
        if "tests/export/" in item.nodeid.replace("\\", "/"):
            item.add_marker(pytest.mark.flaky(reruns=1))


@pytest.fixture(scope="session")
def fast_demo(tmp_path_factory: pytest.TempPathFactory) -> Trajectory:
    """The demo planned at 25 mm/s, with what it cuts (``meta.cut``): streamed in real time
    (17 s of motion instead of 27 s) by test_run_path and test_path_programs, planned once
    per test process for both."""
    job = tmp_path_factory.mktemp("fast_demo") / "job.toml"
    assert FAST_DEMO_JOB.count("feed_speed = 0.025 ") == 1
    job.write_text(FAST_DEMO_JOB)
    traj = plan(load_job(job), None, simulate=False).trajectory
    assert traj is not None and traj.meta.cut is not None
    return traj
