"""Small vector kernels over the last axis (norm, dot, cross), broadcasting, no warnings.

Input checks are in :mod:`.checks`.
"""

from __future__ import annotations

import numpy as np

from .checks import FloatArray


def norm(v: FloatArray) -> FloatArray:
    """Euclidean norm over the last axis (no division, no warnings)."""
    return np.sqrt(np.einsum("...i,...i->...", v, v))


def cross(a: FloatArray, b: FloatArray) -> FloatArray:
    """Cross product over the last axis (..., 3), broadcasting; faster than ``np.cross``."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def dot(a: FloatArray, b: FloatArray) -> FloatArray:
    """Dot product over the last axis (..., 3) -> (...), broadcasting."""
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]


def dot3(a: tuple, b: tuple) -> FloatArray:
    """Dot product of vectors given as component tuples ``(x, y, z)`` of arrays."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross3(a: tuple, b: tuple) -> tuple:
    """Cross product of vectors given as component tuples ``(x, y, z)`` of arrays."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
