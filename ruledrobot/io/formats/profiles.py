"""Profiles (polylines) and how two of them make rulings.

A ruled surface between two profiles pairs each point of one with a point of the
other.  Two rules (``match``):

* ``"parameter"`` — both profiles are resampled at the same values of their
  normalised arc length (``uniform`` spacing, or ``cosine`` spacing, dense at the
  ends of each piece); optional break points (an airfoil's leading edge) split
  the profiles into pieces that are resampled separately, so that the breaks
  meet each other;
* ``"index"`` — point i of one with point i of the other (equal counts required).

Checks: a profile that crosses itself (in its own best-fit plane) is refused,
naming the two segments.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ...geometry._arrays import FloatArray
from ...geometry.interp import interp_linear

__all__ = ["MATCH_RULES", "SPACINGS", "check_simple", "match_profiles", "plane_coordinates",
           "resample"]  # fmt: skip

MATCH_RULES = ("parameter", "index")
SPACINGS = ("uniform", "cosine")


def _dedupe(points: FloatArray) -> FloatArray:
    """The points without consecutive repeats (a segment of length zero)."""
    keep = np.r_[True, np.linalg.norm(np.diff(points, axis=0), axis=1) > 0]
    return points[keep]


def resample(points: ArrayLike, n: int, spacing: str = "uniform") -> FloatArray:
    """Return ``n`` points (n, d) along the polyline ``points`` (N, d).

    At equal steps of the normalised arc length (``uniform``) or at ``(1 - cos(pi u))/2``
    (``cosine``); the first and last points are kept exactly.
    """
    p = _dedupe(np.asarray(points, dtype=np.float64))
    s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))]
    u = np.linspace(0.0, 1.0, n)
    t = 0.5 * (1.0 - np.cos(np.pi * u)) if spacing == "cosine" else u
    out = interp_linear(t * s[-1], s, p)
    out[0], out[-1] = p[0], p[-1]
    return out


def plane_coordinates(points: ArrayLike) -> FloatArray:
    """2-D coordinates (N, 2) of points (N, 3) in their best-fit plane (PCA)."""
    p = np.asarray(points, dtype=np.float64)
    c = p - p.mean(axis=0)
    _, _, vt = np.linalg.svd(c, full_matrices=False)
    return c @ vt[:2].T


def _candidate_pairs(s0: FloatArray, s1: FloatArray) -> tuple[np.ndarray, np.ndarray]:
    """Pairs (i < j) of segments whose bounding boxes share a cell of a uniform grid
    (cell size about the mean segment length): the only ones that can cross."""
    lo, hi = np.minimum(s0, s1), np.maximum(s0, s1)
    length = np.linalg.norm(s1 - s0, axis=1)
    extent = float(np.ptp(np.concatenate([s0, s1]), axis=0).max())
    h = max(float(length.mean()), extent / 4096, 1e-300)
    c0 = np.floor((lo - lo.min(axis=0)) / h).astype(np.int64)
    c1 = np.floor((hi - lo.min(axis=0)) / h).astype(np.int64)
    span = c1 - c0 + 1
    count = span[:, 0] * span[:, 1]
    seg = np.repeat(np.arange(len(s0)), count)
    k = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
    cx = c0[seg, 0] + k % span[seg, 0]
    cy = c0[seg, 1] + k // span[seg, 0]
    cell = cx * (int(c1[:, 1].max()) + 1) + cy
    order = np.lexsort((seg, cell))
    cell, seg = cell[order], seg[order]
    end = np.searchsorted(cell, cell, side="right")  # one past each entry's group
    after = end - np.arange(len(cell)) - 1  # later entries in the same cell
    a = np.repeat(np.arange(len(cell)), after)
    b = a + 1 + np.arange(after.sum()) - np.repeat(np.cumsum(after) - after, after)
    i, j = seg[a], seg[b]
    pairs = np.unique(np.stack([np.minimum(i, j), np.maximum(i, j)], axis=1), axis=0)
    return pairs[:, 0], pairs[:, 1]


def check_simple(points: ArrayLike, where: str, closed: bool = False,
                 labels: list[str] | None = None) -> None:  # fmt: skip
    """Raise ValueError naming two segments of the polyline that cross.

    The polyline (N, 2) (or (N, 3), taken in its best-fit plane); touching ends and
    neighbours do not count.  ``labels`` name the points in the message (e.g. file lines);
    default their indices.  Only segments that share a cell of a grid are compared
    (vectorised, near linear time).
    """
    p = np.asarray(points, dtype=np.float64)
    if p.shape[1] == 3:
        p = plane_coordinates(p)
    a = p if not closed else np.concatenate([p, p[:1]])
    s0, s1 = a[:-1], a[1:]
    m = len(s0)
    if m < 3:
        return
    eps = 1e-12 * max(1e-300, float(np.ptp(p, axis=0).max())) ** 2  # touching within rounding

    def orient(o: FloatArray, q: FloatArray, r: FloatArray) -> FloatArray:
        v = (q[..., 0] - o[..., 0]) * (r[..., 1] - o[..., 1]) \
            - (q[..., 1] - o[..., 1]) * (r[..., 0] - o[..., 0])  # fmt: skip
        return np.where(np.abs(v) <= eps, 0.0, np.sign(v))

    i, j = _candidate_pairs(s0, s1)
    keep = (j > i + 1) & ~(closed & (i == 0) & (j == m - 1))
    i, j = i[keep], j[keep]
    A, B, C, D = s0[i], s1[i], s0[j], s1[j]
    cross = (orient(A, B, C) * orient(A, B, D) < 0) & (orient(C, D, A) * orient(C, D, B) < 0)
    if cross.any():
        k = int(np.argmax(cross))
        si, sj = int(i[k]), int(j[k])
        lab = labels or [f"point {n}" for n in range(len(p))]
        raise ValueError(f"{where}: the profile crosses itself: the segment {lab[si]} to "
                         f"{lab[(si + 1) % len(p)]} crosses the segment {lab[sj]} to "
                         f"{lab[(sj + 1) % len(p)]}; expected a simple profile")


def match_profiles(a: ArrayLike, b: ArrayLike, rule: str, n: int | None, where: str,
                   breaks: tuple[int, int] | None = None, spacing: str = "uniform",
                   names: tuple[str, str] = ("first profile", "second profile"),
                   ) -> tuple[FloatArray, FloatArray]:  # fmt: skip
    """Matched points (K, d) of two profiles (see the module doc).

    ``n``: points per profile for ``"parameter"`` (default: the larger count);
    ``breaks``: one break index per profile (e.g. the leading edges), resampled so
    that point ``k`` of both is its break.
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if rule == "index":
        if len(a) != len(b):
            raise ValueError(f"{where}: the {names[0]} has {len(a)} points and the {names[1]} "
                             f"{len(b)}; match = \"index\" pairs point i with point i and needs "
                             "equal counts (use match = \"parameter\")")  # fmt: skip
        return a, b
    if rule != "parameter":
        raise ValueError(f"{where}: match {rule!r}: expected one of {', '.join(MATCH_RULES)}")
    n = max(len(a), len(b)) if n is None else n
    if breaks is None:
        return resample(a, n, spacing), resample(b, n, spacing)
    k = (n + 1) // 2  # points per piece; the break is shared
    pa = np.concatenate([resample(a[: breaks[0] + 1], k, spacing),
                         resample(a[breaks[0]:], k, spacing)[1:]])  # fmt: skip
    pb = np.concatenate([resample(b[: breaks[1] + 1], k, spacing),
                         resample(b[breaks[1]:], k, spacing)[1:]])  # fmt: skip
    return pa, pb
