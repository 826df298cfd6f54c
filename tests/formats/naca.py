"""NACA 4-digit airfoils from the analytic formula: the independent truth of the tests.

Thickness ``y_t = 5 t (0.2969 sqrt(x) - 0.1260 x - 0.3516 x^2 + 0.2843 x^3 - a4 x^4)``
(``a4 = 0.1036`` closes the trailing edge, 0.1015 is the original open one); camber
line ``y_c = m/p^2 (2 p x - x^2)`` before ``p``, ``m/(1-p)^2 ((1 - 2p) + 2 p x - x^2)``
after; the surfaces are offset from the camber line along its normal.
"""

from __future__ import annotations

import numpy as np


def naca4(code: str, n: int = 81, closed_te: bool = True) -> np.ndarray:
    """Points (2n-1, 2): trailing edge, upper surface, leading edge, lower surface,
    trailing edge (Selig order), x by cosine spacing."""
    m, p, t = int(code[0]) / 100, int(code[1]) / 10, int(code[2:]) / 100
    beta = np.linspace(0.0, np.pi, n)
    x = 0.5 * (1 - np.cos(beta))
    a4 = 0.1036 if closed_te else 0.1015
    yt = 5 * t * (0.2969 * np.sqrt(x) - 0.1260 * x - 0.3516 * x**2 + 0.2843 * x**3 - a4 * x**4)
    if m == 0:
        yc = dyc = np.zeros_like(x)
    else:
        front = x < p
        yc = np.where(front, m / p**2 * (2 * p * x - x**2),
                      m / (1 - p) ** 2 * ((1 - 2 * p) + 2 * p * x - x**2))  # fmt: skip
        dyc = np.where(front, 2 * m / p**2 * (p - x), 2 * m / (1 - p) ** 2 * (p - x))
    th = np.arctan(dyc)
    upper = np.stack([x - yt * np.sin(th), yc + yt * np.cos(th)], axis=1)
    lower = np.stack([x + yt * np.sin(th), yc - yt * np.cos(th)], axis=1)
    return np.concatenate([upper[::-1], lower[1:]])


def selig_text(name: str, pts: np.ndarray) -> str:
    return name + "\n" + "".join(f"{x:.9f} {y:.9f}\n" for x, y in pts)


def lednicer_text(name: str, pts: np.ndarray) -> str:
    le = int(np.argmin(pts[:, 0]))
    upper, lower = pts[: le + 1][::-1], pts[le:]
    body = "".join(f"{x:.9f} {y:.9f}\n" for x, y in upper) + "\n"
    body += "".join(f"{x:.9f} {y:.9f}\n" for x, y in lower)
    return f"{name}\n{len(upper)}. {len(lower)}.\n\n{body}"


def distance_to_polyline(q: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """Distance of points q (K, d) to the polyline poly (N, d), segments of zero length
    included (their first point).

    Exact, each point against the segments that can hold its nearest point only: the
    nearest vertex is ``dv`` away, and a point of a segment within ``dv`` of q lies within
    half the segment's length of one of its ends, so the segments next to the vertices
    within ``dv + L / 2`` (``L`` the longest segment) are all that count (a k-d tree finds
    them).  Every point against every segment made arrays of hundreds of MB for the
    thousands of rulings of the formats matrix (seconds per call)."""
    from scipy.spatial import cKDTree

    a, b = poly[:-1], poly[1:]
    ab = b - a
    ab2 = (ab * ab).sum(1)
    tree = cKDTree(poly)
    dv, _ = tree.query(q)
    reach = dv + 0.5 * float(np.sqrt(ab2.max(initial=0.0)))
    pairs = cKDTree(q).sparse_distance_matrix(tree, float(reach.max(initial=0.0)),
                                              output_type="ndarray")  # fmt: skip
    pairs = pairs[pairs["v"] <= reach[pairs["i"]]]
    i = np.concatenate([pairs["i"], pairs["i"]])
    s = np.concatenate([pairs["j"] - 1, pairs["j"]])  # the segments either side of a vertex
    i, s = i[(s >= 0) & (s < len(a))], s[(s >= 0) & (s < len(a))]
    w = q[i] - a[s]
    t = np.clip((w * ab[s]).sum(1) / ab2[s].clip(1e-30), 0, 1)
    out = dv.copy()
    np.minimum.at(out, i, np.linalg.norm(w - t[:, None] * ab[s], axis=1))
    return out
