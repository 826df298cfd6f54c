"""The block after the cuts (``carved.stl``): booleans of the cuts' own solids.

The block is intersected, with manifold3d (the library trimesh uses for booleans), with
the kept side of every cut (:mod:`.solid`): a half-space for a planar cut and for each
of a roughing loop's supporting planes (a loop keeps the points on the inner side of all
of them, ``n_i . x <= h_i``: what the wire leaves, :mod:`.rough`), the tube of a closed
loop's rulings, and for an open cut the slab between its strip of rulings and a plane
beyond the block on the kept side.  The rulings are refined on the manifold of lines
(four-point scheme) and the strips divided so that the triangles lie within
:data:`.solid.EPS` (5 um) of the ruled surface, so the carved block's faces are the
cuts' surfaces and its edges their exact intersections: a box comes out as a box,
corners and all.

A cut whose surface cannot be closed into a valid solid (:class:`.solid.NotASolid`:
a loop whose sections are not star-shaped, an open strip that folds over seen along
its mean normal or does not cover the block's shadow) is meshed on the grid instead,
that cut alone, and intersected like the others; :class:`Carved` names such cuts
(``carve.json``'s ``carved``, and a note).  Without manifold3d, or when its result is
not a valid solid, the whole block is meshed on the grid (:func:`grid_carved_mesh`).

**The grid** (the fallback, and the carved block before issue 32): the planner's signed
distance of what a job keeps (:func:`ruledrobot.wirecut.part_sdf`: the stock, and every
cut's target surface sampled on its rulings with the sign of the nearest sample's
normal), given the exact cuts' rulings refined by the four-point scheme, and for each
roughing loop ``max_i (n_i . x - h_i)``, exact in sign; the zero level of the largest
meshed by the planner's :func:`ruledrobot.wirecut.stock_mesh` (marching cubes on a grid
of ``resolution``, values kept off zero at grid points, faces turned outwards): a
closed 2-manifold whose sharp edges are rounded to the grid (up to 1.7 mm inside the
part at 2 mm).  The nearest-sample model misjudges roughing loops on its own (their
rulings go on past the strip of the face they bound and cross the waste): hence the
planes for those.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..geometry.box import Box
from ..geometry.checks import FloatArray
from ..geometry.lines import Lines
from ..geometry.mesh import Mesh
from .model import CarveCut
from .rough import Loop
from .solid import NotASolid, convex_cell, kept_solid, to_manifold

__all__ = ["Carved", "SurfacePass", "carve_block", "carved_mesh", "grid_carved_mesh",
           "ruling_frames"]

#: refinement steps of the rulings before meshing on the grid
STEPS = 2
#: the carved mesh's own tolerance [m]: manifold3d collapses edges shorter than this (the
#: booleans leave a few of 1e-10 m where several surfaces meet, which the float32
#: coordinates of an STL weld into one vertex: a mesh no longer closed when read back)
TOLERANCE = 1e-6
#: how far [grid steps] a cut meshed on the grid alone reaches past the block (its own
#: block faces lie outside the block, which the intersection then cuts clean)
GRID_REACH = 4


@dataclass(frozen=True)
class SurfacePass:
    """What the part model reads of a pass.

    Its ``name``, ``target_frames`` (M, 4, 4) (z along each ruling), ``closed``, ``extended``
    (frames added at its ends: none)."""

    name: str
    target_frames: FloatArray = field(repr=False)
    closed: bool
    extended: tuple[int, int] = (0, 0)


@dataclass(frozen=True)
class _Cut:
    name: str
    keep: object


@dataclass(frozen=True)
class _Job:
    cuts: tuple[_Cut, ...]
    stock: Box


def ruling_frames(lines: Lines, centre: FloatArray) -> FloatArray:
    """Frames (N, 4, 4): z along each ruling, origin its point nearest ``centre``."""
    d = lines.direction
    p = lines.point
    o = p + ((centre - p) * d).sum(axis=1)[:, None] * d
    x = np.cross(d, np.where(np.abs(d[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]]))
    x /= np.linalg.norm(x, axis=1)[:, None]
    T = np.zeros((len(d), 4, 4))
    T[:, :3, 0], T[:, :3, 1], T[:, :3, 2], T[:, :3, 3] = x, np.cross(d, x), d, o
    T[:, 3, 3] = 1.0
    return T


@dataclass(frozen=True)
class Carved:
    """The carved block.

    ``mesh`` (closed, outward, base frame, m; None when nothing is kept), ``method``
    ``"boolean"`` (every cut a solid), ``"boolean+grid"`` (the cuts in ``grid`` meshed on the
    grid, each with why its surface is no solid) or ``"grid"`` (the whole block on the grid:
    ``why``), ``solid_triangles`` the cuts' solids' triangles, ``planes`` the half-spaces
    intersected, ``resolution`` the grid's step [m]."""

    mesh: Mesh | None
    method: str
    grid: dict[str, str] = field(default_factory=dict)
    why: str = ""
    solid_triangles: int = 0
    planes: int = 0
    resolution: float = 0.002

    def as_dict(self) -> dict[str, object]:
        """Return the carve's fields for ``carve.json``.

        ``method``, ``grid_cuts`` (cut name -> why on the grid), ``why`` (the whole on the
        grid), ``triangles`` of the mesh, ``solid_triangles``, ``planes``."""
        return {"method": self.method, "grid_cuts": dict(self.grid), "why": self.why or None,
                "triangles": 0 if self.mesh is None else len(self.mesh.faces),
                "solid_triangles": self.solid_triangles, "planes": self.planes}  # fmt: skip

    def note(self) -> str | None:
        """A note in words when any of the block was meshed on the grid, else None."""
        step = f"{self.resolution * 1e3:g} mm grid"
        if self.method == "grid":
            return (f"carved.stl meshed on the {step} ({self.why}): its sharp edges are "
                    "rounded to the grid")  # fmt: skip
        if self.grid:
            cuts = "; ".join(f"{k}: {v}" for k, v in self.grid.items())
            return (f"carved.stl: {len(self.grid)} cut(s) meshed on the {step}, their "
                    f"surfaces not closed into solids ({cuts})")  # fmt: skip
        return None


