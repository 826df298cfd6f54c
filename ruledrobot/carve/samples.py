"""Parts made from closed forms: issue 32's proof parts, and a cell file for each.

Each builder returns ``(vertices (V, 3) m, faces (F, 3))`` in the part's own frame (origin
at the part's centre, which the cell puts at the demo block's centre), closed, faces turned
outwards.  :data:`PARTS` names them; :func:`write_part_cell` writes one as a binary STL in
millimetres beside a cell file of the demo cell (the 200 x 200 x 150 mm block in front of
a UR5e with the 0.4 m bow, 12 mm/s: :data:`ruledrobot.io.demo_cell.DEMO_CELL`), which
``ruledrobot carve`` and ``ruledrobot make`` read (``scripts/parts_table.py``, the tests).

* ``twisted_column``: a square column whose top square is turned by ``twist`` about its
  axis (z); each side the bilinear patch between a bottom and a top edge, a hyperbolic
  paraboloid; two flat caps;
* ``cooling_tower``: the hyperboloid of one sheet ``x^2 + y^2 = a^2 (1 + z^2 / c^2)``,
  ``|z| <= h``, capped;
* ``fairing``: a loft of ellipses whose semi-axes are quadratic in y (not ruled), capped;
* ``channel_block``: a block less a channel across its top whose floor is the saddle
  ``z = z0 + x y / c`` and less a round hole through it (manifold3d booleans);
* ``saddle_top``: a block whose top is the saddle ``z = z0 + x y / c`` (six faces);
* ``box12``, ``box192``: a box, each face an ``n`` x ``n`` grid of squares split in two.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..geometry.checks import FloatArray
from ..io.atomic import atomic_write_text
from ..io.demo_cell import DEMO_CELL
from ..io.mesh import write_stl

__all__ = ["PARTS", "box", "channel_block", "cooling_tower", "fairing", "grid_triangles",
           "saddle_top", "twisted_column", "weld", "write_part_cell"]

Mesh = tuple[FloatArray, FloatArray]


def weld(tris: FloatArray) -> Mesh:
    """A triangle soup (T, 3, 3) as shared vertices and faces, turned outwards.

    Faces are turned away from the origin (the part must be star-shaped about it);
    degenerate triangles are dropped."""
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    flip = np.einsum("ij,ij->i", n, tris.mean(axis=1)) < 0
    tris = np.where(flip[:, None, None], tris[:, ::-1], tris)
    v, inv = np.unique(np.round(tris.reshape(-1, 3), 10), axis=0, return_inverse=True)
    f = inv.reshape(-1, 3)
    good = (f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 0] != f[:, 2])
    return v, f[good]


def grid_triangles(P: FloatArray, closed_u: bool = False) -> FloatArray:
    """Triangles (T, 3, 3) of a grid of points ``P`` (nu, nv, 3), each quad split in two.

    ``closed_u``: the last row joins the first."""
    if closed_u:
        P = np.concatenate([P, P[:1]], axis=0)
    a, b, c, d = P[:-1, :-1], P[1:, :-1], P[1:, 1:], P[:-1, 1:]
    return np.concatenate([np.stack([a, b, c], -2).reshape(-1, 3, 3),
                           np.stack([a, c, d], -2).reshape(-1, 3, 3)])  # fmt: skip


def _caps(P: FloatArray) -> list[FloatArray]:
    """Fans from each end ring's centre of a closed grid ``P`` (nu, nv, 3)."""
    caps = []
    for k in (0, -1):
        ring = P[:, k]
        centre = np.broadcast_to(ring.mean(axis=0), ring.shape)
        caps.append(np.stack([centre, ring, np.roll(ring, -1, axis=0)], 1))
    return caps


