"""The part a job leaves: the stock on the kept side of every cut, as a closed mesh.

The part is the set where a signed distance is negative: the largest of the stock
box's own signed distance and, for every cut that names its kept side, the distance
to the cut's *target* surface (positive on the waste side).  The distance to a ruled
surface is taken at its nearest sample (its rulings, sampled every ``SAMPLE`` metres
over their chords in the stock) along that sample's waste-side normal: exact to
second order near the surface, and of the right sign elsewhere in the stock.  The
zero level is meshed by marching cubes (scikit-image, Lewiner) on a grid of
``resolution`` over the stock — a mesh to look at and send to CAD (``part.stl``);
its faces lie within a fraction of the grid step of the surfaces.  How close the
kept surface is to the target is measured on the wire's path (:mod:`.kerf`), not on
this mesh.

Cuts without ``keep`` name no part side and are left out (a note says so).
"""

from __future__ import annotations

import numpy as np

from ..geometry.box import Box
from ..geometry.checks import FloatArray
from ..geometry.mesh import Mesh
from .cutpath import CutPath
from .kerf import ruling_normals, waste_sign
from .spec import Job
from .toolpath import chords

__all__ = ["RESOLUTION", "part_mesh", "part_sdf", "signed_volume"]

#: grid step of the part mesh [m] and spacing of the surface samples along a ruling
RESOLUTION = 0.002
SAMPLE = 0.001
#: most grid points (about 40 MB of distances): the step grows for large blocks
MAX_POINTS = 5_000_000


def _surface_samples(cp: CutPath, stock: Box, keep) -> tuple[FloatArray, FloatArray]:
    """Points (P, 3) of the pass's target surface inside the stock (grown by 2 mm) and
    their normals (P, 3) pointing into the waste (a closed cut's slits, in the waste,
    are not its surface)."""
    S = cp.target_frames
    if cp.closed:
        a, b = cp.extended
        S = S[a : len(S) - b]
    grown = Box(stock.centre, stock.size + 0.004, stock.rotation)
    c0, c1, hit = chords(S, grown)
    if not hit.any():
        return np.zeros((0, 3)), np.zeros((0, 3))
    S, c0, c1 = S[hit], c0[hit], c1[hit]
    n = max(2, int(np.ceil(float(np.max(c1 - c0)) / SAMPLE)) + 1)
    u = np.linspace(0.0, 1.0, n)
    t = c0[:, None] + (c1 - c0)[:, None] * u[None, :]
    normals = waste_sign(S, stock, keep, cp.closed) * ruling_normals(S, t, cp.closed)
    pts = S[:, None, :3, 3] + t[..., None] * S[:, None, :3, 2]
    return pts.reshape(-1, 3), normals.reshape(-1, 3)


def _cut_sdf(pts: FloatArray, nrm: FloatArray, world: FloatArray, shape: tuple[int, ...],
             band: float) -> FloatArray:  # fmt: skip
    """Signed distance on a grid (``world`` (N, 3), ``shape`` the grid's) to one surface
    sampled by ``pts`` (P, 3) with waste-side normals ``nrm``, exact within ``band`` of it
    and ``+-band`` beyond: a nearest-neighbour search far from a thin sampled surface
    visits nearly every sample (a point on a column's axis is as far from all of them),
    so far cells take the sign of their connected region instead."""
    from scipy import ndimage
    from scipy.spatial import cKDTree

    dist, k = cKDTree(pts).query(world, distance_upper_bound=band)
    near = np.isfinite(dist)
    d = np.full(len(world), np.nan)
    kn = k[near]
    d[near] = np.einsum("ij,ij->i", world[near] - pts[kn], nrm[kn])
    d = d.reshape(shape)
    far = ~near.reshape(shape)
    labels, count = ndimage.label(far)
    out = np.where(far, 0.0, d)
    for lab in range(1, count + 1):
        region = labels == lab
        rim = ndimage.binary_dilation(region) & ~far
        side = float(np.sign(np.nansum(np.sign(d[rim])))) if rim.any() else 1.0
        out[region] = band * (side if side != 0.0 else 1.0)
    return out


def part_sdf(job: Job, passes: tuple[CutPath, ...], world: FloatArray,
             shape: tuple[int, ...], band: float) -> FloatArray:  # fmt: skip
    """Signed distance [m] to the part on a grid of world points ``world`` (N, 3) with
    ``shape`` (module doc): negative inside, the distance within ``band`` of a cut."""
    stock = job.stock
    local = stock.to_box(world)
    q = np.abs(local) - 0.5 * stock.size
    out = np.linalg.norm(np.maximum(q, 0.0), axis=1) + np.minimum(q.max(axis=1), 0.0)
    out = out.reshape(shape)
    for cut in job.cuts:
        if cut.keep is None:
            continue
        samples = [_surface_samples(cp, stock, cut.keep) for cp in passes if cp.name == cut.name]
        pts = np.concatenate([s[0] for s in samples])
        nrm = np.concatenate([s[1] for s in samples])
        if len(pts):
            out = np.maximum(out, _cut_sdf(pts, nrm, world, shape, band))
    return out


def part_mesh(
    job: Job, passes: tuple[CutPath, ...], resolution: float = RESOLUTION
) -> Mesh | None:
    """The part's closed triangle mesh in the base frame [m] (module doc); None when no
    cut names its kept side or nothing of the stock is kept."""
    if all(c.keep is None for c in job.cuts):
        return None
    from skimage.measure import marching_cubes

    stock = job.stock
    h = max(resolution, float(np.prod(stock.size + 4 * resolution) / MAX_POINTS) ** (1 / 3))
    counts = np.ceil((stock.size + 4.0 * h) / h).astype(int) + 1
    axes = [(np.arange(c) - (c - 1) / 2.0) * h for c in counts]
    X, Y, Z = np.meshgrid(*axes, indexing="ij")
    local = np.stack([X, Y, Z], axis=-1).reshape(-1, 3)
    world = local @ stock.rotation.T + stock.centre
    f = part_sdf(job, passes, world, tuple(counts), 3.0 * h)
    if f.min() >= 0.0:
        return None
    verts, faces, _, _ = marching_cubes(f, level=0.0, spacing=(h, h, h))
    verts = verts + np.array([a[0] for a in axes])
    faces = faces.astype(np.int64)
    if signed_volume(verts, faces) < 0.0:  # outward normals (counter-clockwise seen outside)
        faces = faces[:, ::-1]
    return Mesh(verts @ stock.rotation.T + stock.centre, faces)


def signed_volume(vertices: FloatArray, faces: np.ndarray) -> float:
    """Volume [m^3] enclosed by a closed triangle mesh, positive when its faces turn
    counter-clockwise seen from outside (the divergence theorem over the faces)."""
    a, b, c = vertices[faces[:, 0]], vertices[faces[:, 1]], vertices[faces[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)
