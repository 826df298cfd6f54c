r"""Inverse kinematics of a calibrated UR arm: analytic nominal seeds, batched Newton finish.

With the factory corrections the UR closed form no longer holds: joints 2-4 are not
exactly parallel, the wrist axes do not exactly intersect.  The corrections are
small in the arm's geometry, so each of the 8 nominal analytic solutions of a pose
lies within about 1e-2 rad of the calibrated solution of the same branch.  This
module refines all of them at once:

1. **Seeds.**  The nominal closed form (:func:`~ruledrobot.robot.analytic_ik.ur_ik_chunk`)
   of the flange pose gives up to 8 seeds.  Branches the nominal arm cannot reach
   (the pose lies just beyond its reach, inside its shoulder cylinder or closer than
   its folded elbow) are seeded from the closed form of the nominal arm with its
   links lengthened / its shoulder offset shortened by 1 cm, so that poses only the
   calibrated arm reaches are solved too.
2. **Newton / Levenberg-Marquardt** on the calibrated DH chain, vectorised over all
   (pose, branch) pairs, chunk by chunk (no loop over poses).  The residual is the
   flange's position error and its rotation error (the small rotation vector), both
   in the frame turned with joint 1.  The Jacobian is taken at the wrist point
   ``p5`` in that frame, where the nominal UR Jacobian is block triangular
   (``det J = a2 a3 sin q3 sin q5 s``): the linear system is solved by block
   elimination in the order shoulder (1x1), wrist (2x2), q4 (1x1), elbow (2x2), which
   is exact for any matrix and well conditioned for a near-UR one.  Each pivot
   block is damped Levenberg-Marquardt style (``1/p -> p / (p^2 + mu^2)``, ``mu^2 =
   lambda * |e|``), so the iteration converges quadratically away from singularities
   and stays bounded next to them; a step that raises the residual is undone and
   ``lambda`` raised tenfold for that pair.
3. **Result.**  A pair is converged when the position error is below ``tol`` [m]
   and the rotation error below ``tol`` [rad] (default 1e-11).  Pairs that do not
   converge within ``max_iter`` iterations, or stall, are NaN rows flagged in
   :class:`CalibratedIKSolutions`.  A branch keeps its identity: the iteration starts
   at the nominal solution of the branch and moves by about the calibration's size.

Sines and cosines are formed from ``tan(theta / 2)`` (``c = (1 - t^2) / (1 + t^2)``,
``s = 2t / (1 + t^2)``): numpy's ``tan`` is vectorised, its ``sin`` and ``cos`` are
not, and this is about six times faster at the same accuracy (a few 1e-16).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import analytic_ik as _ik
from ._checks import FloatArray

__all__ = ["DEFAULT_MAX_ITER", "DEFAULT_TOL", "CalibratedIKSolutions", "refine_solutions"]

#: Convergence tolerance: position error [m] and rotation error [rad] of a solution.
DEFAULT_TOL = 1e-11
#: Largest number of Newton iterations per (pose, branch).
DEFAULT_MAX_ITER = 40
_CHUNK = 8192  # (pose, branch) pairs per chunk
_MAX_STEP = 0.5  # rad: a longer step is shortened (trust region)
_LAMBDA0 = 1e-3  # damping factor: mu^2 = lambda * |e|
_FALLBACK = 0.01  # m: links lengthened / shoulder shortened for the fallback seeds
_REJECT = 1e3  # a residual above this many times the best undoes the step
_STALL = 6  # iterations without halving the best residual before a pair is given up


@dataclass(frozen=True, eq=False)
class CalibratedIKSolutions(_ik.IKSolutions):
    """:class:`~ruledrobot.robot.IKSolutions` of a calibrated arm, with convergence information.

    Extra attributes (batch shape ``S`` of the input poses)
    ----------
    converged : (*S, 8) bool, the Newton iteration reached the tolerance (equal to
        ``valid``).
    seeded : (*S, 8) bool, the branch had a seed (a nominal solution, or one of the
        fallback seeds).  ``seeded & ~converged`` is a reported non-convergence.
    residual : (*S, 8) the larger of the position error [m] and the rotation error
        [rad] at the last iterate (NaN where not seeded).
    iterations : (*S, 8) int16, Newton iterations used (0 where not seeded).

    The singularity factors ``wrist``, ``elbow``, ``shoulder`` and ``measure`` are
    those of the nominal structure at the calibrated solution (the formulas of
    ``docs/robot.md`` with the nominal ``a2, a3, d5``).
    """

    converged: np.ndarray
    seeded: np.ndarray
    residual: FloatArray
    iterations: np.ndarray


# ---------------------------------------------------------------------- seeds


def fallback_geometries(g: _ik.URGeometry) -> list[_ik.URGeometry]:
    """Nominal geometries that reach a little further than ``g`` in each direction.

    Lengthened links (poses just beyond the reach), a shortened shorter-link
    difference (poses just inside the folded elbow's reach), a shortened shoulder
    offset (wrist points just inside the shoulder cylinder), and the first with the third.
    """
    e = _FALLBACK

    def longer(x: float) -> float:
        return x + np.copysign(e, x)

    def shorter(x: float) -> float:
        return x - np.copysign(min(e, 0.5 * abs(x)), x)

    long_arm = g._replace(a2=longer(g.a2), a3=longer(g.a3))
    if abs(g.a2) >= abs(g.a3):
        folded = g._replace(a2=shorter(g.a2), a3=longer(g.a3))
    else:
        folded = g._replace(a2=longer(g.a2), a3=shorter(g.a3))
    shoulder = g._replace(d4=shorter(g.d4))
    both = long_arm._replace(d4=shorter(g.d4))
    return [long_arm, folded, shoulder, both]


def nominal_seeds(
    g: _ik.URGeometry, flange: FloatArray, seed6: FloatArray
) -> tuple[FloatArray, np.ndarray]:
    """Seeds (n, 8, 6) (DH angles of the nominal table) and (n, 8) "from the closed form of
    the nominal arm" flags; branches the nominal arm misses are filled from
    :func:`fallback_geometries` where those reach (flag False), else NaN."""
    n = flange.shape[0]
    out = np.empty((n, 8, 6))
    for lo in range(0, n, _ik._CHUNK):
        hi = min(lo + _ik._CHUNK, n)
        _ik.ur_ik_chunk(g, flange[lo:hi], seed6[lo:hi], out[lo:hi], None)
    exact = ~np.isnan(out[..., 0])
    missing = np.flatnonzero(~exact.all(axis=1))
    if missing.size:
        sub = out[missing]
        tmp = np.empty_like(sub)
        for gf in fallback_geometries(g):
            hole = np.isnan(sub[..., 0])
            rows = np.flatnonzero(hole.any(axis=1))
            if rows.size == 0:
                break
            _ik.ur_ik_chunk(gf, flange[missing[rows]], seed6[missing[rows]], tmp[: rows.size], None)
            fill = hole[rows] & ~np.isnan(tmp[: rows.size, :, 0])
            blk = sub[rows]
            blk[fill] = tmp[: rows.size][fill]
            sub[rows] = blk
        out[missing] = sub
    return out, exact


# ---------------------------------------------------------------------- the chain


def _cos_sin(theta: FloatArray) -> tuple[FloatArray, FloatArray]:
    """cos and sin of ``theta`` from ``t = tan(theta / 2)`` (vectorised ``tan``)."""
    t = np.tan(0.5 * theta)
    t2 = t * t
    u = 1.0 / (1.0 + t2)
    return (1.0 - t2) * u, (t + t) * u


class _Chain:
    """Constants of a calibrated 6R DH chain, for the iteration in the frame turned with joint 1."""

    def __init__(self, d: FloatArray, a: FloatArray, alpha: FloatArray, offset: FloatArray):
        self.d = [float(v) for v in d]
        self.a = [float(v) for v in a]
        self.ca = [float(np.cos(v)) for v in alpha]
        self.sa = [float(np.sin(v)) for v in alpha]
        self.offset = np.asarray(offset, dtype=np.float64)
        # frame 1 in the frame turned with joint 1: L1 = Tz(d1) Tx(a1) Rx(alpha1)
        ca, sa = self.ca[0], self.sa[0]
        self.x1 = (1.0, 0.0, 0.0)
        self.y1 = (0.0, ca, sa)
        self.z1 = (0.0, -sa, ca)
        self.p1 = (self.a[0], 0.0, self.d[0])


def _cross(u, v):
    return (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])


def _evaluate(ch: _Chain, cs: list, tgt: tuple):
    """Residual and Jacobian at the wrist point of the pairs whose (cos, sin) are ``cs``.

    ``tgt`` = (x_t, y_t, p_t) target columns in the base frame (3-tuples of arrays).
    Returns (e (6-tuple: v5 x, y, z, omega x, y, z), position error norm, rotation
    error norm, Jacobian columns [(v5 3-tuple, omega 3-tuple)] * 6).
    """
    c1, s1 = cs[0]
    # target in the frame turned with joint 1: Rz(-theta1) applied to each column
    xt, yt, pt = ((c1 * v[0] + s1 * v[1], c1 * v[1] - s1 * v[0], v[2]) for v in tgt)
    # frame 2 from the constant frame 1
    c, s = cs[1]
    y1, z1, p1 = ch.y1, ch.z1, ch.p1
    ca, sa, d, a = ch.ca[1], ch.sa[1], ch.d[1], ch.a[1]
    xr = (c, s * y1[1], s * y1[2])
    yr = (-s, c * y1[1], c * y1[2])
    frame_y = (ca * yr[0] + sa * z1[0], ca * yr[1] + sa * z1[1], ca * yr[2] + sa * z1[2])
    frame_z = (ca * z1[0] - sa * yr[0], ca * z1[1] - sa * yr[1], ca * z1[2] - sa * yr[2])
    p = (p1[0] + d * z1[0] + a * xr[0], p1[1] + d * z1[1] + a * xr[1],
         p1[2] + d * z1[2] + a * xr[2])  # fmt: skip
    x, y, z = xr, frame_y, frame_z
    zs, ps = [z1, z], [p1, p]
    for j in range(2, 6):
        c, s = cs[j]
        ca, sa, d, a = ch.ca[j], ch.sa[j], ch.d[j], ch.a[j]
        xr = (c * x[0] + s * y[0], c * x[1] + s * y[1], c * x[2] + s * y[2])
        yr = (c * y[0] - s * x[0], c * y[1] - s * x[1], c * y[2] - s * x[2])
        if d != 0.0:
            p = (p[0] + d * z[0], p[1] + d * z[1], p[2] + d * z[2])
        if a != 0.0:
            p = (p[0] + a * xr[0], p[1] + a * xr[1], p[2] + a * xr[2])
        if sa == 0.0 and ca == 1.0:
            yn, zn = yr, z
        else:
            yn = (ca * yr[0] + sa * z[0], ca * yr[1] + sa * z[1], ca * yr[2] + sa * z[2])
            zn = (ca * z[0] - sa * yr[0], ca * z[1] - sa * yr[1], ca * z[2] - sa * yr[2])
        x, y, z = xr, yn, zn
        if j < 5:
            zs.append(z)
            ps.append(p)
    # zs = z1..z5, ps = p1..p5 (frames 1..5); x, y, z, p the flange
    p5 = ps[4]
    ep = (pt[0] - p[0], pt[1] - p[1], pt[2] - p[2])
    e1 = _cross(x, xt)
    e2 = _cross(y, yt)
    er = (e1[0] + e2[0], e1[1] + e2[1], e1[2] + e2[2])
    h = 0.5 * (er[0] * z[0] + er[1] * z[1] + er[2] * z[2])
    dw = (er[0] - h * z[0], er[1] - h * z[1], er[2] - h * z[2])
    lever = (p[0] - p5[0], p[1] - p5[1], p[2] - p5[2])
    m = _cross(dw, lever)
    ev = (ep[0] - m[0], ep[1] - m[1], ep[2] - m[2])
    pos = np.sqrt(ep[0] * ep[0] + ep[1] * ep[1] + ep[2] * ep[2])
    rot = np.sqrt(dw[0] * dw[0] + dw[1] * dw[1] + dw[2] * dw[2])
    # Jacobian at p5 (frame turned with joint 1): columns (v, omega)
    cols = [((-p5[1], p5[0], 0.0), (0.0, 0.0, 1.0))]
    for k in range(4):
        zk, pk = zs[k], ps[k]
        r = (p5[0] - pk[0], p5[1] - pk[1], p5[2] - pk[2])
        cols.append((_cross(zk, r), zk))
    cols.append((None, zs[4]))
    return ev + dw, pos, rot, cols


# block elimination order: rows (v5 y), (omega x, omega z), (omega y), (v5 x, v5 z);
# columns (q1), (q5, q6), (q4), (q2, q3)
_ROWS = (1, 3, 5, 4, 0, 2)
_COLS = (0, 4, 5, 3, 1, 2)
_BLOCKS = ((0,), (1, 2), (3,), (4, 5))


def _entry(cols, i: int, j: int):
    """Jacobian entry (row i of [v5; omega], joint j), None for a structural zero."""
    part = cols[j][0] if i < 3 else cols[j][1]
    if part is None:
        return None
    v = part[i % 3]
    if isinstance(v, float) and v == 0.0:
        return None
    return v


def _solve(cols, e, mu2):
    """Damped block elimination of ``J dq = e`` (see the module docstring); dq (6-list)."""
    A = [[_entry(cols, _ROWS[r], _COLS[k]) for k in range(6)] for r in range(6)]
    b = [e[_ROWS[r]] for r in range(6)]
    inv = []
    for bi, blk in enumerate(_BLOCKS):
        if len(blk) == 1:
            (k,) = blk
            p = A[k][k]
            P = [[p / (p * p + mu2)]]
        else:
            k, l = blk
            a11, a12, a21, a22 = A[k][k], A[k][l], A[l][k], A[l][l]
            a11 = 0.0 if a11 is None else a11
            a12 = 0.0 if a12 is None else a12
            a21 = 0.0 if a21 is None else a21
            a22 = 0.0 if a22 is None else a22
            det = a11 * a22 - a12 * a21
            f = det / (det * det + mu2)
            P = [[a22 * f, -a12 * f], [-a21 * f, a11 * f]]
        inv.append(P)
        later = [r for b2 in _BLOCKS[bi + 1 :] for r in b2]
        for r in later:
            row = [A[r][k] for k in blk]
            if all(v is None for v in row):
                continue
            # multipliers m = row @ P
            mult = []
            for jj in range(len(blk)):
                acc = None
                for ii, v in enumerate(row):
                    if v is not None:
                        t = v * P[ii][jj]
                        acc = t if acc is None else acc + t
                mult.append(acc)
            for c in later:
                acc = A[r][c]
                for ii, k in enumerate(blk):
                    u = A[k][c]
                    if u is not None and mult[ii] is not None:
                        t = mult[ii] * u
                        acc = -t if acc is None else acc - t
                A[r][c] = acc
            for ii, k in enumerate(blk):
                if mult[ii] is not None:
                    b[r] = b[r] - mult[ii] * b[k]
            for k in blk:
                A[r][k] = None
    x = [None] * 6
    for bi in range(len(_BLOCKS) - 1, -1, -1):
        blk = _BLOCKS[bi]
        later = [r for b2 in _BLOCKS[bi + 1 :] for r in b2]
        rhs = []
        for k in blk:
            acc = b[k]
            for c in later:
                if A[k][c] is not None:
                    acc = acc - A[k][c] * x[c]
            rhs.append(acc)
        P = inv[bi]
        for ii, k in enumerate(blk):
            acc = None
            for jj in range(len(blk)):
                t = P[ii][jj] * rhs[jj]
                acc = t if acc is None else acc + t
            x[k] = acc
    dq = [None] * 6
    for k in range(6):
        dq[_COLS[k]] = x[k]
    return dq


def _refine_chunk(ch: _Chain, theta: FloatArray, tgt: tuple, tol: float, max_iter: int):
    """Newton / LM on (m, 6) DH angles ``theta`` towards the targets; in place.

    A pair whose residual grows beyond ``_REJECT`` times its best is sent back to its
    best iterate with ten times the damping; a pair that has not halved its best
    residual for ``_STALL`` iterations is given up.  Returns (converged (m,),
    residual (m,), iterations (m,)).
    """
    m = theta.shape[0]
    converged = np.zeros(m, dtype=bool)
    residual = np.full(m, np.inf)
    iters = np.zeros(m, dtype=np.int16)
    active = np.arange(m)
    th = theta.copy()  # rows of the active pairs, compacted as pairs finish
    tg = tgt
    best_th = th.copy()
    best_r = np.full(m, np.inf)
    lam = np.full(m, _LAMBDA0)
    stall = np.zeros(m, dtype=np.int16)
    for it in range(max_iter + 1):
        T = np.ascontiguousarray(th.T)
        cs = [_cos_sin(T[j]) for j in range(6)]
        e, pos, rot, cols = _evaluate(ch, cs, tg)
        r = np.maximum(pos, rot)
        done = (pos <= tol) & (rot <= tol)
        better = r < best_r
        reject = ~done & (r > _REJECT * best_r)
        progress = r < 0.5 * best_r
        best_th = np.where(better[:, None], th, best_th)
        best_r = np.where(better, r, best_r)
        stall = np.where(progress, 0, stall + 1)
        give_up = ~done & (stall > _STALL) if it < max_iter else ~done
        out = done | give_up
        if out.any():
            ids = active[out]
            theta[ids] = np.where(done[out, None], th[out], best_th[out])
            converged[ids] = done[out]
            residual[ids] = np.where(done[out], r[out], best_r[out])
            iters[ids] = it
        keep = ~out
        if not keep.any():
            break
        if not keep.all():
            active = active[keep]
            th, best_th, best_r, lam, stall = (
                th[keep],
                best_th[keep],
                best_r[keep],
                lam[keep],
                stall[keep],
            )
            r, reject = r[keep], reject[keep]
            e = tuple(v[keep] for v in e)
            cols = [tuple(_take(part, keep) for part in col) for col in cols]
            tg = tuple(tuple(v[keep] for v in col) for col in tg)
        lam = np.where(reject, lam * 10.0, np.maximum(lam * 0.3, _LAMBDA0))
        dq = _solve(cols, e, lam * r)
        step = np.stack([np.broadcast_to(v, (th.shape[0],)) for v in dq], axis=1)
        big = np.abs(step).max(axis=1)
        step *= np.minimum(1.0, _MAX_STEP / np.maximum(big, 1e-300))[:, None]
        if reject.any():  # back to the best iterate, no step from the rejected one
            step[reject] = 0.0
            th = np.where(reject[:, None], best_th, th)
        th = th + step
    return converged, residual, iters


def _take(part, keep):
    if part is None:
        return None
    return tuple(v[keep] if isinstance(v, np.ndarray) else v for v in part)


def refine_solutions(
    d: FloatArray,
    a: FloatArray,
    alpha: FloatArray,
    offset: FloatArray,
    flange: FloatArray,
    seeds: FloatArray,
    *,
    tol: float = DEFAULT_TOL,
    max_iter: int = DEFAULT_MAX_ITER,
) -> tuple[FloatArray, np.ndarray, FloatArray, np.ndarray]:
    """Refine seeds (n, 8, 6) (joint positions, NaN rows = none) on a calibrated DH chain.

    ``flange`` (n, 4, 4) the flange poses in the robot base frame.  Returns joint
    positions (n, 8, 6) in (-pi, pi] (NaN where not converged), converged (n, 8),
    residual (n, 8) and iterations (n, 8).
    """
    n = flange.shape[0]
    ch = _Chain(d, a, alpha, offset)
    q = np.full((n, 8, 6), np.nan)
    conv = np.zeros((n, 8), dtype=bool)
    res = np.full((n, 8), np.nan)
    its = np.zeros((n, 8), dtype=np.int16)
    flat_seed = seeds.reshape(n * 8, 6)
    pairs = np.flatnonzero(~np.isnan(flat_seed[:, 0]))
    cols = np.ascontiguousarray(flange.reshape(n, 16)[:, :12].T)
    qf, cf, rf, itf = q.reshape(-1, 6), conv.reshape(-1), res.reshape(-1), its.reshape(-1)
    for lo in range(0, pairs.size, _CHUNK):
        pr = pairs[lo : lo + _CHUNK]
        pose = pr // 8
        c = cols[:, pose]
        tgt = ((c[0], c[4], c[8]), (c[1], c[5], c[9]), (c[3], c[7], c[11]))
        theta = flat_seed[pr] + ch.offset
        ok, r, k = _refine_chunk(ch, theta, tgt, tol, max_iter)
        qk = _ik.wrap_angle(theta - ch.offset)
        qf[pr] = np.where(ok[:, None], qk, np.nan)
        cf[pr], rf[pr], itf[pr] = ok, r, k
    return q, conv, res, its