def twisted_column(half: float = 0.05, height: float = 0.12, twist: float = 0.5,
                   n: int = 8) -> Mesh:  # fmt: skip
    """The twisted square column (module doc).

    Bottom square of half-width ``half`` at ``z = -height / 2``, the top one turned by
    ``twist`` [rad]; each side ``n`` x ``n``."""
    ang = np.pi / 4 + np.arange(4) * np.pi / 2
    r = half * np.sqrt(2.0)
    bot = np.stack([r * np.cos(ang), r * np.sin(ang), np.full(4, -height / 2)], 1)
    top = np.stack([r * np.cos(ang + twist), r * np.sin(ang + twist), np.full(4, height / 2)], 1)
    s = np.linspace(0.0, 1.0, n + 1)
    sides, rims = [], ([], [])
    for k in range(4):
        e0 = bot[k] + s[:, None] * (bot[(k + 1) % 4] - bot[k])
        e1 = top[k] + s[:, None] * (top[(k + 1) % 4] - top[k])
        sides.append(grid_triangles(e0[:, None] + s[None, :, None] * (e1 - e0)[:, None]))
        rims[0].append(e0[:-1])
        rims[1].append(e1[:-1])
    caps = [np.stack([np.broadcast_to(q.mean(axis=0), q.shape), q, np.roll(q, -1, axis=0)], 1)
            for q in (np.concatenate(rims[0]), np.concatenate(rims[1]))]  # fmt: skip
    return weld(np.concatenate([*sides, *caps]))


def cooling_tower(a: float = 0.05, c: float = 0.08, h: float = 0.06, nu: int = 64,
                  nz: int = 16) -> Mesh:  # fmt: skip
    """The capped hyperboloid ``x^2 + y^2 = a^2 (1 + z^2 / c^2)``, ``|z| <= h`` (axis z)."""
    u = np.linspace(0, 2 * np.pi, nu, endpoint=False)
    z = np.linspace(-h, h, nz)
    r = a * np.sqrt(1 + z**2 / c**2)
    P = np.stack([np.cos(u)[:, None] * r, np.sin(u)[:, None] * r,
                  np.broadcast_to(z, (nu, nz))], -1)  # fmt: skip
    return weld(np.concatenate([grid_triangles(P, closed_u=True), *_caps(P)]))


def fairing(half: float = 0.08, a0: float = 0.08, b0: float = 0.05, nu: int = 64,
            ny: int = 24) -> Mesh:  # fmt: skip
    """The lofted fairing (not ruled), capped.

    Ellipses ``x = a(y) cos u``, ``z = b(y) sin u`` for ``|y| <= half`` with
    ``a = a0 (1 - 0.4 t^2)``, ``b = b0 (1 - 0.5 t^2)``, ``t = y / half`` (no line lies
    on it)."""
    u = np.linspace(0, 2 * np.pi, nu, endpoint=False)
    y = np.linspace(-half, half, ny)
    t = y / half
    a, b = a0 * (1 - 0.4 * t**2), b0 * (1 - 0.5 * t**2)
    P = np.stack([np.cos(u)[:, None] * a, np.broadcast_to(y, (nu, ny)),
                  np.sin(u)[:, None] * b], -1)  # fmt: skip
    return weld(np.concatenate([grid_triangles(P, closed_u=True), *_caps(P)]))


def _saddle_solid(size, z0: float, c: float, n: int, up: bool) -> Mesh:
    """The box ``|x|, |y| <= size / 2`` between the saddle ``z = z0 + x y / c`` and the
    plane ``z = size_z / 2`` (``up``) or ``-size_z / 2``."""
    hx, hy, hz = 0.5 * np.asarray(size, dtype=float)
    X, Y = np.meshgrid(np.linspace(-hx, hx, n), np.linspace(-hy, hy, n), indexing="ij")
    sad = np.stack([X, Y, z0 + X * Y / c], -1)
    flat = np.stack([X, Y, np.full_like(X, hz if up else -hz)], -1)
    walls = [grid_triangles(np.stack([a, b], 1))
             for a, b in ((sad[0], flat[0]), (sad[-1], flat[-1]), (sad[:, 0], flat[:, 0]),
                          (sad[:, -1], flat[:, -1]))]  # fmt: skip
    tris = np.concatenate([grid_triangles(sad), grid_triangles(flat), *walls])
    centre = np.array([0.0, 0.0, 0.5 * (z0 + (hz if up else -hz))])
    v, f = weld(tris - centre)  # star-shaped about the middle of its height
    return v + centre, f


def saddle_top(size=(0.16, 0.16, 0.12), z0: float = 0.03, c: float = 0.4, n: int = 17) -> Mesh:
    """A block with a saddle top: six faces, none a face of the demo block.

    The block ``|x|, |y| <= size / 2`` from ``z = -size_z / 2`` up to the saddle
    ``z = z0 + x y / c``."""
    return _saddle_solid(size, z0, c, n, up=False)


