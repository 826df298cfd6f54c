"""The wire against the stock along a sampled motion: chords and feed speed.

What the video caption and the browser viewer show of a cut, measured on the
samples themselves (no planner internals): where the wire crosses the stock
(its *chord*, as fractions of the wire from ``wire_start``) and the feed, the
speed of the fastest wire point inside the stock.  A rigid segment's fastest
point lies at one of its ends, so the feed is the larger speed of the two chord
ends, followed as material points of the wire (central differences).

Frames: wire ends and the stock in one frame (the robot base frame, or the
world when both are given there).  Units: m, s, m/s.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..geometry._arrays import FloatArray
from ..geometry.box import Box

__all__ = ["chords", "feed_speeds"]


def chords(ends: ArrayLike, stock: Box) -> tuple[FloatArray, FloatArray, np.ndarray]:
    """The part of each wire inside the stock: ``(lo, hi, inside)``.

    ``ends`` (M, 2, 3) wire start and end points; ``lo``, ``hi`` (M,) the chord as
    fractions of the wire from its start (0 <= lo < hi <= 1, NaN where the wire
    misses the stock); ``inside`` (M,) bool, the wire crosses the stock there.
    """
    e = np.asarray(ends, dtype=np.float64)
    a, b = e[:, 0], e[:, 1]
    t_in, t_out, hit = stock.clip_lines(a, b - a)
    lo = np.clip(t_in, 0.0, 1.0)
    hi = np.clip(t_out, 0.0, 1.0)
    inside = hit & (hi > lo)
    return np.where(inside, lo, np.nan), np.where(inside, hi, np.nan), inside


def feed_speeds(t: ArrayLike, ends: ArrayLike, stock: Box) -> FloatArray:
    """Feed (M,) m/s: speed of the fastest wire point inside the stock, NaN outside.

    ``t`` (M,) sample times (s), ``ends`` (M, 2, 3) wire ends.  The chord ends at
    sample k are followed as points of the wire to samples k - 1 and k + 1
    (one-sided at the first and last sample).
    """
    ta = np.asarray(t, dtype=np.float64)
    e = np.asarray(ends, dtype=np.float64)
    m = ta.size
    out = np.full(m, np.nan)
    if m < 2:
        return out
    lo, hi, inside = chords(e, stock)
    frac = np.stack([np.where(inside, lo, 0.0), np.where(inside, hi, 0.0)], axis=1)  # (M, 2)
    nxt = np.minimum(np.arange(m) + 1, m - 1)
    prv = np.maximum(np.arange(m) - 1, 0)

    def points(k: np.ndarray) -> FloatArray:  # the chord ends of sample j at sample k[j]
        a, b = e[k, 0], e[k, 1]
        return a[:, None, :] + frac[:, :, None] * (b - a)[:, None, :]

    v = np.linalg.norm(points(nxt) - points(prv), axis=-1) / (ta[nxt] - ta[prv])[:, None]
    out[inside] = v.max(axis=1)[inside]
    return out
