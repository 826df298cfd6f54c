"""Rigid motions SE(3): exponential map, logarithm, screw geodesics, conversions.

Conventions (see ``docs/conventions.md``):

* A pose is a 4x4 homogeneous matrix ``T = [[R, p], [0, 1]]`` (float64); the
  columns of ``R`` are the frame's axes in world coordinates, ``p`` its origin.
  Batches carry leading axes: ``(..., 4, 4)``.
* A twist (exponential coordinates) is ``xi = [omega, v]`` of shape ``(..., 6)``,
  angular part first, the same order as Plücker coordinates ``[l, m]``:
  ``T = expm([[omega]_x, v], [0, 0]])``.  ``|omega|`` is the rotation angle.
* A unit quaternion is scalar first, ``q = [w, x, y, z]``; functions return the
  representative with ``w >= 0``.
* A UR pose vector is ``[x, y, z, rx, ry, rz]``: translation and rotation vector
  (axis times angle, angle in ``[0, pi]``), as the UR controller uses it.
* ``geodesic(A, B, t) = A @ exp(t * log(inv(A) @ B))``: the uniform screw motion
  taking ``A`` (t=0) to ``B`` (t=1) with the smallest rotation angle (<= pi).
  ``t`` may be any real number (extrapolation). It equals dual-quaternion ScLERP.

Implementation notes.  All functions are vectorised; the geodesic works on a
unit-quaternion/translation form in cache-sized chunks.  For a pair (A, B) the
relative motion ``D = inv(A) B`` is decomposed once into its screw
(:class:`ScrewPair`): half rotation angle ``phi``, unit axis ``u``, the part
of the translation along the axis and the part across it.  A point of the
geodesic is then (derivation in ``docs/math.md``)::

    q(t) = q_A * (cos(t phi), sin(t phi) u)
    p(t) = p_A + R_A [ t (u.p) u + sin(t phi)/sin(phi) *
                       (cos((1-t) phi) p_perp - sin((1-t) phi) u x p_perp) ]

which needs one ``sin`` and one ``cos`` per evaluation, is exact for a pure
translation (``phi = 0``) and stable for ``phi -> 0`` and ``phi -> pi/2``.

:func:`geodesic` and :func:`geodesic_many` on more than :data:`NUMPY_PAIRS` pairs run
in a compiled loop (:mod:`ruledrobot.geometry._se3_kernel`, numba: the numpy chunk's
operations in the same order, one pair at a time in registers), which gives the numpy
path's results bit for bit where numpy's ``sin``/``cos``/``arctan2`` are libm's (without
AVX-512; else within 1e-15); once loaded it serves every batch (see :func:`uses_kernel`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ._arrays import cross3, dot3
from .checks import FloatArray, as_float_array, first_index

__all__ = [
    "ScrewPair",
    "compose",
    "exp",
    "geodesic",
    "identity",
    "inverse",
    "kernel_loaded",
    "load_kernel",
    "log",
    "matrix_from_quaternion",
    "pose_from_quaternion",
    "pose_from_rotvec",
    "pose_from_ur_vector",
    "quaternion_from_matrix",
    "quaternion_from_pose",
    "rotation_about_axis",
    "rotvec_from_matrix",
    "ur_vector_from_pose",
    "uses_kernel",
    "validate_poses",
]

_CHUNK = 4096  # elements per chunk: ~40 component arrays of 32 kB stay in L2

#: Geodesics of more pairs than this load the compiled kernel (see :func:`uses_kernel`).
NUMPY_PAIRS = 10_000

_kernel = None  # ruledrobot.geometry._se3_kernel once loaded (numba)


# ---------------------------------------------------------------------------
# quaternion kernels on component tuples (each component a 1-D or N-D array)
# ---------------------------------------------------------------------------


def _qmul(a: tuple, b: tuple) -> tuple:
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    )


def _qrotate(q: tuple, v: tuple) -> tuple:
    """Rotate vector components ``v`` by unit quaternion ``q``: v + 2w(u x v) + 2u x (u x v)."""
    w, x, y, z = q
    vx, vy, vz = v
    tx = 2.0 * (y * vz - z * vy)
    ty = 2.0 * (z * vx - x * vz)
    tz = 2.0 * (x * vy - y * vx)
    return (
        vx + w * tx + (y * tz - z * ty),
        vy + w * ty + (z * tx - x * tz),
        vz + w * tz + (x * ty - y * tx),
    )


def _quat_from_rot(m: tuple) -> tuple:
    """Unit quaternion (w >= 0) from rotation matrix components (row-major 9-tuple).

    Shepperd's method: of the four rows of ``4 q q^T`` (each proportional to
    q) take the one with the largest diagonal entry, then normalise.  Stable for
    every angle, including near pi.
    """
    m00, m01, m02, m10, m11, m12, m20, m21, m22 = m
    t0 = 1.0 + m00 + m11 + m22
    t1 = 1.0 + m00 - m11 - m22
    t2 = 1.0 - m00 + m11 - m22
    t3 = 1.0 - m00 - m11 + m22
    d21 = m21 - m12
    d02 = m02 - m20
    d10 = m10 - m01
    s01 = m01 + m10
    s02 = m02 + m20
    s12 = m12 + m21
    c1 = t1 > t0
    best = np.where(c1, t1, t0)
    c2 = t2 > best
    best = np.where(c2, t2, best)
    c3 = t3 > best
    # row 0 by default, then overwrite where another row is the best one
    w = np.where(c3, d10, np.where(c2, d02, np.where(c1, d21, t0)))
    x = np.where(c3, s02, np.where(c2, s01, np.where(c1, t1, d21)))
    y = np.where(c3, s12, np.where(c2, t2, np.where(c1, s01, d02)))
    z = np.where(c3, t3, np.where(c2, s12, np.where(c1, s02, d10)))
    scale = np.copysign(1.0, w) / np.sqrt(w * w + x * x + y * y + z * z)
    return w * scale, x * scale, y * scale, z * scale


def _rot_from_quat(q: tuple) -> tuple:
    """Row-major rotation matrix components from a unit quaternion."""
    w, x, y, z = q
    xx, yy, zz = x * x, y * y, z * z
    xy, xz, yz = x * y, x * z, y * z
    wx, wy, wz = w * x, w * y, w * z
    return (
        1.0 - 2.0 * (yy + zz), 2.0 * (xy - wz), 2.0 * (xz + wy),
        2.0 * (xy + wz), 1.0 - 2.0 * (xx + zz), 2.0 * (yz - wx),
        2.0 * (xz - wy), 2.0 * (yz + wx), 1.0 - 2.0 * (xx + yy),
    )  # fmt: skip


def _pose_components(T: FloatArray) -> tuple[tuple, tuple]:
    """Split (n, 4, 4) poses into rotation (9-tuple) and translation (3-tuple) rows."""
    flat = T.reshape(-1, 16)[:, [0, 1, 2, 4, 5, 6, 8, 9, 10, 3, 7, 11]].T
    return tuple(flat[:9]), tuple(flat[9:])


def _pose_from_components(rot: tuple, trans: tuple, out: FloatArray) -> None:
    """Write rotation/translation component rows into ``out`` of shape (n, 4, 4)."""
    flat = out.reshape(-1, 16)
    for k, col in enumerate((0, 1, 2, 4, 5, 6, 8, 9, 10)):
        flat[:, col] = rot[k]
    flat[:, 3], flat[:, 7], flat[:, 11] = trans
    flat[:, 12:15] = 0.0
    flat[:, 15] = 1.0


# ---------------------------------------------------------------------------
# screw decomposition of a pair and evaluation of its geodesic
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class ScrewPair:
    """The screw (shortest uniform motion) ``D = inv(A) B`` of poses A and B.

    All fields are arrays (or component tuples of arrays) with the batch shape
    of the pair.  Build with :meth:`from_relative` or :meth:`from_qt`; evaluate
    ``exp(t log D)`` with :meth:`relative_at` (one sin and one cos per call).
    """

    phi: FloatArray  # half rotation angle, in [0, pi/2]
    sin_phi: FloatArray
    cos_phi: FloatArray
    axis: tuple  # unit rotation axis u (zero vector when phi == 0)
    axial: tuple  # (u . p) u, p = translation of D
    perp: tuple  # p - axial
    cross: tuple  # u x perp
    any_small: bool  # some sin(phi) < 1e-6 (the series branch is needed)

    @classmethod
    def from_relative(cls, q: tuple, p: tuple) -> ScrewPair:
        """Decompose D given its unit quaternion ``q`` (any sign) and translation ``p``."""
        w, x, y, z = q
        sign = np.copysign(1.0, w)  # shortest motion: rotation angle <= pi <=> w >= 0
        w, x, y, z = w * sign, x * sign, y * sign, z * sign
        s = np.sqrt(x * x + y * y + z * z)
        phi = np.arctan2(s, w)
        inv_s = 1.0 / np.where(s > 0.0, s, 1.0)
        ux, uy, uz = x * inv_s, y * inv_s, z * inv_s
        px, py, pz = p
        dot = ux * px + uy * py + uz * pz
        ax_, ay_, az_ = dot * ux, dot * uy, dot * uz
        qx, qy, qz = px - ax_, py - ay_, pz - az_
        cross = (uy * qz - uz * qy, uz * qx - ux * qz, ux * qy - uy * qx)
        small = bool(np.any(s < 1e-6))
        return cls(phi, s, w, (ux, uy, uz), (ax_, ay_, az_), (qx, qy, qz), cross, small)

    @classmethod
    def from_qt(cls, qa: tuple, pa: tuple, qb: tuple, pb: tuple) -> ScrewPair:
        """The screw of inv(A) B from quaternion/translation parts of A and B."""
        conj = (qa[0], -qa[1], -qa[2], -qa[3])
        q = _qmul(conj, qb)
        p = _qrotate(conj, (pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]))
        return cls.from_relative(q, p)

    def relative_at(self, t: float | FloatArray) -> tuple[tuple, tuple]:
        """Quaternion and translation of ``exp(t log D)`` (see the module doc)."""
        tphi = t * self.phi
        s = np.sin(tphi)
        c = np.cos(tphi)
        S, C = self.sin_phi, self.cos_phi
        cos_rest = C * c + S * s  # cos((1 - t) phi)
        sin_rest = S * c - C * s  # sin((1 - t) phi)
        if self.any_small:
            small = S < 1e-6
            series = t * (1.0 + (1.0 - t * t) * self.phi * self.phi / 6.0)
            ratio = np.where(small, series, s / np.where(small, 1.0, S))
        else:
            ratio = s / S
        ux, uy, uz = self.axis
        a, p, x = self.axial, self.perp, self.cross
        rc, rs = ratio * cos_rest, ratio * sin_rest
        trans = (
            t * a[0] + rc * p[0] - rs * x[0],
            t * a[1] + rc * p[1] - rs * x[1],
            t * a[2] + rc * p[2] - rs * x[2],
        )
        return (c, s * ux, s * uy, s * uz), trans

    def twist(self) -> tuple[tuple, tuple]:
        """Exponential coordinates [omega, v] of D as component tuples."""
        phi, S, C = self.phi, self.sin_phi, self.cos_phi
        small = S < 1e-8
        # phi/sin(phi) -> 1 and phi cot(phi) -> 1 as phi -> 0
        f = np.where(small, 1.0, phi / np.where(small, 1.0, S))
        omega = tuple(2.0 * phi * u for u in self.axis)
        a, p, x = self.axial, self.perp, self.cross
        fc = f * C
        v = tuple(a[k] + fc * p[k] - phi * x[k] for k in range(3))
        return omega, v


def _qt_compose(qa: tuple, pa: tuple, q: tuple, p: tuple) -> tuple[tuple, tuple]:
    """(qa, pa) * (q, p) on component tuples."""
    r = _qrotate(qa, p)
    return _qmul(qa, q), (pa[0] + r[0], pa[1] + r[1], pa[2] + r[2])


def _geodesic_matrix_chunk(
    A: FloatArray, B: FloatArray, t: float | FloatArray, out: FloatArray
) -> None:
    """Geodesic points of pose chunks A, B (c, 4, 4) written into ``out`` (c, 4, 4).

    Works on rotation-matrix rows: ``D = R_A^T R_B`` is formed directly (one
    Shepperd conversion), and the result ``R_A R(t)`` composed as matrices.
    """
    ra, pa = _pose_components(A)
    rb, pb = _pose_components(B)
    a00, a01, a02, a10, a11, a12, a20, a21, a22 = ra
    b00, b01, b02, b10, b11, b12, b20, b21, b22 = rb
    d = (
        a00 * b00 + a10 * b10 + a20 * b20, a00 * b01 + a10 * b11 + a20 * b21,
        a00 * b02 + a10 * b12 + a20 * b22, a01 * b00 + a11 * b10 + a21 * b20,
        a01 * b01 + a11 * b11 + a21 * b21, a01 * b02 + a11 * b12 + a21 * b22,
        a02 * b00 + a12 * b10 + a22 * b20, a02 * b01 + a12 * b11 + a22 * b21,
        a02 * b02 + a12 * b12 + a22 * b22,
    )  # fmt: skip
    dx, dy, dz = pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]
    pd = (
        a00 * dx + a10 * dy + a20 * dz,
        a01 * dx + a11 * dy + a21 * dz,
        a02 * dx + a12 * dy + a22 * dz,
    )
    q, p = ScrewPair.from_relative(_quat_from_rot(d), pd).relative_at(t)
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = _rot_from_quat(q)
    flat = out.reshape(-1, 16)
    flat[:, 0] = a00 * r00 + a01 * r10 + a02 * r20
    flat[:, 1] = a00 * r01 + a01 * r11 + a02 * r21
    flat[:, 2] = a00 * r02 + a01 * r12 + a02 * r22
    flat[:, 4] = a10 * r00 + a11 * r10 + a12 * r20
    flat[:, 5] = a10 * r01 + a11 * r11 + a12 * r21
    flat[:, 6] = a10 * r02 + a11 * r12 + a12 * r22
    flat[:, 8] = a20 * r00 + a21 * r10 + a22 * r20
    flat[:, 9] = a20 * r01 + a21 * r11 + a22 * r21
    flat[:, 10] = a20 * r02 + a21 * r12 + a22 * r22
    px, py, pz = p
    flat[:, 3] = pa[0] + a00 * px + a01 * py + a02 * pz
    flat[:, 7] = pa[1] + a10 * px + a11 * py + a12 * pz
    flat[:, 11] = pa[2] + a20 * px + a21 * py + a22 * pz
    flat[:, 12:15] = 0.0
    flat[:, 15] = 1.0


# ---------------------------------------------------------------------------
# public API on 4x4 matrices
# ---------------------------------------------------------------------------


def identity(shape: tuple[int, ...] = ()) -> FloatArray:
    """Identity poses of batch shape ``shape``: (..., 4, 4)."""
    return np.broadcast_to(np.eye(4), (*shape, 4, 4)).copy()


def validate_poses(T: ArrayLike, name: str = "poses", tol: float = 1e-6) -> FloatArray:
    """Return ``T`` as float64 (..., 4, 4) after checking it is a rigid motion.

    Checks finiteness, the last row ``[0, 0, 0, 1]``, orthonormal rotation
    columns and a right-handed frame (all to ``tol``); raises ValueError naming
    the first offending index.  Works on component rows in cache-sized chunks
    (six column dot products and one triple product), cheap on 10^5 poses.
    """
    T = as_float_array(T, name, (4, 4))
    shape = T.shape[:-2]
    flat = T.reshape(-1, 16)
    n = flat.shape[0]
    err = np.empty(n)
    for lo in range(0, n, _CHUNK):
        c = flat[lo : lo + _CHUNK].T
        x, y, z = (c[0], c[4], c[8]), (c[1], c[5], c[9]), (c[2], c[6], c[10])
        e = np.abs(dot3(x, x) - 1.0)
        e = np.maximum(e, np.abs(dot3(y, y) - 1.0))
        e = np.maximum(e, np.abs(dot3(z, z) - 1.0))
        e = np.maximum(e, np.abs(dot3(x, y)))
        e = np.maximum(e, np.abs(dot3(x, z)))
        e = np.maximum(e, np.abs(dot3(y, z)))
        # right-handed: (x cross y) . z = det R = +1; a reflection gives -1
        xy = cross3(x, y)
        e = np.maximum(e, np.abs(dot3(xy, z) - 1.0))
        for k in (12, 13, 14):
            e = np.maximum(e, np.abs(c[k]))
        err[lo : lo + _CHUNK] = np.maximum(e, np.abs(c[15] - 1.0))
    bad = err > tol
    if bad.any():
        i = int(np.argmax(bad))
        where = first_index(bad.reshape(shape)) if shape else ""
        Ti = flat[i].reshape(4, 4)
        if np.abs(Ti[3] - np.array([0.0, 0.0, 0.0, 1.0])).max() > tol:
            what = "last row must be [0, 0, 0, 1]"
        elif np.linalg.det(Ti[:3, :3]) < 0.0:
            what = "rotation part is a reflection (det < 0)"
        else:
            what = f"rotation part is not orthonormal (error {err[i]:.2e}, tolerance {tol:g})"
        raise ValueError(f"{name}{where}: {what}")
    return T


def compose(A: ArrayLike, B: ArrayLike) -> FloatArray:
    """Product ``A @ B`` of poses (..., 4, 4), broadcasting the batch axes."""
    return np.matmul(np.asarray(A, dtype=np.float64), np.asarray(B, dtype=np.float64))


def inverse(T: ArrayLike) -> FloatArray:
    """Inverse of poses (..., 4, 4): ``[[R^T, -R^T p], [0, 1]]``."""
    T = np.asarray(T, dtype=np.float64)
    out = np.zeros_like(T)
    Rt = np.swapaxes(T[..., :3, :3], -1, -2)
    out[..., :3, :3] = Rt
    out[..., :3, 3] = -np.einsum("...ij,...j->...i", Rt, T[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out


def quaternion_from_matrix(R: ArrayLike) -> FloatArray:
    """Unit quaternion ``[w, x, y, z]`` (w >= 0) of rotation matrices (..., 3, 3)."""
    R = np.asarray(R, dtype=np.float64)
    comps = tuple(R[..., i, j] for i in range(3) for j in range(3))
    return np.stack(_quat_from_rot(comps), axis=-1)


def matrix_from_quaternion(q: ArrayLike) -> FloatArray:
    """Rotation matrices (..., 3, 3) of quaternions ``[w, x, y, z]`` (normalised first)."""
    q = as_float_array(q, "quaternion", (4,))
    n = np.sqrt(np.sum(q * q, axis=-1))
    if np.any(n < 1e-12):
        raise ValueError(f"quaternion{first_index(n < 1e-12)}: zero quaternion has no rotation")
    q = q / n[..., None]
    comps = _rot_from_quat(tuple(q[..., k] for k in range(4)))
    return np.stack(comps, axis=-1).reshape(*q.shape[:-1], 3, 3)


def quaternion_from_pose(T: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Split poses (..., 4, 4) into quaternions (..., 4) ``[w,x,y,z]`` and translations (..., 3)."""
    T = np.asarray(T, dtype=np.float64)
    return quaternion_from_matrix(T[..., :3, :3]), T[..., :3, 3].copy()


