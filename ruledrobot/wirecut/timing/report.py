"""Limits report and feed of sampled joints, by finite differences (the verification)."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ...geometry.checks import as_limits, as_shaped, check_increasing
from ...robot.rates import finite_difference_rates
from .limits import RATIO_TOL, FloatArray

# --------------------------------------------------------------------------- report


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
        out["max_speed_ratio"] <= 1.0 + RATIO_TOL and out["max_acc_ratio"] <= 1.0 + RATIO_TOL
    )
    return out


def _wire_distance(s: FloatArray, sf: FloatArray, at: FloatArray) -> FloatArray:
    """∫ speed_factor ds from s[0] to ``at`` [m], the speed factor linear between samples."""
    h = np.diff(s)
    F = np.concatenate([[0.0], np.cumsum(0.5 * (sf[1:] + sf[:-1]) * h)])
    i = np.clip(np.searchsorted(s, at, side="right") - 1, 0, s.shape[0] - 2)
    r = at - s[i]
    slope = (sf[i + 1] - sf[i]) / h[i]
    return F[i] + r * (sf[i] + 0.5 * slope * r)


def _feed_of_samples(
    t: FloatArray, s_t: FloatArray, s: FloatArray, sf: FloatArray, feed_speed: float
) -> tuple[FloatArray, FloatArray]:
    """Sampled feed (M,) [m/s] by central differences and the feed ratio of every sample
    interval (M−1,) by forward differences, both of the wire distance
    ``W(s) = ∫ speed_factor ds`` at the sampled ``s_t`` (metres moved by the fastest
    wire point in the stock, so that a period that straddles a jump of the speed factor
    is measured by what the wire travelled, not by the speed factor at one point)."""
    M = t.shape[0]
    if M < 2 or not np.any(sf > 0):
        return np.zeros(M), np.zeros(max(M - 1, 0))
    W = _wire_distance(s, sf, s_t)
    ratio = np.diff(W) / np.diff(t) / feed_speed
    feed = np.empty(M)
    feed[1:-1] = (W[2:] - W[:-2]) / (t[2:] - t[:-2])
    feed[0] = ratio[0] * feed_speed
    feed[-1] = ratio[-1] * feed_speed
    return feed, ratio