def carve_block(cuts: tuple[CarveCut, ...], stock: Box, loops: tuple[Loop, ...] = (),
                resolution: float = 0.002) -> Carved:  # fmt: skip
    """The block kept by the exact ``cuts`` and the roughing ``loops`` (module doc).

    Parameters
    ----------
    cuts : the exact cuts (rulings in the base frame, m; their ``keep`` sides)
    stock : the block
    loops : the roughing loops (their planes ``n_i . x <= h_i``, base frame, m)
    resolution : grid step [m] of what is meshed on the grid

    Returns
    -------
    Carved
        The mesh (base frame, m) and how it was made.
    """
    try:
        import manifold3d as m3d
    except ImportError:
        return Carved(grid_carved_mesh(cuts, stock, loops, resolution), "grid",
                      why="manifold3d is not installed: pip install 'ruledrobot[carve]'",
                      resolution=resolution)  # fmt: skip
    R, c = stock.rotation, stock.centre
    half = 0.5 * stock.size
    planes: list[tuple[FloatArray, float]] = []
    for loop in loops:  # keeps n . x <= h: manifold3d keeps -n . x >= -h
        n_local = loop.normals @ R
        h_local = loop.support - loop.normals @ c
        planes += [(-n, -float(h)) for n, h in zip(n_local, h_local, strict=True)]
    keep_in, take_out, grid = [], [], {}
    triangles = 0
    for cut in cuts:
        p, d = (cut.lines.point - c) @ R, cut.lines.direction @ R
        keep = cut.keep if isinstance(cut.keep, str) else (np.asarray(cut.keep) - c) @ R
        try:
            s = kept_solid(p, d, cut.closed, keep, half)
            if s.kind == "plane":
                planes.append((s.normal, s.offset))
                continue
            solid = to_manifold(s.vertices, s.faces)
            triangles += s.triangles
            (take_out if s.subtract else keep_in).append(solid)
        except (ValueError, np.linalg.LinAlgError) as exc:  # NotASolid among them
            grid[cut.name] = str(exc)
            try:
                keep_in.append(_grid_kept(cut, stock, resolution))
            except NotASolid as why:
                return Carved(grid_carved_mesh(cuts, stock, loops, resolution), "grid",
                              grid, f"{cut.name} on the grid alone: {why}",
                              resolution=resolution)  # fmt: skip
    if planes:
        block = convex_cell(np.array([n for n, _ in planes]), np.array([o for _, o in planes]),
                            half)  # fmt: skip
    else:
        block = m3d.Manifold.cube(tuple(float(x) for x in stock.size), True)
    if keep_in:
        block = m3d.Manifold.batch_boolean([block, *keep_in], m3d.OpType.Intersect)
    if take_out:
        block = m3d.Manifold.batch_boolean([block, *take_out], m3d.OpType.Subtract)
    method = "boolean+grid" if grid else "boolean"
    if block.status() != m3d.Error.NoError:
        return Carved(grid_carved_mesh(cuts, stock, loops, resolution), "grid", grid,
                      f"manifold3d failed: {block.status().name}",
                      resolution=resolution)  # fmt: skip
    if block.is_empty():
        return Carved(None, method, grid, "", triangles, len(planes), resolution)
    out = block.set_tolerance(TOLERANCE).to_mesh64()
    v = np.asarray(out.vert_properties, dtype=np.float64)[:, :3]
    f = np.asarray(out.tri_verts, dtype=np.int64)
    return Carved(Mesh(v @ R.T + c, f), method, grid, "", triangles, len(planes), resolution)


