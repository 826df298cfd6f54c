"""Distances between line segments (vectorised): the capsule checks of the planner."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .checks import FloatArray

__all__ = ["segment_distance"]


def segment_distance(p0: ArrayLike, p1: ArrayLike, q0: ArrayLike, q1: ArrayLike) -> FloatArray:
    """Smallest distance (...) between segments ``p0 -> p1`` and ``q0 -> q1`` (..., 3).

    Closest points of the two lines, clamped to the segments (each clamp followed
    by the re-projection of the other parameter), as in Ericson, *Real-Time
    Collision Detection*, 5.1.9; degenerate (point) segments are handled.
    """
    p0, p1, q0, q1 = (np.asarray(v, dtype=np.float64) for v in (p0, p1, q0, q1))
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    a = np.einsum("...i,...i->...", d1, d1)
    e = np.einsum("...i,...i->...", d2, d2)
    f = np.einsum("...i,...i->...", d2, r)
    c = np.einsum("...i,...i->...", d1, r)
    b = np.einsum("...i,...i->...", d1, d2)
    tiny = 1e-18
    pa, pe = a > tiny, e > tiny
    sa, se = np.where(pa, a, 1.0), np.where(pe, e, 1.0)
    denom = a * e - b * b
    general = pa & pe
    # general case: s from the lines' closest points (0 when parallel), clamped
    s = np.where(
        general & (denom > tiny * np.maximum(a * e, tiny)),
        (b * f - c * e) / np.where(denom > 0, denom, 1.0),
        0.0,
    )
    s = np.clip(s, 0.0, 1.0)
    # first segment a point: s = 0; second a point: t = 0 and s projects p onto q0
    s = np.where(pa & ~pe, np.clip(-c / sa, 0.0, 1.0), np.where(pa, s, 0.0))
    t = np.where(pe, (b * s + f) / se, 0.0)
    # t outside [0, 1]: clamp it and recompute s
    t_c = np.clip(t, 0.0, 1.0)
    s = np.where((t != t_c) & pa, np.clip((b * t_c - c) / sa, 0.0, 1.0), s)
    t = t_c
    diff = p0 + s[..., None] * d1 - (q0 + t[..., None] * d2)
    return np.sqrt(np.einsum("...i,...i->...", diff, diff))
