"""Ruled faces cut exactly: a fitted region's rulings, ordered along a transversal.

For a region fitted by a plane or a ruled quadric (:mod:`.quadric`):

* a plane that is a face of the block needs no cut;
* a region that goes round an axis (its vertices, seen along its rulings, surround
  their centroid with no gap wider than :data:`MAX_GAP`) is cut as a closed loop: the
  transversal is the section normal to the mean ruling, points on it found along rays
  from the centroid; the part is inside when the face's normals point away from the
  axis (a hole, the part outside, cannot be cut by a wire: left to roughing);
* any other region is an open cut: the transversal runs through the region's centre
  across the rulings, on the surface, and goes on until its rulings miss the block
  (an open cut must span the block); its kept side is a point of the part just
  behind the face.

At each transversal point the line of the chosen family is the one nearest the
previous point's (families never cross), oriented alike.  Of a doubly ruled face the
family taken is the one most nearly along ``prefer`` (the wire held across the arm's
reach, as in the demo jobs).  Rulings are spaced :data:`SPACING` along the transversal.
"""

from __future__ import annotations

import numpy as np

from ..geometry.box import Box
from ..geometry.checks import FloatArray
from ..geometry.lines import Lines
from .meshquery import MeshQuery
from .model import CarveCut
from .quadric import Fit
from .segment import Region

__all__ = ["KEEP_DEPTHS", "MAX_GAP", "SPACING", "block_face", "exact_cut", "keep_point"]

SPACING = 0.008
MAX_GAP = np.radians(60.0)
#: transversal steps tried past the block on each side of an open cut
MAX_STEPS = 400
#: depths [m] behind an open cut's face tried for its kept point, in this order, below
#: the centroids of the face's KEEP_TRIANGLES largest triangles
KEEP_DEPTHS = (0.002, 0.005, 0.01, 0.02, 0.0005)
KEEP_TRIANGLES = 8


def block_face(fit: Fit, stock: Box, tolerance: float) -> bool:
    """Whether a plane fit is a face of the block (within ``tolerance``)."""
    if fit.kind != "plane":
        return False
    n = -2.0 * fit.b  # Q = -n.x + d
    local = stock.rotation.T @ n
    k = int(np.argmax(np.abs(local)))
    if abs(local[k]) < 1.0 - 1e-6:
        return False
    offset = fit.c - n @ stock.centre  # n.x = d on the plane
    return abs(abs(offset) - 0.5 * stock.size[k]) <= tolerance


def _pick(dirs: FloatArray, previous: FloatArray) -> FloatArray:
    k = int(np.argmax(np.abs(dirs @ previous)))
    d = dirs[k]
    return d if d @ previous >= 0.0 else -d


def _near(region: Region, p: FloatArray) -> FloatArray:
    """The region's outward normal at its vertex nearest ``p``."""
    return region.normals[int(np.argmin(np.linalg.norm(region.points - p, axis=1)))]


def _rulings_along(fit: Fit, region: Region, pts: list[FloatArray], start: FloatArray
                   ) -> FloatArray:  # fmt: skip
    dirs, prev = [], start
    for p in pts:
        d = fit.line_directions(p, _near(region, p))
        if not np.all(np.isfinite(d)):
            raise ValueError("no line of the surface there")
        prev = _pick(d, prev)
        dirs.append(prev)
    return np.asarray(dirs)