def _grid_kept(cut: CarveCut, stock: Box, resolution: float):
    """The kept side of one cut in the block (a ``manifold3d.Manifold``, block frame)
    meshed on the grid: the planner's model of that cut alone over the block grown by
    :data:`GRID_REACH` steps (so that its own block faces lie outside the block)."""
    import manifold3d as m3d

    from ..subdivision import subdivide
    from ..wirecut import part_sdf, stock_mesh

    grown = stock.grown(GRID_REACH * resolution)
    fine = subdivide(cut.lines, scheme="four_point", steps=STEPS, closed=cut.closed)
    passes = (SurfacePass(cut.name, ruling_frames(fine, stock.centre), cut.closed),)
    job = _Job((_Cut(cut.name, cut.keep),), grown)
    mesh = stock_mesh(grown, resolution, lambda world, shape, h: part_sdf(
        job, passes, world, shape, 3.0 * h))  # type: ignore[arg-type]  # fmt: skip
    if mesh is None:
        return m3d.Manifold()
    return to_manifold((mesh.vertices - stock.centre) @ stock.rotation, mesh.faces)


def carved_mesh(cuts: tuple[CarveCut, ...], stock: Box, loops: tuple[Loop, ...] = (),
                resolution: float = 0.002) -> Mesh | None:  # fmt: skip
    """Return the block kept by the exact cuts and the roughing loops as a closed mesh.

    The block kept by the exact ``cuts`` and the roughing ``loops`` [m, base frame]
    (:func:`carve_block`'s mesh); None when nothing is kept."""
    return carve_block(cuts, stock, loops, resolution).mesh


def grid_carved_mesh(cuts: tuple[CarveCut, ...], stock: Box, loops: tuple[Loop, ...] = (),
                     resolution: float = 0.002) -> Mesh | None:  # fmt: skip
    """Return the block kept by the exact cuts and the roughing loops, meshed on a grid.

    The block kept by the exact ``cuts`` and the roughing ``loops`` meshed on the grid of
    ``resolution`` [m] (module doc, "The grid") [m, base frame]; None when nothing is kept."""
    from ..wirecut import part_sdf, stock_mesh

    job, passes = _model(cuts, stock)

    def sdf(world: FloatArray, shape: tuple[int, ...], h: float) -> FloatArray:
        f = part_sdf(job, passes, world, shape, 3.0 * h)  # type: ignore[arg-type]
        for loop in loops:
            f = np.maximum(f, (world @ loop.normals.T - loop.support).max(axis=1).reshape(shape))
        return f

    return stock_mesh(stock, resolution, sdf)


def _model(cuts: tuple[CarveCut, ...], stock: Box) -> tuple[_Job, tuple[SurfacePass, ...]]:
    """The cuts as the planner's part model reads them (refined rulings, keep sides)."""
    from ..subdivision import subdivide

    passes = []
    for c in cuts:
        fine = subdivide(c.lines, scheme="four_point", steps=STEPS, closed=c.closed)
        passes.append(SurfacePass(c.name, ruling_frames(fine, stock.centre), c.closed))
    return _Job(tuple(_Cut(c.name, c.keep) for c in cuts), stock), tuple(passes)


def cut_away(cuts: tuple[CarveCut, ...], stock: Box, world: FloatArray,
             shape: tuple[int, int, int]) -> np.ndarray:  # fmt: skip
    """Which points of a grid the exact cuts take away (what no roughing loop need take).

    ``world`` (N, 3) [m, base frame]: a regular grid of ``shape``; returns (N,) bool, the
    planner's part model (``part_sdf``) of ``cuts`` positive there."""
    from ..wirecut import part_sdf

    if not cuts:
        return np.zeros(len(world), bool)
    job, passes = _model(cuts, stock)
    step = max(float(np.linalg.norm(world[1] - world[0])), 1e-6)
    f = part_sdf(job, passes, world, shape, 3.0 * step)  # type: ignore[arg-type]
    return np.asarray(f).reshape(-1) > 0.0
