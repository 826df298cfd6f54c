"""Angles modulo 2 pi: principal values and the representative nearest a reference.

One implementation for the whole package (joint angles, DH offsets, rotation
angles).  Radians; any shape; vectorised.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .checks import FloatArray

__all__ = ["TWO_PI", "wrap_angle", "wrap_near"]

TWO_PI = 2.0 * np.pi


def wrap_angle(x: ArrayLike) -> FloatArray:
    """Principal values in (-pi, pi] of finite angles [rad] (any shape).

    ``x - 2 pi ceil((x - pi) / 2 pi)``, then a clamp for the one-ulp overshoot
    rounding can leave at either end (+-pi both map to pi).
    """
    x = np.asarray(x, dtype=np.float64)
    y = x - TWO_PI * np.ceil((x - np.pi) / TWO_PI)
    y = np.minimum(y, np.pi)
    return np.where(y > -np.pi, y, np.pi)


def wrap_near(x: ArrayLike, ref: ArrayLike) -> FloatArray:
    """The representatives ``x + 2 pi k`` nearest ``ref`` (broadcasting).

    ``ref + wrap_angle(x - ref)``, so the result lies in ``(ref - pi, ref + pi]``."""
    ref = np.asarray(ref, dtype=np.float64)
    return ref + wrap_angle(np.asarray(x, dtype=np.float64) - ref)
