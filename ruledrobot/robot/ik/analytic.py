r"""Analytic inverse kinematics of Universal Robots arms (all 8 solutions).

Geometry (standard DH, UR convention, ``alpha = [pi/2, 0, 0, pi/2, -pi/2, 0]``,
``a1 = a4 = a5 = a6 = 0``; ``d2``, ``d3`` may be non-zero and are absorbed into
``d4``).  The derivation follows Hawkins, *Analytic Inverse Kinematics for the
Universal Robots UR-5/UR-10 Arms* (2013) and Andersen, *Kinematics of a UR5*
(Aalborg, 2018), but replaces every division by ``sin q5`` and the
Andersen formula for ``q2 + q3 + q4`` (degenerate at ``q5 = +-pi/2, q6 = 0``)
by the atan2 forms below.  Write ``x6, y6, z6, p`` for the columns of the
flange pose ``T_06`` and ``x1 = (c1, s1, 0)``, ``z1 = (s1, -c1, 0)``,
``y1 = (0, 0, 1)`` for the axes of DH frame 1.

1. *Shoulder.*  The origin of frame 5, ``p5 = p - d6 z6``, satisfies
   ``p5 . z1 = d4``.  With ``phi = atan2(p5y, p5x)``, ``r^2 = p5x^2 + p5y^2``,
   ``rho = sqrt(r^2 - d4^2)``: ``q1 = phi + pi/2 +- atan2(rho, d4)``
   (``(c1, s1)`` is formed algebraically, exactly unit length).
   No solution when ``r < |d4|`` (the wrist point is inside the cylinder of
   radius ``d4`` about the base z axis).
2. *Wrist.*  ``x6 . z1 = s5 c6``, ``y6 . z1 = -s5 s6``, ``z6 . z1 = c5``, so
   ``q5 = atan2(+-w, c5)`` with ``w = |(x6 . z1, y6 . z1)| = |sin q5|`` and
   ``q6 = atan2(-+ y6 . z1, +- x6 . z1)``.  At the wrist singularity
   ``w < 1e-12`` only ``q4 +- q6`` is determined: ``q6`` is set to a seed
   (``q6_seed``, default 0) and, if the elbow cannot reach with that seed, to
   the value nearest the seed for which it can (see :func:`_rescue_wrist`).
   Near the singularity (``w < 1e-6``) q6 is ill-conditioned (error ~1e-16/w)
   and the error moves the elbow target by ``d5`` times as much; when that
   pushes a stretched or folded elbow out of reach, the same rescue turns q6
   by the smallest ``delta`` that brings it back, accepted when the pose error
   this costs (about ``w |delta|``) is below 1e-11.
3. *Sum q2 + q3 + q4.*  ``s6 x6 + c6 y6 = -z4`` holds for every ``q5``, and
   ``z4 = sin(q234) x1 - cos(q234) y1``, so
   ``q234 = atan2(z4 . x1, -z4 . y1)``, well defined for every configuration.
4. *Elbow.*  The origin of frame 3 in the arm plane (coordinates along x1
   and y1, relative to the shoulder point ``(0, 0, d1)``) is
   ``(X, Y) = (p5 . x1 - d5 sin q234, p5z - d1 + d5 cos q234)``;
   ``c3 = (X^2 + Y^2 - a2^2 - a3^2) / (2 a2 a3)``, ``q3 = +-atan2(sqrt(1 - c3^2), c3)``,
   ``q2 = atan2(Y k1 - X k2, X k1 + Y k2)`` with ``k1 = a2 + a3 c3``,
   ``k2 = a3 s3``, and ``q4 = q234 - q2 - q3``.  No solution when
   ``|c3| > 1`` (beyond a relative tolerance of 1e-10, below which the
   stretched/folded elbow is returned; the pose error this admits is < 1e-10 m).
5. The second wrist branch is the first one turned by the wrist flip
   ``(q4, q5, q6) -> (q4 + pi, -q5, q6 + pi)``: ``z4`` changes sign, so it
   has its own elbow solutions.

Branch numbering (same order as ``ur_analytic_ik``)::

    index = 4 * shoulder + 2 * wrist + elbow
    shoulder 0: q1 = phi + pi/2 + atan2(rho, d4)    1: ... - atan2(rho, d4)
    wrist    0: sin q5 >= 0                         1: sin q5 <= 0
    elbow    0: sin q3 >= 0                         1: sin q3 <= 0

Singularity factors of a solution (``det J = a2 a3 sin q3 sin q5 s`` for the
6x6 geometric Jacobian, verified in the tests):

* wrist ``|sin q5|`` (joints 2, 3, 4, 6 parallel),
* elbow ``|sin q3|`` (arm stretched or folded),
* shoulder ``|s|`` [m], ``s = p5 . x1 = a2 c2 + a3 c23 + d5 sin q234``: the distance
  of the wrist point ``p5`` from the plane spanned by the base z axis and the
  shoulder axis z1 (zero when ``p5`` lies on the cylinder ``r = d4``),

and the scalar measure ``|sin q3 sin q5 s| / (|a2| + |a3| + |d5|)`` in [0, 1],
i.e. ``|det J| / (|a2 a3| (|a2| + |a3| + |d5|))``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ...geometry.angles import wrap_angle
from .._checks import FloatArray

WRIST_EPS = 1e-12  # |sin q5| below which the wrist is treated as singular
RESCUE_W = 1e-6  # |sin q5| below which a missed elbow may be rescued by turning q6 ...
RESCUE_ERR = 1e-11  # ... if the pose error that costs, |sin q5| |delta q6|, stays below this
ELBOW_TOL = 1e-10  # |c3| up to 1 + ELBOW_TOL is clamped to the stretched/folded elbow
SHOULDER_TOL = 1e-10  # r^2 >= d4^2 (1 - SHOULDER_TOL) is clamped to the shoulder boundary
_CHUNK = 4096  # poses per chunk (about 60 work arrays of 32 kB stay in L2)


class URGeometry(NamedTuple):
    """The six numbers the UR closed form needs (metres).  ``d4`` includes ``d2 + d3``."""

    d1: float
    a2: float
    a3: float
    d4: float
    d5: float
    d6: float


@dataclass(frozen=True, eq=False)
class IKSolutions:
    """All analytic IK solutions of a batch of poses, with singularity information.

    Attributes (batch shape ``S`` of the input poses)
    ----------
    q : (*S, 8, 6) joint positions [rad] in (-pi, pi], NaN rows where a branch
        has no solution.  Branch index ``4 * shoulder + 2 * wrist + elbow``.
    valid : (*S, 8) bool, True where the row is a solution.
    wrist : (*S, 8) ``|sin q5|``.
    elbow : (*S, 8) ``|sin q3|``.
    shoulder : (*S, 8) distance [m] of the wrist point p5 from the plane of the
        base z axis and the shoulder axis (see the module docstring).
    measure : (*S, 8) scaled ``|det J|`` in [0, 1]: ``wrist * elbow * shoulder /
        (|a2| + |a3| + |d5|)``; 0 at any singularity.
    The factors are NaN where ``valid`` is False.
    """

    q: FloatArray
    valid: np.ndarray
    wrist: FloatArray
    elbow: FloatArray
    shoulder: FloatArray
    measure: FloatArray

    def __getitem__(self, index: int | slice | tuple) -> IKSolutions:
        """The solutions of the poses ``index`` picks on the batch axes (every field alike)."""
        return dataclasses.replace(self, **{f.name: getattr(self, f.name)[index]
                                            for f in dataclasses.fields(self)})  # fmt: skip


def _atan2(y: FloatArray, x: FloatArray) -> FloatArray:
    """``arctan2`` in (-pi, pi]: -pi (a tiny negative or -0.0 ``y``, negative ``x``) becomes pi."""
    t = np.arctan2(y, x)
    return np.where(t > -np.pi, t, np.pi)


def _rescue_wrist(
    g: URGeometry, idx: np.ndarray, Px: FloatArray, Py: FloatArray, ux: FloatArray, uy: FloatArray
) -> tuple[FloatArray, FloatArray, np.ndarray]:
    """At a singular wrist, choose the direction of z4 so that the elbow reaches.

    With ``q5 = 0`` or ``pi`` the tool axis is normal to the arm plane and
    ``z4`` may point anywhere in that plane (``q6`` free).  In arm-plane
    coordinates the elbow target is ``P - d5 u`` (``P`` the wrist point, ``u``
    the planar z4); its distance ``D`` from the shoulder must lie in
    ``[| |a2| - |a3| |, |a2| + |a3|]``.  The seed direction ``u`` (from
    ``q6_seed``) missed that range; take the target distance ``D*`` = the seed's
    distance clamped into the range and solve ``|P - d5 u| = D*`` for the unit
    vector ``u`` nearest the seed: ``P . u = (|P|^2 + d5^2 - D*^2) / (2 d5)``.

    Returns the new ``(ux, uy)`` for the entries ``idx`` and a mask of those for
    which some direction works (the others stay unreachable).
    """
    px, py = Px[idx], Py[idx]
    sx, sy = ux[idx], uy[idx]
    dmin = abs(abs(g.a2) - abs(g.a3))
    dmax = abs(g.a2) + abs(g.a3)
    ex, ey = px - g.d5 * sx, py - g.d5 * sy
    dseed = np.sqrt(ex * ex + ey * ey)
    dt = np.clip(dseed, dmin, dmax)
    R2 = px * px + py * py
    R = np.sqrt(R2)
    k = (R2 + g.d5 * g.d5 - dt * dt) / (2.0 * g.d5)
    ok = (R > 0.0) & (np.abs(k) <= R * (1.0 + ELBOW_TOL))
    Rs = np.where(R > 0.0, R, 1.0)
    cg = np.clip(k / Rs, -1.0, 1.0)
    sg = np.sqrt((1.0 - cg) * (1.0 + cg))
    hx, hy = px / Rs, py / Rs
    # candidates u = cg * h +- sg * h_perp, h_perp = (-hy, hx); take the one nearer the seed
    side = np.where(sg * (sy * hx - sx * hy) >= 0.0, 1.0, -1.0)
    nx = cg * hx - side * sg * hy
    ny = cg * hy + side * sg * hx
    return np.where(ok, nx, sx), np.where(ok, ny, sy), ok


def ur_ik_chunk(
    g: URGeometry, T: FloatArray, seed: FloatArray, out: FloatArray, info: FloatArray | None
) -> None:
    """Fill ``out`` (n, 8, 6) with the 8 solutions (DH angles theta) of flange poses ``T``.

    ``T`` (n, 4, 4) flange poses in the DH base frame (validated, finite);
    ``seed`` (n,) value of theta6 used at a singular wrist; ``info`` optional
    (n, 8, 3) array for the factors ``|sin q5|, |sin q3|, |s|``.  NaN rows
    mark branches without a solution.  No floating-point warnings: every
    square root and division is guarded and NaN enters only through the final
    additions, never a comparison.  Angles are in (-pi, pi]: :func:`_atan2`
    and :func:`wrap_angle` map -pi to pi.
    """
    n = T.shape[0]
    d1, a2, a3, d4, d5, d6 = g
    c = np.ascontiguousarray(T.reshape(n, 16)[:, :12].T)  # rows of T, row-major
    xx, yx, zx, px, xy, yy, zy, py, xz, yz, zz, pz = c
    qo = out.reshape(n, 48)
    fo = None if info is None else info.reshape(n, 24)

    # 1. shoulder
    p5x = px - d6 * zx
    p5y = py - d6 * zy
    p5z = pz - d6 * zz
    r2 = p5x * p5x + p5y * p5y
    rho2 = r2 - d4 * d4
    ok_s = rho2 >= -SHOULDER_TOL * d4 * d4
    rho = np.sqrt(np.maximum(rho2, 0.0))
    norm2 = r2 * (rho * rho + d4 * d4)
    deg = norm2 <= 0.0  # p5 on the base axis and d4 == 0: q1 is free, take q1 = 0
    inv_n = 1.0 / np.sqrt(np.where(deg, 1.0, norm2))
    Py = p5z - d1
    a2a3 = 2.0 * a2 * a3
    ss = a2 * a2 + a3 * a3

    for si, sgn1 in enumerate((1.0, -1.0)):
        c1 = np.where(deg, 1.0, -(p5y * d4 + sgn1 * p5x * rho) * inv_n)
        s1 = np.where(deg, 0.0, (p5x * d4 - sgn1 * p5y * rho) * inv_n)
        th1 = _atan2(s1, c1)
        Px = p5x * c1 + p5y * s1  # signed shoulder factor

        # 2. wrist (branch sin q5 >= 0)
        ax = xx * s1 - xy * c1  # x6 . z1 =  s5 c6
        by = yx * s1 - yy * c1  # y6 . z1 = -s5 s6
        c5 = zx * s1 - zy * c1  # z6 . z1 =  c5
        w = np.sqrt(ax * ax + by * by)
        sing = w < WRIST_EPS
        inv_w = 1.0 / np.where(sing, 1.0, w)
        s6 = -by * inv_w
        c6 = ax * inv_w
        any_sing = bool(sing.any())
        if any_sing:  # q6 free: use the seed
            ids = np.flatnonzero(sing)
            s6[ids] = np.sin(seed[ids])
            c6[ids] = np.cos(seed[ids])
        th5 = np.arctan2(w, c5)
        th5m = np.where(th5 < np.pi, -th5, th5)  # q5 = pi stays pi, not -pi
        th6 = _atan2(s6, c6)

        # 3. q2 + q3 + q4 from z4 = -(s6 x6 + c6 y6)
        z4x = -(s6 * xx + c6 * yx)
        z4y = -(s6 * xy + c6 * yy)
        z4z = -(s6 * xz + c6 * yz)
        ux = z4x * c1 + z4y * s1  # planar z4 = (sin q234, -cos q234)
        uy = z4z

        for wi, sgn5 in enumerate((1.0, -1.0)):
            bux, buy = sgn5 * ux, sgn5 * uy
            t6 = th6 if wi == 0 else wrap_angle(th6 + np.pi)
            t5 = th5 if wi == 0 else th5m
            # 4. elbow
            X = Px - d5 * bux
            Y = Py - d5 * buy
            cc = (X * X + Y * Y - ss) / a2a3
            ok_e = np.abs(cc) <= 1.0 + ELBOW_TOL
            rescue = ~ok_e & ok_s & (w < RESCUE_W)
            if d5 != 0.0 and rescue.any():
                idx = np.flatnonzero(rescue)
                nx, ny, ok_r = _rescue_wrist(g, idx, Px, Py, bux, buy)
                # turning q6 by delta at |sin q5| = w moves the pose by about w |delta|
                delta = np.arctan2(bux[idx] * ny - buy[idx] * nx, bux[idx] * nx + buy[idx] * ny)
                ok_r &= w[idx] * np.abs(delta) <= RESCUE_ERR
                nx = np.where(ok_r, nx, bux[idx])
                ny = np.where(ok_r, ny, buy[idx])
                bux, buy = bux.copy(), buy.copy()
                bux[idx], buy[idx] = nx, ny
                # theta6 from z4 = -(s6 x6 + c6 y6):  s6 = -z4 . x6, c6 = -z4 . y6
                z4 = (nx * c1[idx], nx * s1[idx], ny)
                s6n = -(z4[0] * xx[idx] + z4[1] * xy[idx] + z4[2] * xz[idx])
                c6n = -(z4[0] * yx[idx] + z4[1] * yy[idx] + z4[2] * yz[idx])
                t6 = t6.copy()
                t6[idx] = np.where(ok_r, _atan2(s6n, c6n), t6[idx])
                X = Px - d5 * bux
                Y = Py - d5 * buy
                cc = (X * X + Y * Y - ss) / a2a3
                ok_e = np.abs(cc) <= 1.0 + ELBOW_TOL
            t234 = np.arctan2(bux, -buy)
            cc = np.clip(cc, -1.0, 1.0)
            s3 = np.sqrt((1.0 - cc) * (1.0 + cc))
            th3 = np.arctan2(s3, cc)
            k1 = a2 + a3 * cc
            k2 = a3 * s3
            ok = ok_s & ok_e
            nan = np.where(ok, 0.0, np.nan)  # added to every column: NaN rows, no warnings
            th1n = th1 + nan
            t5n = t5 + nan
            t6n = t6 + nan
            for ei in range(2):
                b = 4 * si + 2 * wi + ei
                k2s = k2 if ei == 0 else -k2
                th2 = _atan2(Y * k1 - X * k2s, X * k1 + Y * k2s)
                t3 = th3 if ei == 0 else np.where(th3 < np.pi, -th3, th3)
                th4 = wrap_angle(t234 - th2 - t3)
                o = 6 * b
                qo[:, o] = th1n
                qo[:, o + 1] = th2 + nan
                qo[:, o + 2] = t3 + nan
                qo[:, o + 3] = th4 + nan
                qo[:, o + 4] = t5n
                qo[:, o + 5] = t6n
                if fo is not None:
                    fo[:, 3 * b] = w + nan
                    fo[:, 3 * b + 1] = s3 + nan
                    fo[:, 3 * b + 2] = np.abs(Px) + nan
