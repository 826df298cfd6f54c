"""Compiled (numba) kernel of :func:`ruledrobot.geometry.se3.geodesic` on 4x4 matrices.

:func:`geodesic_rows` is the numpy chunk ``screw._geodesic_matrix_chunk`` written as one
loop over the pairs: the same formulas, the same operations in the same order, every
intermediate a scalar in a register instead of a 32 kB temporary.  Its results agree with
the numpy path to rounding, not bit for bit on every CPU: the kernel calls the C library's
``sin``, ``cos`` and ``atan2`` while numpy may use its own SIMD versions (AVX-512, ARM
SVE; within an ulp or two), and LLVM may vectorise the loop.  The test
``tests/geometry/test_se3_kernel.py`` states the bound (64 float64 epsilons per unit of
``1 + |t|``, per metre for the translation; 2.3 measured) and the one exact identity that
holds everywhere (``t = 0`` gives ``A``).  No ``fastmath``: no fused multiply-adds by
choice.  Where the numpy chunk selects with ``np.where`` the kernel branches; both select
the same value.

Imported by the first geodesic of more than ``se3.NUMPY_PAIRS`` pairs (or
``se3.load_kernel``), so that ``import ruledrobot`` does not load numba; compiled once
and cached next to this file (``cache=True``).
"""

from __future__ import annotations

import math

import numba as nb
from numba import types

_SMALL = 1e-6  # sin(phi) below this: the series of sin(t phi)/sin(phi) (screw.ScrewPair)

# inputs read-only (broadcast views are), output writable; writable inputs convert
_POSES_IN = types.Array(types.float64, 3, "C", readonly=True)
_T_IN = types.Array(types.float64, 1, "C", readonly=True)
_SIG = types.void(_POSES_IN, _POSES_IN, _T_IN, types.float64[:, :, ::1])


