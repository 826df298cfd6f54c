"""The cell a trajectory was planned in: the job it names, rebuilt as a MuJoCo scene."""

from __future__ import annotations

import os
from pathlib import Path

from ...io.trajectory import read_trajectory
from ...robot import model_for
from ...sim import Scene
from .load import load_job

__all__ = ["scene_of_trajectory"]


def scene_of_trajectory(trajectory: str | os.PathLike[str]) -> tuple[Scene | None, str]:
    """Return the scene of the job a trajectory names, else None.

    The job is the trajectory's file, or the plan folder's copy ``job.toml``, with the same
    SHA-256; None: the robot alone on a table.
    """
    import hashlib

    trajectory = Path(trajectory)
    meta = read_trajectory(trajectory).meta
    ref = meta.job or {}
    for cand in (Path(ref.get("path", "")), trajectory.parent / "job.toml"):
        if ref and cand.is_file() and hashlib.sha256(cand.read_bytes()).hexdigest() == ref.get(
            "sha256"
        ):
            job = load_job(cand)
            robot = model_for(meta).with_base(job.robot.base)
            return Scene.from_job(job, robot=robot), f"the cell of {cand} (arm, bow, stock, table)"
    return None, "the robot on a table (the trajectory names no job file that is at hand)"
