"""The cuts as solids for exact booleans (manifold3d): half-spaces, tubes and slabs.

Everything here is in the block's own frame (origin at its centre, axes along its
edges, metres), where the block is ``|x_k| <= size_k / 2``.  A cut keeps one side of
its surface; :func:`kept_solid` gives that side as a half-space or as a closed,
consistently oriented triangle mesh that reaches beyond the block wherever it is not
the cut's own surface, so that the block intersected with it is the block as the cut
leaves it:

* a **plane** (an exact cut whose rulings are coplanar, or a roughing loop's
  supporting planes): the half-space on the kept side, exact;
* a **loop** (a closed cut keeping its inside): the **tube** of its rulings between two
  planes normal to the loop's axis (the mean ruling) beyond the block, capped by fans.
  It is a solid when every section normal to the axis is star-shaped about its
  centroid (checked at every level of the mesh and half-way between);
* an **open cut**: the **slab** between its strip of rulings and a plane beyond the
  block on the kept side, walled along the strip's rim.  The strip is the rulings from
  ``-R`` to ``R`` about their points nearest the block's centre (``R`` the block's
  half-diagonal and :data:`MARGIN`: the rim lies outside the block), and beyond its
  first and last rulings a plane strip (the *apron*) continues the surface along its
  transversal where that misses the block.  It is a solid when the strip is a graph
  over the plane normal to the mean kept-side normal ``u`` (every triangle faces the
  same way along ``u``, the rim a simple curve there) and the block's shadow along
  ``u`` lies inside the rim's with :data:`MARGIN` to spare (then the walls miss the
  block).

The rulings are refined on the manifold of lines (the four-point scheme, as the
planner refines them) until the polygon of neighbouring rulings departs from a
smooth surface by :data:`EPS` at most, and each ruling is divided so that the
triangles of a quad between neighbours (a twisted quad, split along a diagonal)
depart from the ruled surface by :data:`EPS` at most: the twist of a quad is
``dv (d_{i+1} - d_i)``, its triangles lie within a quarter of it.  A surface that
fails its test is not closed here: :func:`kept_solid` says why, and the caller
meshes that cut on the grid (:mod:`.carved`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..geometry.checks import FloatArray
from ..geometry.lines import Lines

__all__ = ["EPS", "MARGIN", "CutSolid", "NotASolid", "convex_cell", "kept_solid", "refine_rulings",
           "to_manifold"]

#: largest departure [m] of the solids' triangles from the ruled surface they mesh, across
#: the rulings and along them (each)
EPS = 5e-6
#: how far [m] the solids' own rims and caps stay outside the block
MARGIN = 0.01
#: most refinement steps of the rulings (each halves their spacing)
MAX_STEPS = 5
#: most divisions of a ruling (a guard against a surface twisting wildly)
MAX_DIVISIONS = 2000
#: least |cos| between a face of a slab's strip and the slab's direction ``u``
MIN_FACING = 1e-3
#: least cosine between a loop's rulings and its axis
MIN_ALONG_AXIS = 0.3
#: most a loop's ruling may turn [deg] about the section's centre from one level to the next
MAX_TURN = 20.0


class NotASolid(ValueError):
    """The cut's surface cannot be closed into a valid solid here (the message says why)."""


@dataclass(frozen=True)
class CutSolid:
    """A cut's kept side in the block's frame.

    ``kind`` ``"plane"`` (``normal`` (3,) and ``offset`` [m]: the points with ``normal . x >=
    offset``), or ``"tube"`` / ``"slab"`` (``vertices`` (V, 3) [m], ``faces`` (F, 3): closed,
    outward); ``subtract`` when the solid is the waste (a loop keeping its outside);
    ``rulings`` after refinement."""

    kind: str
    normal: FloatArray | None = None
    offset: float = 0.0
    vertices: FloatArray | None = None
    faces: np.ndarray | None = None
    subtract: bool = False
    rulings: int = 0

    @property
    def triangles(self) -> int:
        """The solid's triangle count (0 for a half-space)."""
        return 0 if self.faces is None else len(self.faces)


