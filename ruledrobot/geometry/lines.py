"""Oriented lines in Plücker coordinates and the manifold M^4 of lines.

A line is ``[l, m]`` of shape ``(..., 6)``: ``l`` its unit direction, ``m = p x l``
its moment for any point ``p`` on it, so ``|l| = 1`` and ``l . m = 0`` (the
paper's Eq. 1).  Units: metres for moments and points.

Projection of an arbitrary point of R^6 onto M^4:

* :func:`plucker_project` — the paper's Eq. 4 (Gram–Schmidt):
  ``l = p/|p|``, ``m = pbar/|p| - (p . pbar) p / |p|^3``; the axis of the linear
  complex ``(p, pbar)``.  Equivariant under similarities; the default.
* :func:`plucker_nearest` — the exact closest point of M^4 in the Euclidean
  metric of R^6 (the paper's degree-4 problem), solved per element by a
  safeguarded Newton iteration on the quartic's one unknown.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ._arrays import cross, cross3, dot, dot3, norm
from .checks import FloatArray, as_float_array, first_index

__all__ = [
    "CommonNormal",
    "Lines",
    "coincident_neighbours",
    "common_normal",
    "neighbour_gaps",
    "plucker_from_point_direction",
    "plucker_from_two_points",
    "plucker_nearest",
    "plucker_project",
    "plucker_transform",
    "point_nearest_origin",
    "validate_plucker",
]


def plucker_from_point_direction(points: ArrayLike, directions: ArrayLike) -> FloatArray:
    """Plücker rows (..., 6) of lines through ``points`` (..., 3) along ``directions`` (..., 3).

    Directions are normalised; a zero direction raises ValueError naming its index.
    """
    p = as_float_array(points, "points", (3,))
    d = as_float_array(directions, "directions", (3,))
    n = norm(d)
    scale = np.maximum(1.0, np.abs(d).max(axis=-1, initial=0.0)) if d.size else 1.0
    bad = n <= 1e-12 * scale
    if np.any(bad):
        raise ValueError(f"directions{first_index(bad)}: zero direction vector; expected non-zero")
    l = d / n[..., None]
    p, l = np.broadcast_arrays(p, l)
    return np.concatenate([l, cross(p, l)], axis=-1)


def plucker_from_two_points(a: ArrayLike, b: ArrayLike) -> FloatArray:
    """Plücker rows (..., 6) of the lines through ``a`` towards ``b`` (both (..., 3))."""
    a = as_float_array(a, "first points", (3,))
    b = as_float_array(b, "second points", (3,))
    d = b - a
    bad = norm(d) <= 1e-12 * np.maximum(1.0, np.maximum(norm(a), norm(b)))
    if np.any(bad):
        raise ValueError(f"points{first_index(bad)}: the two points coincide; expected distinct")
    return plucker_from_point_direction(a, d)


def validate_plucker(rows: ArrayLike, name: str = "lines", tol: float = 1e-9) -> FloatArray:
    """Check Plücker rows (..., 6) and return them exactly on M^4.

    Requires finite values, ``| |l| - 1 | <= tol`` and ``|l . m| <= tol * max(1, |m|)``;
    raises ValueError naming the first bad index otherwise.  Accepted rows are
    re-normalised with Eq. 4, which leaves exact rows unchanged.
    """
    x = as_float_array(rows, name, (6,))
    l, m = x[..., :3], x[..., 3:]
    ln = norm(l)
    bad = np.abs(ln - 1.0) > tol
    if np.any(bad):
        i = first_index(bad)
        raise ValueError(
            f"{name}{i}: direction must be a unit vector, |l| = {ln[bad][0]:.12g} "
            f"(tolerance {tol:g})"
        )
    lm = np.abs(dot(l, m))
    bad = lm > tol * np.maximum(1.0, norm(m))
    if np.any(bad):
        raise ValueError(
            f"{name}{first_index(bad)}: l . m = {lm[bad][0]:.3e}; Plücker coordinates "
            f"must satisfy l . m = 0 (tolerance {tol:g})"
        )
    return plucker_project(x)


def plucker_project(x: ArrayLike) -> FloatArray:
    """Project points (..., 6) of R^6 onto the line manifold M^4 by Eq. 4.

    ``l = p/|p|``, ``m = pbar/|p| - (p . pbar) p/|p|^3``.  The result is the axis
    of the linear complex ``(p, pbar)``; exactly ``|l| = 1``, ``l . m = 0`` to
    rounding (1e-16 relative).  ``p = 0`` raises ValueError.
    """
    x = np.asarray(x, dtype=np.float64)
    p, pb = x[..., :3], x[..., 3:]
    n = norm(p)
    bad = ~(n > 0.0)
    if np.any(bad):
        raise ValueError(f"plucker{first_index(bad)}: direction part is zero; no line")
    l = p / n[..., None]
    m = pb / n[..., None]
    m = m - dot(l, m)[..., None] * l
    # one more Gram–Schmidt pass removes the last rounding residue of l . m
    m = m - dot(l, m)[..., None] * l
    return np.concatenate([l, m], axis=-1)


def plucker_nearest(x: ArrayLike) -> FloatArray:
    """Exact nearest point of M^4 to points (..., 6) of R^6 (Euclidean metric of R^6).

    The Lagrange conditions of the paper's Eq. 2-3 reduce to one unknown
    ``mu = l . pbar``: ``l = +-(p - mu pbar)/|p - mu pbar|`` and ``m = pbar - mu l``,
    where ``mu`` is a real root of the quartic (``a = |p|^2, b = p.pbar, c = |pbar|^2``)::

        c mu^4 - 2b mu^3 + (a - c^2) mu^2 + 2bc mu - b^2 = 0.

    All roots are found at once as eigenvalues of batched companion matrices;
    every real root and both orientations give a candidate on M^4, and the
    candidate closest to ``x`` wins (the Eq. 4 point is a candidate too, which
    covers ``pbar = 0``).  Vectorised; about 10x the cost of :func:`plucker_project`.
    """
    x = np.asarray(x, dtype=np.float64)
    shape = x.shape[:-1]
    x = x.reshape(-1, 6)
    p, pb = x[:, :3], x[:, 3:]
    a = np.einsum("ni,ni->n", p, p)
    b = np.einsum("ni,ni->n", p, pb)
    c = np.einsum("ni,ni->n", pb, pb)
    if np.any(a <= 0.0):
        raise ValueError(f"plucker{first_index(a <= 0.0)}: direction part is zero; no line")
    best = plucker_project(x)
    best_f = np.sum((best - x) ** 2, axis=-1)
    quartic = c > 1e-300
    if np.any(quartic):
        idx = np.flatnonzero(quartic)
        aa, bb, cc = a[idx], b[idx], c[idx]
        comp = np.zeros((idx.size, 4, 4))
        comp[:, 1, 0] = comp[:, 2, 1] = comp[:, 3, 2] = 1.0
        # monic: mu^4 + k3 mu^3 + k2 mu^2 + k1 mu + k0
        comp[:, 0, 0] = 2.0 * bb / cc
        comp[:, 0, 1] = -(aa - cc * cc) / cc
        comp[:, 0, 2] = -2.0 * bb
        comp[:, 0, 3] = bb * bb / cc
        roots = np.linalg.eigvals(comp)
        real = np.abs(roots.imag) <= 1e-7 * (1.0 + np.abs(roots.real))
        mu = roots.real  # (k, 4)
        pp, pbb = p[idx][:, None, :], pb[idx][:, None, :]
        d = pp - mu[..., None] * pbb
        dn = norm(d)
        ok = real & (dn > 0.0)
        for sign in (1.0, -1.0):
            l = sign * d / np.where(ok, dn, 1.0)[..., None]
            m = pbb - np.einsum("kri,kri->kr", l, pbb)[..., None] * l
            cand = np.concatenate([l, m], axis=-1)
            f = np.sum((cand - x[idx][:, None, :]) ** 2, axis=-1)
            f = np.where(ok, f, np.inf)
            j = np.argmin(f, axis=1)
            fj = f[np.arange(idx.size), j]
            better = fj < best_f[idx]
            best[idx[better]] = plucker_project(cand[np.arange(idx.size), j][better])
            best_f[idx[better]] = fj[better]
    return best.reshape(*shape, 6)


def point_nearest_origin(plucker: ArrayLike) -> FloatArray:
    """Point of each line (..., 6) closest to the origin: ``l x m`` (..., 3)."""
    x = np.asarray(plucker, dtype=np.float64)
    return cross(x[..., :3], x[..., 3:])


def plucker_transform(T: ArrayLike, plucker: ArrayLike) -> FloatArray:
    """Apply rigid motions T (..., 4, 4) to lines (..., 6): ``l' = R l``, ``m' = R m + t x R l``."""
    T = np.asarray(T, dtype=np.float64)
    x = np.asarray(plucker, dtype=np.float64)
    R, t = T[..., :3, :3], T[..., :3, 3]
    l = np.einsum("...ij,...j->...i", R, x[..., :3])
    m = np.einsum("...ij,...j->...i", R, x[..., 3:]) + cross(t, l)
    return np.concatenate([l, m], axis=-1)


#: Consecutive lines whose gap (:func:`neighbour_gaps`) is below this fraction of the
#: sequence's median gap, or below :data:`COINCIDENT_ABS` m, count as coincident.
COINCIDENT_REL = 1e-3
COINCIDENT_ABS = 1e-9


def neighbour_gaps(plucker: ArrayLike, closed: bool = False) -> FloatArray:
    """How far apart consecutive lines are over the region they occupy (N-1,) or (N,) m.

    The region is the segment of half-length ``L`` (the RMS spread of the lines'
    points nearest their centroid, at least 1e-3 m) centred on line i's point
    nearest the centroid; the gap is the largest distance from its ends and middle
    to line i+1 (``|p x l - m|``).  Orientation does not count (a line and its
    reverse have gap 0).  ``closed`` adds the gap from the last line to the first.
    """
    x = np.asarray(plucker, dtype=np.float64)
    l, m = x[:, :3], x[:, 3:]
    foot0 = cross(l, m)
    c = foot0.mean(axis=0)
    foot = foot0 + dot(c - foot0, l)[:, None] * l  # point of each line nearest the centroid
    L = max(float(np.sqrt(((foot - c) ** 2).sum(axis=1).mean())), 1e-3)
    nxt = np.r_[np.arange(1, len(x)), 0] if closed else np.arange(1, len(x))
    a = np.arange(len(nxt))
    gap = np.zeros(len(nxt))
    for k in (-1.0, 0.0, 1.0):
        p = foot[a] + k * L * l[a]
        gap = np.maximum(gap, norm(cross(p, l[nxt]) - m[nxt]))
    return gap


def coincident_neighbours(plucker: ArrayLike, closed: bool = False) -> np.ndarray:
    """Indices i (K,) whose line coincides with line i+1 (mod N when ``closed``).

    Gap below ``COINCIDENT_REL`` x the median gap or below ``COINCIDENT_ABS``."""
    gap = neighbour_gaps(plucker, closed)
    if gap.size == 0:
        return np.zeros(0, dtype=int)
    limit = max(COINCIDENT_ABS, COINCIDENT_REL * float(np.median(gap)))
    return np.flatnonzero(gap < limit)


@dataclass(frozen=True)
class CommonNormal:
    """Common normal of line pairs (L1, L2); every field has the pairs' batch shape.

    * ``foot1``, ``foot2`` (..., 3): its feet on L1 and L2.
    * ``direction`` (..., 3): unit vector along it, from L1 towards L2
      (``(foot2 - foot1)/distance``); for intersecting lines ``l1 x l2/|l1 x l2|``.
    * ``distance`` (...): ``|foot2 - foot1| >= 0`` (DH ``a``).
    * ``angle`` (...): twist angle from l1 to l2 about ``direction``, in (-pi, pi] (DH ``alpha``).
    * ``parallel`` (...): ``|l1 x l2| <= angle_tol``.  The normal is then not unique:
      ``foot1`` is the projection of the reference point onto L1 (default: the
      point of L1 nearest the origin), ``foot2`` its projection onto L2.  For
      identical lines ``direction`` is an arbitrary unit vector normal to l1.
    * ``intersecting`` (...): not parallel and ``distance <= dist_tol``.
    """

    foot1: FloatArray
    foot2: FloatArray
    direction: FloatArray
    distance: FloatArray
    angle: FloatArray
    parallel: FloatArray
    intersecting: FloatArray


def _any_normal(l: FloatArray) -> FloatArray:
    """A unit vector normal to each unit vector l (..., 3), smooth away from a seam."""
    e = np.where(np.abs(l[..., :1]) < 0.9, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    n = cross(l, e)
    return n / norm(n)[..., None]


def common_normal(
    line1: ArrayLike,
    line2: ArrayLike,
    reference: ArrayLike | None = None,
    angle_tol: float = 1e-10,
    dist_tol: float = 1e-12,
) -> CommonNormal:
    """Common normal of Plücker lines ``line1``, ``line2`` (..., 6) (broadcast).

    Skew and intersecting lines: the feet minimise ``|F1 - F2|`` (closed form
    with ``s^2 = |l1 x l2|^2`` as denominator).  Parallel lines (``s <=
    angle_tol``): feet at the projections of ``reference`` (..., 3), see
    :class:`CommonNormal`.  ``dist_tol`` (m) decides "intersecting".
    """
    x1 = np.asarray(line1, dtype=np.float64)
    x2 = np.asarray(line2, dtype=np.float64)
    shape = np.broadcast_shapes(x1.shape, x2.shape)
    # struct of arrays: one contiguous array per coordinate
    a = np.ascontiguousarray(np.moveaxis(np.broadcast_to(x1, shape), -1, 0))
    b = np.ascontiguousarray(np.moveaxis(np.broadcast_to(x2, shape), -1, 0))
    l1, m1, l2, m2 = tuple(a[:3]), tuple(a[3:]), tuple(b[:3]), tuple(b[3:])
    p1 = cross3(l1, m1)
    p2 = cross3(l2, m2)
    c = cross3(l1, l2)
    s2 = dot3(c, c)
    s = np.sqrt(s2)
    cosang = dot3(l1, l2)
    d = tuple(p2[k] - p1[k] for k in range(3))
    dl1 = dot3(d, l1)
    dl2 = dot3(d, l2)
    parallel = s <= angle_tol
    any_parallel = bool(parallel.any())
    s2safe = np.where(parallel, 1.0, s2) if any_parallel else s2
    t1 = (dl1 - cosang * dl2) / s2safe
    t2 = (cosang * dl1 - dl2) / s2safe
    # non-parallel lines: the normal is exactly along n = l1 x l2 / s; the signed
    # distance (p2 - p1) . n is well conditioned even when the feet are not
    inv_s = 1.0 / (np.where(parallel, 1.0, s) if any_parallel else s)
    n = tuple(ck * inv_s for ck in c)
    signed = dot3(d, n)
    dist = np.abs(signed)
    sign = np.where(signed < 0.0, -1.0, 1.0)
    if any_parallel:
        # parallel lines: feet at the projections of the reference point
        if reference is None:
            ref = p1
        else:
            r = np.moveaxis(
                np.broadcast_to(np.asarray(reference, dtype=np.float64), (*shape[:-1], 3)), -1, 0
            )
            ref = tuple(r)
        t1 = np.where(parallel, dot3(tuple(ref[k] - p1[k] for k in range(3)), l1), t1)
        t2 = np.where(parallel, dot3(tuple(ref[k] - p2[k] for k in range(3)), l2), t2)
    f1 = tuple(p1[k] + t1 * l1[k] for k in range(3))
    f2 = tuple(p2[k] + t2 * l2[k] for k in range(3))
    intersecting = ~parallel & (dist <= dist_tol)
    flip = np.where(intersecting, 1.0, sign)
    direction = tuple(nk * flip for nk in n)
    if any_parallel:
        # the gap between the feet, made exactly normal to l1
        gap = tuple(f2[k] - f1[k] for k in range(3))
        along = dot3(gap, l1)
        gap = tuple(gap[k] - along * l1[k] for k in range(3))
        gap_len = np.sqrt(dot3(gap, gap))
        inv_g = 1.0 / np.where(gap_len > 0.0, gap_len, 1.0)
        direction = tuple(np.where(parallel, gap[k] * inv_g, direction[k]) for k in range(3))
        dist = np.where(parallel, gap_len, dist)
        identical = parallel & (gap_len <= dist_tol)
        if np.any(identical):
            other = np.moveaxis(_any_normal(np.stack(l1, axis=-1)), -1, 0)
            direction = tuple(np.where(identical, other[k], direction[k]) for k in range(3))
    # twist angle about the normal direction, in (-pi, pi]
    angle = np.arctan2(dot3(c, direction), cosang)
    dist = np.where(intersecting, 0.0, dist)
    f2 = tuple(np.where(intersecting, f1[k], f2[k]) for k in range(3))
    f1 = np.stack(f1, axis=-1)
    f2 = np.stack(f2, axis=-1)
    direction = np.stack(direction, axis=-1)
    return CommonNormal(f1, f2, direction, dist, angle, parallel, intersecting)


@dataclass(frozen=True)
class Lines:
    """A sequence of oriented lines: Plücker rows ``plucker`` (N, 6) = ``[l, m]``.

    Immutable (the array is read-only).  Build with :meth:`from_point_direction`,
    :meth:`from_two_points` or :meth:`from_plucker`.
    """

    plucker: FloatArray = field(repr=False)

    def __post_init__(self) -> None:
        arr = np.array(self.plucker, dtype=np.float64)
        if arr.ndim != 2 or arr.shape[1] != 6:
            raise ValueError(f"lines: expected Plücker rows of shape (N, 6), got {arr.shape}")
        arr.setflags(write=False)
        object.__setattr__(self, "plucker", arr)

    @classmethod
    def from_point_direction(cls, points: ArrayLike, directions: ArrayLike) -> Lines:
        """Lines through ``points`` (N, 3) along ``directions`` (N, 3) (normalised)."""
        return cls(_as_rows(plucker_from_point_direction(points, directions)))

    @classmethod
    def from_two_points(cls, a: ArrayLike, b: ArrayLike) -> Lines:
        """Lines through ``a`` (N, 3) pointing towards ``b`` (N, 3)."""
        return cls(_as_rows(plucker_from_two_points(a, b)))

    @classmethod
    def from_plucker(cls, rows: ArrayLike, tol: float = 1e-9) -> Lines:
        """Lines from Plücker rows (N, 6), validated (see :func:`validate_plucker`)."""
        return cls(_as_rows(validate_plucker(rows, "lines", tol)))

    @property
    def direction(self) -> FloatArray:
        """Unit directions ``l`` (N, 3)."""
        return self.plucker[:, :3]

    @property
    def moment(self) -> FloatArray:
        """Moments ``m`` (N, 3), metres."""
        return self.plucker[:, 3:]

    @property
    def point(self) -> FloatArray:
        """Point of each line nearest the origin (N, 3)."""
        return point_nearest_origin(self.plucker)

    def points_at(self, v: ArrayLike) -> FloatArray:
        """Points ``point + v l``: ``v`` (N,) -> (N, 3), ``v`` (N, K) -> (N, K, 3)."""
        v = np.asarray(v, dtype=np.float64)
        if v.ndim == 1:
            return self.point + v[:, None] * self.direction
        return self.point[:, None] + v[..., None] * self.direction[:, None]

    def transform(self, T: ArrayLike) -> Lines:
        """The lines moved by the rigid motion T (4, 4) (or one pose per line (N, 4, 4))."""
        return Lines(plucker_transform(T, self.plucker))


    def __len__(self) -> int:
        return self.plucker.shape[0]

    def __getitem__(self, index: int | slice | ArrayLike) -> Lines:
        rows = self.plucker[index]
        return Lines(rows.reshape(-1, 6))

    def __iter__(self):  # pragma: no cover - convenience
        return iter(self.plucker)


def _as_rows(x: FloatArray) -> FloatArray:
    if x.ndim == 1:
        x = x[None]
    if x.ndim != 2:
        raise ValueError(f"lines: expected a sequence of lines (N, ...), got shape {x.shape}")
    return x