def pose_from_quaternion(q: ArrayLike, translation: ArrayLike | None = None) -> FloatArray:
    """Poses (..., 4, 4) from quaternions ``[w,x,y,z]`` (..., 4) and translations (..., 3)."""
    R = matrix_from_quaternion(q)
    return _pose_from_rt(R, translation)


def _pose_from_rt(R: FloatArray, translation: ArrayLike | None) -> FloatArray:
    if translation is None:
        p = np.zeros(R.shape[:-1])
    else:
        p = as_float_array(translation, "translation", (3,))
    shape = np.broadcast_shapes(R.shape[:-2], p.shape[:-1])
    out = np.zeros((*shape, 4, 4))
    out[..., :3, :3] = R
    out[..., :3, 3] = p
    out[..., 3, 3] = 1.0
    return out


def rotation_about_axis(axis: ArrayLike, angle: ArrayLike) -> FloatArray:
    """Rotation matrices (..., 3, 3) by ``angle`` (rad) about unit ``axis`` (..., 3) (Rodrigues)."""
    axis = np.asarray(axis, dtype=np.float64)
    angle = np.asarray(angle, dtype=np.float64)
    return _rotation_from_rotvec(axis * angle[..., None])


def _rotation_from_rotvec(rv: FloatArray) -> FloatArray:
    theta = np.sqrt(np.sum(rv * rv, axis=-1))
    half = 0.5 * theta
    small = theta < 1e-6
    # sin(theta/2)/theta with its series for small angles
    k = np.where(small, 0.5 - theta * theta / 48.0, np.sin(half) / np.where(small, 1.0, theta))
    q = (np.cos(half), k * rv[..., 0], k * rv[..., 1], k * rv[..., 2])
    return np.stack(_rot_from_quat(q), axis=-1).reshape(*rv.shape[:-1], 3, 3)