def _unit(v: FloatArray) -> FloatArray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _basis(a: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Two unit vectors (3,) completing ``a`` (3,) to a right-handed frame (e1, e2, a)."""
    e1 = np.cross(a, [1.0, 0.0, 0.0] if abs(a[0]) < 0.9 else [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(a, e1)


def nearest_points(p: FloatArray, d: FloatArray) -> FloatArray:
    """Each line's point (N, 3) nearest the origin (the block's centre).

    Lines through ``p`` (N, 3) along unit ``d`` (N, 3)."""
    return p - np.einsum("ij,ij->i", p, d)[:, None] * d


def _between(o: FloatArray, d: FloatArray, fine: Lines, closed: bool, reach: float) -> float:
    """How far [m] the strips between neighbouring rulings (``o`` (N, 3) their points
    nearest the origin, ``d`` (N, 3)) depart from the rulings one refinement step puts
    between them (``fine``: the old rulings at even places): the distance from the
    midpoints of neighbours' points at ``-reach``, 0 and ``reach`` along them to the new
    ruling between.  It holds the surface's bending across the rulings and how the
    rulings' points pair up along them (the strip's quads join points at equal
    distances from the rulings' points nearest the origin)."""
    v = np.array([-reach, 0.0, reach])
    P = o[:, None, :] + v[None, :, None] * d[:, None, :]  # (N, 3, 3)
    nxt = np.roll(P, -1, axis=0) if closed else P[1:]
    mid = 0.5 * ((P if closed else P[:-1]) + nxt)
    new = fine[1::2]
    rel = mid - new.point[:, None, :]
    return float(np.linalg.norm(np.cross(rel, new.direction[:, None, :]), axis=-1).max())


def refine_rulings(p: FloatArray, d: FloatArray, closed: bool, reach: float, eps: float = EPS
                   ) -> tuple[FloatArray, FloatArray]:  # fmt: skip
    """Refine rulings by the four-point scheme on the manifold of lines to within ``eps``.

    The rulings through ``p`` (N, 3) along ``d`` (N, 3) [block frame, m], refined until the
    strips between neighbours lie within ``eps`` [m] of the rulings a further step would put
    between them (:func:`_between` over ``reach`` [m]), or :data:`MAX_STEPS`.  Returns
    points (M, 3) nearest the origin and unit directions (M, 3).
    """
    from ..subdivision import subdivide

    lines = Lines.from_point_direction(p, d)
    for _ in range(MAX_STEPS):
        if len(lines) < 3:
            break
        fine = subdivide(lines, scheme="four_point", steps=1, closed=closed)
        if _between(nearest_points(lines.point, lines.direction), lines.direction, fine,
                    closed, reach) <= eps:  # fmt: skip
            break
        lines = fine
    return nearest_points(lines.point, lines.direction), lines.direction


def planar(p: FloatArray, d: FloatArray, reach: float, tol: float = 1e-7
           ) -> tuple[FloatArray, float] | None:  # fmt: skip
    """Return the plane ``(n (3,), n . x)`` of rulings when they lie on one, else None.

    Rulings through ``p`` (N, 3) along ``d`` (N, 3) whose points within ``reach`` [m] all
    lie on one plane within ``tol`` [m].
    """
    o = nearest_points(p, d)
    pts = np.concatenate([o - reach * d, o + reach * d])
    c = pts.mean(axis=0)
    _, s, vt = np.linalg.svd(pts - c, full_matrices=False)
    n = vt[-1]
    if np.abs((pts - c) @ n).max() > tol or s[1] <= 1e-9 * s[0]:
        return None
    return n, float(n @ c)


def _levels(span: float, twist_rate: float, eps: float) -> int:
    """How many points divide a ruling of length ``span`` [m] so that quads twisting
    ``twist_rate`` [m per m] lie within ``eps`` of their triangles (module doc)."""
    k = int(np.ceil(span * twist_rate / (4.0 * eps))) + 1
    if k > MAX_DIVISIONS:
        raise NotASolid(f"the surface twists too fast to mesh within {eps * 1e3:g} mm "
                        f"({k} divisions of a ruling)")  # fmt: skip
    return max(k, 2)


def _grid_faces(idx: np.ndarray, closed: bool) -> np.ndarray:
    """Triangles (T, 3) of a grid of vertex indices ``idx`` (N, K): quads between
    neighbouring rulings ``i, i+1`` (periodic when ``closed``) and levels ``k, k+1`` as
    ``(i,k) (i+1,k) (i+1,k+1)`` and ``(i,k) (i+1,k+1) (i,k+1)``."""
    a = idx if closed else idx[:-1]
    b = np.roll(idx, -1, axis=0) if closed else idx[1:]
    a0, a1, b0, b1 = a[:, :-1], a[:, 1:], b[:, :-1], b[:, 1:]
    return np.concatenate([np.stack([a0, b0, b1], -1).reshape(-1, 3),
                           np.stack([a0, b1, a1], -1).reshape(-1, 3)])  # fmt: skip


