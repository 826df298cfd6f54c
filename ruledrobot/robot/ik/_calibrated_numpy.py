"""The calibrated IK's Newton finish in numpy, for small batches (see ``calibrated_ik``).

Batches of at most ``calibrated_ik.NUMPY_POSES`` poses are refined here rather than in
the compiled kernel: a process that only solves single poses and short moves (the
emulator's ``get_inverse_kin`` and moves, in its 500 Hz clock thread) then never loads
numba, whose import and first kernel load take about a second in C calls that hold the
interpreter lock up to about 0.1 s at a time.  Same iteration and rules as the
kernel, vectorised over the pairs with numpy: residual and Jacobian at the wrist point in
the frame turned with joint 1, damped block elimination (shoulder, wrist, q4, elbow),
trust region, rejected steps halved from the best iterate, stall and budget give-ups.

Sines and cosines are formed from ``tan(theta / 2)`` (``c = (1 - t^2) / (1 + t^2)``,
``s = 2t / (1 + t^2)``): numpy's ``tan`` is vectorised, its ``sin`` and ``cos`` are
not, and this is about six times faster at the same accuracy (a few 1e-16).
"""

from __future__ import annotations

import numpy as np

from .._checks import FloatArray
from . import analytic as _ik

_CHUNK = 8192  # (pose, branch) pairs per chunk
_MAX_STEP = 0.5  # rad: a longer step is shortened (trust region)
_LAMBDA0 = 1e-6  # damping factor: mu^2 = lambda * |e|
_BULK = 5  # iterations per chunk; the pairs still open then are iterated together
_REJECT = 1e3  # a residual above this many times the best halves the step
_STALL = 8  # iterations without reducing the best residual by 30 % before a pair is given up


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


class _Batch:
    """Iteration state of a batch of (pose, branch) pairs; angles stored as (6, m)."""

    def __init__(self, idx, th, tgt, best_th=None, best_r=None, step=None, stall=None):
        m = idx.shape[0]
        self.idx = idx
        self.th = th
        self.tgt = tgt
        self.best_th = th.copy() if best_th is None else best_th
        self.best_r = np.full(m, np.inf) if best_r is None else best_r
        self.step = np.zeros_like(th) if step is None else step
        self.stall = np.zeros(m, dtype=np.int16) if stall is None else stall

    def take(self, keep: np.ndarray) -> _Batch:
        return _Batch(
            self.idx[keep],
            self.th[:, keep],
            tuple(tuple(v[keep] for v in col) for col in self.tgt),
            self.best_th[:, keep],
            self.best_r[keep],
            self.step[:, keep],
            self.stall[keep],
        )

    @staticmethod
    def concat(batches: list[_Batch]) -> _Batch:
        cat = np.concatenate
        tgt = tuple(tuple(cat([b.tgt[c][k] for b in batches]) for k in range(3)) for c in range(3))
        return _Batch(
            cat([b.idx for b in batches]),
            cat([b.th for b in batches], axis=1),
            tgt,
            cat([b.best_th for b in batches], axis=1),
            cat([b.best_r for b in batches]),
            cat([b.step for b in batches], axis=1),
            cat([b.stall for b in batches]),
        )


