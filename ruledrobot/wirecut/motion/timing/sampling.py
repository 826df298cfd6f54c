"""Sampling a solved time law at the controller rate, and its verification."""

from __future__ import annotations

import math

import numpy as np

from ....robot.motion.rates import trajectory_limits_report
from .problem import _Problem
from .report import _feed_of_samples
from .result import TimedPath
from .solvers import _StalledError
from .tolerances import FEED_HOLD_TOL, FEED_TOL, MAX_SAMPLES, RATIO_MAX, FloatArray

# --------------------------------------------------------------------------- sampling


class _TooLongError(ValueError):
    """Internal: the law lasts more than ``MAX_SAMPLES`` periods (the caller diagnoses
    it, :func:`.diagnose.too_long`)."""


def _sample_law(
    grid: FloatArray, x: FloatArray, dt: float, what: str
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Sample the constant-σ̈-per-stage law at t = k·dt (duration rounded up).

    Returns t (M,), σ (M,), σ̇ (M,), σ̈ (M,).
    """
    sd = np.sqrt(np.maximum(x, 0.0))
    D = np.diff(grid)
    u = np.diff(x) / (2.0 * D)
    den = sd[:-1] + sd[1:]
    stuck = den <= 0
    if stuck.any():
        raise _StalledError(int(np.flatnonzero(stuck)[0]))
    tau = np.concatenate([[0.0], np.cumsum(2.0 * D / den)])
    T = float(tau[-1])
    n = max(1, math.ceil(T / dt - 1e-9))
    if n + 1 > MAX_SAMPLES:
        raise _TooLongError(
            f"{what}: the timed path lasts {T:.6g} s = {n + 1} samples at dt = {dt} s, more "
            f"than MAX_SAMPLES = {MAX_SAMPLES}; split the path or raise the feed/limits"
        )
    k = T / (n * dt)  # ≤ 1: internal time per output time
    t = np.arange(n + 1) * dt
    tq = t * k
    tq[-1] = T
    idx = np.clip(np.searchsorted(tau, tq, side="right") - 1, 0, grid.shape[0] - 2)
    h = tq - tau[idx]
    sig = grid[idx] + sd[idx] * h + 0.5 * u[idx] * h * h
    sig = np.clip(sig, grid[idx], grid[idx + 1])
    sig[-1] = grid[-1]
    sdq = np.maximum(sd[idx] + u[idx] * h, 0.0) * k
    sdq[-1] = sd[-1] * k
    sddq = u[idx] * (k * k)
    return t, sig, sdq, sddq


def _timed_from_law(
    prob: _Problem,
    t: FloatArray,
    sig: FloatArray,
    sdq: FloatArray,
    sddq: FloatArray,
    dt: float,
    vlim: FloatArray,
    alim: FloatArray,
    method: str,
) -> tuple[TimedPath, FloatArray, FloatArray]:
    """The sampled trajectory, and the σ intervals (lo, hi) where it breaks a limit."""
    spl = prob.spline
    q = spl(sig)
    p1 = spl(sig, 1)
    p2 = spl(sig, 2)
    q[0] = prob.q_w[0]
    q[-1] = prob.q_w[-1]
    qd = p1 * sdq[:, None]
    qdd = p2 * (sdq * sdq)[:, None] + p1 * sddq[:, None]
    s_t = prob.s_at(sig)
    s_t[0] = prob.s[0]
    s_t[-1] = prob.s[-1]
    feed_speed = prob.feed_speed
    rep = trajectory_limits_report(t, q, vlim, alim)
    feed, f_ratio = _feed_of_samples(t, s_t, prob.s, prob.sf, feed_speed)
    gap = np.clip(np.searchsorted(prob.s, s_t, side="right") - 1, 0, prob.s.shape[0] - 2)
    inside = (prob.sf[gap] > 0) & (prob.sf[gap + 1] > 0)
    stencil = inside.copy()  # the feed's difference stencil lies in the stock too
    stencil[1:] &= inside[:-1]
    stencil[:-1] &= inside[1:]
    limited = stencil & (feed < (1.0 - FEED_HOLD_TOL) * feed_speed)
    tp = TimedPath(
        t=t, q=q, qd=qd, qdd=qdd, s_of_t=s_t, feed=feed, feed_limited=limited,
        segment=np.zeros(t.shape[0], dtype=np.int64), dt=dt, vel_limits=vlim.copy(),
        acc_limits=alim.copy(), feed_speed=feed_speed,
        max_speed_ratio=rep["max_speed_ratio"], max_acc_ratio=rep["max_acc_ratio"],
        max_feed_ratio=float(f_ratio.max()) if f_ratio.size else 0.0, method=method,
    )  # fmt: skip
    lo: list[FloatArray] = []
    hi: list[FloatArray] = []
    if tp.max_speed_ratio > RATIO_MAX or tp.max_feed_ratio > 1.0 + FEED_TOL:
        v = np.abs(np.diff(q, axis=0)) / (dt * vlim)
        k = np.flatnonzero((v > RATIO_MAX).any(axis=1) | (f_ratio > 1.0 + FEED_TOL))
        lo.append(sig[k])
        hi.append(sig[k + 1])
    if tp.max_acc_ratio > RATIO_MAX:
        a = np.abs(np.diff(q, 2, axis=0)) / (dt * dt * alim)
        k = np.flatnonzero((a > RATIO_MAX).any(axis=1))
        lo.append(sig[k])
        hi.append(sig[k + 2])
    if not lo:
        return tp, np.zeros(0), np.zeros(0)
    return tp, np.concatenate(lo), np.concatenate(hi)