def _monotone_angles(P: FloatArray, centre: FloatArray, e1: FloatArray, e2: FloatArray
                     ) -> int:  # fmt: skip
    """+1 (-1) when the closed polygons ``P`` (N, K, 3) each wind once counter-clockwise
    (clockwise) about ``centre`` (K, 3) seen along ``e1 x e2`` with every step turning the
    same way (star-shaped sections), else 0."""
    r = P - centre[None]
    ang = np.arctan2(r @ e2, r @ e1)
    step = np.angle(np.exp(1j * (np.roll(ang, -1, axis=0) - ang)))  # (N, K) in (-pi, pi]
    turns = step.sum(axis=0) / (2 * np.pi)
    if np.all(step > 0.0) and np.allclose(turns, 1.0, atol=1e-6):
        return 1
    if np.all(step < 0.0) and np.allclose(turns, -1.0, atol=1e-6):
        return -1
    return 0


def tube(p: FloatArray, d: FloatArray, half: FloatArray, eps: float = EPS) -> CutSolid:
    """The closed loop of rulings ``p``, ``d`` (N, 3) [block frame] as a capped tube (module doc).

    NotASolid when its sections are not star-shaped."""
    a = _unit(d.sum(axis=0))
    along = d @ a
    if along.min() < MIN_ALONG_AXIS:
        raise NotASolid(f"a ruling {np.degrees(np.arccos(along.min())):.0f} deg from the "
                        "loop's axis")  # fmt: skip
    corners = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)]) * half
    h0, h1 = (corners @ a).min() - MARGIN, (corners @ a).max() + MARGIN
    slope = d / along[:, None]  # per unit of level
    twist = float(np.linalg.norm(np.roll(slope, -1, axis=0) - slope, axis=1).max())
    h = np.linspace(h0, h1, _levels(h1 - h0, twist, eps))
    P = p[:, None, :] + (h[None, :] - (p @ a)[:, None])[..., None] * slope[:, None, :]
    e1, e2 = _basis(a)
    q = P.mean(axis=0)  # (K, 3)
    # between two levels a ruling's point moves linearly, and so does the centre: a ruling
    # that turns by more than MAX_TURN about the centre from one level to the next passes
    # (nearly) through the axis there (a cone's apex), where every section is star-shaped
    # and the tube is still pinched
    r = P - q[None]
    rx, ry = r @ e1, r @ e2
    turn_step = np.abs(np.angle((rx[:, 1:] + 1j * ry[:, 1:]) * (rx[:, :-1] - 1j * ry[:, :-1])))
    if turn_step.max() > np.radians(MAX_TURN):
        raise NotASolid("a ruling passes through the loop's axis in the block's reach "
                        "(a cone's apex)")  # fmt: skip
    turn = _monotone_angles(P, q, e1, e2)
    # half-way between levels the section runs through the midpoints of the quads'
    # ruling edges and diagonals (i,k)-(i+1,k+1)
    mid = 0.5 * (P[:, :-1] + P[:, 1:])
    diag = 0.5 * (P[:, :-1] + np.roll(P, -1, axis=0)[:, 1:])
    inter = np.stack([mid, diag], axis=1).reshape(-1, *mid.shape[1:])
    if turn == 0 or _monotone_angles(inter, 0.5 * (q[:-1] + q[1:]), e1, e2) != turn:
        raise NotASolid("a section of the loop is not star-shaped about its centre")
    if turn < 0:
        P = P[::-1]
    n, k = P.shape[:2]
    idx = np.arange(n * k).reshape(n, k)
    faces = [_grid_faces(idx, closed=True)]
    bottom, top = n * k, n * k + 1
    faces.append(np.stack([np.full(n, bottom), np.roll(idx[:, 0], -1), idx[:, 0]], 1))
    faces.append(np.stack([np.full(n, top), idx[:, -1], np.roll(idx[:, -1], -1)], 1))
    V = np.concatenate([P.reshape(-1, 3), q[:1], q[-1:]])
    return CutSolid("tube", vertices=V, faces=np.concatenate(faces), rulings=n)