@nb.njit(_SIG, cache=True, nogil=True, error_model="numpy")
def geodesic_rows(A, B, t, out):
    """Compute ``out[i] = A[i] exp(t[i] log(inv(A[i]) B[i]))`` row by row.

    For contiguous (n, 4, 4) ``A``, ``B``, ``out`` and (n,) ``t``; the formulas of
    ``screw._geodesic_matrix_chunk``.
    """
    for i in range(A.shape[0]):
        a = A[i]
        b = B[i]
        ti = t[i]
        a00, a01, a02, pa0 = a[0, 0], a[0, 1], a[0, 2], a[0, 3]
        a10, a11, a12, pa1 = a[1, 0], a[1, 1], a[1, 2], a[1, 3]
        a20, a21, a22, pa2 = a[2, 0], a[2, 1], a[2, 2], a[2, 3]
        b00, b01, b02, pb0 = b[0, 0], b[0, 1], b[0, 2], b[0, 3]
        b10, b11, b12, pb1 = b[1, 0], b[1, 1], b[1, 2], b[1, 3]
        b20, b21, b22, pb2 = b[2, 0], b[2, 1], b[2, 2], b[2, 3]
        # D = R_A^T R_B, translation R_A^T (p_B - p_A)
        m00 = a00 * b00 + a10 * b10 + a20 * b20
        m01 = a00 * b01 + a10 * b11 + a20 * b21
        m02 = a00 * b02 + a10 * b12 + a20 * b22
        m10 = a01 * b00 + a11 * b10 + a21 * b20
        m11 = a01 * b01 + a11 * b11 + a21 * b21
        m12 = a01 * b02 + a11 * b12 + a21 * b22
        m20 = a02 * b00 + a12 * b10 + a22 * b20
        m21 = a02 * b01 + a12 * b11 + a22 * b21
        m22 = a02 * b02 + a12 * b12 + a22 * b22
        dx, dy, dz = pb0 - pa0, pb1 - pa1, pb2 - pa2
        px = a00 * dx + a10 * dy + a20 * dz
        py = a01 * dx + a11 * dy + a21 * dz
        pz = a02 * dx + a12 * dy + a22 * dz
        # Shepperd (screw._quat_from_rot): the row of 4 q q^T with the largest diagonal
        t0 = 1.0 + m00 + m11 + m22
        t1 = 1.0 + m00 - m11 - m22
        t2 = 1.0 - m00 + m11 - m22
        t3 = 1.0 - m00 - m11 + m22
        best = t0
        row = 0
        if t1 > best:
            best = t1
            row = 1
        if t2 > best:
            best = t2
            row = 2
        if t3 > best:
            row = 3
        if row == 3:
            w, x, y, z = m10 - m01, m02 + m20, m12 + m21, t3
        elif row == 2:
            w, x, y, z = m02 - m20, m01 + m10, t2, m12 + m21
        elif row == 1:
            w, x, y, z = m21 - m12, t1, m01 + m10, m02 + m20
        else:
            w, x, y, z = t0, m21 - m12, m02 - m20, m10 - m01
        scale = math.copysign(1.0, w) / math.sqrt(w * w + x * x + y * y + z * z)
        w, x, y, z = w * scale, x * scale, y * scale, z * scale
        # the screw (screw.ScrewPair.from_relative)
        sign = math.copysign(1.0, w)
        w, x, y, z = w * sign, x * sign, y * sign, z * sign
        s = math.sqrt(x * x + y * y + z * z)
        phi = math.atan2(s, w)
        inv_s = 1.0 / (s if s > 0.0 else 1.0)
        ux, uy, uz = x * inv_s, y * inv_s, z * inv_s
        dot = ux * px + uy * py + uz * pz
        ax_, ay_, az_ = dot * ux, dot * uy, dot * uz
        qx, qy, qz = px - ax_, py - ay_, pz - az_
        cx, cy, cz = uy * qz - uz * qy, uz * qx - ux * qz, ux * qy - uy * qx
        # exp(t log D) (screw.ScrewPair.relative_at)
        tphi = ti * phi
        sn = math.sin(tphi)
        cs = math.cos(tphi)
        cos_rest = w * cs + s * sn
        sin_rest = s * cs - w * sn
        if s < _SMALL:
            ratio = ti * (1.0 + (1.0 - ti * ti) * phi * phi / 6.0)
        else:
            ratio = sn / s
        rc, rs = ratio * cos_rest, ratio * sin_rest
        tx = ti * ax_ + rc * qx - rs * cx
        ty = ti * ay_ + rc * qy - rs * cy
        tz = ti * az_ + rc * qz - rs * cz
        qw, qx_, qy_, qz_ = cs, sn * ux, sn * uy, sn * uz
        # rotation of q(t) (screw._rot_from_quat), then A's rotation times it
        xx, yy, zz = qx_ * qx_, qy_ * qy_, qz_ * qz_
        xy, xz, yz = qx_ * qy_, qx_ * qz_, qy_ * qz_
        wx, wy, wz = qw * qx_, qw * qy_, qw * qz_
        r00 = 1.0 - 2.0 * (yy + zz)
        r01 = 2.0 * (xy - wz)
        r02 = 2.0 * (xz + wy)
        r10 = 2.0 * (xy + wz)
        r11 = 1.0 - 2.0 * (xx + zz)
        r12 = 2.0 * (yz - wx)
        r20 = 2.0 * (xz - wy)
        r21 = 2.0 * (yz + wx)
        r22 = 1.0 - 2.0 * (xx + yy)
        o = out[i]
        o[0, 0] = a00 * r00 + a01 * r10 + a02 * r20
        o[0, 1] = a00 * r01 + a01 * r11 + a02 * r21
        o[0, 2] = a00 * r02 + a01 * r12 + a02 * r22
        o[0, 3] = pa0 + a00 * tx + a01 * ty + a02 * tz
        o[1, 0] = a10 * r00 + a11 * r10 + a12 * r20
        o[1, 1] = a10 * r01 + a11 * r11 + a12 * r21
        o[1, 2] = a10 * r02 + a11 * r12 + a12 * r22
        o[1, 3] = pa1 + a10 * tx + a11 * ty + a12 * tz
        o[2, 0] = a20 * r00 + a21 * r10 + a22 * r20
        o[2, 1] = a20 * r01 + a21 * r11 + a22 * r21
        o[2, 2] = a20 * r02 + a21 * r12 + a22 * r22
        o[2, 3] = pa2 + a20 * tx + a21 * ty + a22 * tz
        o[3, 0] = 0.0
        o[3, 1] = 0.0
        o[3, 2] = 0.0
        o[3, 3] = 1.0
