"""Input checks of the robot layer: the package's checks (:mod:`ruledrobot.geometry.checks`)
and the pose checks every robot entry point shares.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..geometry.checks import FloatArray, as_point, first_index, readonly
from ..geometry.checks import as_float_array as as_array
from ..geometry.checks import as_per_joint as as_joint_vector
from ..geometry.se3 import validate_poses

__all__ = [
    "POSE_TOL",
    "FloatArray",
    "as_array",
    "as_joint_vector",
    "as_point",
    "as_pose_or_vector",
    "as_poses",
    "first_index",
    "readonly",
]

#: Tolerance of the rigid-motion check on poses (orthonormality, last row).
POSE_TOL = 1e-6


def as_poses(value: ArrayLike, name: str = "poses", tol: float = POSE_TOL) -> FloatArray:
    """Return ``value`` as float64 poses (..., 4, 4) checked to be rigid motions.

    See :func:`ruledrobot.geometry.se3.validate_poses`.
    """
    return validate_poses(value, name, tol)


def as_pose_or_vector(value: ArrayLike, name: str) -> FloatArray:
    """One pose: a 4x4 matrix or a UR pose vector ``[x, y, z, rx, ry, rz]`` (m, rad)."""
    arr = np.asarray(value, dtype=np.float64) if not isinstance(value, np.ndarray) else value
    if np.shape(arr) == (6,):
        from ..geometry.se3 import pose_from_ur_vector

        vec = as_array(arr, name, (6,))
        return pose_from_ur_vector(vec)
    if np.shape(arr) != (4, 4):
        raise ValueError(
            f"{name}: expected a 4x4 pose or a UR pose vector [x, y, z, rx, ry, rz], "
            f"got shape {np.shape(arr)}"
        )
    return as_poses(arr, name)