def _segments_cross(xy: FloatArray) -> bool:
    """Whether the closed polygon ``xy`` (n, 2) crosses or touches itself (a pair of
    non-neighbouring edges meets); orientations within a relative 1e-12 of zero count as
    collinear (a straight run of the rim: its edges meet only where they overlap)."""
    a, b = xy, np.roll(xy, -1, axis=0)
    n = len(xy)
    tol = 1e-12 * float(np.ptp(xy, axis=0).max()) ** 2

    def orient(p, q, r):
        o = (q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1]) - \
            (q[..., 1] - p[..., 1]) * (r[..., 0] - p[..., 0])
        return np.where(np.abs(o) <= tol, 0.0, np.sign(o))

    def on(p, q, r):  # r within the bounding box of p, q (r collinear with them)
        return np.all((np.minimum(p, q) <= r) & (r <= np.maximum(p, q)), axis=-1)

    C, D = a[None], b[None]
    for s in range(0, n, 256):  # rows in chunks: n^2 pairs
        i = np.arange(s, min(n, s + 256))[:, None]
        j = np.arange(n)[None, :]
        gap = np.abs(i - j)
        far = (gap > 1) & (gap != n - 1)
        A, B = a[i[:, 0]][:, None], b[i[:, 0]][:, None]
        d1, d2, d3, d4 = orient(A, B, C), orient(A, B, D), orient(C, D, A), orient(C, D, B)
        hit = (d1 * d2 < 0.0) & (d3 * d4 < 0.0)
        hit |= ((d1 == 0.0) & on(A, B, C)) | ((d2 == 0.0) & on(A, B, D))
        hit |= ((d3 == 0.0) & on(C, D, A)) | ((d4 == 0.0) & on(C, D, B))
        if (hit & far).any():
            return True
    return False


def _inside_polygon(pts: FloatArray, xy: FloatArray) -> np.ndarray:
    """Whether points (M, 2) lie inside the closed polygon ``xy`` (n, 2) (crossings)."""
    a, b = xy[None], np.roll(xy, -1, axis=0)[None]
    x, y = pts[:, None, 0], pts[:, None, 1]
    crosses = (a[..., 1] > y) != (b[..., 1] > y)
    t = (y - a[..., 1]) / np.where(b[..., 1] != a[..., 1], b[..., 1] - a[..., 1], 1.0)
    xs = a[..., 0] + t * (b[..., 0] - a[..., 0])
    return (np.sum(crosses & (x < xs), axis=1) % 2) == 1


