"""Fitting a region: a plane, or a quadric, and the lines that lie on it.

Every ruled quadric — plane, cylinder, cone, hyperboloid of one sheet, hyperbolic
paraboloid — is the zero set of ``Q(x) = x^T A x + 2 b^T x + c``.  A region is fitted
by the smallest singular vector of its vertices' monomials (in coordinates centred
and scaled to the region), and accepted when every vertex lies within ``tolerance``
of the fit (the first-order distance ``|Q| / |grad Q|``) and the fit's normals agree
with the mesh's (within :data:`NORMAL_ANGLE`).  A plane is tried first (its quadric is
not unique).

The lines through a point ``p`` of ``Q`` that lie on it are the directions ``d`` of
its tangent plane with ``d^T A d = 0``: with ``lambda1 <= lambda2`` the eigenvalues of
``A`` restricted to the tangent plane (eigenvectors ``u1, u2``), ``d = sqrt(lambda2) u1
+- sqrt(-lambda1) u2`` when ``lambda1 <= 0 <= lambda2`` — two families on a doubly ruled
quadric, one (``u1``) on a cylinder or cone, none on an ellipsoid (both eigenvalues of
one sign): such a region is not ruled and is roughed.  These lines lie on the fitted
surface exactly (``Q(p + t d)`` vanishes in every power of ``t``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..geometry.checks import FloatArray
from .segment import Region

__all__ = ["NORMAL_ANGLE", "Fit", "fit_region"]

NORMAL_ANGLE = np.radians(10.0)
#: weight of the normal rows against the vertices' (:func:`_normal_rows`): they choose
#: among quadrics the vertices cannot tell apart, and barely move one they fix (a
#: faceted mesh's vertex normals are approximate; at weight 1 they tilted a saddle's fit
#: enough to change its rulings and slow the planned wire to 10.2 mm/s of 12)
NORMAL_WEIGHT = 1e-3
#: a tangent-plane eigenvalue this small relative to the other is zero (developables)
FLAT = 1e-3


@dataclass(frozen=True)
class Fit:
    """A fitted region.

    ``kind`` ``"plane"``, ``"ruled"`` (a ruled quadric) or ``"curved"`` (a quadric with no real
    lines: ellipsoid, paraboloid, two-sheet hyperboloid), ``"free"`` (no quadric within
    tolerance) or ``"undetermined"`` (more than one quadric within it: :func:`fit_region`);
    ``A`` (3, 3), ``b`` (3,), ``c`` in metres (base frame), ``residual`` [m] the largest
    distance of a vertex."""

    kind: str
    A: FloatArray = field(repr=False)
    b: FloatArray = field(repr=False)
    c: float
    residual: float

    def value_grad(self, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``Q(x)`` (N,) and its gradient (N, 3) at points ``x`` (N, 3)."""
        Ax = x @ self.A
        return np.einsum("ij,ij->i", x, Ax) + 2.0 * x @ self.b + self.c, 2.0 * (Ax + self.b)

    def distance(self, x: FloatArray) -> FloatArray:
        """First-order distance [m] of points (N, 3) from the surface."""
        q, g = self.value_grad(x)
        return np.abs(q) / np.maximum(np.linalg.norm(g, axis=1), 1e-300)

    def root_along(self, origin: FloatArray, direction: FloatArray, nearest: float) -> float | None:
        """The ``t`` nearest ``nearest`` with ``Q(origin + t direction) = 0``; None if none."""
        o, d = origin, direction
        a2 = float(d @ self.A @ d)
        a1 = float(2.0 * (o @ self.A @ d + self.b @ d))
        a0 = float(o @ self.A @ o + 2.0 * self.b @ o + self.c)
        if abs(a2) < 1e-12 * (abs(a1) + abs(a0) + 1e-300):
            return None if a1 == 0.0 else -a0 / a1
        disc = a1 * a1 - 4.0 * a2 * a0
        if disc < 0.0:
            return None
        r = np.array([(-a1 - np.sqrt(disc)) / (2 * a2), (-a1 + np.sqrt(disc)) / (2 * a2)])
        return float(r[np.argmin(np.abs(r - nearest))])

    def line_directions(self, p: FloatArray, normal: FloatArray) -> FloatArray:
        """Return the unit directions (2, 3) of the lines on the surface through ``p`` (3,).

        The same twice on a developable, a plane's: its tangent basis; NaN when none.
        ``normal``: the outward normal there, orienting the tangent basis.
        """
        _, g = self.value_grad(p[None])
        n = g[0] / np.linalg.norm(g[0])
        if n @ normal < 0.0:
            n = -n
        e1 = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(n, e1)
        if self.kind == "plane":
            return np.stack([e1, e2])
        E = np.stack([e1, e2], axis=1)
        lam, U = np.linalg.eigh(E.T @ self.A @ E)
        u1, u2 = E @ U[:, 0], E @ U[:, 1]
        scale = max(abs(lam[0]), abs(lam[1]), 1e-300)
        if lam[0] > FLAT * scale:
            return np.full((2, 3), np.nan)  # positive definite: no line
        if lam[1] < -FLAT * scale:
            return np.full((2, 3), np.nan)  # negative definite
        l1, l2 = min(lam[0], 0.0), max(lam[1], 0.0)
        if -l1 <= FLAT * scale:  # developable: one family
            return np.stack([u1, u1])
        if l2 <= FLAT * scale:
            return np.stack([u2, u2])
        d = np.stack([np.sqrt(l2) * u1 + np.sqrt(-l1) * u2, np.sqrt(l2) * u1 - np.sqrt(-l1) * u2])
        return d / np.linalg.norm(d, axis=1)[:, None]


