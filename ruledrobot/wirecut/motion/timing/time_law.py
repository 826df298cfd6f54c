""":func:`time_path`: the time-optimal timing of a cut path (method: the package doc)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numpy.typing import ArrayLike

from ....geometry.checks import as_number, as_shaped, check_increasing
from .diagnose import TimingFailure, too_long
from .inputs import as_factor, as_rate_limits
from .problem import _prepare
from .result import TimedPath
from .sampling import _sample_law, _timed_from_law, _TooLongError
from .solvers import _solve, _StalledError
from .tolerances import FEED_TOL, MAX_SAMPLES, MAX_TRIES, REFINE_ROUNDS

# --------------------------------------------------------------------------- public


def time_path(
    s: ArrayLike,
    q: ArrayLike,
    speed_factor: ArrayLike,
    feed_speed: float,
    vel_limits: ArrayLike,
    acc_limits: ArrayLike,
    dt: float,
    start_at_rest: bool = True,
    end_at_rest: bool = True,
    safety: float = 0.98,
    *,
    solver: str = "toppra",
) -> TimedPath:
    """Time-optimal timing of a joint path under joint and feed limits.

    Args:
        s: (N,) strictly increasing path parameter of the samples (any unit), N >= 2.
        q: (N, J) joint positions [rad] along the path; consecutive samples close.
        speed_factor: (N,) >= 0, metres moved by the fastest wire point inside the
            stock per unit of ``s`` (0 where the wire is out of the stock). The feed
            bound is ``speed_factor(s)·ds/dt <= feed_speed``.
        feed_speed: wire feed bound [m/s], > 0; held (within ``FEED_HOLD_TOL``)
            wherever the joints allow it.
        vel_limits: (J,) joint velocity limits [rad/s], > 0.
        acc_limits: (J,) joint acceleration limits [rad/s²], > 0.
        dt: controller period [s] (0.002 e-Series, 0.008 CB3), > 0.
        start_at_rest: start with zero velocity; otherwise at the largest path speed
            from which the rest of the path can be followed (the caller must match it).
        end_at_rest: end with zero velocity; otherwise as fast as the limits allow.
        safety: in (0, 1], factor on the joint velocity and acceleration limits used
            by the solver, so that the sampled finite differences stay within the true
            limits. The feed bound is not scaled.
        solver: ``"toppra"`` (controllable sets by toppra, falling back to
            ``"reachability"`` when toppra fails) or ``"reachability"`` (the
            closed-form recursion of this module only).

    Returns:
        :class:`TimedPath` sampled every ``dt`` from 0 to the end; its ratios are
        measured on the sampled output against the true (unscaled) limits and are
        ``<= 1 + RATIO_TOL`` (feed ``<= 1 + FEED_TOL``).

    Raises:
        TimingFailure: (a ValueError) no usable trajectory — the path speed collapses to
            zero, the timed path would last more than ``MAX_SAMPLES`` periods, or the
            sampled output still breaks a limit after every round; its fields and message
            say where (the caller's ``s``) and what binds (:mod:`.diagnose`).
        ValueError: bad input (the message names the argument and index).
    """
    s_arr = as_shaped(s, "s", (None,))
    N = s_arr.shape[0]
    if N < 2:
        raise ValueError(f"s: expected at least 2 samples, got {N}")
    check_increasing(s_arr, "s")
    q_arr = as_shaped(q, "q", (N, None))
    J = q_arr.shape[1]
    if J < 1:
        raise ValueError("q: expected at least one joint column, got shape (N, 0)")
    sf = as_shaped(speed_factor, "speed_factor", (N,))
    neg = np.flatnonzero(sf < 0)
    if neg.size:
        i = int(neg[0])
        raise ValueError(f"speed_factor[{i}]: expected a value >= 0, got {sf[i]}")
    feed = as_number(feed_speed, "feed_speed")
    vlim, alim, dt = as_rate_limits(vel_limits, acc_limits, dt, J)
    safety = as_factor(safety, "safety")
    if solver not in ("toppra", "reachability"):
        raise ValueError(f"solver: expected 'toppra' or 'reachability', got {solver!r}")
    use_toppra = solver == "toppra"

    prob = _prepare(s_arr, q_arr, sf, feed)
    scale = safety
    tp: TimedPath | None = None
    for attempt in range(MAX_TRIES):
        v_k, a_k = vlim * scale, alim * scale
        x, method = _solve(prob, v_k, a_k, start_at_rest, end_at_rest, use_toppra=use_toppra)
        try:
            law = _sample_law(prob.grid, x, dt, "time_path")
        except _StalledError:
            if method != "toppra":
                raise too_long(prob, x, v_k, a_k, dt, MAX_SAMPLES, stalled=True) from None
            x, method = _solve(prob, v_k, a_k, start_at_rest, end_at_rest, use_toppra=False)
            method = "reachability (fallback: toppra profile stalls)"
            try:
                law = _sample_law(prob.grid, x, dt, "time_path")
            except _StalledError:
                raise too_long(prob, x, v_k, a_k, dt, MAX_SAMPLES, stalled=True) from None
            except _TooLongError:
                raise too_long(prob, x, v_k, a_k, dt, MAX_SAMPLES) from None
        except _TooLongError:
            raise too_long(prob, x, v_k, a_k, dt, MAX_SAMPLES) from None
        tp, lo, hi = _timed_from_law(prob, *law, dt, vlim, alim, method)
        if lo.size == 0:
            if attempt:
                how = "grid refined" + (", limits tightened" if attempt > REFINE_ROUNDS else "")
                tp = replace(tp, method=f"{tp.method}; limits met after {attempt} round(s), {how}")
            return tp
        if attempt < REFINE_ROUNDS:  # the law is too coarse there: more stages
            prob.refine(lo, hi)
        else:  # last resort: tighter limits everywhere
            scale *= 0.995 / max(tp.max_speed_ratio, tp.max_acc_ratio, 1.0)
            if tp.max_feed_ratio > 1.0 + FEED_TOL:
                prob.feed_scale *= 0.995 / tp.max_feed_ratio
                prob.set_grid(prob.grid)
    assert tp is not None
    s0, s1 = (float(v) for v in prob.s_at(np.array([lo[0], hi[0]])))
    raise TimingFailure(
        f"time_path: sampled output still exceeds the limits after {MAX_TRIES} rounds "
        f"(joint speed ratio {tp.max_speed_ratio:.4f}, acceleration ratio "
        f"{tp.max_acc_ratio:.4f}, feed ratio {tp.max_feed_ratio:.4f}), first between "
        f"s = {s0:.6g} and {s1:.6g}; the path bends faster "
        f"there than dt = {dt} s resolves — resample it more densely or smooth it",
        reason="limits", duration=tp.duration, s_range=(s0, s1),
    )
