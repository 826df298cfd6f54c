"""The block after the cuts (``carved.stl``): the planner's part model, and the loops' planes.

The planner's signed distance of what a job keeps (:func:`ruledrobot.wirecut.part_sdf`:
the stock, and every cut's target surface sampled on its rulings with the sign of the
nearest sample's normal) is given the exact cuts' rulings directly, refined on the
manifold of lines (four-point scheme) to a spacing near the planner's.

A roughing loop (:mod:`.rough`) keeps the points on the inner side of all its planes,
and there its signed distance is ``max_i (n_i . x - h_i)``, exact in sign.  The
nearest-sample model misjudges such loops: their rulings go on past the strip of the
face they bound and cross the waste, and a point of the waste nearest such a fin takes
its side.  Measured on the 90 x 60 x 45 mm ellipsoid in a 200 x 200 x 150 mm block, one
seam loop (amplitude 0.5, two waves): the nearest-sample model keeps 1.75 L, the
planes 1.52 L, and the block left when the swept surface itself (the strips between
consecutive rulings, voxels of 1.5 mm) is flooded from the part 1.48 L (1.42 L against
1.48 L at amplitude 0.6, 1.15 L against 1.20 L at 0.9 with three waves; the flood loses
one voxel layer at the surface); the planes are what the wire leaves.  The zero level
of the largest of both is meshed by the planner's own :func:`ruledrobot.wirecut.stock_mesh`
(marching cubes on a grid of ``resolution``, values kept off zero at grid points, faces
turned outwards): a closed 2-manifold.
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

__all__ = ["SurfacePass", "carved_mesh", "ruling_frames"]

#: refinement steps of the rulings before meshing
STEPS = 2


@dataclass(frozen=True)
class SurfacePass:
    """What the part model reads of a pass: its ``name``, ``target_frames`` (M, 4, 4)
    (z along each ruling), ``closed``, ``extended`` (frames added at its ends: none)."""

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


def carved_mesh(cuts: tuple[CarveCut, ...], stock: Box, loops: tuple[Loop, ...] = (),
                resolution: float = 0.002) -> Mesh | None:  # fmt: skip
    """The block kept by the exact ``cuts`` and the roughing ``loops`` as a closed mesh
    [m, base frame] (module doc); None when nothing is kept."""
    from ..subdivision import subdivide
    from ..wirecut import part_sdf, stock_mesh

    passes = []
    for c in cuts:
        fine = subdivide(c.lines, scheme="four_point", steps=STEPS, closed=c.closed)
        passes.append(SurfacePass(c.name, ruling_frames(fine, stock.centre), c.closed))
    job = _Job(tuple(_Cut(c.name, c.keep) for c in cuts), stock)

    def sdf(world: FloatArray, shape: tuple[int, ...], h: float) -> FloatArray:
        f = part_sdf(job, tuple(passes), world, shape, 3.0 * h)  # type: ignore[arg-type]
        for loop in loops:
            f = np.maximum(f, (world @ loop.normals.T - loop.support).max(axis=1).reshape(shape))
        return f

    return stock_mesh(stock, resolution, sdf)
