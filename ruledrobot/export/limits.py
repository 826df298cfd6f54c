"""Checks of a joint trajectory against a robot's limits, before anything moves.

The first sample that breaks a limit is named (the planner's report,
:func:`ruledrobot.robot.motion.rates.trajectory_limits_report`, gives the worst one; both
difference the samples with :func:`ruledrobot.robot.motion.rates.finite_difference_rates`).

Speeds and accelerations are finite differences of the samples (the way the
controller will see them when the samples are streamed one per period):
``v_k = (q_k - q_{k-1}) / (t_k - t_{k-1})`` belongs to sample k,
``a_k = (v_{k+1} - v_k) / ((t_{k+1} - t_{k-1}) / 2)`` to sample k.
"""

from __future__ import annotations

import numpy as np

from ..robot import RobotModel
from ..robot.ik.path import LIMIT_TOL
from ..robot.motion.rates import finite_difference_rates
from ..robot.motion.trajectory import Trajectory

__all__ = ["check_trajectory"]


def check_trajectory(
    traj: Trajectory,
    model: RobotModel,
    *,
    speed_scale: float = 1.0,
    tolerance: float = 0.01,
) -> None:
    """Raise ValueError at the first sample and joint outside the model's limits.

    Positions must lie within ``[lower, upper]``; speeds within
    ``max_velocity`` and accelerations within ``max_acceleration``, both
    ``(1 + tolerance)`` times (finite differences of sampled, rounded files
    carry a little noise).  ``speed_scale`` replays the trajectory that much
    faster (speeds scale by it, accelerations by its square).  The message
    names the sample index (0-based, the CSV data row), its time, the joint
    (``q1`` .. ``q6``), the value and the limit.
    """
    if not speed_scale > 0:
        raise ValueError(f"speed_scale: must be positive, got {speed_scale}")
    t = np.asarray(traj.t, dtype=float)
    q = np.asarray(traj.q, dtype=float)
    n = model.n_joints
    if t.ndim != 1 or q.ndim != 2 or q.shape != (t.size, n):
        raise ValueError(
            f"trajectory: expected t (M,) and q (M, {n}), got t {t.shape} and q {q.shape}"
        )
    if t.size < 2:
        raise ValueError(f"trajectory: needs at least 2 samples, got {t.size}")
    bad = ~np.isfinite(q)
    if bad.any():
        k, j = np.argwhere(bad)[0]
        raise ValueError(f"trajectory sample {k}: joint q{j + 1} is not a finite number")
    if np.any(~np.isfinite(t)) or np.any(np.diff(t) <= 0):
        k = int(np.argmax(~np.isfinite(t[1:]) | (np.diff(t) <= 0))) + 1
        raise ValueError(f"trajectory sample {k}: time t = {float(t[k])!r} does not increase")
    ts = (t - t[0]) / speed_scale
    lo, hi = np.asarray(model.lower), np.asarray(model.upper)
    bad = (q < lo - LIMIT_TOL) | (q > hi + LIMIT_TOL)
    if bad.any():
        k, j = np.argwhere(bad)[0]
        raise ValueError(
            f"trajectory sample {k} (t = {t[k]:.4f} s): joint q{j + 1} position {q[k, j]:.6g} rad "
            f"outside the limits [{lo[j]:.6g}, {hi[j]:.6g}] rad of {model.name}"
        )
    v, a = finite_difference_rates(ts, q)
    scaled = f" at speed_scale {speed_scale:g}" if speed_scale != 1.0 else ""
    for rate, limit, what, unit in (
        (v, model.max_velocity, "speed", "rad/s"),
        (a, model.max_acceleration, "acceleration", "rad/s^2"),
    ):
        bad = np.abs(rate) > np.asarray(limit) * (1.0 + tolerance)
        if bad.any():
            k, j = np.argwhere(bad)[0]
            raise ValueError(
                f"trajectory sample {k + 1} (t = {t[k + 1]:.4f} s): joint q{j + 1} {what} "
                f"{abs(rate[k, j]):.4g} {unit} exceeds the limit {limit[j]:.4g} {unit} of "
                f"{model.name}{scaled}"
            )
