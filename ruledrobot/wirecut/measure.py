"""Independent measurements of a sampled cut trajectory (used by the report and tests).

Everything here works on the *sampled* joints (the joint-limit check is
:func:`ruledrobot.wirecut.timing.trajectory_limits_report`) (what the controller receives),
through forward kinematics — never on the planner's internal numbers.
"""

from __future__ import annotations

import numpy as np

from ..geometry.checks import FloatArray

__all__ = ["feed_speeds", "wire_points"]


def wire_points(flange: FloatArray, points_in_flange: FloatArray) -> FloatArray:
    """World positions (M, K, 3) of flange-frame points (M, K, 3) under poses (M, 4, 4)."""
    return np.einsum("mij,mkj->mki", flange[:, :3, :3], points_in_flange) + flange[:, None, :3, 3]


def feed_speeds(
    t: FloatArray, flange: FloatArray, ends_in_flange: FloatArray, inside: np.ndarray
) -> FloatArray:
    """Speed (M,) m/s of the fastest wire point inside the stock at each sample.

    ``flange`` (M, 4, 4) are the sampled flange poses, ``ends_in_flange`` (M, 2, 3)
    the chord ends as points of the wire at each sample, ``inside`` (M,) where the
    wire crosses the stock.  Central differences of the same material points.
    """
    m = len(t)
    if m < 3:
        return np.zeros(m)
    e = np.where(inside[:, None, None], ends_in_flange, 0.0)
    nxt, prv = np.r_[np.arange(1, m), m - 1], np.r_[0, np.arange(m - 1)]
    ahead = wire_points(flange[nxt], e)
    behind = wire_points(flange[prv], e)
    v = np.linalg.norm(ahead - behind, axis=-1) / (t[nxt] - t[prv])[:, None]
    return np.where(inside, v.max(axis=1), 0.0)