def _apron(o: FloatArray, d: FloatArray, half: FloatArray, length: float, end: int) -> FloatArray:
    """Rulings' points (m, 3) continuing the strip beyond its ruling ``end`` (0 or -1) in
    its plane with the transversal, out to ``length`` [m]; none (0, 3) where that plane
    strip would come within 1 mm of the block."""
    from ..geometry.box import Box

    k, j = (0, 1) if end == 0 else (-1, -2)
    e = o[k] - o[j]
    e = e - (e @ d[k]) * d[k]
    if np.linalg.norm(e) < 1e-12:
        return np.zeros((0, 3))
    e /= np.linalg.norm(e)
    s = np.linspace(0.0, length, 65)[1:]
    pts = o[k] + s[:, None] * e
    _, _, hit = Box(np.zeros(3), 2.0 * half).clip_lines(pts, np.broadcast_to(d[k], pts.shape),
                                                        margin=0.001)  # fmt: skip
    if hit.any():
        return np.zeros((0, 3))
    return pts[[len(s) // 4 - 1, len(s) // 2 - 1, len(s) - 1]]


def slab(p: FloatArray, d: FloatArray, keep: FloatArray, half: FloatArray, eps: float = EPS
         ) -> CutSolid:  # fmt: skip
    """Return the open cut of rulings ``p``, ``d`` as the slab on the side of ``keep``.

    ``p``, ``d`` (N, 3) [block frame], ``keep`` (3,) (module doc); NotASolid when the strip
    is no graph along its mean normal or does not cover the block's shadow.
    """
    reach = float(np.linalg.norm(half)) + MARGIN
    o = nearest_points(p, d)
    # the apron: the strip's first and last rulings continued in their plane
    first, last = _apron(o, d, half, reach, 0), _apron(o, d, half, reach, -1)
    o = np.concatenate([first[::-1], o, last])
    d = np.concatenate([np.broadcast_to(d[0], first.shape), d, np.broadcast_to(d[-1], last.shape)])
    twist = float(np.linalg.norm(np.diff(d, axis=0), axis=1).max())
    v = np.linspace(-reach, reach, _levels(2.0 * reach, twist, eps))
    P = o[:, None, :] + v[None, :, None] * d[:, None, :]  # (N, K, 3)
    n, k = P.shape[:2]
    idx = np.arange(n * k).reshape(n, k)
    F = _grid_faces(idx, closed=False)
    flat = P.reshape(-1, 3)
    tri = flat[F]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area2 = np.linalg.norm(normal, axis=1)
    normal = normal / np.where(area2 > 0.0, area2, 1.0)[:, None]
    # the kept side: the keep point against its nearest vertex's faces
    near = int(np.argmin(np.linalg.norm(flat - keep, axis=1)))
    touching = np.any(F == near, axis=1)
    side = float(np.sign((keep - flat[near]) @ normal[touching].sum(axis=0)))
    if side == 0.0:
        raise NotASolid("the kept point lies on the surface")
    inside = np.all(np.abs(tri.mean(axis=1)) <= half, axis=1)
    weights = area2 * (inside if inside.any() else 1.0)
    u = side * normal.T @ weights
    if np.linalg.norm(u) == 0.0:
        raise NotASolid("the surface has no mean normal in the block")
    u /= np.linalg.norm(u)
    facing = side * normal @ u
    if facing.min() < MIN_FACING:
        turn = float(np.degrees(np.arccos(np.clip(facing.min(), -1.0, 1.0))))
        raise NotASolid(f"the surface turns {turn:.0f} deg from its mean normal (no graph "
                        "along it)")  # fmt: skip
    e1, e2 = _basis(u)
    rim = np.concatenate([idx[:, 0], idx[-1, 1:], idx[-2::-1, -1], idx[0, -2:0:-1]])
    xy = np.stack([flat[rim] @ e1, flat[rim] @ e2], axis=1)
    if _segments_cross(xy):
        raise NotASolid("the surface overlaps itself seen along its mean normal")
    corners = np.array([[i, j, kk] for i in (-1, 1) for j in (-1, 1) for kk in (-1, 1)]) * half
    cxy = np.stack([corners @ e1, corners @ e2], axis=1)
    if not _inside_polygon(cxy, xy).all():
        raise NotASolid("the surface does not cover the block seen along its mean normal")
    from scipy.spatial import ConvexHull

    eq = ConvexHull(cxy).equations  # a . x + b <= 0 inside the block's shadow
    seg = np.roll(xy, -1, axis=0) - xy
    steps = int(np.ceil(np.linalg.norm(seg, axis=1).max() / (0.25 * MARGIN)))
    dense = (xy[:, None] + np.linspace(0.0, 1.0, steps + 1)[None, :, None] * seg[:, None]
             ).reshape(-1, 2)  # fmt: skip
    if (dense @ eq[:, :2].T + eq[:, 2]).max(axis=1).min() < 0.5 * MARGIN:
        raise NotASolid("the surface's rim passes over the block seen along its mean normal")
    far = max(float((corners @ u).max()), float((flat @ u).max())) + MARGIN
    top = flat + (far - flat @ u)[:, None] * u
    m = n * k
    a, b = rim, np.roll(rim, -1)  # the rim's edges a -> b as the strip's faces run them
    walls = np.concatenate([np.stack([b, a, a + m], 1), np.stack([b, a + m, b + m], 1)])
    faces = np.concatenate([F, F[:, ::-1] + m, walls])
    if side > 0.0:  # the strip's faces turn to the kept side: every face turned outwards
        faces = faces[:, ::-1]
    return CutSolid("slab", vertices=np.concatenate([flat, top]), faces=faces,
                    rulings=n)  # fmt: skip


def kept_solid(p: FloatArray, d: FloatArray, closed: bool, keep: str | FloatArray,
               half: FloatArray, eps: float = EPS) -> CutSolid:  # fmt: skip
    """A cut's kept side (module doc).

    Rulings through ``p`` (N, 3) along unit ``d`` (N, 3), ``keep`` ``"inside"``/``"outside"``
    (a loop) or a point (3,), all in the block's frame, ``half`` (3,) the block's half-sizes
    [m]. NotASolid says why not."""
    reach = float(np.linalg.norm(half)) + MARGIN
    d = d * np.r_[1.0, np.cumprod(np.where(np.einsum("ij,ij->i", d[1:], d[:-1]) < 0.0, -1.0,
                                            1.0))][:, None]  # oriented alike  # fmt: skip
    if not isinstance(keep, str):
        plane = planar(p, d, reach)
        if plane is not None:
            n, off = plane
            side = float(n @ keep - off)
            if side == 0.0:
                raise NotASolid("the kept point lies on the cut's plane")
            return CutSolid("plane", normal=np.sign(side) * n, offset=np.sign(side) * off,
                            rulings=len(p))  # fmt: skip
    o, d = refine_rulings(p, d, closed, float(np.linalg.norm(half)), eps)
    if closed:
        if not isinstance(keep, str) or keep not in ("inside", "outside"):
            raise NotASolid(f"a loop keeping {keep!r}")
        solid = tube(o, d, half, eps)
        return CutSolid(solid.kind, vertices=solid.vertices, faces=solid.faces,
                        subtract=keep == "outside", rulings=solid.rulings)  # fmt: skip
    if isinstance(keep, str):
        raise NotASolid(f"an open cut keeping {keep!r}")
    return slab(o, d, np.asarray(keep, dtype=np.float64), half, eps)


def to_manifold(vertices: FloatArray, faces: np.ndarray) -> Any:
    """A ``manifold3d.Manifold`` of a closed, outward mesh (V, 3) [m], (F, 3).

    NotASolid when manifold3d refuses it (its status) or finds no volume."""
    import manifold3d as m3d

    mesh = m3d.Mesh64(vert_properties=np.ascontiguousarray(vertices, dtype=np.float64),
                      tri_verts=np.ascontiguousarray(faces, dtype=np.uint64))  # fmt: skip
    solid = m3d.Manifold(mesh)
    status = solid.status()
    if status != m3d.Error.NoError:
        raise NotASolid(f"manifold3d refuses the mesh: {status.name}")
    if solid.is_empty() or solid.volume() <= 0.0:
        raise NotASolid("the mesh encloses no volume")
    return solid


def convex_cell(normals: FloatArray, offsets: FloatArray, half: FloatArray) -> Any:
    """Return the block cut to half-spaces as a ``manifold3d.Manifold`` (a convex polytope).

    The block ``|x_k| <= half_k`` (block frame, m) cut to the half-spaces ``normals . x >=
    offsets`` ((P, 3), (P,)): its vertices the half-spaces' intersection (scipy's qhull) and
    manifold3d's hull of them, in one step where manifold3d's ``trim_by_plane`` takes one
    per plane (0.9 s for a roughing's 384 planes, against 4 ms).  An empty Manifold when
    nothing is left; ``trim_by_plane`` in turn when qhull fails.
    """
    import manifold3d as m3d
    from scipy.optimize import linprog
    from scipy.spatial import HalfspaceIntersection, QhullError

    A = np.concatenate([-normals, np.eye(3), -np.eye(3)])  # A x <= b
    b = np.concatenate([-offsets, half, half])
    norm = np.linalg.norm(A, axis=1)
    # the centre of the largest ball inside: max r with A x + r |A_i| <= b
    lp = linprog(np.r_[0.0, 0.0, 0.0, -1.0], A_ub=np.c_[A, norm], b_ub=b,
                 bounds=[(None, None)] * 3 + [(0.0, None)], method="highs")  # fmt: skip
    if lp.status != 0 or lp.x[3] <= 1e-9:
        return m3d.Manifold()
    try:
        cell = HalfspaceIntersection(np.c_[A, -b], lp.x[:3])
        solid = m3d.Manifold.hull_points(cell.intersections)
    except (QhullError, ValueError):
        solid = None
    if solid is None or solid.status() != m3d.Error.NoError or solid.is_empty():
        solid = m3d.Manifold.cube(tuple(float(x) for x in 2.0 * half), True)
        for n, off in zip(normals, offsets, strict=True):
            solid = solid.trim_by_plane(tuple(float(x) for x in n), float(off))
    return solid
