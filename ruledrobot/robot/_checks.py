"""Input checking for the robot layer.

Every public entry point funnels user data through these helpers, so that bad
input raises :class:`ValueError` whose message names the argument, the first
offending index and what was expected (the project's error contract).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..geometry._arrays import FloatArray, first_index
from ..geometry._arrays import as_float_array as as_array
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
    """``value`` as float64 poses (..., 4, 4) checked to be rigid motions (see
    :func:`ruledrobot.geometry.se3.validate_poses`)."""
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


def as_joint_vector(value: ArrayLike, name: str, n: int, allow_inf: bool = False) -> FloatArray:
    """A per-joint parameter: a scalar (broadcast) or a length-``n`` vector.

    With ``allow_inf`` the entries may be +-inf (an unlimited joint), never NaN.
    """
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name}: expected numbers, got {type(value).__name__} ({exc})") from None
    if arr.ndim > 1 or (arr.ndim == 1 and arr.shape[0] != n):
        raise ValueError(f"{name}: expected a scalar or shape ({n},), got shape {arr.shape}")
    arr = np.broadcast_to(arr, (n,)).astype(np.float64)
    bad = np.isnan(arr) if allow_inf else ~np.isfinite(arr)
    if bad.any():
        what = "NaN" if allow_inf else "NaN or infinity"
        raise ValueError(f"{name}{first_index(bad)}: contains {what}")
    return arr


def as_point(value: ArrayLike, name: str) -> FloatArray:
    """A read-only point or vector (3,) in metres; ValueError naming ``name`` otherwise."""
    v = as_array(value, name)
    if v.shape != (3,):
        raise ValueError(f"{name}: expected 3 numbers (m), got shape {v.shape}")
    return readonly(v)


def readonly(arr: FloatArray) -> FloatArray:
    """A read-only copy of ``arr`` (model data must not change behind a frozen dataclass)."""
    out = np.array(arr, dtype=np.float64, copy=True)
    out.setflags(write=False)
    return out
