"""Time law of a cut: limits on the sampled output, constant feed, joint-limited
stretches, rest-to-rest, point-to-point moves, concatenation, bad input.

Tolerance on the limit ratios: ``time_path`` itself measures its sampled output
against the true limits and refines until every ratio is <= 1, so the tests allow
only ``RATIO_TOL = 1e-9`` on top — the rounding of a second difference
(|q| ~ 1 rad, eps ~ 2e-16, dt² = 4e-6 s² → ~5e-11 rad/s², against limits of
1 rad/s² or more). The feed is allowed ``FEED_TOL = 1e-6`` (round-off of the
controllable sets).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from ruledrobot.wirecut.motion import timing
from ruledrobot.wirecut.motion.timing import (
    FEED_TOL,
    RATIO_TOL,
    TimedPath,
    TimingFailure,
    concatenate,
    joint_move,
    time_path,
    trajectory_limits_report,
)

DT = 0.002  # e-Series controller period
VL = np.array([2.0, 2.0, 3.0, 3.0, 3.0, 3.0])  # rad/s (UR5e: π; lower to hit them)
AL = np.array([4.0, 4.0, 6.0, 8.0, 8.0, 8.0])  # rad/s²


def random_path(seed: int, n: int, joints: int) -> tuple[np.ndarray, np.ndarray]:
    """A smooth random joint path: (s (n,), q (n, joints)), s over a random span."""
    rng = np.random.default_rng(seed)
    s = np.sort(rng.uniform(0.0, rng.uniform(0.5, 50.0), n))
    s[0], s[-1] = 0.0, s[-1] + 1.0
    s = np.maximum.accumulate(s + np.arange(n) * 1e-6)
    u = (s - s[0]) / (s[-1] - s[0])
    q = np.zeros((n, joints))
    for h in range(rng.integers(1, 4)):
        amp = rng.normal(size=joints) * rng.uniform(0.05, 1.0)
        q += amp * np.sin(np.pi * (h + 1) * rng.uniform(0.5, 2.0) * u[:, None]
                          + rng.uniform(0, 6, size=joints))  # fmt: skip
    return s, q


def independent_feed(tp: TimedPath, s: np.ndarray, sf: np.ndarray) -> np.ndarray:
    """Feed of each sample interval [m/s], the speed factor taken at the interval's
    midpoint (fine for a speed factor that varies slowly)."""
    mid = 0.5 * (tp.s_of_t[1:] + tp.s_of_t[:-1])
    return np.interp(mid, s, sf) * np.diff(tp.s_of_t) / np.diff(tp.t)


def check_sampling(tp: TimedPath, dt: float) -> None:
    M = tp.n_samples
    assert tp.t.shape == (M,) and tp.q.shape[0] == tp.qd.shape[0] == tp.qdd.shape[0] == M
    np.testing.assert_array_equal(tp.t, np.arange(M) * dt)
    assert tp.duration == tp.t[-1]
    assert np.all(np.diff(tp.s_of_t) >= 0)


# --------------------------------------------------------------------------- limits


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    seed=st.integers(0, 2**31 - 1),
    n=st.sampled_from([2, 3, 9, 60, 400]),
    joints=st.integers(1, 6),
    dt=st.sampled_from([0.002, 0.008]),
    rest=st.tuples(st.booleans(), st.booleans()),
    feed=st.floats(0.005, 0.3),
)
def test_limits_hold_on_the_sampled_output(seed, n, joints, dt, rest, feed):
    s, q = random_path(seed, n, joints)
    rng = np.random.default_rng(seed + 1)
    # m of wire motion per unit s: at most 0.5 m over the whole path
    sf = rng.uniform(0.0, 1.0, n) * rng.uniform(0.01, 0.5) / (s[-1] - s[0])
    vl, al = VL[:joints], AL[:joints]
    tp = time_path(s, q, sf, feed, vl, al, dt, start_at_rest=rest[0], end_at_rest=rest[1])
    check_sampling(tp, dt)
    rep = trajectory_limits_report(tp.t, tp.q, vl, al)
    assert rep["max_speed_ratio"] <= 1.0 + RATIO_TOL
    assert rep["max_acc_ratio"] <= 1.0 + RATIO_TOL
    assert rep["ok"] and tp.within_limits
    assert tp.max_speed_ratio == rep["max_speed_ratio"]
    assert tp.max_acc_ratio == rep["max_acc_ratio"]
    assert tp.max_feed_ratio <= 1.0 + FEED_TOL
    np.testing.assert_array_equal(tp.q[0], q[0])
    np.testing.assert_array_equal(tp.q[-1], q[-1])
    assert tp.s_of_t[0] == s[0] and tp.s_of_t[-1] == s[-1]


def test_time_optimal_uses_the_limits():
    """Without a feed bound the law runs at the (safety-scaled) joint limits."""
    s, q = random_path(3, 500, 6)
    tp = time_path(s, q, np.zeros(500), 0.1, VL, AL, DT, safety=0.98)
    assert max(tp.max_speed_ratio, tp.max_acc_ratio) > 0.97
    assert tp.max_feed_ratio == 0.0 and not tp.feed_limited.any()


def test_toppra_and_the_closed_form_recursion_agree():
    s, q = random_path(11, 800, 6)
    sf = np.full(800, 0.05)
    a = time_path(s, q, sf, 0.02, VL, AL, DT)
    b = time_path(s, q, sf, 0.02, VL, AL, DT, solver="reachability")
    assert a.method.startswith("toppra") and b.method.startswith("reachability")
    assert abs(a.duration - b.duration) <= 2 * DT
    np.testing.assert_allclose(a.q[: min(a.n_samples, b.n_samples)],
                               b.q[: min(a.n_samples, b.n_samples)], atol=1e-5)  # fmt: skip


def test_toppra_failure_falls_back_to_the_closed_form(monkeypatch):
    from toppra.algorithm import TOPPRA

    def broken(self, sdmin, sdmax):
        K = np.zeros((self._N + 1, 2))
        K[: self._N // 2] = np.nan  # "the controllable set is empty" (toppra #14, #226)
        return K

    monkeypatch.setattr(TOPPRA, "compute_controllable_sets", broken)
    s, q = random_path(5, 300, 6)
    tp = time_path(s, q, np.full(300, 0.02), 0.01, VL, AL, DT)
    assert tp.method.startswith("reachability (fallback: toppra")
    assert "empty or NaN" in tp.method
    assert tp.within_limits and tp.max_feed_ratio <= 1.0 + FEED_TOL


def test_repeated_samples_do_not_slow_the_path_down():
    s, q = random_path(8, 300, 6)
    q2 = q.copy()
    q2[100:130] = q2[100]  # the planner held still for 30 samples
    sf = np.zeros(300)
    ref = time_path(s, q, sf, 0.1, VL, AL, DT)
    tp = time_path(s, q2, sf, 0.1, VL, AL, DT)
    assert tp.within_limits
    assert tp.duration < 1.2 * ref.duration


def test_one_long_gap_is_crossed_at_speed():
    """A jump between two samples (a sparse lead-in, an IK branch change) is split into
    stages, so the law accelerates across it instead of creeping at the feed."""
    n = 400
    s = np.linspace(0.0, 1.0, n)
    q = np.stack([0.2 * np.sin(2 * s + k) for k in range(6)], axis=1)
    q[200:, 5] += 2.0
    tp = time_path(s, q, np.full(n, 0.3), 0.02, VL, AL, DT)
    assert tp.within_limits and tp.max_speed_ratio > 0.95  # joint 6 runs across the gap
    assert tp.duration < 0.3 / 0.02 + 2.0  # the cut at the feed + the jump


def test_limits_that_cannot_be_met_raise(monkeypatch):
    s, q, sf = feed_path(50)
    real = timing.sampling._timed_from_law

    def always_over(prob, t, sig, *rest):  # every round reports samples 0..1 over a limit
        tp, _, _ = real(prob, t, sig, *rest)
        return tp, sig[:1], sig[1:2]

    monkeypatch.setattr(timing.time_law, "_timed_from_law", always_over)
    with pytest.raises(TimingFailure, match=r"exceeds the limits after 6 rounds.*between s =") as e:
        time_path(s, q, sf, 0.05, VL, AL, DT)
    assert e.value.reason == "limits"  # a failed plan (the timing check), not bad input


def test_a_path_speed_that_collapses_names_the_place(monkeypatch):
    s, q, sf = feed_path(50)
    real = timing.problem._x_upper

    def zero_in_the_middle(prob, vlim):
        x = real(prob, vlim)
        mid = np.abs(prob.grid - prob.grid[-1] / 2) < prob.grid[-1] / 10
        return np.where(mid, 0.0, x)

    monkeypatch.setattr(timing.solvers, "_x_upper", zero_in_the_middle)
    with pytest.raises(TimingFailure, match=r"collapses to zero between s = 0\.4.*binding") as e:
        time_path(s, q, sf, 0.05, VL, AL, DT, solver="reachability")
    assert e.value.reason == "stall" and e.value.duration == math.inf
    assert 0.39 < e.value.s_range[0] < e.value.s_range[1] < 0.7  # the zeroed stretch (in σ)


# --------------------------------------------------------------------------- feed


def feed_path(n: int = 600):
    """A slow 6-joint path with a constant speed factor: 0.4 m of wire per unit s."""
    s = np.linspace(0.0, 1.0, n)
    q = np.stack([0.2 * np.sin(1.3 * s + k) + 0.05 * k * s for k in range(6)], axis=1)
    return s, q, np.full(n, 0.4)


def test_constant_feed_is_held_in_the_interior():
    s, q, sf = feed_path()
    feed = 0.02  # m/s → 20 s for the cut, the joints creep far below their limits
    tp = time_path(s, q, sf, feed, VL, AL, DT)
    f = independent_feed(tp, s, sf) / feed
    reached = np.flatnonzero(f >= 0.99)
    first, last = reached[0], reached[-1]
    # the start and stop ramps are short ...
    assert tp.t[first] < 0.2 and tp.duration - tp.t[last + 1] < 0.2
    # ... and in between the feed is the set feed within 1 %
    assert np.abs(f[first : last + 1] - 1.0).max() < 0.01
    assert np.abs(tp.feed[first + 1 : last] / feed - 1.0).max() < 0.01
    assert not tp.feed_limited[first + 1 : last].any()
    assert tp.feed_limited[0] and tp.feed_limited[-1]  # the ramps are reported
    assert tp.max_feed_ratio <= 1.0 + FEED_TOL and f.max() <= 1.0 + 1e-6
    assert abs(tp.duration - 0.4 / feed) < 0.5


def test_feed_is_held_from_stock_entry_to_exit():
    s, q, _ = feed_path()
    sf = np.where((s > 0.3) & (s < 0.7), 0.4, 0.0)  # the wire is in the stock in the middle
    tp = time_path(s, q, sf, 0.02, VL, AL, DT)
    inside = (tp.s_of_t > 0.31) & (tp.s_of_t < 0.69)
    assert np.abs(tp.feed[inside] / 0.02 - 1.0).max() < 0.01
    assert not tp.feed_limited.any()
    assert tp.max_feed_ratio <= 1.0 + FEED_TOL
    # out of the stock the path runs faster than in it
    out = tp.s_of_t < 0.25
    assert np.gradient(tp.s_of_t, DT)[out].max() > 2 * 0.02 / 0.4


def test_joint_limited_stretch_lowers_the_feed_and_says_so():
    n = 800
    s = np.linspace(0.0, 1.0, n)
    q = np.stack([0.1 * s + 0.05 * k for k in range(6)], axis=1)
    q[:, 0] += 0.5 * np.tanh((s - 0.5) / 0.05)  # joint 1 swings fast in the middle
    sf = np.full(n, 0.5)
    vl = VL.copy()
    vl[0] = 0.5
    feed = 0.05  # ṡ = 0.1 per s at the feed; joint 1 would need 10·0.1 = 1 rad/s
    tp = time_path(s, q, sf, feed, vl, AL, DT)
    assert tp.within_limits
    mid = np.abs(tp.s_of_t - 0.5) < 0.01
    assert tp.feed_limited[mid].all()
    assert tp.feed[mid].max() < 0.8 * feed
    # joint 1 runs at its (safety-scaled) limit there
    rep = trajectory_limits_report(tp.t, tp.q, vl, AL)
    assert rep["speed_ratio"][0] > 0.95
    calm = ((tp.s_of_t > 0.1) & (tp.s_of_t < 0.25)) | ((tp.s_of_t > 0.75) & (tp.s_of_t < 0.9))
    assert not tp.feed_limited[calm].any()
    assert np.abs(tp.feed[calm] / feed - 1.0).max() < 0.01
    iv = tp.feed_limited_s_intervals()
    assert any(a < 0.5 < b for a, b in iv)
    ti = tp.feed_limited_intervals
    assert ti.shape[1] == 2 and np.all(ti[:, 1] >= ti[:, 0])


# --------------------------------------------------------------------------- rest


@pytest.mark.parametrize("start,end", [(True, True), (False, True), (True, False), (False, False)])
def test_starts_and_ends_at_rest_when_asked(start, end):
    s, q, sf = feed_path(300)
    tp = time_path(s, q, sf, 0.05, VL, AL, DT, start_at_rest=start, end_at_rest=end)
    assert tp.within_limits
    v0 = np.abs(tp.qd[0]).max()
    v1 = np.abs(tp.qd[-1]).max()
    assert (v0 == 0.0) if start else (v0 > 1e-3)
    assert (v1 == 0.0) if end else (v1 > 1e-3)
    if start:  # the first period moves no more than the acceleration allows
        assert np.all(np.abs(tp.q[1] - tp.q[0]) <= 0.5 * AL * DT**2 * (1 + 1e-9))


def test_tiny_feed_is_refused_before_allocating_a_huge_trajectory():
    s, q, sf = feed_path(100)
    with pytest.raises(ValueError, match="MAX_SAMPLES"):
        time_path(s, q, sf, 1e-9, VL, AL, DT)


def test_path_that_does_not_move():
    q = np.tile([0.1, -1.0, 1.2, 0.0, 0.5, 0.0], (5, 1))
    tp = time_path(np.arange(5.0), q, np.zeros(5), 0.1, VL, AL, DT)
    assert tp.n_samples == 2 and np.all(tp.q == q[0]) and tp.within_limits


# --------------------------------------------------------------------------- joint_move


def test_joint_move_synchronised_within_limits_exact_endpoints():
    q0 = np.array([0.0, -1.5, 1.2, -0.3, 1.57, 0.0])
    q1 = np.array([0.8, -1.0, 0.2, -0.3, 1.0, 2.5])
    tp = joint_move(q0, q1, VL, AL, DT)
    check_sampling(tp, DT)
    np.testing.assert_array_equal(tp.q[0], q0)
    np.testing.assert_array_equal(tp.q[-1], q1)
    assert np.all(tp.qd[[0, -1]] == 0) and np.all(tp.qdd[[0, -1]] == 0)
    rep = trajectory_limits_report(tp.t, tp.q, VL, AL)
    assert rep["ok"] and max(rep["max_speed_ratio"], rep["max_acc_ratio"]) > 0.9
    # synchronised: every moving joint has covered the same fraction at every sample
    moving = q1 != q0
    frac = (tp.q[:, moving] - q0[moving]) / (q1 - q0)[moving]
    assert np.abs(frac - frac[:, :1]).max() < 1e-12
    np.testing.assert_allclose(frac[:, 0], tp.s_of_t, atol=1e-12)
    assert np.all(np.diff(tp.s_of_t) >= 0)
    # acceleration is continuous (sine-squared ramps): no jump larger than a few steps
    jump = np.abs(np.diff(tp.qdd, axis=0)).max(axis=0)
    assert np.all(jump <= AL * 0.05)


def test_joint_move_speed_scale_slows_it_down():
    q0, q1 = np.zeros(6), np.array([1.0, 0.5, -0.5, 0.2, 0.0, 3.0])
    fast = joint_move(q0, q1, VL, AL, DT)
    slow = joint_move(q0, q1, VL, AL, DT, speed_scale=0.5)
    assert slow.duration == pytest.approx(2 * fast.duration, abs=2 * DT)
    assert slow.max_speed_ratio <= 0.5 + 1e-9


def test_joint_move_long_move_cruises_at_the_velocity_limit():
    tp = joint_move(np.zeros(6), np.array([0, 0, 0, 0, 0, 12.0]), VL, AL, DT)
    assert tp.max_speed_ratio == pytest.approx(1.0, abs=1e-6)
    assert tp.max_acc_ratio <= 1.0 + RATIO_TOL


def test_joint_move_zero_length():
    q0 = np.array([0.1, 0.2, 0.3, 0.4, 0.5, 0.6])
    tp = joint_move(q0, q0.copy(), VL, AL, DT)
    assert tp.n_samples == 1 and tp.duration == 0.0
    np.testing.assert_array_equal(tp.q[0], q0)
    assert tp.within_limits


def test_joint_move_tiny_move():
    q0 = np.zeros(6)
    q1 = q0 + 1e-12
    tp = joint_move(q0, q1, VL, AL, DT)
    np.testing.assert_array_equal(tp.q[-1], q1)
    assert tp.within_limits


# --------------------------------------------------------------------------- concatenate


def test_concatenate_approach_cut_retract():
    s, q, sf = feed_path(300)
    home = np.zeros(6)
    parts = [
        joint_move(home, q[0], VL, AL, DT),
        time_path(s, q, sf, 0.05, VL, AL, DT),
        joint_move(q[-1], home, VL, AL, DT),
    ]
    whole = concatenate(parts, DT)
    check_sampling(whole, DT)
    assert whole.n_samples == sum(p.n_samples for p in parts) - 2  # no duplicate joints
    assert whole.duration == pytest.approx(sum(p.duration for p in parts), abs=1e-9)
    np.testing.assert_array_equal(np.bincount(whole.segment), [p.n_samples for p in parts[:1]]
                                  + [p.n_samples - 1 for p in parts[1:]])  # fmt: skip
    k = parts[0].n_samples
    np.testing.assert_array_equal(whole.q[k - 1 : k - 1 + parts[1].n_samples], parts[1].q)
    assert whole.within_limits and whole.feed_speed == 0.05
    assert np.all(np.diff(whole.s_of_t) >= 0)
    rep = trajectory_limits_report(whole.t, whole.q, VL, AL)
    assert rep["max_acc_ratio"] == whole.max_acc_ratio


def test_concatenate_names_the_discontinuous_segment():
    a = joint_move(np.zeros(6), np.ones(6), VL, AL, DT)
    b = joint_move(np.ones(6), np.full(6, 2.0), VL, AL, DT)
    c = joint_move(np.full(6, 2.0) + 1e-6, np.zeros(6), VL, AL, DT)
    concatenate([a, b], DT)
    with pytest.raises(ValueError, match=r"parts\[2\].*parts\[1\]"):
        concatenate([a, b, c], DT)
    with pytest.raises(ValueError, match=r"parts\[1\]: expected samples every dt"):
        concatenate([a, joint_move(np.ones(6), np.zeros(6), VL, AL, 0.008)], DT)
    with pytest.raises(ValueError, match="parts"):
        concatenate([], DT)
    with pytest.raises(ValueError, match=r"parts\[0\]: expected a TimedPath"):
        concatenate([np.zeros((3, 6))], DT)
    with pytest.raises(ValueError, match=r"parts\[1\]: expected 6 joints"):
        concatenate([a, joint_move(np.ones(5), np.zeros(5), VL[:5], AL[:5], DT)], DT)


def test_concatenate_within_continuity_tolerance():
    a = joint_move(np.zeros(6), np.ones(6), VL, AL, DT)
    b = joint_move(np.ones(6) + 5e-10, np.zeros(6), VL, AL, DT)
    whole = concatenate([a, b], DT)
    assert whole.n_samples == a.n_samples + b.n_samples - 1


# --------------------------------------------------------------------------- report


def test_report_on_a_known_parabola():
    t = np.arange(101) * DT
    a = np.array([1.0, -2.0])
    q = 0.5 * a * t[:, None] ** 2
    rep = trajectory_limits_report(t, q, [10.0, 10.0], [4.0, 4.0])
    assert rep["max_acc_ratio"] == pytest.approx(0.5)
    assert rep["worst_acc"][1] == 1
    np.testing.assert_allclose(rep["max_speed"], np.abs(a) * (t[-1] - DT / 2))
    assert rep["ok"]
    rep = trajectory_limits_report(t, q, [10.0, 10.0], [4.0, 1.5])
    assert not rep["ok"] and rep["max_acc_ratio"] == pytest.approx(2.0 / 1.5)


# --------------------------------------------------------------------------- bad input


def _args(**over):
    s, q, sf = feed_path(20)
    args = dict(s=s, q=q, speed_factor=sf, feed_speed=0.05, vel_limits=VL, acc_limits=AL,
                dt=DT)  # fmt: skip
    args.update(over)
    return args


S20, Q20, SF20 = feed_path(20)


@pytest.mark.parametrize(
    "over,match",
    [
        (dict(s=np.r_[S20[:5], S20[4], S20[6:]]), r"s\[5\]: expected strictly increasing"),
        (dict(s=S20[::-1]), r"s\[1\]: expected strictly increasing"),
        (dict(s=S20[:1], q=Q20[:1], speed_factor=SF20[:1]), r"s: expected at least 2"),
        (dict(q=Q20[:, :, None]), r"q: expected shape"),
        (dict(q=Q20[:-1]), r"q: expected shape \(20, n\)"),
        (dict(q=np.where(np.arange(20)[:, None] == 7, np.nan, Q20)), r"q\[\[7, 0\]\]"),
        (dict(s=np.r_[S20[:3], np.inf, S20[4:]]), r"s\[3\]: expected a finite"),
        (dict(speed_factor=SF20[:-1]), r"speed_factor: expected shape"),
        (dict(speed_factor=-SF20), r"speed_factor\[0\]: expected a value >= 0"),
        (dict(feed_speed=0.0), r"feed_speed: expected a number > 0"),
        (dict(feed_speed=-1.0), r"feed_speed"),
        (dict(feed_speed=float("nan")), r"feed_speed: expected a finite"),
        (dict(vel_limits=-VL), r"vel_limits\[0\]: expected a limit > 0"),
        (dict(vel_limits=VL[:5]), r"vel_limits: expected shape \(6,\)"),
        (dict(acc_limits=np.r_[AL[:2], 0.0, AL[3:]]), r"acc_limits\[2\]"),
        (dict(dt=0.0), r"dt: expected a number > 0"),
        (dict(safety=1.5), r"safety"),
        (dict(solver="cvxpy"), r"solver"),
    ],
)
def test_time_path_bad_input_names_the_item(over, match):
    with pytest.raises(ValueError, match=match):
        time_path(**_args(**over))


def test_other_functions_bad_input_names_the_item():
    with pytest.raises(ValueError, match=r"q1: expected shape \(6,\)"):
        joint_move(np.zeros(6), np.zeros(5), VL, AL, DT)
    with pytest.raises(ValueError, match=r"q0\[2\]: expected a finite"):
        joint_move([0, 0, math.nan, 0, 0, 0], np.zeros(6), VL, AL, DT)
    with pytest.raises(ValueError, match=r"acc_limits\[1\]"):
        joint_move(np.zeros(6), np.ones(6), VL, [1, -1, 1, 1, 1, 1], DT)
    with pytest.raises(ValueError, match=r"speed_scale"):
        joint_move(np.zeros(6), np.ones(6), VL, AL, DT, speed_scale=0.0)
    with pytest.raises(ValueError, match=r"t\[2\]: expected strictly increasing"):
        trajectory_limits_report([0.0, 0.1, 0.1], np.zeros((3, 6)), VL, AL)
    with pytest.raises(ValueError, match=r"q: expected shape \(3, n\)"):
        trajectory_limits_report([0.0, 0.1, 0.2], np.zeros((4, 6)), VL, AL)


def test_result_is_frozen():
    tp = joint_move(np.zeros(6), np.ones(6), VL, AL, DT)
    with pytest.raises(ValueError):
        tp.q[0, 0] = 1.0
    with pytest.raises(AttributeError):
        tp.dt = 0.1  # type: ignore[misc]
    assert "TimedPath" in repr(tp)
    assert timing.MAX_SAMPLES > 1_000_000