def _plane(region: Region) -> tuple[FloatArray, float, float]:
    c = region.points.mean(axis=0)
    _, _, vt = np.linalg.svd(region.points - c, full_matrices=False)
    n = vt[2]
    if n @ region.normals.mean(axis=0) < 0.0:
        n = -n
    return n, float(n @ c), float(np.abs((region.points - c) @ n).max())


def _normal_rows(x: FloatArray, y: FloatArray, z: FloatArray, n: FloatArray) -> FloatArray:
    """Rows (3P, 10) of ``(A x + b) x n = 0`` in the monomial coefficients: the
    quadric's gradient along each vertex normal ``n`` (P, 3).  Vertices on a few
    curves alone do not fix a quadric — a faceted cylinder's or cone's all lie on its
    two rims, where ``x^2 + y^2 - r^2`` and ``z (z - h)`` both vanish, and the fit came
    out as any mix of the two (a cylinder fitted to 4e-14 mm was refused as its normals
    disagreed); the normals tell them apart."""
    o, e = np.zeros_like(x), np.ones_like(x)
    # v = A x + b = G q with G (P, 3, 10), q = [a00 a11 a22 a01 a02 a12 b0 b1 b2 c]
    G = np.stack([
        np.stack([x, o, o, y, z, o, e, o, o, o], axis=1),
        np.stack([o, y, o, x, o, z, o, e, o, o], axis=1),
        np.stack([o, o, z, o, x, y, o, o, e, o], axis=1),
    ], axis=1)  # fmt: skip
    rows = np.cross(np.moveaxis(G, 2, 1), n[:, None, :], axis=2)  # (P, 10, 3)
    return np.moveaxis(rows, 2, 1).reshape(-1, 10)


def _quadric(q: FloatArray, c0: FloatArray, s: float) -> tuple[FloatArray, FloatArray, float]:
    """``A`` (3, 3), ``b`` (3,), ``c`` in metres of the monomial coefficients ``q`` (10,)
    in coordinates ``x' = (x - c0) / s``."""
    A_ = np.array([[q[0], q[3], q[4]], [q[3], q[1], q[5]], [q[4], q[5], q[2]]])
    b_ = q[6:9]
    A = A_ / s**2
    b = b_ / s - A @ c0
    return A, b, float(c0 @ A @ c0 - 2.0 * (b_ / s) @ c0 + q[9])