def channel_block(size=(0.18, 0.18, 0.12), width: float = 0.08, z0: float = 0.02,
                  c: float = 0.4, hole: float = 0.03, n: int = 17) -> Mesh:  # fmt: skip
    """A block with a saddle channel and a round hole (manifold3d booleans).

    The block of ``size`` less a channel along x of ``width`` whose floor is the saddle
    ``z = z0 + x y / c``, less a hole of diameter ``hole`` along y through its lower half
    (manifold3d booleans)."""
    import manifold3d as m3d

    def solid(v, f):
        return m3d.Manifold(m3d.Mesh(vert_properties=np.asarray(v, np.float32),
                                     tri_verts=np.asarray(f, np.uint32)))  # fmt: skip

    hz = 0.5 * float(size[2])
    body = m3d.Manifold.cube(tuple(size), center=True)
    cut = solid(*_saddle_solid((size[0] + 0.02, width, size[2] + 0.02), z0, c, n, up=True))
    tube = m3d.Manifold.cylinder(size[1] + 0.02, hole / 2, hole / 2, 48, center=True)
    tube = tube.rotate((90.0, 0.0, 0.0)).translate((0.0, 0.0, -0.5 * hz))
    mesh = (body - cut - tube).to_mesh()
    return np.asarray(mesh.vert_properties[:, :3], float), np.asarray(mesh.tri_verts, np.int64)


def box(size=(0.12, 0.1, 0.08), n: int = 1) -> Mesh:
    """The box ``|x_k| <= size_k / 2`` of ``12 n^2`` triangles.

    Each face an ``n`` x ``n`` grid of squares split in two (n = 1: the 12 of a CAD
    export, n = 4: 192)."""
    h = 0.5 * np.asarray(size, dtype=float)
    faces = []
    for axis in range(3):
        u, v = [k for k in range(3) if k != axis]
        A, B = np.meshgrid(np.linspace(-h[u], h[u], n + 1), np.linspace(-h[v], h[v], n + 1),
                           indexing="ij")  # fmt: skip
        for sign in (-1.0, 1.0):
            P = np.zeros((*A.shape, 3))
            P[..., u], P[..., v], P[..., axis] = A, B, sign * h[axis]
            faces.append(grid_triangles(P))
    return weld(np.concatenate(faces))


#: issue 32's parts by name: what each is, and its builder
PARTS: dict[str, tuple[str, Callable[[], Mesh]]] = {
    "twisted_column": ("twisted column (4 hyperbolic paraboloids, 2 caps)", twisted_column),
    "cooling_tower": ("cooling tower (hyperboloid loop, 2 caps)", cooling_tower),
    "fairing": ("lofted fairing (not ruled)", fairing),
    "channel_block": ("block, saddle channel, 30 mm hole", channel_block),
    "saddle_top": ("block with a saddle top (6 faces)", saddle_top),
    "box12": ("box of 12 triangles", lambda: box(n=1)),
    "box192": ("box of 192 triangles", lambda: box(n=4)),
}


def write_part_cell(folder: str | Path, name: str, rough_cuts: int = 4,
                    extra: str = "") -> Path:  # fmt: skip
    """Write part ``name`` of :data:`PARTS` and its cell file into ``folder``; the cell file.

    ``NAME.stl`` in mm and ``cell.toml``: the demo cell, the part's centre at the block's.
    ``extra``: text appended to the cell (more tables or keys)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    what, build = PARTS[name]
    v, f = build()
    write_stl(folder / f"{name}.stl", v * 1e3, f, header=f"ruledrobot sample: {what}, mm")
    text = (f'# {what}, carved from the demo block\n\n[part]\nfile = "{name}.stl"\n'
            f'units = "mm"\npose = [0.5, 0.0, 0.3, 0.0, 0.0, 0.0]\ntolerance = 0.0005\n'
            f"rough_cuts = {rough_cuts}\n\n{DEMO_CELL}\n[cut]\nfeed_speed = 0.012\n"
            f"approach_speed = 0.6\n{extra}")  # fmt: skip
    return atomic_write_text(folder / "cell.toml", text)
