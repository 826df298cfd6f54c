"""Independent reference implementations and data generators for the robot tests."""

from __future__ import annotations

import numpy as np

from ..conftest import random_poses, random_rotations  # noqa: F401  (shared generators)


def dh_matrix(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    """Standard DH link transform Rz(theta) Tz(d) Tx(a) Rx(alpha), written out."""
    ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
    return np.array(
        [
            [ct, -st * ca, st * sa, a * ct],
            [st, ct * ca, -ct * sa, a * st],
            [0.0, sa, ca, d],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def dh_fk_reference(q: np.ndarray, d, a, alpha, offset=None) -> np.ndarray:
    """Product of standard DH matrices, one pose at a time (slow, obviously correct)."""
    q = np.asarray(q, dtype=float)
    offset = np.zeros(q.shape[-1]) if offset is None else np.asarray(offset)
    flat = q.reshape(-1, q.shape[-1])
    out = np.empty((flat.shape[0], 4, 4))
    for k, row in enumerate(flat):
        T = np.eye(4)
        for i in range(row.shape[0]):
            T = T @ dh_matrix(row[i] + offset[i], d[i], a[i], alpha[i])
        out[k] = T
    return out.reshape(*q.shape[:-1], 4, 4)


def angle_diff(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Elementwise |x - y| modulo 2 pi, in [0, pi]."""
    d = np.remainder(np.asarray(x) - np.asarray(y), 2 * np.pi)
    return np.minimum(d, 2 * np.pi - d)


def pose_error(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Max absolute entry difference of poses (..., 4, 4)."""
    return np.abs(np.asarray(A) - np.asarray(B)).max(axis=(-1, -2))


def solutions_contain(sols: np.ndarray, q: np.ndarray, tol: float) -> np.ndarray:
    """(n,) bool: some valid row of sols (n, 8, 6) equals q (n, 6) modulo 2 pi."""
    d = angle_diff(sols, q[:, None, :]).max(axis=-1)
    d = np.where(np.isnan(d), np.inf, d)
    return d.min(axis=1) < tol