def pose_from_rotvec(rotvec: ArrayLike, translation: ArrayLike | None = None) -> FloatArray:
    """Poses (..., 4, 4) from rotation vectors (..., 3) (axis * angle, rad) and translations."""
    rv = as_float_array(rotvec, "rotvec", (3,))
    return _pose_from_rt(_rotation_from_rotvec(rv), translation)


def rotvec_from_matrix(R: ArrayLike) -> FloatArray:
    """Rotation vectors (..., 3), angle in [0, pi], of rotation matrices (..., 3, 3)."""
    q = quaternion_from_matrix(R)
    s = np.sqrt(np.sum(q[..., 1:] ** 2, axis=-1))
    half = np.arctan2(s, q[..., 0])
    small = s < 1e-12
    f = np.where(small, 2.0, 2.0 * half / np.where(small, 1.0, s))
    return q[..., 1:] * f[..., None]


def pose_from_ur_vector(x: ArrayLike) -> FloatArray:
    """Poses (..., 4, 4) from UR pose vectors ``[x, y, z, rx, ry, rz]`` (m, rad)."""
    x = as_float_array(x, "UR pose vector", (6,))
    return pose_from_rotvec(x[..., 3:], x[..., :3])


def ur_vector_from_pose(T: ArrayLike) -> FloatArray:
    """UR pose vectors ``[x, y, z, rx, ry, rz]`` (..., 6) of poses (..., 4, 4)."""
    T = np.asarray(T, dtype=np.float64)
    return np.concatenate([T[..., :3, 3], rotvec_from_matrix(T[..., :3, :3])], axis=-1)


