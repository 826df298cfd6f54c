"""Jobs for the batch tests: the demo job made cheap, and variants of it.

``FAST_JOB`` is the demo job with two refinement steps and a 40 mm/s feed (a 10 s
trajectory, about 3 s to plan and verify in MuJoCo); ``FAR_JOB`` moves surface and
stock out of reach (infeasible at once: the ``reach`` check); ``BROKEN_JOB`` has a
negative feed (bad input, found by the job's parser on the worker).
"""

from __future__ import annotations

import faulthandler
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

from ruledrobot.io.lines import save_lines
from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.job.load import job_document, parse_job

FAST_JOB = DEMO_JOB.replace("steps = 4", "steps = 2").replace(
    "feed_speed = 0.01 ", "feed_speed = 0.04 "
)
FAR_JOB = FAST_JOB.replace("pose = [0.5, 0.0, 0.3,", "pose = [2.5, 0.0, 0.3,").replace(
    "centre = [0.5, 0.0, 0.3]", "centre = [2.5, 0.0, 0.3]"
)
BROKEN_JOB = FAST_JOB.replace("feed_speed = 0.04 ", "feed_speed = -1 ")
_SURFACE = """builtin = "hyperbolic_paraboloid"
params = { c = 0.4 }
u = [-0.12, 0.12]          # rulings at x = u (m) in the surface frame
rulings = 9                # input rulings, refined below
pose = [0.5, 0.0, 0.3, 0.0, 0.0, 0.0]   # surface frame in the robot base frame
"""
assert _SURFACE in FAST_JOB


def file_job(lines_path: str, calibration: str | None = None) -> str:
    """``FAST_JOB`` with its rulings read from a lines file (the same surface), and on a
    calibrated robot when ``calibration`` names a calibration file."""
    text = FAST_JOB.replace(_SURFACE, f'file = "{lines_path}"\n')
    if calibration:
        text = text.replace("speed_scale = 1.0",
                            f'speed_scale = 1.0\ncalibration = "{calibration}"')  # fmt: skip
    return text


def write_calibration(path: Path) -> Path:
    """A factory calibration of the job's UR5e without a ``source`` field (it is then
    known by its path, which goes into ``trajectory.json``)."""
    import json

    from ruledrobot.io.calibration import save_calibration
    from ruledrobot.robot import random_calibration

    path.parent.mkdir(parents=True, exist_ok=True)
    save_calibration(path, random_calibration("ur5e", seed=3))
    doc = json.loads(path.read_text())
    doc.pop("source", None)
    path.write_text(json.dumps(doc))
    return path


def write_rulings(path: Path) -> Path:
    """The rulings of ``FAST_JOB``'s surface, in the base frame, as a lines file."""
    lines = parse_job(job_document(FAST_JOB, "fast job")).surface.lines()
    path.parent.mkdir(parents=True, exist_ok=True)
    return save_lines(path, lines)


@contextmanager
def deadline(seconds: float) -> Iterator[None]:
    """Bound a test in time: past ``seconds`` the test process prints every thread's
    stack and exits (a hung cluster must not hang the suite)."""
    faulthandler.dump_traceback_later(seconds, exit=True)
    try:
        yield
    finally:
        faulthandler.cancel_dump_traceback_later()
