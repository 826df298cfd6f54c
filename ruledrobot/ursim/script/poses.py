"""URScript's pose built-ins (``pose_trans``, ``pose_inv``, ``pose_add``, ``pose_sub``,
``pose_dist``, ``point_dist``, ``interpolate_pose``) for the interpreter
(:mod:`.library`): poses are UR pose vectors ``[x, y, z, rx, ry, rz]`` (m, rad), as
:class:`~.library.PoseValue` lists."""

from __future__ import annotations

import numpy as np

from ...geometry import se3
from .values import PoseValue, matrix_of, pose_of, vector_of

__all__ = ["interpolate_pose", "point_dist", "pose_add", "pose_dist", "pose_inv", "pose_sub",
           "pose_trans"]


def pose_trans(p_from: list, p_from_to: list) -> PoseValue:
    """``pose_trans(p_from, p_from_to)``: ``p_from_to`` taken in the frame of ``p_from``.

    The pose of ``T(p_from) T(p_from_to)``: start at the frame ``p_from`` places and move by
    ``p_from_to`` in it.  A UR pose [m, rad].
    """
    T = matrix_of(p_from, "pose_trans") @ matrix_of(p_from_to, "pose_trans")
    return pose_of(se3.ur_vector_from_pose(T))


def pose_inv(p: list) -> PoseValue:
    """``pose_inv(p_from)``: the inverse pose transformation, ``T(p_from)^-1`` [m, rad]."""
    return pose_of(se3.ur_vector_from_pose(se3.inverse(matrix_of(p, "pose_inv"))))


def pose_add(p1: list, p2: list) -> PoseValue:
    """``pose_add(p_1, p_2)``: positions added [m], rotations multiplied (a pose).

    UR's manual: ``p_3.P = p_1.P + p_2.P``, ``p_3.R = p_1.R * p_2.R`` (so that
    ``pose_add(pose_sub(a, b), b)`` is ``a``; tested).
    """
    a, b = matrix_of(p1, "pose_add"), matrix_of(p2, "pose_add")
    T = np.eye(4)
    T[:3, :3] = a[:3, :3] @ b[:3, :3]
    T[:3, 3] = a[:3, 3] + b[:3, 3]
    return pose_of(se3.ur_vector_from_pose(T))


def pose_sub(p_to: list, p_from: list) -> PoseValue:
    """``pose_sub(p_to, p_from)``: positions subtracted [m], rotation ``R(p_to) R(p_from)^T``.

    On UR's forum it undoes :meth:`pose_add` (``pose_add(pose_sub(p_1, p_2), p_2) == p_1``);
    with the emulator's :meth:`pose_add` that holds only when the two rotations commute.
    """
    a, b = matrix_of(p_to, "pose_sub"), matrix_of(p_from, "pose_sub")
    T = np.eye(4)
    T[:3, :3] = a[:3, :3] @ b[:3, :3].T
    T[:3, 3] = a[:3, 3] - b[:3, 3]
    return pose_of(se3.ur_vector_from_pose(T))


def pose_dist(p_from: list, p_to: list) -> float:
    """``pose_dist(p_from, p_to)``: the distance between two poses.

    UR's controller also weighs the rotation (two poses differing only in orientation are a
    non-zero distance apart, in no particular unit); the emulator returns the distance of the
    positions [m], as :meth:`point_dist`.
    """
    return float(np.linalg.norm(vector_of(p_to, 6, "pose_dist")[:3] - vector_of(p_from, 6,
                                                                      "pose_dist")[:3]))


def point_dist(p_from: list, p_to: list) -> float:
    """``point_dist(p_from, p_to)``: the distance between the two poses' positions [m].

    Rotations are not considered.
    """
    return pose_dist(p_from, p_to)


def interpolate_pose(p_from: list, p_to: list, alpha: float) -> PoseValue:
    """``interpolate_pose(p_from, p_to, alpha)``: the pose a fraction ``alpha`` along.

    The position on the straight line [m], the orientation on the shortest rotation between the
    two [rad]; ``alpha`` 0 gives ``p_from``, 1 ``p_to``, values outside [0, 1] extrapolate.
    """
    A, B = matrix_of(p_from, "interpolate_pose"), matrix_of(p_to, "interpolate_pose")
    T = np.eye(4)
    T[:3, :3] = se3.geodesic(A, B, float(alpha))[:3, :3]
    T[:3, 3] = A[:3, 3] + float(alpha) * (B[:3, 3] - A[:3, 3])
    return pose_of(se3.ur_vector_from_pose(T))
