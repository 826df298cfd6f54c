"""The IK solution of one pose nearest given joints (the planner's moves off and over the
block: a pass's lifted pose, a transit over the stock).

The emulator's controller chooses differently, as a UR controller does for ``movel`` and
``movep`` (:meth:`ruledrobot.robot.motion.arm_kinematics.ArmKinematics.ik_nearest_pose`:
the solutions within the joint limits first, then the nearest in the Euclidean norm,
seeded by the last joint); the planner wants the smallest largest joint step and refuses
a nearest solution beyond the limits rather than taking another branch."""

from __future__ import annotations

import numpy as np

from ...geometry.angles import wrap_near
from ...geometry.checks import FloatArray
from .model import RobotModel

__all__ = ["nearest_ik"]


def nearest_ik(model: RobotModel, pose: FloatArray, q: FloatArray) -> FloatArray | None:
    """The joints reaching ``pose`` nearest ``q``, or None.

    Parameters
    ----------
    model : the arm; ``pose`` is a pose of the frame its ``fk`` gives (the flange when no
        tool is set).
    pose : (4, 4) the pose in the robot base frame (m).
    q : (J,) the joints [rad] to stay near.

    Returns
    -------
    (J,) joints [rad]: of the closed-form solutions of ``pose`` (``model.ik``), each joint
    taken as its 2 pi representative nearest ``q``, the one nearest ``q`` in the largest
    joint step (max norm); None when no branch reaches ``pose`` or that solution is
    outside the joint limits.
    """
    sols = model.ik(pose)
    sols = sols[~np.isnan(sols).any(axis=1)]
    if not len(sols):
        return None
    sols = wrap_near(sols, q)
    best = sols[np.argmin(np.abs(sols - q).max(axis=1))]
    return best if model.within_limits(best) else None
