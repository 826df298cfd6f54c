"""Decimation of a sampled TCP path into linear-move waypoints (Douglas-Peucker in SE(3)).

The path is cut into straight TCP segments such that every dropped sample
lies within ``tolerance`` metres of its segment and within
``angle_tolerance`` radians of the orientation interpolated along it (slerp
at the sample's arc-length fraction).  The first and last samples are always
kept.  Used for ``movel``/``movep`` programs and for the runner's path mode.
"""

from __future__ import annotations

import numpy as np

from ..geometry.se3 import pose_from_rotvec, rotvec_from_matrix

__all__ = ["decimate_tcp_path"]


def _rot(rv: np.ndarray) -> np.ndarray:
    return pose_from_rotvec(rv)[..., :3, :3]


def _segment_errors(p: np.ndarray, R: np.ndarray, i: int, j: int) -> tuple[np.ndarray, np.ndarray]:
    """Position and angle errors of samples i+1..j-1 against the segment i -> j."""
    a, b = p[i], p[j]
    inner = p[i + 1 : j]
    ab = b - a
    L2 = float(ab @ ab)
    if L2 > 0.0:
        s = np.clip(((inner - a) @ ab) / L2, 0.0, 1.0)
    else:
        s = np.zeros(len(inner))
    proj = a + s[:, None] * ab
    pos = np.linalg.norm(inner - proj, axis=1)
    # orientation: slerp between the ends at the fraction s (uniform in arc when L = 0)
    if L2 == 0.0:
        s = np.arange(1, j - i) / (j - i)
    Ri, Rj = R[i], R[j]
    rel = rotvec_from_matrix(Ri.T @ Rj)
    interp = Ri @ _rot(s[:, None] * rel[None, :])  # (n, 3, 3)
    err = np.einsum("nji,njk->nik", interp, R[i + 1 : j])  # interp^T R_k
    ang = np.linalg.norm(rotvec_from_matrix(err), axis=-1)
    return pos, ang


def decimate_tcp_path(
    tcp: np.ndarray,
    tolerance: float = 0.0005,
    angle_tolerance: float = 0.005,
    max_segment: int = 0,
) -> np.ndarray:
    """Indices of the samples to keep from TCP UR vectors (M, 6).

    ``tolerance`` [m] and ``angle_tolerance`` [rad] bound the deviation of the
    dropped samples from the straight segments; ``max_segment > 0`` also caps
    the number of samples a segment may span.  Returns sorted indices,
    first and last included.
    """
    tcp = np.asarray(tcp, dtype=float)
    if tcp.ndim != 2 or tcp.shape[1] != 6 or tcp.shape[0] < 1:
        raise ValueError(f"tcp: expected shape (M, 6) UR pose vectors, got {tcp.shape}")
    if not tolerance > 0 or not angle_tolerance > 0:
        raise ValueError("tolerance and angle_tolerance: must be positive")
    M = tcp.shape[0]
    if M <= 2:
        return np.arange(M)
    p = tcp[:, :3]
    R = _rot(tcp[:, 3:])
    keep = np.zeros(M, dtype=bool)
    keep[0] = keep[-1] = True
    stack = [(0, M - 1)]
    while stack:
        i, j = stack.pop()
        if j - i < 2:
            continue
        pos, ang = _segment_errors(p, R, i, j)
        score = np.maximum(pos / tolerance, ang / angle_tolerance)
        k = int(np.argmax(score))
        too_long = max_segment > 0 and j - i > max_segment
        if score[k] > 1.0 or too_long:
            m = i + 1 + k if score[k] > 1.0 else (i + j) // 2
            keep[m] = True
            stack.append((i, m))
            stack.append((m, j))
    return np.flatnonzero(keep)
