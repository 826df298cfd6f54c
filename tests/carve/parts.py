"""Parts made from closed forms (the meshes of :mod:`ruledrobot.carve.samples`, or made here).

Each returns ``(vertices (V, 3), faces (F, 3))`` in metres in the part's own frame,
closed, faces turned outwards (every part here is star-shaped about its origin), and
the closed form to check cuts against (a function of points giving the first-order
distance to the ruled surface in metres, in the same frame).
"""

from __future__ import annotations

import numpy as np

from ruledrobot.carve import samples
from ruledrobot.carve.samples import grid_triangles as _grid
from ruledrobot.carve.samples import weld as _weld


def hyperboloid_column(a=0.06, c=0.3, h=0.1, nu=96, nz=24):
    """``x^2 + y^2 = a^2 (1 + z^2 / c^2)`` for ``|z| <= h``, capped (axis z)."""
    v, f = samples.cooling_tower(a, c, h, nu, nz)

    def distance(x):
        F = x[:, 0] ** 2 + x[:, 1] ** 2 - a**2 * (1 + x[:, 2] ** 2 / c**2)
        g = np.stack([2 * x[:, 0], 2 * x[:, 1], -2 * a**2 * x[:, 2] / c**2], 1)
        return np.abs(F) / np.linalg.norm(g, axis=1)

    return v, f, distance


def saddle_block(size=(0.2, 0.2, 0.15), z0=0.035, c=0.4, n=25):
    """The block ``|x|, |y| <= size/2``, from its bottom to the saddle ``z = z0 + x y / c``."""
    v, f = samples.saddle_top(size, z0, c, n)

    def distance(p):
        F = p[:, 2] - z0 - p[:, 0] * p[:, 1] / c
        g = np.stack([-p[:, 1] / c, -p[:, 0] / c, np.ones(len(p))], 1)
        return np.abs(F) / np.linalg.norm(g, axis=1)

    return v, f, distance


def ellipsoid(axes=(0.09, 0.06, 0.045), nu=64, nv=32):
    """The ellipsoid of semi-axes ``axes``."""
    u = np.linspace(0, 2 * np.pi, nu, endpoint=False)
    t = np.linspace(0, np.pi, nv)
    P = np.stack([np.cos(u)[:, None] * np.sin(t), np.sin(u)[:, None] * np.sin(t),
                  np.broadcast_to(np.cos(t), (nu, nv))], -1) * np.asarray(axes)
    v, f = _weld(_grid(P, closed_u=True))
    return v, f, None


def write_stl_ascii(path, v, f, scale=1.0):
    """An ASCII STL of the mesh (coordinates divided by ``scale``: 0.001 writes mm)."""
    tri = v[f] / scale
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    length = np.linalg.norm(n, axis=1)
    n = n / np.where(length > 0.0, length, 1.0)[:, None]
    facet = ("facet normal %.9g %.9g %.9g\nouter loop\n" + "vertex %.12g %.12g %.12g\n" * 3
             + "endloop\nendfacet\n")  # fmt: skip
    body = (facet * len(tri)) % tuple(np.concatenate([n[:, None], tri], axis=1).ravel().tolist())
    path.write_text("solid part\n" + body + "endsolid part\n")
    return path


def write_obj(path, v, f, scale=1.0):
    text = "".join(f"v {x:.12g} {y:.12g} {z:.12g}\n" for x, y, z in v / scale)
    text += "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in f)
    path.write_text(text)
    return path


def box(size=(0.12, 0.1, 0.08), n=1):
    """The box ``|x_k| <= size_k / 2`` of ``12 n^2`` triangles (:func:`samples.box`)."""
    v, f = samples.box(size, n)
    h = 0.5 * np.asarray(size)

    def inside(x):
        return np.all(np.abs(x) < h, axis=1)

    return v, f, inside


def prism(radius=0.05, half=0.07, sides=6, rings=2, turn=0.3):
    """A right prism on the regular ``sides``-gon of circumradius ``radius`` along z,
    ``|z| <= half``, its side in ``rings - 1`` bands, each end cap fanned from one rim
    vertex as CAD triangulates a planar face (``sides - 2`` triangles, long slivers
    for many sides); the first vertex at the angle ``turn`` [rad] from x."""
    u = np.linspace(0, 2 * np.pi, sides, endpoint=False) + turn
    z = np.linspace(-half, half, rings)
    P = np.stack([np.broadcast_to(radius * np.cos(u)[:, None], (sides, rings)),
                  np.broadcast_to(radius * np.sin(u)[:, None], (sides, rings)),
                  np.broadcast_to(z, (sides, rings))], -1)  # fmt: skip
    caps = []
    for k in (0, -1):
        ring = P[:, k]
        caps.append(np.stack([np.broadcast_to(ring[0], ring[1:-1].shape), ring[1:-1], ring[2:]],
                             axis=1))  # fmt: skip
    v, f = _weld(np.concatenate([_grid(P, closed_u=True), *caps]))
    normals = np.stack([np.cos(u + np.pi / sides), np.sin(u + np.pi / sides)], 1)
    apothem = radius * np.cos(np.pi / sides)

    def inside(x):
        return (np.all(x[:, :2] @ normals.T < apothem, axis=1)) & (np.abs(x[:, 2]) < half)

    return v, f, inside