def _within(fit: Fit, region: Region, tolerance: float) -> tuple[bool, float]:
    """Whether ``fit`` holds the region's vertices within ``tolerance`` [m] with its
    normals agreeing with theirs (98 % within :data:`NORMAL_ANGLE`); the largest
    distance [m] of a vertex."""
    P = region.points
    res = float(fit.distance(P).max())
    _, g = fit.value_grad(P)
    g /= np.maximum(np.linalg.norm(g, axis=1), 1e-300)[:, None]
    agree = np.abs(np.einsum("ij,ij->i", g, region.normals)) >= np.cos(NORMAL_ANGLE)
    return bool(res <= tolerance and agree.mean() >= 0.98), res


def _apart(one: Fit, other: Fit, region: Region) -> float:
    """How far apart [m] two fits of a region lie over it: the largest difference of
    their first-order signed distances (each signed along the region's normals) at its
    vertices and the points between them (``region.between``)."""
    x = np.concatenate([region.points, region.between])
    sd = []
    for fit in (one, other):
        _, g = fit.value_grad(region.points)
        sign = 1.0 if np.median(np.einsum("ij,ij->i", g, region.normals)) >= 0.0 else -1.0
        q, g = fit.value_grad(x)
        sd.append(sign * q / np.maximum(np.linalg.norm(g, axis=1), 1e-300))
    return float(np.abs(sd[0] - sd[1]).max())


def fit_region(region: Region, tolerance: float) -> Fit:
    """The plane or quadric of a region within ``tolerance`` [m] (module doc).

    Whatever its number of triangles: a plane is accepted by its residual alone (a
    face of two triangles is as much a plane as one of two hundred; every cut is then
    measured against the whole part, :mod:`.measure`).  A quadric must also be
    determined by the region where it matters, on the face: when the next best fit
    (the second smallest singular vector, independent of the best) holds the vertices
    and normals within the tolerance too, the two must not lie farther apart than the
    tolerance anywhere on the region's triangles (vertices, edge midpoints,
    centroids) — else the region (a fold of a few triangles) says too little to choose
    a surface between its vertices, and the fit is ``"undetermined"`` (``residual``:
    how far apart the two lie).  A narrow arc of a cylinder is determined there,
    though its continuation beyond the face is not: that is measured (no gouge)."""
    n, d, res = _plane(region)
    if res <= tolerance:
        return Fit("plane", np.zeros((3, 3)), -0.5 * n, d, res)
    P = region.points
    c0 = P.mean(axis=0)
    s = float(np.sqrt(((P - c0) ** 2).sum(axis=1).mean()))
    x, y, z = ((P - c0) / s).T
    D = np.stack([x * x, y * y, z * z, 2 * x * y, 2 * x * z, 2 * y * z,
                  2 * x, 2 * y, 2 * z, np.ones_like(x)], axis=1)  # fmt: skip
    vt = np.linalg.svd(np.vstack([D, NORMAL_WEIGHT * _normal_rows(x, y, z, region.normals)]),
                       full_matrices=False)[2]  # fmt: skip
    A, b, c = _quadric(vt[-1], c0, s)
    fit = Fit("ruled", A, b, c, 0.0)
    ok, res = _within(fit, region, tolerance)
    if not ok:
        return Fit("free", A, b, c, res)
    other = Fit("ruled", *_quadric(vt[-2], c0, s), 0.0)
    if _within(other, region, tolerance)[0]:
        gap = _apart(fit, other, region)
        if gap > tolerance:
            return Fit("undetermined", A, b, c, gap)
    ruled = [np.all(np.isfinite(fit.line_directions(p, nn)))
             for p, nn in zip(P[:: max(1, len(P) // 64)], region.normals[:: max(1, len(P) // 64)],
                              strict=True)]  # fmt: skip
    kind = "ruled" if np.mean(ruled) >= 0.95 else "curved"
    return Fit(kind, A, b, c, res)
