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
kept surface is to the target is measured on the wire's path (:mod:`..cut.kerf`), not on
this mesh.

A ruling runs on past the strip of the surface it bounds where it crosses the waste (a
roughing loop's rulings, each the line where two supporting planes meet, cross the
waste beyond the strip: fins), and a waste point nearest such a fin takes the fin's
side.  So the sign near the surface is checked against the surface's own partition of
the stock (:func:`_settle_sides`): the grid points within half a grid step of the
surface (by the samples' tangent planes) wall the stock into pieces that no path of
grid neighbours crosses the surface between, each piece takes the side most of its
points take, and a point of the wall on the part's side counts only within a few grid
steps of a piece of the part (a fin's wall lies in the waste).  Where the nearest
sample is right everywhere — a surface that bounds its sides everywhere in the stock,
as every cut of the demos — nothing changes.

Cuts without ``keep`` name no part side and are left out (a note says so).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ...geometry.box import Box
from ...geometry.checks import FloatArray
from ...geometry.mesh import Mesh, signed_volume
from ..cut.cutpath import CutPath
from ..cut.kerf import ruling_normals, waste_sign
from ..cut.wire_geometry import chords
from ..job.spec import Job

__all__ = ["RESOLUTION", "GridSDF", "part_mesh", "part_sdf", "signed_volume", "stock_mesh"]

#: grid step of the part mesh [m] and spacing of the surface samples along a ruling
RESOLUTION = 0.002
SAMPLE = 0.001
#: most grid points (about 40 MB of distances): the step grows for large blocks
MAX_POINTS = 5_000_000
#: distances nearer zero than this fraction of the grid step are moved out to it
SNAP = 0.005


def _surface_samples(
    passes: list[CutPath], stock: Box, keep
) -> tuple[FloatArray, FloatArray]:
    """Points (P, 3) of a cut's target surface inside the stock (grown by 2 mm), over all
    its ``passes``, and their normals (P, 3) pointing into the waste (a closed cut's
    slits, in the waste, are not its surface).

    A loop cut in two passes (:mod:`..cut.closed`) is two arcs, each cut out to the meeting
    ruling and back along its own kerf: only the way out is sampled (sampled both ways,
    every point of the arc had two samples of opposite normals, and the nearest of them
    gave the distance its sign at random: hundreds of specks of part in the waste and of
    waste in the part).  The normals are taken on each arc's whole sequence of rulings
    before those missing the block are left out (a difference across the gap between
    two stretches in the block, as where a column as wide as the block crosses only its
    corners, turns them anywhere), periodic only for a loop cut in one pass.  Which way
    is the waste, for ``"inside"``/``"outside"``: from the centroid of the chord
    midpoints of the whole cut (an arc's own centroid can lie near the arc)."""
    whole = len(passes) == 1
    arcs = []
    grown = stock.grown(0.002)
    for cp in passes:
        S = cp.target_frames
        if cp.closed:
            a, b = cp.extended
            S = S[a : len(S) - b]
            if not whole and np.allclose(S, S[::-1], rtol=0.0, atol=1e-12):
                S = S[: len(S) // 2 + 1]  # out and back along its own kerf: the way out
        c0, c1, hit = chords(S, grown)
        if not hit.any():
            continue
        c0, c1 = np.where(hit, c0, 0.0), np.where(hit, c1, 0.0)
        n = max(2, int(np.ceil(float(np.max(c1 - c0)) / SAMPLE)) + 1)
        t = c0[:, None] + (c1 - c0)[:, None] * np.linspace(0.0, 1.0, n)[None, :]
        normals = ruling_normals(S, t, cp.closed and whole)
        pts = S[:, None, :3, 3] + t[..., None] * S[:, None, :3, 2]
        arcs.append((S, cp.closed and whole, pts[hit], normals[hit]))
    if not arcs:
        return np.zeros((0, 3)), np.zeros((0, 3))
    if isinstance(keep, str):  # the centroid of every arc's chord midpoints
        centre = np.concatenate([p[:, p.shape[1] // 2] for _, _, p, _ in arcs]).mean(axis=0)
    out_p, out_n = [], []
    for S, closed, pts, normals in arcs:
        if isinstance(keep, str):
            k = pts.shape[1] // 2
            inward = np.einsum("mi,mi->m", centre - pts[:, k], normals[:, k])
            part_along_normal = (float(np.mean(inward)) > 0.0) == (keep == "inside")
            sign = -1.0 if part_along_normal else 1.0
        else:
            sign = waste_sign(S, stock, keep, closed)
        out_p.append(pts.reshape(-1, 3))
        out_n.append(sign * normals.reshape(-1, 3))
    return np.concatenate(out_p), np.concatenate(out_n)


def _cut_sdf(pts: FloatArray, nrm: FloatArray, world: FloatArray, shape: tuple[int, ...],
             band: float, domain: np.ndarray | None = None, step: float | None = None
             ) -> FloatArray:  # fmt: skip
    """Signed distance on a grid (``world`` (N, 3), ``shape`` the grid's) to one surface
    sampled by ``pts`` (P, 3) with waste-side normals ``nrm``, exact within ``band`` of it
    and ``+-band`` beyond: a nearest-neighbour search far from a thin sampled surface
    visits nearly every sample (a point on a column's axis is as far from all of them),
    so far cells take the sign of their connected region instead.  With ``domain`` (the
    grid points in the stock) and ``step`` (the grid's), the sides are settled by the
    surface's partition of the stock (:func:`_settle_sides`)."""
    from scipy import ndimage
    from scipy.spatial import cKDTree

    near = np.zeros(len(world), dtype=bool)
    k = np.zeros(len(world), dtype=np.intp)
    ask = np.flatnonzero(_within_reach(pts, world, shape, band))
    dist, k[ask] = cKDTree(pts).query(world[ask], distance_upper_bound=band, workers=-1)
    near[ask] = np.isfinite(dist)
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
    if domain is not None and step is not None:
        out = _settle_sides(out, np.where(far, np.inf, np.abs(d)), domain, step)
    return out


def _within_reach(pts: FloatArray, world: FloatArray, shape: tuple[int, ...], band: float
                  ) -> np.ndarray:  # fmt: skip
    """Which grid points (N,) may lie within ``band`` of a sample of ``pts`` (P, 3): the
    grid cells holding a sample (clipped to the grid), grown by ``band`` in steps and one
    more.  Only these are asked of the k-d tree: the others are farther than ``band``
    from every sample and would come back without a neighbour, so the answer is the
    same in a fraction of the time.  Every point when ``world`` is not one regular grid
    of ``shape`` with square corners."""
    from scipy import ndimage

    every = np.ones(len(world), dtype=bool)
    if len(shape) != 3 or min(shape) < 2 or len(pts) == 0:
        return every
    g = world.reshape(*shape, 3)
    origin = g[0, 0, 0]
    axes = np.stack([g[1, 0, 0], g[0, 1, 0], g[0, 0, 1]]) - origin  # (3, 3): a step each
    steps = np.linalg.norm(axes, axis=1)
    unit = axes / np.maximum(steps, 1e-300)[:, None]
    if steps.min() <= 0.0 or np.abs(unit @ unit.T - np.eye(3)).max() > 1e-9:
        return every
    top = np.array(shape) - 1
    cell = np.clip(np.floor((pts - origin) @ (unit.T / steps)), 0, top).astype(np.intp)
    seeds = np.zeros(shape, dtype=np.uint8)
    seeds[cell[:, 0], cell[:, 1], cell[:, 2]] = 1
    grow = int(np.ceil(band / steps.min())) + 1
    return ndimage.maximum_filter(seeds, size=2 * grow + 1, mode="constant").ravel() > 0


#: a grid point is in the surface's wall within this fraction of the grid step of it
WALL = 0.75
#: a wall point on the part's side counts as part within this many grid steps of a piece
#: of the part
WALL_REACH = 2
#: a piece takes a side when the signs of its points near the surface add up to this
#: fraction of their number (70:30); a piece split more evenly is left as it is (a wall
#: with a gap, where rulings miss the stock: the pieces are not the surface's sides)
DECISIVE = 0.4


def _settle_sides(f: FloatArray, plane: FloatArray, domain: np.ndarray, step: float
                  ) -> FloatArray:  # fmt: skip
    """The signed distance ``f`` (grid) with its sides settled by the surface's partition
    of the stock (module doc): ``plane`` the distance to the nearest sample's tangent
    plane (inf far from the surface), ``domain`` the grid points in the stock, ``step``
    the grid step.  A segment between grid neighbours that crosses the surface has an
    end within half a step of it, so the wall (points within ``WALL`` steps) leaves no
    path between the pieces; a piece takes the side of the most of its points near the
    surface when they agree enough (``DECISIVE``), and a point of the wall on the part's
    side stays part only within ``WALL_REACH`` steps of a piece of the part (where no
    piece is part, nothing changes: a part thinner than the wall)."""
    from scipy import ndimage

    wall = plane <= WALL * step
    pieces, count = ndimage.label(domain & ~wall)
    if count == 0:
        return f
    near = np.isfinite(plane) & (pieces > 0)
    votes = np.bincount(pieces[near], weights=np.sign(f[near]), minlength=count + 1)
    voters = np.bincount(pieces[near], minlength=count + 1)
    side = np.where(np.abs(votes) >= DECISIVE * np.maximum(voters, 1), np.sign(votes), 0.0)
    side[0] = 0.0
    piece_side = side[pieces]
    out = np.where((piece_side != 0.0) & (np.sign(f) != piece_side), piece_side * np.abs(f), f)
    part = piece_side < 0.0
    if part.any():
        kept = ndimage.binary_dilation(part, iterations=WALL_REACH)
        fin = wall & domain & (out < 0.0) & ~kept
        out = np.where(fin, -out, out)
    return out


def part_sdf(job: Job, passes: tuple[CutPath, ...], world: FloatArray,
             shape: tuple[int, ...], band: float) -> FloatArray:  # fmt: skip
    """Return the signed distance [m] to the part on a grid of world points.

    Points ``world`` (N, 3) with ``shape`` (module doc): negative inside, the distance
    within ``band`` of a cut.
    """
    stock = job.stock
    out = stock.signed_distance(world).reshape(shape)
    domain = out <= 0.0
    step = _grid_step(world, shape)
    for cut in job.cuts:
        if cut.keep is None:
            continue
        pts, nrm = _surface_samples([cp for cp in passes if cp.name == cut.name], stock, cut.keep)
        if len(pts):
            out = np.maximum(out, _cut_sdf(pts, nrm, world, shape, band, domain, step))
    return out


def _grid_step(world: FloatArray, shape: tuple[int, ...]) -> float | None:
    """The step of a regular grid of points ``world`` with ``shape`` (the distance between
    neighbours along each axis, the largest), or None when not one grid."""
    if len(shape) != 3 or min(shape) < 2:
        return None
    g = world.reshape(*shape, 3)
    steps = [float(np.linalg.norm(np.take(g, 1, axis=k)[0, 0] - np.take(g, 0, axis=k)[0, 0]))
             for k in range(3)]  # fmt: skip
    return max(steps)


def part_mesh(
    job: Job, passes: tuple[CutPath, ...], resolution: float = RESOLUTION
) -> Mesh | None:
    """The part's closed triangle mesh in the base frame [m] (module doc).

    None when no cut names its kept side or nothing of the stock is kept."""
    if all(c.keep is None for c in job.cuts):
        return None
    return stock_mesh(job.stock, resolution,
                      lambda world, shape, h: part_sdf(job, passes, world, shape, 3.0 * h))


#: a signed distance on a grid: ``sdf(world (N, 3) [m], shape, step [m]) -> (shape)``
GridSDF = Callable[[FloatArray, tuple[int, ...], float], FloatArray]


def stock_mesh(stock: Box, resolution: float, sdf: GridSDF) -> Mesh | None:
    """Return the zero level of ``sdf`` (negative inside) as a closed triangle mesh, or None.

    In the base frame [m], marched on a grid over ``stock`` and 2 steps beyond it; None when
    ``sdf`` is nowhere negative.

    The grid step is ``resolution`` [m], grown so that the grid holds at most
    ``MAX_POINTS``; the distances are kept off zero at grid points
    (:func:`_off_grid_points`), marched by scikit-image's marching cubes (Lewiner) and
    the faces turned to wind counter-clockwise seen from outside.  The planner's part
    (:func:`part_mesh`) and the carved block (:mod:`ruledrobot.carve.carved`) are both
    this mesh of their own distance."""
    from skimage.measure import marching_cubes

    h = max(resolution, float(np.prod(stock.size + 4 * resolution) / MAX_POINTS) ** (1 / 3))
    counts = np.ceil((stock.size + 4.0 * h) / h).astype(int) + 1
    axes = [(np.arange(c) - (c - 1) / 2.0) * h for c in counts]
    R = stock.rotation  # world = centre + x R[:, 0] + y R[:, 1] + z R[:, 2], by broadcasting
    world = np.empty((*counts, 3))
    world[...] = stock.centre
    world += axes[0][:, None, None, None] * R[:, 0]
    world += axes[1][None, :, None, None] * R[:, 1]
    world += axes[2][None, None, :, None] * R[:, 2]
    world = world.reshape(-1, 3)
    f = _off_grid_points(sdf(world, tuple(counts), h), h)
    if f.min() >= 0.0:
        return None
    verts, faces, _, _ = marching_cubes(f, level=0.0, spacing=(h, h, h))
    verts = verts + np.array([a[0] for a in axes])
    faces = faces.astype(np.int64)
    if signed_volume(verts, faces) < 0.0:  # outward normals (counter-clockwise seen outside)
        faces = faces[:, ::-1]
    return Mesh(verts @ stock.rotation.T + stock.centre, faces)


def _off_grid_points(f: FloatArray, h: float) -> FloatArray:
    """The distances ``f`` with none nearer zero than ``SNAP * h``: the surface passes no
    grid point.  Marching cubes puts a vertex of every sign-changing edge at a grid point
    that holds 0 (or nearly: a stock face on a grid plane, a cut through a grid point), so
    that several vertices of different index coincide: zero-area triangles, and in an STL
    (which welds equal coordinates, in float32) edges shared by 4 to 16 faces.  Moved off
    by ``SNAP * h`` (10 um at the 2 mm step; the surface moves no farther), every vertex
    lies at least that far from a grid point and the mesh is a closed 2-manifold after
    the float32 rounding of STL too."""
    eps = SNAP * h
    return np.where(np.abs(f) < eps, np.where(f < 0.0, -eps, eps), f)
