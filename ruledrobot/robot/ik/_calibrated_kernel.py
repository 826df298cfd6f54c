"""Compiled (numba) kernels of :mod:`ruledrobot.robot.ik.calibrated`: seeds and Newton finish.

:func:`seeds`: the nominal closed form (``analytic_ik``'s formulas) of every pose, with
the fallback geometries for the branches it misses, in scalar code.

:func:`refine`: the damped Newton / Levenberg-Marquardt iteration of every (pose, branch)
pair on the calibrated chain (the rules of :mod:`~ruledrobot.robot.ik.calibrated`).  One
pair's iteration is a chain of dependent operations (5 frames, 4 divisions in the
elimination), so the kernel iterates ``_L`` pairs side by side: their state lives in one
flat array ``V`` (rows of ``_L`` lanes, constant offsets), and the three costly parts of
a round - sines and cosines, the residual, the damped step - are loops over the lanes
without branches, which LLVM turns into vector code (two AVX2 vectors per row).  The
bookkeeping (convergence, best iterate, stall, budget, rejected steps) is per lane; a
lane whose pair finishes takes the next pair at once.  Measured on the 2-core machine:
the lanes take the iteration from 3.1-3.4x to 1.2-1.5x the time of the nominal closed
form (numpy, all 8 branches), against the same code one pair at a time.

Sines and cosines: Cody-Waite reduction by pi/2 and the fdlibm minimax kernels, the
quadrant applied with arithmetic instead of branches (within 1 ulp of libm on 1e6
random angles in [-10, 10]).

Imported by the first calibrated IK of more than ``calibrated_ik.NUMPY_POSES`` poses (or
``calibrated_ik.load_kernels``), so that ``import ruledrobot`` does not load numba;
compiled once and cached next to this file (``cache=True``).  The cache is checked against
this file alone (numba does not see a change in a function or a global of another module
it compiled in), so the kernels import nothing of the project: the closed form's formulas
and tolerances are ``analytic_ik``'s written again in scalar code, and
``tests/robot/test_calibrated_kernel.py`` holds the two to the same seeds.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

_MAX_STEP = 0.5  # rad: a longer step is shortened (trust region)
_LAMBDA0 = 1e-6  # damping factor: mu^2 = lambda * |e|
_REJECT = 1e3  # a residual above this many times the best halves the step
_STALL = 8  # iterations without reducing the best residual by 30 % before a pair is given up
_TWO_PI = 2.0 * math.pi

_jit = nb.njit(cache=True, nogil=True, error_model="numpy", fastmath={"contract"})

# fdlibm (k_sin.c, k_cos.c, e_rem_pio2.c)
_INV_PIO2 = 6.36619772367581382433e-01
_PIO2_1 = 1.57079632673412561417e00  # first 33 bits of pi/2
_PIO2_1T = 6.07710050650619224932e-11  # pi/2 - _PIO2_1
_S1, _S2, _S3 = -1.66666666666666324348e-01, 8.33333333332248946124e-03, -1.98412698298579493134e-04
_S4, _S5, _S6 = 2.75573137070700676789e-06, -2.50507602534068634195e-08, 1.58969099521155010221e-10
_C1, _C2, _C3 = 4.16666666666666019037e-02, -1.38888888888741095749e-03, 2.48015872894767294178e-05
_C4, _C5, _C6 = -2.75573143513906633035e-07, 2.08757232129817482790e-09, -1.13596475577881948265e-11


_L = 8  # lanes: pairs iterated side by side (two AVX2 vectors of doubles)

# rows of the lane state V (row-major (rows, _L), flat): one array, constant offsets, so
# that the loops over the lanes vectorise
_TH, _C, _S, _BEST, _STEP, _DQ = 0, 6, 12, 18, 24, 30  # 6 rows each
_TG = 36  # 12 rows: the target flange pose's rows (row-major 3x4)
_FR = 48  # 30 rows: axis and origin of frames 1..5 in the frame turned with joint 1
_E = 78  # 6 rows: the error twist at p5, elimination order
_POS, _ROT, _MU2 = 84, 85, 86
_ROWS = 87


@_jit
def _sincos_row(V, j):
    """``V[C + j], V[S + j] = cos, sin V[TH + j]`` in every lane, branch-free."""
    for ln in range(_L):
        x = V[(_TH + j) * _L + ln]
        k = np.floor(x * _INV_PIO2 + 0.5)
        r = (x - k * _PIO2_1) - k * _PIO2_1T
        z = r * r
        sn = r + r * z * (_S1 + z * (_S2 + z * (_S3 + z * (_S4 + z * (_S5 + z * _S6)))))
        hz = 0.5 * z
        w = 1.0 - hz
        pc = _C1 + z * (_C2 + z * (_C3 + z * (_C4 + z * (_C5 + z * _C6))))
        cs = w + (((1.0 - w) - hz) + z * z * pc)
        # x = q pi/2 + r, q = k mod 4: swap for odd q; cos < 0 for q = 1, 2, sin for 2, 3
        q = k - 4.0 * np.floor(0.25 * k)
        odd = q - 2.0 * np.floor(0.5 * q)
        cq = odd * sn + (1.0 - odd) * cs
        sq = odd * cs + (1.0 - odd) * sn
        V[(_C + j) * _L + ln] = cq * (1.0 - 2.0 * (q * (3.0 - q) * 0.5))  # -1 for q = 1, 2
        V[(_S + j) * _L + ln] = sq * (1.0 - 2.0 * np.floor(0.5 * q))  # -1 for q = 2, 3


@_jit
def _sincos(V):
    """Cos and sin of the six angles of every lane (written out: the lane loops vectorise)."""
    _sincos_row(V, 0)
    _sincos_row(V, 1)
    _sincos_row(V, 2)
    _sincos_row(V, 3)
    _sincos_row(V, 4)
    _sincos_row(V, 5)


@_jit
def _wrap(x):
    """``geometry.angles.wrap_angle`` of one angle: the principal value in (-pi, pi]."""
    y = x - _TWO_PI * np.ceil((x - math.pi) / _TWO_PI)
    y = min(y, math.pi)
    return y if y > -math.pi else math.pi


@_jit
def _turn(c, s, u0, u1, u2, v0, v1, v2):
    """Axes ``u``, ``v`` of a frame turned by the angle of cos ``c``, sin ``s`` about the third
    axis: ``c u + s v``, ``c v - s u``."""
    return (c * u0 + s * v0, c * u1 + s * v1, c * u2 + s * v2,
            c * v0 - s * u0, c * v1 - s * u1, c * v2 - s * u2)  # fmt: skip


@_jit
def _joint(V, ln, j, d, a, ca, sa, frame):
    """Frame ``j + 1`` from frame ``j`` (axes x, y, z and origin p, 12 numbers) of lane
    ``ln``."""
    x0, x1, x2, y0, y1, y2, z0, z1, z2, p0, p1, p2 = frame
    cj = V[(_C + j) * _L + ln]
    sj = V[(_S + j) * _L + ln]
    xr0, xr1, xr2, yr0, yr1, yr2 = _turn(cj, sj, x0, x1, x2, y0, y1, y2)  # Rz(theta)
    p0 = p0 + d * z0 + a * xr0
    p1 = p1 + d * z1 + a * xr1
    p2 = p2 + d * z2 + a * xr2
    y0, y1, y2, z0, z1, z2 = _turn(ca, sa, yr0, yr1, yr2, z0, z1, z2)  # Rx(alpha)
    return xr0, xr1, xr2, y0, y1, y2, z0, z1, z2, p0, p1, p2


@_jit
def _stored(V, ln, k, frame):
    """Store the axis and origin of frame ``k + 1`` of lane ``ln``; returns the frame."""
    z0, z1, z2, p0, p1, p2 = frame[6], frame[7], frame[8], frame[9], frame[10], frame[11]
    V[(_FR + 6 * k) * _L + ln] = z0
    V[(_FR + 6 * k + 1) * _L + ln] = z1
    V[(_FR + 6 * k + 2) * _L + ln] = z2
    V[(_FR + 6 * k + 3) * _L + ln] = p0
    V[(_FR + 6 * k + 4) * _L + ln] = p1
    V[(_FR + 6 * k + 5) * _L + ln] = p2
    return frame


@_jit
def _forward(V, ch):
    """Residual of every lane: the calibrated chain (``ch`` (4, 6): d, a, cos alpha,
    sin alpha) in the frame turned with joint 1; frames 1..5, the error twist at the wrist
    point p5 in the elimination order (v5 y, omega x, omega z, omega y, v5 x, v5 z) and the
    position and rotation errors go to ``V``."""
    d0, d1, d2, d3, d4, d5 = ch[0, 0], ch[0, 1], ch[0, 2], ch[0, 3], ch[0, 4], ch[0, 5]
    a0, a1, a2, a3, a4, a5 = ch[1, 0], ch[1, 1], ch[1, 2], ch[1, 3], ch[1, 4], ch[1, 5]
    c0, c1, c2, c3, c4, c5 = ch[2, 0], ch[2, 1], ch[2, 2], ch[2, 3], ch[2, 4], ch[2, 5]
    s0, s1, s2, s3, s4, s5 = ch[3, 0], ch[3, 1], ch[3, 2], ch[3, 3], ch[3, 4], ch[3, 5]
    for ln in range(_L):
        k1 = V[_C * _L + ln]
        n1 = V[_S * _L + ln]
        t0, t1, t3 = V[_TG * _L + ln], V[(_TG + 1) * _L + ln], V[(_TG + 3) * _L + ln]
        t4, t5, t7 = V[(_TG + 4) * _L + ln], V[(_TG + 5) * _L + ln], V[(_TG + 7) * _L + ln]
        # target columns in the frame turned with joint 1 (Rz(-theta1) applied)
        xt0 = k1 * t0 + n1 * t4
        xt1 = k1 * t4 - n1 * t0
        xt2 = V[(_TG + 8) * _L + ln]
        yt0 = k1 * t1 + n1 * t5
        yt1 = k1 * t5 - n1 * t1
        yt2 = V[(_TG + 9) * _L + ln]
        pt0 = k1 * t3 + n1 * t7
        pt1 = k1 * t7 - n1 * t3
        pt2 = V[(_TG + 11) * _L + ln]
        # frame 1: Tz(d1) Tx(a1) Rx(alpha1); frames 2..5 stored, the wrist point p5
        f = _stored(V, ln, 0, (1.0, 0.0, 0.0, 0.0, c0, s0, 0.0, -s0, c0, a0, 0.0, d0))
        f = _stored(V, ln, 1, _joint(V, ln, 1, d1, a1, c1, s1, f))
        f = _stored(V, ln, 2, _joint(V, ln, 2, d2, a2, c2, s2, f))
        f = _stored(V, ln, 3, _joint(V, ln, 3, d3, a3, c3, s3, f))
        f = _stored(V, ln, 4, _joint(V, ln, 4, d4, a4, c4, s4, f))
        q0, q1, q2 = f[9], f[10], f[11]
        x0, x1, x2, y0, y1, y2, z0, z1, z2, p0, p1, p2 = _joint(V, ln, 5, d5, a5, c5, s5, f)
        ep0, ep1, ep2 = pt0 - p0, pt1 - p1, pt2 - p2
        # rotation error: x cross x_t + y cross y_t = omega + (z . omega) z for small omega
        er0 = (x1 * xt2 - x2 * xt1) + (y1 * yt2 - y2 * yt1)
        er1 = (x2 * xt0 - x0 * xt2) + (y2 * yt0 - y0 * yt2)
        er2 = (x0 * xt1 - x1 * xt0) + (y0 * yt1 - y1 * yt0)
        h = 0.5 * (er0 * z0 + er1 * z1 + er2 * z2)
        w0, w1, w2 = er0 - h * z0, er1 - h * z1, er2 - h * z2
        l0, l1, l2 = p0 - q0, p1 - q1, p2 - q2
        # the error twist at p5: v5 = v_p - omega x (p - p5)
        V[_E * _L + ln] = ep1 - (w2 * l0 - w0 * l2)
        V[(_E + 1) * _L + ln] = w0
        V[(_E + 2) * _L + ln] = w2
        V[(_E + 3) * _L + ln] = w1
        V[(_E + 4) * _L + ln] = ep0 - (w1 * l2 - w2 * l1)
        V[(_E + 5) * _L + ln] = ep2 - (w0 * l1 - w1 * l0)
        V[_POS * _L + ln] = math.sqrt(ep0 * ep0 + ep1 * ep1 + ep2 * ep2)
        V[_ROT * _L + ln] = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)


@_jit
def _column(V, ln, k):
    """Jacobian column at p5 of the joint turning about frame ``k + 1``'s axis (k = 0..3:
    joints 2..5) in lane ``ln``, rows in the elimination order."""
    a0 = V[(_FR + 6 * k) * _L + ln]
    a1 = V[(_FR + 6 * k + 1) * _L + ln]
    a2 = V[(_FR + 6 * k + 2) * _L + ln]
    r0 = V[(_FR + 27) * _L + ln] - V[(_FR + 6 * k + 3) * _L + ln]
    r1 = V[(_FR + 28) * _L + ln] - V[(_FR + 6 * k + 4) * _L + ln]
    r2 = V[(_FR + 29) * _L + ln] - V[(_FR + 6 * k + 5) * _L + ln]
    return a2 * r0 - a0 * r2, a0, a2, a1, a1 * r2 - a2 * r1, a0 * r1 - a1 * r0


@_jit
def _minus(f, r, s):
    """Row ``r`` minus ``f`` times row ``s`` (4 entries each: an elimination step)."""
    return r[0] - f * s[0], r[1] - f * s[1], r[2] - f * s[2], r[3] - f * s[3]


@_jit
def _minus2(f, g, r, s, t):
    """Row ``r`` minus ``f`` times row ``s`` and ``g`` times row ``t`` (4 entries each)."""
    return (r[0] - (f * s[0] + g * t[0]), r[1] - (f * s[1] + g * t[1]),
            r[2] - (f * s[2] + g * t[2]), r[3] - (f * s[3] + g * t[3]))  # fmt: skip


@_jit
def _step(V):
    """Damped block elimination of ``J dq = e`` in every lane (see ``calibrated_ik``).

    Elimination order: rows (v5 y), (omega x, omega z), (omega y), (v5 x, v5 z); columns
    (q1), (q5, q6), (q4), (q2, q3).  Each pivot block is inverted damped:
    ``1/p -> p / (p^2 + mu2)``, ``adj(B) -> adj(B) det / (det^2 + mu2)``.  Structural zeros
    are skipped: joint 1 (axis (0, 0, 1) through the origin) turns about no x or y axis,
    joint 6 (axis z5 through p5) moves p5 by nothing.
    """
    for ln in range(_L):
        mu2 = V[_MU2 * _L + ln]
        b0, b1 = V[_E * _L + ln], V[(_E + 1) * _L + ln]
        b2, b3 = V[(_E + 2) * _L + ln], V[(_E + 3) * _L + ln]
        b4, b5 = V[(_E + 4) * _L + ln], V[(_E + 5) * _L + ln]
        u0 = V[(_FR + 27) * _L + ln]  # v5 y of q1 = p5 x
        u4 = -V[(_FR + 28) * _L + ln]  # v5 x of q1 = -p5 y
        m01, m11, m21, m31, m41, m51 = _column(V, ln, 3)  # q5
        m12 = V[(_FR + 24) * _L + ln]  # q6: omega = z5, v5 = 0
        m22 = V[(_FR + 26) * _L + ln]
        m32 = V[(_FR + 25) * _L + ln]
        m03, m13, m23, m33, m43, m53 = _column(V, ln, 2)  # q4
        m04, m14, m24, m34, m44, m54 = _column(V, ln, 0)  # q2
        m05, m15, m25, m35, m45, m55 = _column(V, ln, 1)  # q3
        # block 0: pivot u0; rows 2 (omega z, entry 1) and 4 (v5 x, entry u4) below it
        p0 = u0 / (u0 * u0 + mu2)
        f4 = u4 * p0
        m21 -= p0 * m01
        m23, m24, m25, b2 = _minus(p0, (m23, m24, m25, b2), (m03, m04, m05, b0))
        m41 -= f4 * m01
        m43, m44, m45, b4 = _minus(f4, (m43, m44, m45, b4), (m03, m04, m05, b0))
        # block 1: rows (omega x, omega z) x columns (q5, q6); rows 3, 4, 5 below
        det = m11 * m22 - m12 * m21
        f = det / (det * det + mu2)
        P00, P01, P10, P11 = m22 * f, -m12 * f, -m21 * f, m11 * f
        g0 = m31 * P00 + m32 * P10
        g1 = m31 * P01 + m32 * P11
        h0 = m41 * P00
        h1 = m41 * P01
        k0 = m51 * P00
        k1 = m51 * P01
        row1, row2 = (m13, m14, m15, b1), (m23, m24, m25, b2)
        m33, m34, m35, b3 = _minus2(g0, g1, (m33, m34, m35, b3), row1, row2)
        m43, m44, m45, b4 = _minus2(h0, h1, (m43, m44, m45, b4), row1, row2)
        m53, m54, m55, b5 = _minus2(k0, k1, (m53, m54, m55, b5), row1, row2)
        # block 2: pivot m33; rows 4, 5
        p3 = m33 / (m33 * m33 + mu2)
        f43 = m43 * p3
        f53 = m53 * p3
        row3 = (m33, m34, m35, b3)  # column q4 of rows 4, 5 is not read again
        _, m44, m45, b4 = _minus(f43, (m43, m44, m45, b4), row3)
        _, m54, m55, b5 = _minus(f53, (m53, m54, m55, b5), row3)
        # block 3: rows (v5 x, v5 z) x columns (q2, q3)
        det = m44 * m55 - m45 * m54
        f = det / (det * det + mu2)
        x4 = (m55 * b4 - m45 * b5) * f
        x5 = (m44 * b5 - m54 * b4) * f
        # back substitution
        x3 = p3 * (b3 - m34 * x4 - m35 * x5)
        r1 = b1 - m13 * x3 - m14 * x4 - m15 * x5
        r2 = b2 - m23 * x3 - m24 * x4 - m25 * x5
        x1 = P00 * r1 + P01 * r2
        x2 = P10 * r1 + P11 * r2
        x0 = p0 * (b0 - m01 * x1 - m03 * x3 - m04 * x4 - m05 * x5)
        V[_DQ * _L + ln] = x0  # q1
        V[(_DQ + 1) * _L + ln] = x4  # q2
        V[(_DQ + 2) * _L + ln] = x5  # q3
        V[(_DQ + 3) * _L + ln] = x3  # q4
        V[(_DQ + 4) * _L + ln] = x1  # q5
        V[(_DQ + 5) * _L + ln] = x2  # q6


@_jit
def refine(ch, offset, flange, seeds, shift, tol, max_iter, theta, conv, res, its):
    """Refine the IK seeds (n, 8, 6) on the chain ``ch`` by Newton steps.

    The seeds are DH angles of the seed table (NaN rows = none); the chain ``ch`` (4, 6): d,
    a, cos alpha, sin alpha.  Fills ``theta`` (n, 8, 6) joint positions in (-pi, pi] (NaN
    where not converged), ``conv`` (n, 8), ``res`` (n, 8) (residual at the solution, or the
    best one of a pair that failed; NaN where not seeded) and ``its`` (n, 8) (Newton steps
    taken).

    ``_L`` lanes iterate side by side; a lane whose pair finishes takes the next pair at
    once.  Each round: cos and sin, the residual and the damped step of every lane
    (vectorised), then per lane the bookkeeping (convergence, best iterate, stall, budget,
    rejected steps) and the update.
    """
    n = flange.shape[0]
    total = 8 * n
    V = np.zeros(_ROWS * _L)
    best_r = np.full(_L, np.inf)
    stall = np.zeros(_L, dtype=np.int64)
    it = np.zeros(_L, dtype=np.int64)
    pair = np.full(_L, -1, dtype=np.int64)
    reject = np.zeros(_L, dtype=np.bool_)
    nxt = 0  # next (pose, branch) pair to hand out
    active = 0
    while True:
        # hand out pairs to free lanes (pairs without a seed are written on the way)
        for ln in range(_L):
            if pair[ln] >= 0:
                continue
            while nxt < total:
                i, b = nxt // 8, nxt % 8
                nxt += 1
                if math.isnan(seeds[i, b, 0]):
                    for j in range(6):
                        theta[i, b, j] = np.nan
                    conv[i, b] = False
                    res[i, b] = np.nan
                    its[i, b] = 0
                    continue
                pair[ln] = 8 * i + b
                active += 1
                for j in range(6):
                    t = seeds[i, b, j] + shift[j]
                    V[(_TH + j) * _L + ln] = t
                    V[(_BEST + j) * _L + ln] = t
                    V[(_STEP + j) * _L + ln] = 0.0
                for r in range(3):
                    for k in range(4):
                        V[(_TG + 4 * r + k) * _L + ln] = flange[i, r, k]
                best_r[ln] = np.inf
                stall[ln] = 0
                it[ln] = 0
                break
        if active == 0:
            break
        _sincos(V)
        _forward(V, ch)
        for ln in range(_L):
            if pair[ln] < 0:
                V[_MU2 * _L + ln] = 1.0
                continue
            pos, rot = V[_POS * _L + ln], V[_ROT * _L + ln]
            r = max(pos, rot)
            done = pos <= tol and rot <= tol
            better = r < best_r[ln]
            reject[ln] = (not done) and r > _REJECT * best_r[ln]
            if better:
                for j in range(6):
                    V[(_BEST + j) * _L + ln] = V[(_TH + j) * _L + ln]
            stall[ln] = 0 if r < 0.7 * best_r[ln] else stall[ln] + 1
            if better:
                best_r[ln] = r
            V[_MU2 * _L + ln] = _LAMBDA0 * r
            if done or stall[ln] > _STALL or it[ln] >= max_iter:
                i, b = pair[ln] // 8, pair[ln] % 8
                its[i, b] = it[ln]
                conv[i, b] = done
                if done:
                    res[i, b] = r
                    for j in range(6):
                        theta[i, b, j] = _wrap(V[(_TH + j) * _L + ln] - offset[j])
                else:
                    res[i, b] = best_r[ln]
                    for j in range(6):
                        theta[i, b, j] = np.nan
                pair[ln] = -1
                active -= 1
                V[_MU2 * _L + ln] = 1.0
        _step(V)
        for ln in range(_L):
            if pair[ln] < 0:
                continue
            big = 0.0
            for j in range(6):
                big = max(big, abs(V[(_DQ + j) * _L + ln]))
            scale = 1.0 if big <= _MAX_STEP else _MAX_STEP / big
            if reject[ln]:  # back to the best iterate, half the step taken from it
                for j in range(6):
                    h = 0.5 * V[(_STEP + j) * _L + ln]
                    V[(_STEP + j) * _L + ln] = h
                    V[(_TH + j) * _L + ln] = V[(_BEST + j) * _L + ln] + h
            else:
                for j in range(6):
                    dj = V[(_DQ + j) * _L + ln] * scale
                    V[(_STEP + j) * _L + ln] = dj
                    V[(_TH + j) * _L + ln] += dj
            it[ln] += 1


# --------------------------------------------------------------------------- seeds

_ELBOW_TOL = 1e-10  # analytic_ik.ELBOW_TOL
_SHOULDER_TOL = 1e-10  # analytic_ik.SHOULDER_TOL
_RESCUE_W = 1e-6  # analytic_ik.RESCUE_W: poses with a wrist this close to singular go to numpy


@_jit
def _atan2(y, x):
    """``analytic_ik._atan2``: arctan2 in (-pi, pi]."""
    t = math.atan2(y, x)
    return t if t > -math.pi else math.pi


@_jit
def _closed_form(g, tg, out, ok):
    """The 8 nominal closed-form solutions (DH angles) of one flange pose, ``analytic_ik``'s
    formulas for a regular wrist.  ``g`` (6,) d1, a2, a3, d4, d5, d6; ``tg`` (12,) the pose's
    rows; fills ``out`` (8, 6) and ``ok`` (8,).  Returns False (and fills nothing useful)
    when a shoulder branch has ``|sin q5|`` below ``_RESCUE_W``: the numpy closed form, with
    its singular-wrist rules, seeds such a pose."""
    d1, a2, a3, d4, d5, d6 = g[0], g[1], g[2], g[3], g[4], g[5]
    xx, yx, zx, px = tg[0], tg[1], tg[2], tg[3]
    xy, yy, zy, py = tg[4], tg[5], tg[6], tg[7]
    xz, yz, zz, pz = tg[8], tg[9], tg[10], tg[11]
    p5x = px - d6 * zx
    p5y = py - d6 * zy
    p5z = pz - d6 * zz
    r2 = p5x * p5x + p5y * p5y
    rho2 = r2 - d4 * d4
    ok_s = rho2 >= -_SHOULDER_TOL * d4 * d4
    rho = math.sqrt(max(rho2, 0.0))
    norm2 = r2 * (rho * rho + d4 * d4)
    deg = norm2 <= 0.0
    inv_n = 1.0 / math.sqrt(norm2) if not deg else 1.0
    Py = p5z - d1
    a2a3 = 2.0 * a2 * a3
    ss = a2 * a2 + a3 * a3
    for si in range(2):
        sgn1 = 1.0 if si == 0 else -1.0
        if deg:
            c1, s1 = 1.0, 0.0
        else:
            c1 = -(p5y * d4 + sgn1 * p5x * rho) * inv_n
            s1 = (p5x * d4 - sgn1 * p5y * rho) * inv_n
        th1 = _atan2(s1, c1)
        Px = p5x * c1 + p5y * s1
        ax = xx * s1 - xy * c1
        by = yx * s1 - yy * c1
        c5 = zx * s1 - zy * c1
        w = math.sqrt(ax * ax + by * by)
        if w < _RESCUE_W:
            return False
        s6 = -by / w
        c6 = ax / w
        th5 = math.atan2(w, c5)
        th6 = _atan2(s6, c6)
        ux = -(s6 * xx + c6 * yx) * c1 - (s6 * xy + c6 * yy) * s1
        uy = -(s6 * xz + c6 * yz)
        for wi in range(2):
            sgn5 = 1.0 if wi == 0 else -1.0
            bux, buy = sgn5 * ux, sgn5 * uy
            if wi == 0:
                t5, t6 = th5, th6
            else:
                t5 = -th5 if th5 < math.pi else th5
                t6 = _wrap(th6 + math.pi)
            X = Px - d5 * bux
            Y = Py - d5 * buy
            cc = (X * X + Y * Y - ss) / a2a3
            ok_b = ok_s and abs(cc) <= 1.0 + _ELBOW_TOL
            t234 = math.atan2(bux, -buy)
            cc = min(max(cc, -1.0), 1.0)
            s3 = math.sqrt((1.0 - cc) * (1.0 + cc))
            th3 = math.atan2(s3, cc)
            k1 = a2 + a3 * cc
            k2 = a3 * s3
            for ei in range(2):
                b = 4 * si + 2 * wi + ei
                ok[b] = ok_b
                if not ok_b:
                    continue
                k2s = k2 if ei == 0 else -k2
                th2 = _atan2(Y * k1 - X * k2s, X * k1 + Y * k2s)
                t3 = th3 if ei == 0 else (-th3 if th3 < math.pi else th3)
                out[b, 0] = th1
                out[b, 1] = th2
                out[b, 2] = t3
                out[b, 3] = _wrap(t234 - th2 - t3)
                out[b, 4] = t5
                out[b, 5] = t6
    return True


@_jit
def seeds(geoms, flange, out, exact, numpy_rows):
    """Nominal seeds of ``calibrated_ik.nominal_seeds``.

    The closed form of ``geoms[0]`` (d1, a2, a3, d4, d5, d6), branches it misses filled from
    ``geoms[1]`` (1 cm further) for every pose with a missing branch, from ``geoms[2]`` (3 cm)
    for poses with none. Fills ``out`` (n, 8, 6) (NaN rows = none) and ``exact`` (n, 8);
    ``numpy_rows`` (n,) is set where the wrist is nearly singular and the caller must seed the
    pose with the numpy closed form.
    """
    n = flange.shape[0]
    tg = np.empty(12)
    sol = np.empty((8, 6))
    ok = np.empty(8, dtype=np.bool_)
    alt = np.empty((8, 6))
    ok2 = np.empty(8, dtype=np.bool_)
    for i in range(n):
        for r in range(3):
            for k in range(4):
                tg[4 * r + k] = flange[i, r, k]
        regular = _closed_form(geoms[0], tg, sol, ok)
        numpy_rows[i] = not regular
        if not regular:
            continue
        n_ok = 0
        for b in range(8):
            exact[i, b] = ok[b]
            n_ok += ok[b]
        if n_ok < 8:
            for level in range(1, 3):
                if level == 2 and n_ok > 0:
                    break
                if not _closed_form(geoms[level], tg, alt, ok2):
                    regular = False
                    break
                for b in range(8):
                    if not ok[b] and ok2[b]:
                        ok[b] = True
                        n_ok += 1
                        for j in range(6):
                            sol[b, j] = alt[b, j]
        numpy_rows[i] = not regular
        if not regular:
            continue
        for b in range(8):
            if ok[b]:
                for j in range(6):
                    out[i, b, j] = sol[b, j]
            else:
                for j in range(6):
                    out[i, b, j] = np.nan
