"""Points against the part: exact distance to its triangles and inside/outside.

* :meth:`MeshQuery.distance`: the distance [m] from points (N, 3) to the nearest triangle,
  exact (point-triangle closest points, Ericson's regions) over candidate triangles: the
  owners of the nearest samples (a KD-tree of points spread over every triangle) and
  every triangle sharing a corner with the nearest one, which holds the nearest triangle
  for points near a surface smoother than its triangles.
* :meth:`MeshQuery.inside`: the parity of a ray's crossings (direction :data:`RAY`,
  slanted so that it meets no edge of an axis-aligned mesh exactly), with the triangles
  bucketed on a grid normal to the ray.
* :meth:`MeshQuery.signed`: distance, negative inside.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..geometry.checks import FloatArray
from .readers import PartMesh

__all__ = ["RAY", "MeshQuery", "point_triangle_distance"]

RAY = np.array([0.0123, 0.0317, 1.0]) / np.linalg.norm([0.0123, 0.0317, 1.0])
#: nearest samples whose triangles are tested per point near the surface
CANDIDATES = 8
#: exact within this distance [m]; farther, the approximate search's factor ``1 + EPS``
NEAR = 0.015
EPS = 0.25
#: samples of the coarse search for far points
COARSE = 3000


def point_triangle_distance(p: FloatArray, a: FloatArray, b: FloatArray,
                            c: FloatArray) -> FloatArray:  # fmt: skip
    """Distance [m] from points ``p`` (..., 3) to triangles ``a, b, c`` (..., 3) (broadcast),
    exact (the closest point in the triangle's vertex, edge or face region)."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = np.einsum("...i,...i", ab, ap), np.einsum("...i,...i", ac, ap)
    bp = p - b
    d3, d4 = np.einsum("...i,...i", ab, bp), np.einsum("...i,...i", ac, bp)
    cp = p - c
    d5, d6 = np.einsum("...i,...i", ab, cp), np.einsum("...i,...i", ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = va + vb + vc
        v_face, w_face = vb / denom, vc / denom
        t_ab = d1 / (d1 - d3)
        t_ac = d2 / (d2 - d6)
        t_bc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
    q = a + v_face[..., None] * ab + w_face[..., None] * ac
    cases = [
        ((d1 <= 0) & (d2 <= 0), a),
        ((d3 >= 0) & (d4 <= d3), b),
        ((d6 >= 0) & (d5 <= d6), c),
        ((vc <= 0) & (d1 >= 0) & (d3 <= 0), a + t_ab[..., None] * ab),
        ((vb <= 0) & (d2 >= 0) & (d6 <= 0), a + t_ac[..., None] * ac),
        ((va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0), b + t_bc[..., None] * (c - b)),
    ]
    for mask, point in reversed(cases):  # the first region that holds wins
        q = np.where(mask[..., None], point, q)
    return np.linalg.norm(p - q, axis=-1)


@dataclass(frozen=True)
class MeshQuery:
    """Distance and inside tests against a closed mesh (see the module doc)."""

    mesh: PartMesh
    spacing: float = field(default=0.003)

    def __post_init__(self) -> None:
        from scipy.spatial import cKDTree

        tri = self.mesh.triangles
        pts, owner = [tri[:, 0], tri[:, 1], tri[:, 2], tri.mean(axis=1)], []
        owner = [np.arange(len(tri))] * 4
        # more samples on triangles larger than the spacing (barycentric grid)
        edge = np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2).max(axis=1)
        n = np.clip(np.ceil(edge / self.spacing).astype(int), 1, 16)
        for k in np.unique(n[n > 1]):
            sel = np.flatnonzero(n == k)
            i, j = np.meshgrid(np.arange(k + 1), np.arange(k + 1), indexing="ij")
            keep = (i + j) <= k
            u, v = i[keep] / k, j[keep] / k
            w = 1.0 - u - v
            t = tri[sel]
            p = (w[None, :, None] * t[:, None, 0] + u[None, :, None] * t[:, None, 1]
                 + v[None, :, None] * t[:, None, 2])  # fmt: skip
            pts.append(p.reshape(-1, 3))
            owner.append(np.repeat(sel, len(u)))
        object.__setattr__(self, "_samples", np.concatenate(pts))
        object.__setattr__(self, "_owner", np.concatenate(owner))
        object.__setattr__(self, "_tree", cKDTree(self._samples))
        # a coarse tree for points far from the surface: at most COARSE samples, the gap
        # between them bounds its error
        rng = np.random.default_rng(0)
        pick = self._samples
        if len(pick) > COARSE:
            pick = pick[rng.choice(len(pick), COARSE, replace=False)]
        area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]),
                                    axis=1).sum()  # fmt: skip
        object.__setattr__(self, "_coarse", cKDTree(pick))
        object.__setattr__(self, "_coarse_gap", float(2.0 * np.sqrt(area / len(pick))))
        self._build_ray_grid()
        # the triangles sharing a corner with each triangle (padded with itself)
        f = self.mesh.faces
        vf = np.argsort(f.ravel(), kind="stable") // 3
        start = np.searchsorted(np.sort(f.ravel()), np.arange(len(self.mesh.vertices) + 1))
        rings = [np.unique(np.concatenate([vf[start[v]:start[v + 1]] for v in tri_v]))
                 for tri_v in f]  # fmt: skip
        width = max(len(r) for r in rings)
        ring = np.repeat(np.arange(len(f))[:, None], width, axis=1)
        for k, r in enumerate(rings):
            ring[k, : len(r)] = r
        object.__setattr__(self, "_ring", ring)

    def distance(self, points: FloatArray, chunk: int = 20_000) -> FloatArray:
        """(N,) distance [m] from ``points`` (N, 3) to the part's surface: exact within
        :data:`NEAR` of it; beyond, the distance to the nearest of :data:`COARSE` samples
        found within a factor ``1 + EPS`` (far from a closed surface an exact search
        visits most samples)."""
        points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        out = np.empty(len(points))
        tri = self.mesh.triangles
        for s in range(0, len(points), chunk):
            p = points[s : s + chunk]
            d, _ = self._coarse.query(p, k=1, eps=EPS)
            near = np.flatnonzero(d < NEAR + self._coarse_gap)
            if len(near):
                _, idx = self._tree.query(p[near], k=CANDIDATES)
                own = self._owner[idx]
                t = tri[np.concatenate([own, self._ring[own[:, 0]]], axis=1)]
                dn = point_triangle_distance(p[near, None, :], t[..., 0, :], t[..., 1, :],
                                             t[..., 2, :])  # fmt: skip
                d[near] = dn.min(axis=1)
            out[s : s + chunk] = d
        return out

    def _build_ray_grid(self) -> None:
        tri = self.mesh.triangles
        e1 = np.cross(RAY, [1.0, 0.0, 0.0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(RAY, e1)
        uv = np.stack([tri @ e1, tri @ e2], axis=-1)  # (F, 3, 2)
        lo, hi = uv.min(axis=1), uv.max(axis=1)
        origin = lo.min(axis=0)
        span = hi.max(axis=0) - origin
        cells = int(np.clip(np.sqrt(len(tri)) / 2, 4, 256))
        step = np.maximum(span / cells, 1e-9)
        i0 = np.floor((lo - origin) / step).astype(int).clip(0, cells - 1)
        i1 = np.floor((hi - origin) / step).astype(int).clip(0, cells - 1)
        faces, keys = [], []
        for f in range(len(tri)):  # the bounding boxes in cells (few per triangle)
            xs, ys = np.arange(i0[f, 0], i1[f, 0] + 1), np.arange(i0[f, 1], i1[f, 1] + 1)
            k = (xs[:, None] * cells + ys[None, :]).ravel()
            keys.append(k)
            faces.append(np.full(len(k), f))
        keys_a, faces_a = np.concatenate(keys), np.concatenate(faces)
        order = np.argsort(keys_a, kind="stable")
        start = np.searchsorted(keys_a[order], np.arange(cells * cells + 1))
        object.__setattr__(self, "_ray", (e1, e2, origin, step, cells, faces_a[order], start, uv))

    def inside(self, points: FloatArray) -> np.ndarray:
        """(N,) bool: ``points`` (N, 3) inside the closed part (ray parity)."""
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        e1, e2, origin, step, cells, faces, start, uv = self._ray
        q = np.stack([p @ e1, p @ e2], axis=-1)
        c = np.floor((q - origin) / step).astype(int)
        ok = np.all((c >= 0) & (c < cells), axis=1)
        key = np.where(ok, c[:, 0] * cells + c[:, 1], 0)
        n = np.where(ok, start[key + 1] - start[key], 0)
        pi = np.repeat(np.arange(len(p)), n)
        offs = np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n)
        fi = faces[np.repeat(start[key], n) + offs]
        t = uv[fi]  # (M, 3, 2)
        x = q[pi]
        a, b, cc = t[:, 0], t[:, 1], t[:, 2]
        den = ((b[:, 1] - cc[:, 1]) * (a[:, 0] - cc[:, 0])
               + (cc[:, 0] - b[:, 0]) * (a[:, 1] - cc[:, 1]))  # fmt: skip
        with np.errstate(divide="ignore", invalid="ignore"):
            l1 = ((b[:, 1] - cc[:, 1]) * (x[:, 0] - cc[:, 0])
                  + (cc[:, 0] - b[:, 0]) * (x[:, 1] - cc[:, 1])) / den  # fmt: skip
            l2 = ((cc[:, 1] - a[:, 1]) * (x[:, 0] - cc[:, 0])
                  + (a[:, 0] - cc[:, 0]) * (x[:, 1] - cc[:, 1])) / den  # fmt: skip
        l3 = 1.0 - l1 - l2
        hit = (den != 0) & (l1 >= 0) & (l2 >= 0) & (l3 >= 0)
        tri = self.mesh.triangles[fi]
        depth = (l1[:, None] * tri[:, 0] + l2[:, None] * tri[:, 1] + l3[:, None] * tri[:, 2]) @ RAY
        hit &= depth > p[pi] @ RAY
        return np.bincount(pi[hit], minlength=len(p)) % 2 == 1

    def signed(self, points: FloatArray) -> FloatArray:
        """(N,) signed distance [m]: negative inside the part."""
        d = self.distance(points)
        return np.where(self.inside(points), -d, d)
