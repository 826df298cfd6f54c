"""Robot layer: UR catalogue (DH), forward kinematics, analytic IK, path IK.

Typical use::

    import ruledrobot as rr

    robot = rr.robot.load("ur5e").with_tool([0, 0, 0.15, 0, 0, 0])
    T = robot.fk(q)                      # (..., 6) -> (..., 4, 4) TCP poses
    sols = robot.ik(T)                   # (..., 4, 4) -> (..., 8, 6), NaN rows = no solution
    path = robot.path_ik(poses)          # (N, 4, 4) -> PathIKResult (continuous q, flags)
    cal = rr.io.load_calibration("my_ur5e.json")      # the robot's factory calibration
    robot = rr.robot.load("ur5e", calibration=cal)    # exact FK, IK refined on it

Units m, rad, s; poses are float64 4x4 homogeneous matrices.  See
``docs/robot.md`` for the catalogue, frames, branch numbering and the
path-IK rules.
"""

from __future__ import annotations

from numpy.typing import ArrayLike

from ._checks import FloatArray
from .arm.calibration import Calibration, CalibrationBounds, CalibrationError
from .arm.calibration_random import random_calibration
from .arm.catalogue import MODEL_NAMES, load
from .arm.model import DEFAULT_ACCELERATION, RobotModel
from .ik.analytic import IKSolutions, URGeometry, wrap_angle
from .ik.calibrated import CalibratedIKSolutions
from .ik.path import PathIKResult, PathStatus, path_ik
from .motion.trajectory import KinematicsRef, Payload, Phase, Trajectory, TrajectoryMeta, model_for

__all__ = [
    "DEFAULT_ACCELERATION",
    "MODEL_NAMES",
    "CalibratedIKSolutions",
    "Calibration",
    "CalibrationBounds",
    "CalibrationError",
    "IKSolutions",
    "KinematicsRef",
    "PathIKResult",
    "PathStatus",
    "Payload",
    "Phase",
    "RobotModel",
    "Trajectory",
    "TrajectoryMeta",
    "URGeometry",
    "fk",
    "ik",
    "load",
    "model_for",
    "path_ik",
    "random_calibration",
    "wrap_angle",
]


def fk(model: RobotModel, q: ArrayLike) -> FloatArray:
    """``model.fk(q)``: TCP poses (..., 4, 4) in the world frame of joint positions (..., 6)."""
    return model.fk(q)


def ik(
    model: RobotModel,
    T: ArrayLike,
    *,
    q6_seed: ArrayLike = 0.0,
    return_info: bool = False,
    check: bool = True,
) -> FloatArray | IKSolutions:
    """``model.ik(T, ...)``: all 8 analytic solutions (..., 8, 6) of TCP poses (..., 4, 4)."""
    return model.ik(T, q6_seed=q6_seed, return_info=return_info, check=check)  # type: ignore[call-overload]