def exp(xi: ArrayLike) -> FloatArray:
    """Exponential map: twists ``[omega, v]`` (..., 6) -> poses (..., 4, 4).

    ``R = Rodrigues(omega)``, ``p = V v`` with
    ``V = I + (1 - cos th)/th^2 [w]x + (th - sin th)/th^3 [w]x^2`` (series near 0).
    """
    xi = as_float_array(xi, "twist", (6,))
    w, v = xi[..., :3], xi[..., 3:]
    th2 = np.sum(w * w, axis=-1)
    th = np.sqrt(th2)
    small = th < 1e-4
    ths = np.where(small, 1.0, th)
    b = np.where(small, 0.5 - th2 / 24.0, (1.0 - np.cos(th)) / (ths * ths))
    c = np.where(small, 1.0 / 6.0 - th2 / 120.0, (th - np.sin(th)) / (ths * ths * ths))
    wv = np.cross(w, v)
    p = v + b[..., None] * wv + c[..., None] * np.cross(w, wv)
    return _pose_from_rt(_rotation_from_rotvec(w), p)


def log(T: ArrayLike) -> FloatArray:
    """Logarithm: poses (..., 4, 4) -> twists ``[omega, v]`` (..., 6), ``|omega| <= pi``.

    Uses the quaternion form (stable near 0 and near pi); at exactly pi the
    axis sign is that of the quaternion representative with ``w >= 0``.
    """
    T = as_float_array(T, "pose", (4, 4))
    shape = T.shape[:-2]
    flat = T.reshape(-1, 4, 4)
    rot, trans = _pose_components(flat)
    omega, v = ScrewPair.from_relative(_quat_from_rot(rot), trans).twist()
    return np.stack([*omega, *v], axis=-1).reshape(*shape, 6)


