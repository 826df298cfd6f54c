"""Feed of sampled joints, by finite differences (the verification); the limits report
(:func:`trajectory_limits_report`) is the robot layer's, shared with the runner."""

from __future__ import annotations

import numpy as np

from .tolerances import FloatArray

# --------------------------------------------------------------------------- report


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
