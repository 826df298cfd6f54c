"""The MuJoCo model's geoms as triangle meshes, and their poses from MuJoCo's kinematics.

The viewer draws exactly the geometry the simulation uses: every visible geom
of the compiled model (groups 0-2, as MuJoCo's own viewer shows by default) is
turned into a triangle mesh in its **geom frame** (MuJoCo's convention:
capsules and cylinders along z with ``size = (radius, half length)``, boxes
with half sizes, planes with half extents, meshes from ``mesh_vert`` /
``mesh_face``); its pose in the world at each sample is MuJoCo's own
``geom_xpos`` / ``geom_xmat`` after ``mj_kinematics``.  Nothing of the robot's
shape is derived again here.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..geometry._arrays import FloatArray
from ..geometry.se3 import quaternion_from_matrix

__all__ = ["GeomMesh", "geom_meshes", "geom_poses", "revolve"]

_SEGMENTS = 24  # around the axis of round geoms
_PLANE_HALF = 3.0  # m: an infinite plane is drawn this far


@dataclass(frozen=True, eq=False)
class GeomMesh:
    """One MuJoCo geom as a triangle mesh.

    ``geom_id`` its index in the model; ``name`` (``"geom12"`` when unnamed);
    ``body`` the body name; ``vertices`` (V, 3) float32 m in the geom frame;
    ``faces`` (F, 3) uint32; ``rgba`` (4,) in [0, 1]; ``static``: on the world
    body (its pose never changes).
    """

    geom_id: int
    name: str
    body: str
    vertices: NDArray[np.float32] = field(repr=False)
    faces: NDArray[np.uint32] = field(repr=False)
    rgba: FloatArray = field(repr=False)
    static: bool


def revolve(r: ArrayLike, z: ArrayLike, segments: int = _SEGMENTS) -> tuple[FloatArray, np.ndarray]:
    """A surface of revolution about z: profile radii ``r`` (P,) at heights ``z`` (P,).

    Returns vertices (P * segments, 3) and faces (2 (P - 1) segments, 3), outward
    for a profile running from bottom (z low) to top.  A zero radius collapses a
    ring to a point (degenerate triangles, harmless).
    """
    r = np.asarray(r, dtype=np.float64)
    z = np.asarray(z, dtype=np.float64)
    phi = np.linspace(0.0, 2.0 * np.pi, segments, endpoint=False)
    v = np.stack(
        [r[:, None] * np.cos(phi), r[:, None] * np.sin(phi), np.broadcast_to(z[:, None],
                                                                            (r.size, segments))],
        axis=-1,
    ).reshape(-1, 3)
    i = np.arange(r.size - 1)[:, None]
    j = np.arange(segments)[None, :]
    a = i * segments + j
    b = i * segments + (j + 1) % segments
    c, d = a + segments, b + segments
    faces = np.concatenate([np.stack([a, b, d], -1), np.stack([a, d, c], -1)], axis=1)
    return v, faces.reshape(-1, 3)


def _arc(n: int, lo: float, hi: float) -> FloatArray:
    return np.linspace(lo, hi, n)


def _box(half: FloatArray) -> tuple[FloatArray, np.ndarray]:
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    faces = np.array([[0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6], [0, 1, 5], [0, 5, 4],
                      [2, 6, 7], [2, 7, 3], [0, 4, 6], [0, 6, 2], [1, 3, 7],
                      [1, 7, 5]])  # fmt: skip
    return corners * half, faces


def _primitive(mj: Any, kind: int, size: FloatArray) -> tuple[FloatArray, np.ndarray] | None:
    """Mesh of a primitive geom of type ``kind`` and MuJoCo ``size`` (3,), geom frame."""
    T = mj.mjtGeom
    if kind == T.mjGEOM_BOX:
        return _box(size)
    if kind == T.mjGEOM_PLANE:
        hx = size[0] if size[0] > 0 else _PLANE_HALF
        hy = size[1] if size[1] > 0 else _PLANE_HALF
        v = np.array([[-hx, -hy, 0], [hx, -hy, 0], [hx, hy, 0], [-hx, hy, 0]], float)
        return v, np.array([[0, 1, 2], [0, 2, 3]])
    if kind in (T.mjGEOM_SPHERE, T.mjGEOM_ELLIPSOID):
        th = _arc(13, -0.5 * np.pi, 0.5 * np.pi)
        v, f = revolve(np.cos(th), np.sin(th))
        scale = size if kind == T.mjGEOM_ELLIPSOID else np.full(3, size[0])
        return v * scale, f
    if kind == T.mjGEOM_CAPSULE:
        radius, half = size[0], size[1]
        th = _arc(7, 0.0, 0.5 * np.pi)
        r = np.r_[np.cos(th[::-1]), np.cos(th)] * radius
        z = np.r_[-half - radius * np.sin(th[::-1]), half + radius * np.sin(th)]
        return revolve(r, z)
    if kind == T.mjGEOM_CYLINDER:
        radius, half = size[0], size[1]
        return revolve([0.0, radius, radius, 0.0], [-half, -half, half, half])
    return None


def geom_meshes(mj: Any, model: Any, groups: tuple[int, ...] = (0, 1, 2)) -> tuple[GeomMesh, ...]:
    """Every geom of ``model`` (a compiled ``mujoco.MjModel``) in ``groups``, as meshes.

    Colours: the geom's material colour when it has one, else its ``rgba``.
    Geom types without a surface (height fields, SDFs) are left out.
    """
    out = []
    for g in range(model.ngeom):
        if int(model.geom_group[g]) not in groups:
            continue
        kind = int(model.geom_type[g])
        if kind == mj.mjtGeom.mjGEOM_MESH:
            mid = int(model.geom_dataid[g])
            va, vn = int(model.mesh_vertadr[mid]), int(model.mesh_vertnum[mid])
            fa, fn = int(model.mesh_faceadr[mid]), int(model.mesh_facenum[mid])
            mesh: tuple[FloatArray, np.ndarray] | None = (
                np.asarray(model.mesh_vert[va : va + vn], float),
                np.asarray(model.mesh_face[fa : fa + fn]),
            )
        else:
            mesh = _primitive(mj, kind, np.asarray(model.geom_size[g], float))
        if mesh is None:
            continue
        mat = int(model.geom_matid[g])
        rgba = np.array(model.mat_rgba[mat] if mat >= 0 else model.geom_rgba[g], float)
        body = int(model.geom_bodyid[g])
        name = mj.mj_id2name(model, mj.mjtObj.mjOBJ_GEOM, g) or f"geom{g}"
        out.append(GeomMesh(g, name, mj.mj_id2name(model, mj.mjtObj.mjOBJ_BODY, body) or "world",
                            mesh[0].astype(np.float32), mesh[1].astype(np.uint32), rgba,
                            body == 0))  # fmt: skip
    return tuple(out)


def geom_poses(
    mj: Any, model: Any, q: ArrayLike, geom_ids: ArrayLike | None = None
) -> tuple[FloatArray, FloatArray]:
    """World poses of geoms at joint positions ``q`` (K, J): MuJoCo's kinematics.

    For each row, ``qpos[:J] = q[k]`` and ``mj_kinematics``; returns positions
    (K, G, 3) m (``geom_xpos``) and unit quaternions (K, G, 4) ``[w, x, y, z]`` of
    ``geom_xmat``, for ``geom_ids`` (G,) (default: all geoms).
    """
    qa = np.atleast_2d(np.asarray(q, dtype=np.float64))
    ids = np.arange(model.ngeom) if geom_ids is None else np.asarray(geom_ids, dtype=int)
    data = mj.MjData(model)
    J = qa.shape[1]
    pos = np.empty((qa.shape[0], ids.size, 3))
    mat = np.empty((qa.shape[0], ids.size, 9))
    for k in range(qa.shape[0]):  # one pass through MuJoCo per sample
        data.qpos[:J] = qa[k]
        mj.mj_kinematics(model, data)
        pos[k] = data.geom_xpos[ids]
        mat[k] = data.geom_xmat[ids]
    return pos, quaternion_from_matrix(mat.reshape(*mat.shape[:-1], 3, 3))