def _qt_from_matrices(T: FloatArray) -> tuple[tuple, tuple]:
    rot, trans = _pose_components(T)
    return _quat_from_rot(rot), trans


def load_kernel() -> None:
    """Load (or, the first time after an install, compile: a few seconds) the compiled
    geodesic kernel; the first geodesic of more than :data:`NUMPY_PAIRS` pairs does this
    by itself.  Importing numba and loading the kernel take about a second."""
    global _kernel
    if _kernel is None:
        from . import _se3_kernel

        _kernel = _se3_kernel  # set only once the module is complete (other threads)


def kernel_loaded() -> bool:
    """Whether the compiled geodesic kernel (numba) is loaded in this process."""
    return _kernel is not None


def uses_kernel(n: int) -> bool:
    """Whether a geodesic of ``n`` pairs runs in the compiled kernel: when it is loaded
    (then at every size: it takes ~1 us for one pair where numpy takes ~200 us), or when
    ``n > NUMPY_PAIRS`` (which loads it).  The kernel's results are the numpy path's bit
    for bit, so the choice changes the time only; a process that computes only small
    batches (the emulator's clock thread) never waits a second for numba."""
    return _kernel is not None or n > NUMPY_PAIRS


def _geodesic_kernel(A: FloatArray, B: FloatArray, t: FloatArray) -> FloatArray:
    """Geodesic of (n, 4, 4) pairs at (n,) parameters in the compiled kernel."""
    load_kernel()
    out = np.empty((A.shape[0], 4, 4))
    _kernel.geodesic_rows(  # type: ignore[union-attr]
        np.ascontiguousarray(A), np.ascontiguousarray(B), np.ascontiguousarray(t), out
    )
    return out