def _iterate(ch: _Chain, b: _Batch, out: tuple, tol: float, first: int, last: int, final: bool):
    """Newton / LM iterations ``first..last`` on batch ``b``; finished pairs go to ``out``.

    The iteration is not monotone (a Newton step may raise the residual for a while
    and still converge, and often does next to singularities); a step that raises a
    pair's residual beyond ``_REJECT`` times its best is halved and taken again from
    the best iterate; a pair that has not reduced its best
    residual by 30 % for ``_STALL`` iterations is given up, and with ``final`` every pair still
    open after iteration ``last``.  Returns the batch of the pairs still open (or None).
    """
    theta_out, conv_out, res_out, it_out = out
    for it in range(first, last + 1):
        th = b.th
        cs = [_cos_sin(th[j]) for j in range(6)]
        e, pos, rot, cols = _evaluate(ch, cs, b.tgt)
        r = np.maximum(pos, rot)
        done = (pos <= tol) & (rot <= tol)
        better = r < b.best_r
        reject = ~done & (r > _REJECT * b.best_r)
        b.best_th = np.where(better, th, b.best_th)
        b.stall = np.where(r < 0.7 * b.best_r, 0, b.stall + 1)
        b.best_r = np.where(better, r, b.best_r)
        give_up = ~done & (b.stall > _STALL)
        if final and it == last:
            give_up = ~done
        fin = done | give_up
        if fin.any():
            ids = b.idx[fin]
            theta_out[ids] = np.where(done[fin], th[:, fin], b.best_th[:, fin]).T
            conv_out[ids] = done[fin]
            res_out[ids] = np.where(done[fin], r[fin], b.best_r[fin])
            it_out[ids] = it
            keep = ~fin
            if not keep.any():
                return None
            b = b.take(keep)
            r, reject = r[keep], reject[keep]
            e = tuple(v[keep] for v in e)
            cols = [tuple(_take(part, keep) for part in col) for col in cols]
        if it == last:
            return b
        dq = _solve(cols, e, _LAMBDA0 * r)
        step = np.stack([np.broadcast_to(v, r.shape) for v in dq])
        big = np.abs(step).max(axis=0)
        step *= np.minimum(1.0, _MAX_STEP / np.maximum(big, 1e-300))
        if reject.any():  # back to the best iterate, half the step taken from it
            step = np.where(reject, 0.5 * b.step, step)
            b.th = np.where(reject, b.best_th, b.th)
        b.step = step
        b.th = b.th + step
    return b


def _take(part, keep):
    if part is None:
        return None
    return tuple(v[keep] if isinstance(v, np.ndarray) else v for v in part)


def refine(
    table: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
    flange: FloatArray,
    seeds: FloatArray,
    shift: FloatArray,
    *,
    tol: float,
    max_iter: int,
) -> tuple[FloatArray, np.ndarray, FloatArray, np.ndarray]:
    """:func:`calibrated.refine_solutions` in numpy (its inputs and results).

    ``table`` the calibrated DH table ``(d, a, alpha, offset)`` (6,) each [m, m, rad, rad];
    ``shift`` (6,) [rad] the calibrated offsets minus those of the seeds' table, turning
    the seeds (n, 8, 6) into DH angles of the calibrated table.
    """
    n = flange.shape[0]
    ch = _Chain(*table)
    flat_seed = seeds.reshape(n * 8, 6)
    pairs = np.flatnonzero(~np.isnan(flat_seed[:, 0]))
    theta = np.full((n * 8, 6), np.nan)
    conv = np.zeros(n * 8, dtype=bool)
    res = np.full(n * 8, np.nan)
    its = np.zeros(n * 8, dtype=np.int16)
    out = (theta, conv, res, its)
    cols = np.ascontiguousarray(flange.reshape(n, 16)[:, :12].T)
    bulk = min(_BULK, max_iter)
    rest = []
    for lo in range(0, pairs.size, _CHUNK):
        pr = pairs[lo : lo + _CHUNK]
        c = cols[:, pr // 8]
        tgt = ((c[0], c[4], c[8]), (c[1], c[5], c[9]), (c[3], c[7], c[11]))
        th = np.ascontiguousarray((flat_seed[pr] + shift).T)
        left = _iterate(ch, _Batch(pr, th, tgt), out, tol, 0, bulk, bulk == max_iter)
        if left is not None:
            rest.append(left)
    if rest:  # the slow pairs of every chunk together
        _iterate(ch, _Batch.concat(rest), out, tol, bulk, max_iter, True)
    ok = np.flatnonzero(conv)
    for lo in range(0, ok.size, _CHUNK):
        rows = ok[lo : lo + _CHUNK]
        theta[rows] = _ik.wrap_angle(theta[rows] - ch.offset)
    theta[~conv] = np.nan
    return theta.reshape(n, 8, 6), conv.reshape(n, 8), res.reshape(n, 8), its.reshape(n, 8)
