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
#: FAST_DEMO_JOB narrowed: the surface 12 cm wide (u = ±6 cm) through a block 8 cm wide,
#: 2 cm of surface beyond each side of the block as in the demo: 3.3 s in the block at
#: 25 mm/s instead of 8.3 s, the same feed and the same lead-in and lead-out
SHORT_DEMO_JOB = (FAST_DEMO_JOB.replace("u = [-0.12, 0.12]", "u = [-0.06, 0.06]")
                  .replace("size = [0.2, 0.2, 0.15]", "size = [0.08, 0.2, 0.15]"))  # fmt: skip


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """These tests run real-time servers (500 Hz streams, timed faults) on whatever else
    the machine is doing: a failure is rerun once, and the run says so ("1 rerun")."""
    for item in items:
        if "tests/export/" in item.nodeid.replace("\\", "/"):
            item.add_marker(pytest.mark.flaky(reruns=1))


@pytest.fixture(scope="session")
def fast_demo(tmp_path_factory: pytest.TempPathFactory) -> Trajectory:
    """The demo planned at 25 mm/s, its approach at the joints' full speed and 4 rad/s^2
    (the model's 1.4 rad/s^2 is a planning default, the arm's ceiling is 40:
    ruledrobot.ursim.arm.backend.HARDWARE_ACCELERATION), with what it cuts
    (``meta.cut``): streamed in real time by test_run_path (10.1 s of motion, 8.3 s in
    the block; 13.5 s with the demo's approach at 0.3 of the speed and 1.4 rad/s^2)."""
    job = tmp_path_factory.mktemp("fast_demo") / "job.toml"
    text = (FAST_DEMO_JOB.replace("approach_speed = 0.3", "approach_speed = 1.0")
            .replace("speed_scale = 1.0\n", "speed_scale = 1.0\nacceleration = 4.0\n"))  # fmt: skip
    assert text.count("feed_speed = 0.025 ") == 1 and text.count("acceleration = 4.0") == 1
    assert text.count("approach_speed = 1.0") == 1
    job.write_text(text)
    traj = plan(load_job(job), None, simulate=False).trajectory
    assert traj is not None and traj.meta.cut is not None
    return traj


@pytest.fixture(scope="session")
def short_demo(tmp_path_factory: pytest.TempPathFactory) -> Trajectory:
    """The narrowed demo at 25 mm/s (:data:`SHORT_DEMO_JOB`), with what it cuts: streamed
    in real time by test_path_programs (its cut, lead-in to lead-out: 4.7 s of motion
    instead of the fast demo's 9.7 s)."""
    job = tmp_path_factory.mktemp("short_demo") / "job.toml"
    assert SHORT_DEMO_JOB.count("u = [-0.06, 0.06]") == 1
    assert SHORT_DEMO_JOB.count("size = [0.08, 0.2, 0.15]") == 1
    job.write_text(SHORT_DEMO_JOB)
    traj = plan(load_job(job), None, simulate=False).trajectory
    assert traj is not None and traj.meta.cut is not None
    return traj
