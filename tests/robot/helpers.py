"""Independent reference implementations and data generators for the robot tests."""

from __future__ import annotations

import numpy as np


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


def random_rotations(rng: np.random.Generator, n: int) -> np.ndarray:
    """Uniform random rotations (n, 3, 3) from unit quaternions."""
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    w, x, y, z = q.T
    R = np.empty((n, 3, 3))
    R[:, 0] = np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1)
    R[:, 1] = np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1)
    R[:, 2] = np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1)
    return R


def random_poses(rng: np.random.Generator, n: int, scale: float = 1.0) -> np.ndarray:
    """Random rigid motions (n, 4, 4), translations ~ N(0, scale^2)."""
    T = np.zeros((n, 4, 4))
    T[:, :3, :3] = random_rotations(rng, n)
    T[:, :3, 3] = scale * rng.normal(size=(n, 3))
    T[:, 3, 3] = 1.0
    return T


def solutions_contain(sols: np.ndarray, q: np.ndarray, tol: float) -> np.ndarray:
    """(n,) bool: some valid row of sols (n, 8, 6) equals q (n, 6) modulo 2 pi."""
    d = angle_diff(sols, q[:, None, :]).max(axis=-1)
    d = np.where(np.isnan(d), np.inf, d)
    return d.min(axis=1) < tol
