"""Oriented boxes: the stock of a cut, clipping of lines and segments.

A :class:`Box` is given by its centre (3,) m, its full edge lengths ``size``
(3,) m and a rotation (3, 3) whose columns are the box axes in world
coordinates.  Clipping uses the slab method, vectorised over lines.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from .checks import FloatArray, as_float_array

__all__ = ["Box"]

#: the unit cube's corners (8, 3), +-1/2, corner 4i + 2j + k at (i, j, k) of (low, high)
_UNIT_CORNERS = np.array([[i, j, k] for i in (-0.5, 0.5) for j in (-0.5, 0.5)
                          for k in (-0.5, 0.5)])  # fmt: skip
#: corner index pairs (12, 2) that differ in one axis: the cube's edges
_EDGES = np.array([(a, b) for a in range(8) for b in range(a + 1, 8)
                   if bin(a ^ b).count("1") == 1])  # fmt: skip


@dataclass(frozen=True)
class Box:
    """An oriented box: ``centre`` (3,), edge lengths ``size`` (3,) > 0, ``rotation`` (3, 3)."""

    centre: FloatArray
    size: FloatArray
    rotation: FloatArray = field(default_factory=lambda: np.eye(3))

    def __post_init__(self) -> None:
        c = as_float_array(self.centre, "box_centre")
        if c.shape != (3,):
            raise ValueError(f"box_centre: expected 3 numbers, got shape {c.shape}")
        s = as_float_array(self.size, "box_size")
        if s.shape != (3,):
            raise ValueError(f"box_size: expected 3 edge lengths, got shape {s.shape}")
        if np.any(s <= 0.0):
            k = int(np.flatnonzero(s <= 0.0)[0])
            raise ValueError(f"box_size[{k}]: expected a positive edge length (m), "
                             f"got {float(s[k])!r}")  # fmt: skip
        R = as_float_array(self.rotation, "box_rotation")
        if R.shape != (3, 3):
            raise ValueError(f"box_rotation: expected a 3x3 rotation matrix, got shape {R.shape}")
        if not np.allclose(R.T @ R, np.eye(3), atol=1e-9) or np.linalg.det(R) <= 0.0:
            raise ValueError("box_rotation: expected a rotation matrix (orthonormal, det +1)")
        for name, arr in (("centre", c), ("size", s), ("rotation", R)):
            arr = arr.copy()
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    @property
    def pose(self) -> FloatArray:
        """The box frame (4, 4) in world coordinates."""
        T = np.eye(4)
        T[:3, :3] = self.rotation
        T[:3, 3] = self.centre
        return T

    @property
    def corners(self) -> FloatArray:
        """The 8 corners (8, 3) in world coordinates [m].

        Corner ``4i + 2j + k`` lies at ``(i, j, k)`` of the box axes' (low, high) halves."""
        return self.centre + (_UNIT_CORNERS * self.size) @ self.rotation.T

    @property
    def edges(self) -> FloatArray:
        """The 12 edges (12, 2, 3) as pairs of corners in world coordinates [m]."""
        return self.corners[_EDGES]

    def moved(self, T: ArrayLike) -> Box:
        """The box carried by the rigid motion ``T`` (4, 4).

        Centre ``R c + p``, axes ``R rotation``, the same size (a block placed elsewhere, the
        stock of a job file seen from the world frame of a robot base ``T``)."""
        T = as_float_array(T, "T")
        if T.shape != (4, 4):
            raise ValueError(f"T: expected a pose (4, 4), got shape {T.shape}")
        R, p = T[:3, :3], T[:3, 3]
        return Box(R @ self.centre + p, self.size, R @ self.rotation)

    def grown(self, margin: float) -> Box:
        """Return the box grown by ``margin`` [m] on every side.

        Edge lengths ``size + 2 margin``; a negative margin shrinks it, refused when an edge
        would vanish: the same box as :meth:`contains` and :meth:`clip_lines` test with
        ``margin``.
        """
        return Box(self.centre, self.size + 2.0 * float(margin), self.rotation)

    def to_box(self, points: ArrayLike) -> FloatArray:
        """World points (..., 3) in box coordinates."""
        return (np.asarray(points, dtype=np.float64) - self.centre) @ self.rotation

    def signed_distance(self, points: ArrayLike) -> FloatArray:
        """Signed distance [m] of world points (N, 3) to the box's surface (N,): negative inside.

        ``|max(q, 0)| + min(max_k q_k, 0)`` with ``q = |p_box| - size / 2`` (the exact
        distance of an axis-aligned box, Quilez), one box axis at a time over the points'
        columns: no (N, 3) temporaries (5e6 points in 0.2-0.3 s against 0.5-1.5 s)."""
        cols = np.asarray(points, dtype=np.float64).T  # (3, N), a view
        c, R, half = self.centre, self.rotation, 0.5 * self.size
        outside = np.zeros(cols.shape[1])
        inside = np.full(cols.shape[1], -np.inf)
        for k in range(3):
            qk = (cols[0] - c[0]) * R[0, k]
            qk += (cols[1] - c[1]) * R[1, k]
            qk += (cols[2] - c[2]) * R[2, k]
            np.abs(qk, out=qk)
            qk -= half[k]
            np.maximum(inside, qk, out=inside)
            np.maximum(qk, 0.0, out=qk)
            qk *= qk
            outside += qk
        np.sqrt(outside, out=outside)
        np.minimum(inside, 0.0, out=inside)
        return outside + inside

    def contains(self, points: ArrayLike, margin: float = 0.0) -> np.ndarray:
        """Whether points (..., 3) lie inside the box grown by ``margin`` (m) on every side."""
        return np.all(np.abs(self.to_box(points)) <= 0.5 * self.size + margin, axis=-1)

    def clip_lines(
        self, origins: ArrayLike, directions: ArrayLike, margin: float = 0.0
    ) -> tuple[FloatArray, FloatArray, np.ndarray]:
        """Return the parameters where lines cross the box grown by ``margin``.

        ``(t_in, t_out, hit)`` for lines ``origin + t direction`` (..., 3): the chord is
        ``t_in <= t <= t_out``.

        Slab method: in box coordinates the line meets slab ``k`` for ``t`` between
        ``(+-h_k - p_k)/d_k``; a direction parallel to a slab meets it everywhere or
        nowhere.  ``hit`` is True where the chord has positive length; elsewhere the
        parameters are NaN.
        """
        p = self.to_box(origins)
        d = np.asarray(directions, dtype=np.float64) @ self.rotation
        half = 0.5 * self.size + margin
        parallel = np.abs(d) <= 1e-15
        safe = np.where(parallel, 1.0, d)
        t1 = (-half - p) / safe
        t2 = (half - p) / safe
        inside = np.abs(p) <= half
        lo = np.where(parallel, np.where(inside, -np.inf, np.inf), np.minimum(t1, t2))
        hi = np.where(parallel, np.where(inside, np.inf, -np.inf), np.maximum(t1, t2))
        t_in, t_out = lo.max(axis=-1), hi.min(axis=-1)
        hit = t_out > t_in
        return np.where(hit, t_in, np.nan), np.where(hit, t_out, np.nan), hit

    def segment_hits(self, a: ArrayLike, b: ArrayLike, margin: ArrayLike = 0.0) -> np.ndarray:
        """Whether segments ``a -> b`` (..., 3) touch the box grown by ``margin``.

        ``margin`` [m]: a number, or one per segment as an array that broadcasts against
        the points (..., 3) as in :meth:`clip_lines` (e.g. (S, 1) for segments (n, S, 3)).
        The slab method of :meth:`clip_lines`, compiled
        (:func:`ruledrobot.geometry._collide_kernel.segments_hit_box`); a point segment
        touches when the point is inside (:meth:`contains`).
        """
        from ._collide_kernel import segments_hit_box

        a = np.asarray(a, dtype=np.float64)
        b = np.asarray(b, dtype=np.float64)
        points = np.broadcast_shapes(a.shape, b.shape)
        shape = points[:-1]
        n = int(np.prod(shape))
        m = np.broadcast_to(np.asarray(margin, dtype=np.float64), points)[..., 0]
        out = np.empty(n, dtype=bool)
        segments_hit_box(
            np.ascontiguousarray(np.broadcast_to(a, points).reshape(n, 3)),
            np.ascontiguousarray(np.broadcast_to(b, points).reshape(n, 3)),
            np.ascontiguousarray(m.reshape(n)),
            self.centre, np.ascontiguousarray(self.rotation), 0.5 * self.size, out,
        )  # fmt: skip
        return out.reshape(shape)
