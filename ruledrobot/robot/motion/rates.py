"""Joint speeds and accelerations of a sampled trajectory, by finite differences, and
their ratios to the joint limits.

The one independent check of a trajectory against joint limits, used by the
time law's own verification, the planner's report and the export runner.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ...geometry.checks import FloatArray, as_limits, as_shaped, check_increasing

__all__ = ["RATIO_MAX", "RATIO_TOL", "finite_difference_rates", "trajectory_limits_report"]

#: Ratios (sampled value / limit) up to ``1 + RATIO_TOL`` count as within the limit:
#: finite differences of positions of size ~1 rad divided by dt² = 4e-6 s² carry a
#: rounding error of ~1e-16/4e-6 ≈ 3e-11 rad/s²; 1e-9 covers it with margin.
RATIO_TOL = 1e-9
#: the largest ratio within a limit: every check of speeds, accelerations and torques
#: against their limits (plan, simulation, export) compares with this
RATIO_MAX = 1.0 + RATIO_TOL


def finite_difference_rates(t: FloatArray, q: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Speeds (M-1, J) and accelerations (M-2, J) of samples ``q`` (M, J) at times ``t`` (M,).

    ``v_k = (q_{k+1} - q_k) / (t_{k+1} - t_k)`` per interval and
    ``a_k = (v_{k+1} - v_k) / ((t_{k+2} - t_k) / 2)`` per interior sample (the usual
    second difference when the sampling is uniform).  Units: rad/s, rad/s^2.
    """
    t = np.asarray(t, dtype=np.float64)
    q = np.asarray(q, dtype=np.float64)
    v = np.diff(q, axis=0) / np.diff(t)[:, None]
    if q.shape[0] < 3:
        return v, np.zeros((0, q.shape[1]))
    return v, np.diff(v, axis=0) / (0.5 * (t[2:] - t[:-2]))[:, None]


def trajectory_limits_report(
    t: ArrayLike, q: ArrayLike, vel_limits: ArrayLike, acc_limits: ArrayLike
) -> dict[str, Any]:
    """Joint speed and acceleration of a sampled trajectory by finite differences.

    Independent of how the trajectory was made: velocity ``v_k = (q_{k+1} − q_k) /
    (t_{k+1} − t_k)`` per interval, acceleration ``(v_k − v_{k−1}) / ((t_{k+1} −
    t_{k−1})/2)`` per interior sample (the usual second difference when the
    sampling is uniform).

    Args:
        t: (M,) strictly increasing sample times [s].
        q: (M, J) joint positions [rad].
        vel_limits: (J,) joint velocity limits [rad/s], > 0.
        acc_limits: (J,) joint acceleration limits [rad/s²], > 0.

    Returns:
        dict with ``max_speed_ratio``, ``max_acc_ratio`` (floats), ``speed_ratio``,
        ``acc_ratio`` (J,) per joint, ``max_speed`` [rad/s], ``max_acc`` [rad/s²]
        (J,), ``worst_speed`` and ``worst_acc`` (sample index, joint) of the largest
        ratio (None when there is nothing to difference), ``ok`` (both ratios
        ``<= 1 + RATIO_TOL``), ``n_samples``, ``duration`` [s], ``dt_min``, ``dt_max``.

    Raises:
        ValueError: bad shapes, non-finite values, non-increasing ``t``, limits <= 0.
    """
    t = as_shaped(t, "t", (None,))
    q = as_shaped(q, "q", (t.shape[0], None))
    J = q.shape[1]
    vlim = as_limits(vel_limits, "vel_limits", J)
    alim = as_limits(acc_limits, "acc_limits", J)
    check_increasing(t, "t")
    M = t.shape[0]
    out: dict[str, Any] = {
        "n_samples": M,
        "duration": float(t[-1] - t[0]) if M else 0.0,
        "dt_min": float(np.diff(t).min()) if M > 1 else 0.0,
        "dt_max": float(np.diff(t).max()) if M > 1 else 0.0,
        "speed_ratio": np.zeros(J),
        "acc_ratio": np.zeros(J),
        "max_speed": np.zeros(J),
        "max_acc": np.zeros(J),
        "max_speed_ratio": 0.0,
        "max_acc_ratio": 0.0,
        "worst_speed": None,
        "worst_acc": None,
    }
    if M >= 2:
        v, a = finite_difference_rates(t, q)
        r = np.abs(v) / vlim
        k, j = np.unravel_index(int(np.argmax(r)), r.shape)
        out.update(
            speed_ratio=r.max(axis=0), max_speed=np.abs(v).max(axis=0),
            max_speed_ratio=float(r[k, j]), worst_speed=(int(k), int(j)),
        )  # fmt: skip
        if M >= 3:
            r = np.abs(a) / alim
            k, j = np.unravel_index(int(np.argmax(r)), r.shape)
            out.update(
                acc_ratio=r.max(axis=0), max_acc=np.abs(a).max(axis=0),
                max_acc_ratio=float(r[k, j]), worst_acc=(int(k) + 1, int(j)),
            )  # fmt: skip
    out["ok"] = bool(
        out["max_speed_ratio"] <= RATIO_MAX and out["max_acc_ratio"] <= RATIO_MAX
    )
    return out