def geodesic(A: ArrayLike, B: ArrayLike, t: ArrayLike) -> FloatArray:
    """Screw-motion geodesic ``A exp(t log(inv(A) B))`` for poses (..., 4, 4).

    ``A`` and ``B`` broadcast against each other and against ``t`` (a float or
    an array of the batch shape); ``t`` may lie outside [0, 1].  Returns poses
    of the broadcast batch shape.  The result equals dual-quaternion ScLERP
    (smallest rotation angle; for a relative rotation of exactly pi the
    direction is that of the quaternion with ``w >= 0``).
    """
    A = np.asarray(A, dtype=np.float64)
    B = np.asarray(B, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)
    if A.shape[-2:] != (4, 4) or B.shape[-2:] != (4, 4):
        raise ValueError(f"geodesic: expected poses (..., 4, 4), got {A.shape} and {B.shape}")
    shape = np.broadcast_shapes(A.shape[:-2], B.shape[:-2], t.shape)
    n = int(np.prod(shape))
    A = np.broadcast_to(A, (*shape, 4, 4)).reshape(n, 4, 4)
    B = np.broadcast_to(B, (*shape, 4, 4)).reshape(n, 4, 4)
    scalar_t = t.ndim == 0
    if uses_kernel(n):
        return _geodesic_kernel(A, B, np.broadcast_to(t, shape).reshape(n)).reshape(*shape, 4, 4)
    tt = float(t) if scalar_t else np.broadcast_to(t, shape).reshape(n)
    out = np.empty((n, 4, 4))
    for lo in range(0, n, _CHUNK):
        hi = min(lo + _CHUNK, n)
        _geodesic_matrix_chunk(A[lo:hi], B[lo:hi], tt if scalar_t else tt[lo:hi], out[lo:hi])
    return out.reshape(*shape, 4, 4)


