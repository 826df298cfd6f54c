"""Implicit equations of the closed-form ruled surfaces: a point's first-order distance.

For ``F(p) = 0`` the Sampson distance ``F / |grad F|`` (exact to first order in the
distance; :mod:`.surfaces` makes the surfaces, these judge points against them).
Units: m.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ._arrays import norm
from .checks import FloatArray, as_float_array, as_number

__all__ = ["cylindroid_residual", "helicoid_residual", "hyperbolic_paraboloid_residual",
           "hyperboloid_residual"]


def _finite(value: Any, name: str) -> float:
    """A finite number of any sign (:func:`.checks.as_number`: booleans refused)."""
    return as_number(value, name, positive=False)


def _positive(value: Any, name: str) -> float:
    x = _finite(value, name)
    if x <= 0.0:
        raise ValueError(f"{name}: expected a positive number, got {value!r}")
    return x


def _nonzero(value: Any, name: str) -> float:
    x = _finite(value, name)
    if x == 0.0:
        raise ValueError(f"{name}: expected a non-zero number, got {value!r}")
    return x


def cylindroid_residual(points: ArrayLike, c: float = 0.5) -> FloatArray:
    """Return the first-order distance (...,) [m] of ``points`` (..., 3) from the cylindroid.

    The cylindroid ``F = z (x^2 + y^2) - 2 c x y = 0``: ``F / |grad F|``; 0 where ``F = 0``
    (also on the singular double line, the segment ``|z| <= c`` of the z axis).
    """
    p = as_float_array(points, "points", (3,))
    c = _nonzero(c, "c")
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    F = z * (x * x + y * y) - 2.0 * c * x * y
    g = np.stack([2 * x * z - 2 * c * y, 2 * y * z - 2 * c * x, x * x + y * y], axis=-1)
    return _sampson(F, g)


def hyperbolic_paraboloid_residual(points: ArrayLike, c: float = 1.0) -> FloatArray:
    """First-order distance (...,) metres of ``points`` (..., 3) from ``z = x y / c``."""
    p = as_float_array(points, "points", (3,))
    c = _nonzero(c, "c")
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    F = x * y / c - z
    g = np.stack([y / c, x / c, -np.ones_like(z)], axis=-1)
    return _sampson(F, g)


def hyperboloid_residual(points: ArrayLike, a: float = 1.0, c: float = 1.0) -> FloatArray:
    """Return the first-order distance (...,) [m] of ``points`` (..., 3) from a hyperboloid.

    The hyperboloid of revolution ``F = (x^2 + y^2)/a^2 - z^2/c^2 - 1 = 0`` (``F / |grad
    F|``).
    """
    p = as_float_array(points, "points", (3,))
    a, c = _positive(a, "a"), _positive(c, "c")
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    F = (x * x + y * y) / a**2 - z * z / c**2 - 1.0
    g = np.stack([2 * x / a**2, 2 * y / a**2, -2 * z / c**2], axis=-1)
    return _sampson(F, g)


def helicoid_residual(points: ArrayLike, pitch: float = 0.2) -> FloatArray:
    """Return the first-order distance (...,) [m] of ``points`` (..., 3) from the helicoid.

    The helicoid ``F = x sin(z/p) - y cos(z/p) = 0`` (``grad F`` never vanishes).
    """
    p = as_float_array(points, "points", (3,))
    pitch = _nonzero(pitch, "pitch")
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    s, c = np.sin(z / pitch), np.cos(z / pitch)
    F = x * s - y * c
    g = np.stack([s, -c, (x * c + y * s) / pitch], axis=-1)
    return _sampson(F, g)


def _sampson(F: FloatArray, grad: FloatArray) -> FloatArray:
    gn = norm(grad)
    safe = np.where(gn > 0.0, gn, 1.0)
    return np.where(F == 0.0, 0.0, F / safe)
