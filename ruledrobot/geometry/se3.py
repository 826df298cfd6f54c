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
path's results to rounding (a few float64 epsilons; not bit for bit where numpy's SIMD
``sin``/``cos``/``arctan2`` differ from libm's); once loaded it serves every batch (see
:func:`uses_kernel`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from ._arrays import cross3, dot3
from .checks import FloatArray, as_float_array, first_index
from .screw import (  # noqa: F401  (re-exported: the geodesic's kernels and tests read them here)
    ScrewPair,
    _geodesic_matrix_chunk,
    _pose_components,
    _pose_from_components,
    _qmul,
    _qrotate,
    _qt_compose,
    _quat_from_rot,
    _rot_from_quat,
)

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
    "transform_points",
    "ur_vector_from_pose",
    "uses_kernel",
    "validate_poses",
]

_CHUNK = 4096  # elements per chunk: ~40 component arrays of 32 kB stay in L2

#: Geodesics of more pairs than this load the compiled kernel (see :func:`uses_kernel`).
NUMPY_PAIRS = 10_000

_kernel = None  # ruledrobot.geometry._se3_kernel once loaded (numba)


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


def transform_points(T: ArrayLike, points: ArrayLike) -> FloatArray:
    """Points given in frames ``T``, in the frame ``T`` is given in: ``R p + t``.

    Parameters
    ----------
    T : (..., 4, 4) poses [m].
    points : (..., K, 3) points [m] in each pose's frame; the batch axes broadcast
        against ``T``'s, so (K, 3) points are the same points in every frame.

    Returns
    -------
    (..., K, 3) the points in the frame ``T`` is given in (the batch axes broadcast).
    """
    T = np.asarray(T, dtype=np.float64)
    p = np.asarray(points, dtype=np.float64)
    # R p as the sum of R's columns weighted by p's coordinates: three broadcast
    # multiply-adds, 2.5-4 times faster than einsum's generic loop for 3 x 3 (measured)
    R = T[..., None, :3, :3]  # (..., 1, 3, 3)
    return (R[..., 0] * p[..., 0, None] + R[..., 1] * p[..., 1, None]
            + R[..., 2] * p[..., 2, None] + T[..., None, :3, 3])  # fmt: skip


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
    """Load the compiled geodesic kernel (compiling it the first time after an install).

    Compiling takes a few seconds; the first geodesic of more than :data:`NUMPY_PAIRS` pairs
    does this by itself.  Importing numba and loading the kernel take about a second.
    """
    global _kernel
    if _kernel is None:
        from . import _se3_kernel

        _kernel = _se3_kernel  # set only once the module is complete (other threads)


def kernel_loaded() -> bool:
    """Whether the compiled geodesic kernel (numba) is loaded in this process."""
    return _kernel is not None


def uses_kernel(n: int) -> bool:
    """Whether a geodesic of ``n`` pairs runs in the compiled kernel.

    When it is loaded (then at every size: it takes ~1 us for one pair where numpy takes ~200
    us), or when ``n > NUMPY_PAIRS`` (which loads it). The kernel's results are the numpy
    path's bit for bit, so the choice changes the time only; a process that computes only small
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