def geodesic_many(A: FloatArray, B: FloatArray, ts: Sequence[float]) -> list[FloatArray]:
    """``[geodesic(A, B, t) for t in ts]`` computing the logarithm of each pair once."""
    A = np.asarray(A, dtype=np.float64)
    B = np.asarray(B, dtype=np.float64)
    shape = np.broadcast_shapes(A.shape[:-2], B.shape[:-2])
    n = int(np.prod(shape))
    A = np.broadcast_to(A, (*shape, 4, 4)).reshape(n, 4, 4)
    B = np.broadcast_to(B, (*shape, 4, 4)).reshape(n, 4, 4)
    if uses_kernel(n):
        A, B = np.ascontiguousarray(A), np.ascontiguousarray(B)
        return [_geodesic_kernel(A, B, np.full(n, float(t))).reshape(*shape, 4, 4) for t in ts]
    outs = [np.empty((n, 4, 4)) for _ in ts]
    for lo in range(0, n, _CHUNK):
        hi = min(lo + _CHUNK, n)
        for t, out in zip(ts, outs, strict=True):
            _geodesic_matrix_chunk(A[lo:hi], B[lo:hi], float(t), out[lo:hi])
    return [o.reshape(*shape, 4, 4) for o in outs]


# ---------------------------------------------------------------------------
# the "qt" form: rows [qw, qx, qy, qz, px, py, pz] (..., 7), used internally by
# the subdivision engine so that a refinement converts matrices only twice
# ---------------------------------------------------------------------------


