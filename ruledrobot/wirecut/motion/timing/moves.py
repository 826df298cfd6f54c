"""Joint moves (rest to rest) and the concatenation of timed parts."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from ....geometry.checks import as_number, as_shaped
from ....robot.motion.rates import trajectory_limits_report
from .diagnose import Binding, TimingFailure
from .inputs import as_factor, as_rate_limits
from .result import TimedPath
from .tolerances import CONTINUITY_TOL, MAX_SAMPLES, FloatArray


def joint_move(
    q0: ArrayLike,
    q1: ArrayLike,
    vel_limits: ArrayLike,
    acc_limits: ArrayLike,
    dt: float,
    speed_scale: float = 1.0,
) -> TimedPath:
    """Synchronised point-to-point joint motion from rest to rest (approach/retract).

    All joints follow the straight segment ``q0 + σ(t)·(q1 − q0)`` and arrive
    together. ``σ(t)`` has sine-squared acceleration ramps (continuous acceleration,
    peak equal to the limit of the most constrained joint, bounded jerk) and a
    cruise at the velocity limit of the most constrained joint when the move is
    long enough. The duration is rounded up to whole periods by slowing down.

    Args:
        q0: (J,) start [rad].
        q1: (J,) goal [rad]; may equal ``q0`` (a single sample is returned).
        vel_limits: (J,) [rad/s], > 0.
        acc_limits: (J,) [rad/s²], > 0.
        dt: controller period [s], > 0.
        speed_scale: in (0, 1]: the same motion slowed down in time — velocities
            scaled by ``speed_scale``, accelerations by its square.

    Returns:
        :class:`TimedPath` with ``s_of_t`` the fraction of the move (0…1), exact
        endpoints, zero velocity and acceleration at both ends, no feed.
    """
    a0 = as_shaped(q0, "q0", (None,))
    J = a0.shape[0]
    a1 = as_shaped(q1, "q1", (J,))
    vlim, alim, dt = as_rate_limits(vel_limits, acc_limits, dt, J)
    k_s = as_factor(speed_scale, "speed_scale")
    delta = a1 - a0
    D = np.abs(delta)
    moving = D > 0
    if not moving.any():
        z = np.zeros((1, J))
        return TimedPath(
            t=np.zeros(1), q=a0[None, :].copy(), qd=z, qdd=z.copy(), s_of_t=np.zeros(1),
            feed=np.zeros(1), feed_limited=np.zeros(1, dtype=bool),
            segment=np.zeros(1, dtype=np.int64), dt=dt, vel_limits=vlim, acc_limits=alim,
            feed_speed=None, max_speed_ratio=0.0, max_acc_ratio=0.0, max_feed_ratio=0.0,
            method="joint_move",
        )  # fmt: skip
    v_s = k_s * float(np.min(vlim[moving] / D[moving]))  # σ per second
    a_s = k_s * k_s * float(np.min(alim[moving] / D[moving]))  # σ per second²
    V = min(v_s, math.sqrt(a_s / 2.0))
    Ta = 2.0 * V / a_s
    T = 2.0 * Ta + (1.0 - V * Ta) / V
    n = max(1, math.ceil(T / dt - 1e-9))
    if n + 1 > MAX_SAMPLES:
        cruise = V < math.sqrt(a_s / 2.0)  # the velocity limit binds, else the acceleration
        lim = vlim if cruise else alim
        j = int(np.argmin(np.where(moving, lim / np.maximum(D, 1e-300), np.inf)))
        b = Binding("velocity" if cruise else "acceleration", j + 1, V * V, V, float(D[j]))
        raise TimingFailure(
            f"joint_move: the move lasts {T:.6g} s = {n + 1} samples, more than MAX_SAMPLES "
            f"= {MAX_SAMPLES}; joint {j + 1} sets it: {float(D[j]):.3g} rad to go at its "
            f"{b.kind} limit {float(lim[j]):.3g} rad/s{'' if cruise else '²'}",
            reason="too_long", duration=T, s_range=(0.0, 1.0), share=1.0, binding=b,
            path_speed=V,
        )
    k = T / (n * dt)
    t = np.arange(n + 1) * dt
    tau = t * k
    tau[-1] = T

    def ramp(r: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """σ, σ̇, σ̈ of the acceleration ramp at time r ∈ [0, Ta]."""
        ph = 2.0 * math.pi * r / Ta
        pos = V * (r * r / (2.0 * Ta) - Ta / (4.0 * math.pi**2) * (1.0 - np.cos(ph)))
        vel = V * (r / Ta - np.sin(ph) / (2.0 * math.pi))
        acc = V / Ta * (1.0 - np.cos(ph))
        return pos, vel, acc

    sig = np.empty(n + 1)
    sd = np.empty(n + 1)
    sdd = np.empty(n + 1)
    acc_ph = tau <= Ta
    dec_ph = tau >= T - Ta
    cru_ph = ~acc_ph & ~dec_ph
    p, v, a = ramp(tau[acc_ph])
    sig[acc_ph], sd[acc_ph], sdd[acc_ph] = p, v, a
    p, v, a = ramp(T - tau[dec_ph])
    sig[dec_ph], sd[dec_ph], sdd[dec_ph] = 1.0 - p, v, -a
    sig[cru_ph] = V * Ta / 2.0 + V * (tau[cru_ph] - Ta)
    sd[cru_ph] = V
    sdd[cru_ph] = 0.0
    sig[0], sig[-1] = 0.0, 1.0
    sd[[0, -1]] = 0.0
    sdd[[0, -1]] = 0.0
    sd *= k
    sdd *= k * k
    q = a0 + sig[:, None] * delta
    q[0] = a0
    q[-1] = a1
    rep = trajectory_limits_report(t, q, vlim, alim)
    return TimedPath(
        t=t, q=q, qd=sd[:, None] * delta, qdd=sdd[:, None] * delta, s_of_t=sig,
        feed=np.zeros(n + 1), feed_limited=np.zeros(n + 1, dtype=bool),
        segment=np.zeros(n + 1, dtype=np.int64), dt=dt, vel_limits=vlim, acc_limits=alim,
        feed_speed=None, max_speed_ratio=rep["max_speed_ratio"],
        max_acc_ratio=rep["max_acc_ratio"], max_feed_ratio=0.0, method="joint_move",
    )  # fmt: skip


def dwell(
    q: ArrayLike, duration: float, vel_limits: ArrayLike, acc_limits: ArrayLike, dt: float
) -> TimedPath:
    """Hold still at ``q`` (J,) [rad] for ``duration`` [s], rounded up to whole periods.

    E.g. while the wire heats.  ``s_of_t`` runs 0…1 over the hold.
    """
    a = as_shaped(q, "q", (None,))
    J = a.shape[0]
    vlim, alim, dt = as_rate_limits(vel_limits, acc_limits, dt, J)
    duration = as_number(duration, "duration", allow_zero=True)
    n = max(1, math.ceil(duration / dt - 1e-9)) + 1
    if n > MAX_SAMPLES:
        raise ValueError(f"dwell: {duration:.6g} s = {n} samples, more than MAX_SAMPLES")
    z = np.zeros((n, J))
    return TimedPath(
        t=np.arange(n) * dt, q=np.repeat(a[None, :], n, axis=0), qd=z, qdd=z.copy(),
        s_of_t=np.linspace(0.0, 1.0, n), feed=np.zeros(n), feed_limited=np.zeros(n, dtype=bool),
        segment=np.zeros(n, dtype=np.int64), dt=dt, vel_limits=vlim, acc_limits=alim,
        feed_speed=None, max_speed_ratio=0.0, max_acc_ratio=0.0, max_feed_ratio=0.0,
        method="dwell",
    )  # fmt: skip


def concatenate(parts: Sequence[TimedPath], dt: float) -> TimedPath:
    """Join timed paths end to start.

    Each part must be sampled every ``dt`` and start where the previous one ends
    (positions within ``CONTINUITY_TOL`` rad). The first sample of every later part is
    dropped (it duplicates the previous end), times are shifted, ``s_of_t`` is offset
    so that it is continuous and ``segment`` records the part of every sample. The
    ratios are re-measured on the joined samples against the elementwise smallest
    limits of the parts (a velocity jump at a joint shows up as an acceleration
    ratio); the feed ratio is the largest of the parts'.

    Raises:
        ValueError: no parts, a part not sampled every ``dt`` (index named), joint
            counts differ, or a discontinuity (the index of the later part named).
    """
    dt = as_number(dt, "dt")
    parts = list(parts)
    if not parts:
        raise ValueError("parts: expected at least one TimedPath, got none")
    for i, p in enumerate(parts):
        if not isinstance(p, TimedPath):
            raise ValueError(f"parts[{i}]: expected a TimedPath, got {type(p).__name__}")
    J = parts[0].q.shape[1]
    for i, p in enumerate(parts):
        if p.q.shape[1] != J:
            raise ValueError(f"parts[{i}]: expected {J} joints like parts[0], got {p.q.shape[1]}")
        h = np.diff(p.t)
        if h.size and np.max(np.abs(h - dt)) > 1e-9 * max(1.0, dt):
            raise ValueError(
                f"parts[{i}]: expected samples every dt = {dt} s, got periods "
                f"{h.min():.9g}…{h.max():.9g} s"
            )
    for i in range(1, len(parts)):
        gap = np.abs(parts[i].q[0] - parts[i - 1].q[-1])
        if gap.max() > CONTINUITY_TOL:
            j = int(np.argmax(gap))
            raise ValueError(
                f"parts[{i}]: starts {gap[j]:.3g} rad away from the end of parts[{i - 1}] "
                f"(joint {j + 1}); positions must match within {CONTINUITY_TOL} rad"
            )
    keep = [slice(None)] + [slice(1, None)] * (len(parts) - 1)
    qs = [p.q[k] for p, k in zip(parts, keep, strict=True)]
    n = [x.shape[0] for x in qs]
    M = sum(n)
    s_chunks = []
    offset = 0.0
    for i, (p, k) in enumerate(zip(parts, keep, strict=True)):
        if i > 0:
            offset += float(parts[i - 1].s_of_t[-1]) - float(p.s_of_t[0])
        s_chunks.append(p.s_of_t[k] + offset)
    q = np.concatenate(qs)
    t = np.arange(M) * dt
    vlim = np.min([p.vel_limits for p in parts], axis=0)
    alim = np.min([p.acc_limits for p in parts], axis=0)
    rep = trajectory_limits_report(t, q, vlim, alim)
    feeds = {p.feed_speed for p in parts if p.feed_speed is not None}
    return TimedPath(
        t=t, q=q,
        qd=np.concatenate([p.qd[k] for p, k in zip(parts, keep, strict=True)]),
        qdd=np.concatenate([p.qdd[k] for p, k in zip(parts, keep, strict=True)]),
        s_of_t=np.concatenate(s_chunks),
        feed=np.concatenate([p.feed[k] for p, k in zip(parts, keep, strict=True)]),
        feed_limited=np.concatenate([p.feed_limited[k] for p, k in zip(parts, keep, strict=True)]),
        segment=np.repeat(np.arange(len(parts), dtype=np.int64), n), dt=dt,
        vel_limits=vlim, acc_limits=alim,
        feed_speed=feeds.pop() if len(feeds) == 1 else None,
        max_speed_ratio=rep["max_speed_ratio"], max_acc_ratio=rep["max_acc_ratio"],
        max_feed_ratio=max(p.max_feed_ratio for p in parts), method="concatenate",
    )  # fmt: skip
