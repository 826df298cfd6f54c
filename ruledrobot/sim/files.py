"""Trajectory files in MuJoCo: what ``ruledrobot simulate TRAJECTORY --out DIR`` does.

:func:`play_file` plays a trajectory file (:mod:`ruledrobot.io.trajectory`) on the
robot it was planned for; :func:`simulate` writes the playback report, plots, the
simulated trajectory and, on request, a video (:mod:`.render`).
"""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path
from typing import Any

from ..geometry.checks import FloatArray
from ..robot.arm.model import RobotModel
from .playback import PlaybackResult, ProgressCallback, play
from .scene import Scene

__all__ = ["play_file", "simulate"]


def _with_tool(model_or_scene: RobotModel | Scene, tool: FloatArray) -> RobotModel | Scene:
    if isinstance(model_or_scene, Scene):
        return dataclasses.replace(model_or_scene, robot=model_or_scene.robot.with_tool(tool))
    return model_or_scene.with_tool(tool)


def _robot_of(model_or_scene: RobotModel | Scene) -> RobotModel:
    return model_or_scene.robot if isinstance(model_or_scene, Scene) else model_or_scene


def play_file(
    path: str | os.PathLike[str],
    model_or_scene: RobotModel | Scene | None = None,
    **options: Any,
) -> PlaybackResult:
    """Play a trajectory file (CSV and its sidecar, ``ruledrobot.io.trajectory``).

    Without ``model_or_scene`` the robot is the one the trajectory was planned for
    (:func:`ruledrobot.robot.model_for`: its model, kinematics, TCP offset and
    payload).  A model or scene given must be of the trajectory's robot and
    kinematics; its tool is replaced by the trajectory's TCP offset, so the TCP
    errors refer to the file's TCP.  ``options`` go to :func:`play`.  ValueError
    names the file on bad content or a mismatched robot.
    """
    from ..io.trajectory import read_trajectory
    from ..robot import model_for
    from ..robot.motion.trajectory import KinematicsRef

    traj = read_trajectory(path)
    planned = model_for(traj.meta)
    if model_or_scene is None:
        model_or_scene = planned
    robot = _robot_of(model_or_scene)
    if robot.name != planned.name or (
        KinematicsRef.of(robot).checksum != traj.meta.kinematics.checksum
    ):
        raise ValueError(
            f"{path}: planned for a {planned.name} ({traj.meta.kinematics.source} kinematics), "
            f"not for the {robot.name} given"
        )
    model_or_scene = _with_tool(model_or_scene, planned.tool)
    return play(model_or_scene, traj.t, traj.q, **options)


def simulate(
    trajectory: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    *,
    model_or_scene: RobotModel | Scene | None = None,
    video: bool = False,
    fps: int = 25,
    width: int = 640,
    height: int = 480,
    progress: ProgressCallback | None = None,
    **options: Any,
) -> dict[str, Path]:
    """What ``ruledrobot simulate TRAJECTORY.csv --out DIR [--video]`` does.

    Plays the trajectory file (:func:`play_file`) in the scene given, else in
    a :class:`~ruledrobot.sim.scene.Scene` of the file's robot on a table;
    writes ``report.json``, ``tracking.png``, ``limits.png`` and ``simulated.csv``
    into ``out_dir`` and, with ``video``, ``video.mp4`` and ``strip.png`` of
    the simulated motion (raises
    :class:`~ruledrobot.sim.render.RenderUnavailable`, after writing the
    report, when no OpenGL backend works).  Returns ``{name: path}``.
    """
    from ..io.trajectory import read_trajectory

    traj = read_trajectory(trajectory)
    if model_or_scene is None:
        from ..robot import model_for

        model_or_scene = Scene(model_for(traj.meta), width=width, height=height)
    result = play_file(trajectory, model_or_scene, progress=progress, **options)
    paths = result.write(out_dir)
    if video:
        from .render import render_strip, render_video

        paths["video"] = render_video(
            result,
            Path(out_dir) / "video.mp4",
            fps=fps,
            width=width,
            height=height,
            progress=progress,
            phases=traj.meta.phases if result.t.size == traj.n else None,
        )
        paths["strip"] = render_strip(
            result, Path(out_dir) / "strip.png", width=width, height=height
        )
    return paths