def qt_from_matrix(T: ArrayLike) -> FloatArray:
    """Poses (n, 4, 4) -> rows ``[qw, qx, qy, qz, px, py, pz]`` (n, 7), ``qw >= 0``."""
    T = np.asarray(T, dtype=np.float64).reshape(-1, 4, 4)
    out = np.empty((T.shape[0], 7))
    for lo in range(0, T.shape[0], _CHUNK):
        q, p = _qt_from_matrices(T[lo : lo + _CHUNK])
        out[lo : lo + _CHUNK] = np.stack([*q, *p], axis=-1)
    return out


def matrix_from_qt(x: ArrayLike) -> FloatArray:
    """Rows ``[qw, qx, qy, qz, px, py, pz]`` (n, 7) -> poses (n, 4, 4) (quaternions normalised)."""
    x = np.asarray(x, dtype=np.float64).reshape(-1, 7)
    out = np.empty((x.shape[0], 4, 4))
    for lo in range(0, x.shape[0], _CHUNK):
        c = np.ascontiguousarray(x[lo : lo + _CHUNK].T)
        inv = 1.0 / np.sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2] + c[3] * c[3])
        q = (c[0] * inv, c[1] * inv, c[2] * inv, c[3] * inv)
        _pose_from_components(_rot_from_quat(q), (c[4], c[5], c[6]), out[lo : lo + _CHUNK])
    return out


def _qt_split(x: FloatArray) -> tuple[tuple, tuple]:
    c = np.ascontiguousarray(x.T)
    return (c[0], c[1], c[2], c[3]), (c[4], c[5], c[6])


def _qt_join(q: tuple, p: tuple) -> FloatArray:
    return np.stack([*q, *p], axis=-1)


def qt_geodesic_many(a: FloatArray, b: FloatArray, ts: Sequence[float]) -> list[FloatArray]:
    """Geodesic points (n, 7) of qt pairs ``a``, ``b`` (n, 7) at each scalar t of ``ts``."""
    n = a.shape[0]
    outs = [np.empty((n, 7)) for _ in ts]
    for lo in range(0, n, _CHUNK):
        hi = min(lo + _CHUNK, n)
        qa, pa = _qt_split(a[lo:hi])
        qb, pb = _qt_split(b[lo:hi])
        pair = ScrewPair.from_qt(qa, pa, qb, pb)
        for t, out in zip(ts, outs, strict=True):
            q, p = pair.relative_at(float(t))
            out[lo:hi] = _qt_join(*_qt_compose(qa, pa, q, p))
    return outs


def qt_geodesic(a: FloatArray, b: FloatArray, t: ArrayLike) -> FloatArray:
    """Geodesic points (n, 7) of qt pairs at per-pair (n,) or scalar ``t``."""
    t = np.asarray(t, dtype=np.float64)
    if t.ndim == 0:
        return qt_geodesic_many(a, b, [float(t)])[0]
    qa, pa = _qt_split(a)
    qb, pb = _qt_split(b)
    q, p = ScrewPair.from_qt(qa, pa, qb, pb).relative_at(np.broadcast_to(t, (a.shape[0],)))
    return _qt_join(*_qt_compose(qa, pa, q, p))


def qt_log_at(base: FloatArray, x: FloatArray) -> FloatArray:
    """Left-invariant logarithm at ``base``: twists ``log(inv(base) x)`` (n, 6) of qt rows."""
    qa, pa = _qt_split(base)
    qb, pb = _qt_split(x)
    omega, v = ScrewPair.from_qt(qa, pa, qb, pb).twist()
    return np.stack([*omega, *v], axis=-1)


def qt_exp_at(base: FloatArray, xi: FloatArray) -> FloatArray:
    """``base @ exp(xi)`` for qt rows ``base`` (n, 7) and twists ``xi`` (n, 6)."""
    E = exp(xi)
    rel = qt_from_matrix(E)
    qa, pa = _qt_split(base)
    qr, pr = _qt_split(rel)
    return _qt_join(*_qt_compose(qa, pa, qr, pr))


def qt_flip(x: FloatArray) -> FloatArray:
    """Frames turned by pi about their own x axis (z and y reversed): ``T @ Rx(pi)``."""
    q, p = _qt_split(x)
    one = np.ones_like(q[0])
    zero = np.zeros_like(q[0])
    qf = _qmul(q, (zero, one, zero, zero))
    return _qt_join(qf, p)
