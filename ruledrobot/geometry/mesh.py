"""Triangle meshes of discrete ruled surfaces (for STL/OBJ export and pictures).

A mesh is ``vertices`` (V, 3) float64 metres (world frame) and ``faces`` (F, 3)
int64 vertex indices, counter-clockwise seen from the side the normal
``(b - a) x (c - a)`` points to.  For rulings ``i`` with two vertices each,
``a_i`` (the end at ``-half_width``) and ``b_i`` (at ``+half_width`` along the
ruling's direction), the quad between rulings i and i+1 is split into the
triangles ``(a_i, a_{i+1}, b_{i+1})`` and ``(a_i, b_{i+1}, b_i)``; their normal
is ``x_u x x_v`` (sequence direction x ruling direction).

* :func:`strip_mesh`: the strip ``|v| <= half_width`` about a centre point on
  every ruling (default: the discrete striction point).
* :func:`box_clipped_mesh`: every ruling clipped to an oriented box (the chord
  inside it), quads between consecutive chords where both exist.

Closed surfaces are joined back to the first ruling; after a flip (Möbius band)
ruling 0 enters the last quad reversed, i.e. with ``a_0`` and ``b_0`` swapped.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._arrays import norm
from .box import Box
from .checks import FloatArray, as_float_array, check_finite, first_index
from .lines import Lines
from .ruled import RuledSurface

__all__ = [
    "ClippedMesh",
    "Mesh",
    "box_clipped_mesh",
    "mesh_normals",
    "signed_volume",
    "strip_mesh",
    "validate_mesh",
]

IntArray = NDArray[np.int64]


class Mesh(NamedTuple):
    """A triangle mesh: ``vertices`` (V, 3) m, ``faces`` (F, 3) int64 indices.

    A named tuple, so ``vertices, faces = strip_mesh(...)`` works.
    """

    vertices: FloatArray
    faces: IntArray


class ClippedMesh(NamedTuple):
    """Result of :func:`box_clipped_mesh`.

    * ``vertices`` (V, 3), ``faces`` (F, 3): the mesh of the chords (two
      vertices per hitting ruling, entry first, in the order of the rulings);
    * ``chords`` (N, 2, 3): entry and exit point of every ruling (entry first
      along the ruling's direction); NaN for rulings that miss the box;
    * ``hit`` (N,) bool: the ruling meets the box in a segment of positive length.
    """

    vertices: FloatArray
    faces: IntArray
    chords: FloatArray
    hit: NDArray[np.bool_]

    @property
    def missed(self) -> IntArray:
        """Indices of the rulings that miss the box."""
        return np.flatnonzero(~self.hit).astype(np.int64)


def validate_mesh(vertices: ArrayLike, faces: ArrayLike) -> Mesh:
    """Check a triangle mesh and return it as float64 vertices / int64 faces.

    Raises ValueError naming the item: ``vertices`` not (V, 3) or not finite
    (``vertices[i]``), ``faces`` not (F, 3) integers, or ``faces[i]`` holding a
    vertex index outside ``0 .. V-1``.
    """
    try:
        v = np.asarray(vertices, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"vertices: expected numbers ({exc})") from None
    if v.ndim != 2 or v.shape[1] != 3:
        raise ValueError(f"vertices: expected shape (V, 3), got {v.shape}")
    check_finite(v, "vertices", (3,))
    f = np.asarray(faces)
    if f.size == 0:
        f = f.reshape(0, 3) if f.ndim < 2 or f.shape[-1] == 3 else f
    if f.ndim != 2 or f.shape[1] != 3:
        raise ValueError(f"faces: expected shape (F, 3), got {f.shape}")
    integral_floats = (
        np.issubdtype(f.dtype, np.floating)
        and bool(np.all(np.isfinite(f)))
        and bool(np.all(f == np.round(f)))
    )
    if f.dtype == bool or not (np.issubdtype(f.dtype, np.integer) or integral_floats):
        raise ValueError(f"faces: expected integer vertex indices, got dtype {f.dtype}")
    f = f.astype(np.int64)
    bad = (f < 0) | (f >= v.shape[0])
    if np.any(bad):
        i, j = (int(k) for k in np.argwhere(bad)[0])
        raise ValueError(
            f"faces[{i}]: vertex index {int(f[i, j])} out of range 0..{v.shape[0] - 1} "
            f"({v.shape[0]} vertices)"
        )
    return Mesh(v, f)


def _quad_faces(a0: IntArray, b0: IntArray, a1: IntArray, b1: IntArray) -> IntArray:
    """Two triangles per quad (a0, a1, b1), (a0, b1, b0); inputs (Q,) -> (2Q, 3)."""
    t1 = np.stack([a0, a1, b1], axis=-1)
    t2 = np.stack([a0, b1, b0], axis=-1)
    return np.stack([t1, t2], axis=1).reshape(-1, 3).astype(np.int64)


def _pairs(n: int, closed: bool) -> tuple[IntArray, IntArray]:
    i = np.arange(n if closed else n - 1)
    return i, (i + 1) % n


def _topology(surface: RuledSurface | Lines, name: str) -> tuple[Lines, bool, bool]:
    """(lines, closed, flip) of a RuledSurface, or of Lines read as an open surface."""
    if isinstance(surface, RuledSurface):
        return surface.lines, bool(surface.closed), bool(surface.closed and surface.flip)
    if isinstance(surface, Lines):
        return surface, False, False
    raise ValueError(
        f"{name}: expected ruledrobot.RuledSurface or Lines, got {type(surface).__name__}"
    )


def strip_mesh(
    surface: RuledSurface | Lines,
    half_width: float | ArrayLike = 0.1,
    centre: str | ArrayLike = "striction",
) -> Mesh:
    """Triangle mesh of the strip ``|v| <= half_width`` of a discrete ruled surface.

    ``surface``: a :class:`RuledSurface` (its ``closed``/``flip`` decide how the
    last ruling is joined) or :class:`Lines` (an open surface).
    ``half_width``: metres, a number or one per ruling (N,), > 0.
    ``centre``: ``"striction"`` (the discrete striction points,
    :meth:`RuledSurface.striction_points`), ``"nearest_origin"`` (each ruling's
    point nearest the world origin) or points (N, 3), projected onto their rulings.

    Returns :class:`Mesh` with ``V = 2N`` vertices (``a_i = c_i - h_i l_i`` at
    index ``2i``, ``b_i = c_i + h_i l_i`` at ``2i+1``) and ``F = 2(N-1)``
    triangles (open) or ``2N`` (closed).
    """
    lines, closed, flip = _topology(surface, "surface")
    n = len(lines)
    l = lines.direction
    h = as_float_array(half_width, "half_width")
    if h.ndim > 1 or (h.ndim == 1 and h.shape[0] != n):
        raise ValueError(f"half_width: expected a number or one per ruling ({n},), got {h.shape}")
    if np.any(h <= 0.0):
        where = first_index(np.atleast_1d(h <= 0.0)) if h.ndim else ""
        raise ValueError(f"half_width{where}: expected a positive width (m)")
    h = np.broadcast_to(h, (n,))
    if isinstance(centre, str):
        if centre == "striction":
            surf = surface if isinstance(surface, RuledSurface) else RuledSurface(lines)
            c = surf.striction_points()
        elif centre == "nearest_origin":
            c = lines.point
        else:
            raise ValueError(
                f"centre: expected 'striction', 'nearest_origin' or points (N, 3), got {centre!r}"
            )
    else:
        pts = as_float_array(centre, "centre", (3,))
        if pts.shape != (n, 3):
            raise ValueError(f"centre: expected points of shape ({n}, 3), got {pts.shape}")
        p0 = lines.point
        c = p0 + np.einsum("ni,ni->n", pts - p0, l)[:, None] * l
    vertices = np.empty((n, 2, 3))
    vertices[:, 0] = c - h[:, None] * l
    vertices[:, 1] = c + h[:, None] * l
    i, j = _pairs(n, closed)
    a0, b0 = 2 * i, 2 * i + 1
    a1, b1 = 2 * j, 2 * j + 1
    if flip:
        a1[-1], b1[-1] = b1[-1], a1[-1]
    return Mesh(vertices.reshape(-1, 3), _quad_faces(a0, b0, a1, b1))


def box_clipped_mesh(
    lines: RuledSurface | Lines,
    box_centre: ArrayLike,
    box_size: ArrayLike,
    box_rotation: ArrayLike | None = None,
) -> ClippedMesh:
    """Clip every ruling to an oriented box and mesh the chords.

    ``lines``: :class:`Lines` (open) or a :class:`RuledSurface` (closed ones are
    joined back to ruling 0, reversed after a flip).
    ``box_centre`` (3,) m and ``box_rotation`` (3, 3) (columns: the box axes in
    world coordinates; default identity) place the box; ``box_size`` (3,) m are
    its full edge lengths along those axes.

    Slab method, vectorised: in box coordinates each ruling ``p + t l`` meets the
    slab ``|x_k| <= s_k/2`` for ``t`` between ``(-s_k/2 - p_k)/l_k`` and
    ``(s_k/2 - p_k)/l_k`` (all ``t`` when ``l_k = 0`` and ``|p_k| <= s_k/2``, none
    otherwise); the chord is the intersection of the three intervals.  A ruling
    hits the box when that chord has positive length.  Quads join consecutive
    rulings that both hit.  Returns :class:`ClippedMesh`.
    """
    lines, closed, flip = _topology(lines, "lines")
    box = Box(box_centre, box_size, np.eye(3) if box_rotation is None else box_rotation)
    x = lines.plucker
    l = x[:, :3]
    p0 = np.cross(l, x[:, 3:])
    foot = p0 + np.einsum("ni,ni->n", box.centre - p0, l)[:, None] * l  # nearest the centre
    tmin, tmax, hit = box.clip_lines(foot, l)
    n = len(lines)
    chords = np.full((n, 2, 3), np.nan)
    chords[hit, 0] = foot[hit] + tmin[hit, None] * l[hit]
    chords[hit, 1] = foot[hit] + tmax[hit, None] * l[hit]
    index = np.cumsum(hit) - 1  # vertex pair index of each hitting ruling
    i, j = _pairs(n, closed)
    a0, b0 = 2 * index[i], 2 * index[i] + 1
    a1, b1 = 2 * index[j], 2 * index[j] + 1
    if flip:
        a1[-1], b1[-1] = b1[-1], a1[-1]
    both = hit[i] & hit[j]
    faces = _quad_faces(a0[both], b0[both], a1[both], b1[both])
    return ClippedMesh(chords[hit].reshape(-1, 3), faces, chords, hit)


def mesh_normals(vertices: ArrayLike, faces: ArrayLike) -> FloatArray:
    """Unit facet normals (F, 3) of a triangle mesh; zero for degenerate triangles."""
    v, f = validate_mesh(vertices, faces)
    tri = v[f]
    nrm = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    size = norm(nrm)
    return np.where(size[:, None] > 0.0, nrm / np.where(size > 0.0, size, 1.0)[:, None], 0.0)


def signed_volume(vertices: FloatArray, faces: np.ndarray) -> float:
    """Return the volume [m^3] enclosed by a closed triangle mesh.

    Positive when its faces turn counter-clockwise seen from outside (the divergence theorem
    over the faces).
    """
    a, b, c = vertices[faces[:, 0]], vertices[faces[:, 1]], vertices[faces[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)