def _closed(fit: Fit, region: Region, axis: FloatArray) -> tuple[FloatArray, FloatArray] | None:
    c = region.centroid
    e1 = np.cross(axis, [1.0, 0.0, 0.0] if abs(axis[0]) < 0.9 else [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    rel = region.points - c
    ang = np.sort(np.arctan2(rel @ e2, rel @ e1))
    gaps = np.diff(np.r_[ang, ang[0] + 2 * np.pi])
    if gaps.max() > MAX_GAP:
        return None
    radius = float(np.median(np.hypot(rel @ e1, rel @ e2)))
    m = max(16, int(np.ceil(2 * np.pi * radius / SPACING)))
    pts = []
    for phi in np.linspace(0.0, 2 * np.pi, m, endpoint=False):
        u = np.cos(phi) * e1 + np.sin(phi) * e2
        r = fit.root_along(c, u, radius)
        if r is None or r <= 0.0:
            return None
        pts.append(c + r * u)
    return np.asarray(pts), axis


def _open(fit: Fit, region: Region, stock: Box, d0: FloatArray, p0: FloatArray,
          n0: FloatArray, lead: float) -> tuple[FloatArray, FloatArray] | None:  # fmt: skip
    e = np.cross(n0, d0)
    e /= np.linalg.norm(e)
    pts, dirs_at = {0: p0}, {0: d0}
    half = float(np.linalg.norm(stock.size))
    for sign in (1, -1):
        k, d = 0, d0
        while abs(k) < MAX_STEPS:
            k += sign
            o = p0 + k * SPACING * e
            r = fit.root_along(o, n0, 0.0)
            if r is None or abs(r) > half:
                return None  # the surface ends before the block does
            p = o + r * n0
            # a plane's rulings are all parallel to the first, d0 (its tangent basis would
            # turn them towards the nearest basis vector: a fan about the first ruling)
            dirs = np.stack([d0, d0]) if fit.kind == "plane" else fit.line_directions(p, n0)
            if not np.all(np.isfinite(dirs)):
                return None
            d = _pick(dirs, d)
            pts[k], dirs_at[k] = p, d
            _, _, hit = stock.clip_lines(p, d, margin=lead)
            if not hit:
                break
    ks = sorted(pts)
    return np.asarray([pts[k] for k in ks]), np.asarray([dirs_at[k] for k in ks])


def keep_point(region: Region, query: MeshQuery, stock: Box) -> FloatArray | None:
    """A point (3,) [m] of the part in the block just behind the region's face.

    The centroid of one of its largest triangles, :data:`KEEP_DEPTHS` in along the triangle's
    inward normal (the first inside the part, by ray parity, and at least half that depth from
    its surface); None when there is none. A triangle's centroid, not a vertex: a vertex lies
    on the face's rim, and a point below it on the neighbouring face (a cap fanned from a rim
    vertex) is on the surface, neither inside nor outside."""
    tri = query.mesh.triangles[region.faces]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area = np.linalg.norm(n, axis=1)
    c = tri.mean(axis=1)
    # the largest triangles first; equal ones in coordinate order (not the file's order)
    r = np.round(c, 7)
    order = np.lexsort((r[:, 2], r[:, 1], r[:, 0], -np.round(area / area.max(), 6)))
    pick = order[:KEEP_TRIANGLES]
    n = n[pick] / np.maximum(area[pick], 1e-300)[:, None]
    depth = np.asarray(KEEP_DEPTHS)
    cand = (c[pick][None] - depth[:, None, None] * n[None]).reshape(-1, 3)  # depth-major
    ok = query.inside(cand) & stock.contains(cand)
    if ok.any():
        ok[ok] = query.distance(cand[ok]) >= 0.5 * np.repeat(depth, len(pick))[ok]
    return cand[int(np.argmax(ok))] if ok.any() else None


def exact_cut(fit: Fit, region: Region, stock: Box, query: MeshQuery, prefer: FloatArray,
              name: str, lead: float = 0.02) -> CarveCut | str:  # fmt: skip
    """The cut of a ruled region (module doc), or why there is none (a note)."""
    # the vertex nearest the region's centre; of several alike (a column's waist), the first
    # in coordinate order, so that the cut does not hang on the file's vertex order
    r = np.round(region.points, 7)
    dist = np.round(np.linalg.norm(region.points - region.centroid, axis=1), 6)
    i = int(np.lexsort((r[:, 2], r[:, 1], r[:, 0], dist))[0])
    p0, n0 = region.points[i], region.normals[i]
    dirs = fit.line_directions(p0, n0)
    if not np.all(np.isfinite(dirs)):
        return f"region {region.index}: no line of its surface at its centre"
    if fit.kind == "plane":  # the in-plane direction nearest prefer (else nearest vertical)
        pr = prefer - (prefer @ n0) * n0
        if np.linalg.norm(pr) < 0.2:
            pr = np.array([0.0, 0.0, 1.0]) - n0[2] * n0
        dirs = np.stack([pr, pr]) / np.linalg.norm(pr)
    # the family most nearly along prefer; of two alike (a hyperboloid about prefer), the
    # one turning positively about the normal, so that the choice does not hang on rounding
    score = [round(abs(d @ prefer), 3) + 1e-6 * np.sign(np.linalg.det(np.stack([n0, d, prefer]))
                                                        * (d @ prefer)) for d in dirs]  # fmt: skip
    d0 = dirs[int(np.argmax(score))]
    d0 = d0 if d0 @ prefer >= 0.0 else -d0
    what = f"region {region.index}: {'plane' if fit.kind == 'plane' else 'ruled quadric'}"
    try:
        loop = None if fit.kind == "plane" else _closed(fit, region, d0)
        if loop is not None:
            pts, axis = loop
            D = _rulings_along(fit, region, list(pts), d0)
            axis = D.mean(axis=0)  # again about the mean ruling
            loop = _closed(fit, region, axis / np.linalg.norm(axis))
            if loop is None:
                return f"{what}: its loop is lost about the mean ruling"
            pts = loop[0]
            D = _rulings_along(fit, region, list(pts), d0)
            outward = np.mean(np.einsum("ij,ij->i", region.normals, region.points - pts.mean(0)))
            if outward < 0.0:
                return f"{what}: a hole (the part outside the loop) cannot be cut by a wire"
            return CarveCut(name, "exact", Lines.from_point_direction(pts, D), True, "inside",
                            f"{what}, closed", region.index)  # fmt: skip
        found = _open(fit, region, stock, d0, p0, n0, lead)
        if found is None:
            return f"{what}: its surface ends inside the block (an open cut must span it)"
        pts, D = found
    except ValueError as exc:
        return f"{what}: {exc}"
    keep = keep_point(region, query, stock)
    if keep is None:
        return f"{what}: no point of the part found behind the face"
    return CarveCut(name, "exact", Lines.from_point_direction(pts, D), False, keep,
                    f"{what}, open", region.index)  # fmt: skip
