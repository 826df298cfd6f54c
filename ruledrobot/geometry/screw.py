"""Screw motions on quaternion/translation components: the algebra under :mod:`.se3`'s
geodesics, logarithm and conversions.

Everything here works on *component tuples* (each component a 1-D or N-D array, so a
chunk of poses is computed with whole-array operations): unit quaternions scalar first
``(w, x, y, z)``, translations ``(x, y, z)``, rotation matrices as their nine entries row
by row.  :class:`ScrewPair` decomposes a relative motion ``D = inv(A) B`` once (half angle,
unit axis, translation along and across the axis) and evaluates the uniform screw motion
at any ``t`` with one ``sin`` and one ``cos``; :func:`_geodesic_matrix_chunk` is the
geodesic of a chunk of pose pairs written into 4x4 matrices.  The compiled kernel
(:mod:`._se3_kernel`) runs the same formulas one pair at a time.  Derivation:
``docs/math.md``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .checks import FloatArray

__all__ = ["ScrewPair"]


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
