"""Joint speeds and accelerations of a sampled trajectory, by finite differences.

The one independent check of a trajectory against joint limits, used by the
time law's own verification, the planner's report and the export runner.
"""

from __future__ import annotations

import numpy as np

from ._checks import FloatArray

__all__ = ["finite_difference_rates"]


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
