"""Resampling of sampled sequences: linear and cubic Hermite, batched over trailing axes.

One implementation for every consumer (the planner's chord ends, the renderer's
frames, the simulation's reference, the runner's controller grid).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .checks import FloatArray

__all__ = ["interp_hermite", "interp_linear"]


def _bracket(x: FloatArray, xp: FloatArray) -> tuple[np.ndarray, FloatArray]:
    """Interval index k (M,) with xp[k] <= x < xp[k+1] (clamped) and the fraction in it."""
    k = np.clip(np.searchsorted(xp, x, side="right") - 1, 0, xp.size - 2)
    w = np.clip((x - xp[k]) / (xp[k + 1] - xp[k]), 0.0, 1.0)
    return k, w


def interp_linear(x: ArrayLike, xp: ArrayLike, fp: ArrayLike) -> FloatArray:
    """Interpolate ``fp`` (N, ...) sampled at increasing ``xp`` (N,) linearly at ``x`` (M,).

    Returns (M, ...).  Outside ``[xp[0], xp[-1]]`` the end values hold (as ``np.interp``);
    exact on the samples, ``(1 - w) f_k + w f_{k+1}``.
    """
    x = np.asarray(x, dtype=np.float64)
    xp = np.asarray(xp, dtype=np.float64)
    fp = np.asarray(fp, dtype=np.float64)
    if xp.size == 1:
        return np.repeat(fp, x.size, axis=0)
    k, w = _bracket(x, xp)
    w = w.reshape(w.shape + (1,) * (fp.ndim - 1))
    return (1.0 - w) * fp[k] + w * fp[k + 1]


def interp_hermite(
    x: ArrayLike, xp: ArrayLike, fp: ArrayLike, dfp: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """Cubic Hermite interpolation of values ``fp`` and slopes ``dfp`` (N, J) at ``x`` (M,).

    Values and slopes (M, J). C1, exact on the samples."""
    x = np.asarray(x, dtype=np.float64)
    xp = np.asarray(xp, dtype=np.float64)
    fp = np.asarray(fp, dtype=np.float64)
    dfp = np.asarray(dfp, dtype=np.float64)
    k, s1 = _bracket(x, xp)
    h = (xp[k + 1] - xp[k])[:, None]
    s = s1[:, None]
    q0, q1, v0, v1 = fp[k], fp[k + 1], dfp[k], dfp[k + 1]
    h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
    h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
    values = h00 * q0 + h10 * h * v0 + h01 * q1 + h11 * h * v1
    d00, d10 = (6 * s**2 - 6 * s) / h, 3 * s**2 - 4 * s + 1
    d01, d11 = (-6 * s**2 + 6 * s) / h, 3 * s**2 - 2 * s
    return values, d00 * q0 + d10 * v0 + d01 * q1 + d11 * v1
