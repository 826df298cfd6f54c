"""The unit sphere S^2: geodesics (slerp, with extrapolation), log and exp maps.

Points are unit vectors (..., 3).  ``geodesic(a, b, t)`` is the great-circle
arc through ``a`` (t=0) and ``b`` (t=1) with constant speed (the paper's
Eq. 12), defined for every real ``t``; antipodal pairs have no unique geodesic
and are rejected.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from ._arrays import dot, norm
from .checks import FloatArray, as_float_array, first_index

__all__ = ["exp", "geodesic", "geodesic_many", "log", "validate_unit"]

ANTIPODAL_TOL = 1e-9  # pairs with |a + b| below this have no unique geodesic


def validate_unit(v: ArrayLike, name: str = "unit vectors", tol: float = 1e-9) -> FloatArray:
    """Return unit vectors (..., 3), re-normalised, after checking ``| |v| - 1 | <= tol``."""
    v = as_float_array(v, name, (3,))
    n = norm(v)
    bad = np.abs(n - 1.0) > tol
    if np.any(bad):
        raise ValueError(
            f"{name}{first_index(bad)}: expected a unit vector, got length {n[bad][0]:.12g}"
        )
    return v / n[..., None]


def _pair(a: FloatArray, b: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Angle phi, sin(phi) and the unit tangent at a towards b (zero when a == b)."""
    cos = dot(a, b)
    w = b - cos[..., None] * a
    s = norm(w)
    phi = np.arctan2(s, cos)
    anti = norm(a + b) <= ANTIPODAL_TOL
    if np.any(anti):
        raise ValueError(
            f"sphere geodesic{first_index(anti)}: antipodal points have no unique geodesic"
        )
    u = w / np.where(s > 0.0, s, 1.0)[..., None]
    return phi, s, u


def geodesic_many(a: ArrayLike, b: ArrayLike, ts: Sequence[float]) -> list[FloatArray]:
    """``[geodesic(a, b, t) for t in ts]`` with one angle computation per pair."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    phi, _, u = _pair(a, b)
    out = []
    for t in ts:
        tp = t * phi
        out.append(np.cos(tp)[..., None] * a + np.sin(tp)[..., None] * u)
    return out


def geodesic(a: ArrayLike, b: ArrayLike, t: ArrayLike) -> FloatArray:
    """Point at parameter ``t`` of the great circle from ``a`` to ``b`` (all broadcast).

    ``cos(t phi) a + sin(t phi) u`` with ``phi`` the angle of a and b and ``u``
    the unit tangent at ``a`` towards ``b``: equal to Eq. 12 (slerp) for t in
    [0, 1], defined for every real t, exact (``a``) for ``a == b``.
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)
    phi, _, u = _pair(a, b)
    tp = t * phi
    return np.cos(tp)[..., None] * a + np.sin(tp)[..., None] * u


def log(base: ArrayLike, x: ArrayLike) -> FloatArray:
    """Logarithm at ``base``: the tangent vector (..., 3) of length ``angle(base, x)`` towards x."""
    base = np.asarray(base, dtype=np.float64)
    x = np.asarray(x, dtype=np.float64)
    phi, _, u = _pair(base, x)
    return phi[..., None] * u


def exp(base: ArrayLike, v: ArrayLike) -> FloatArray:
    """Exponential at ``base`` of tangent vectors ``v`` (..., 3): ``cos|v| base + sin|v| v/|v|``."""
    base = np.asarray(base, dtype=np.float64)
    v = np.asarray(v, dtype=np.float64)
    n = norm(v)
    small = n < 1e-8
    sinc = np.where(small, 1.0 - n * n / 6.0, np.sin(n) / np.where(small, 1.0, n))
    out = np.cos(n)[..., None] * base + sinc[..., None] * v
    # remove the rounding drift off the sphere
    return out / norm(out)[..., None]
