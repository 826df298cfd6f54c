"""The runner's monitoring on synthetic plans, no controller: the deviation match
(``Session.check_deviation``: an arm that follows the plan with the servo's lag is never
reported off it, an arm that leaves or stops is, whatever the shape of the path) and
the stream's schedule (``Session.keep_schedule``).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ruledrobot.export.run_session import Session, Stop

WINDOW = 200  # samples: (3 x lookahead + 0.1 s) at 500 Hz, the runner's for lookahead 0.1 s


def session(limit: float = 0.05) -> Session:
    s = Session(None, {"host": "127.0.0.1", "frequency": 500.0, "watchdog": 0.0,
                       "deviation_limit": limit, "max_latency": 0.1})  # fmt: skip
    s.window = WINDOW
    return s


def smooth_move(a: np.ndarray, b: np.ndarray, n: int) -> np.ndarray:
    """(n, 6) rest-to-rest move from a to b (cosine profile: creeps at both ends)."""
    s = 0.5 - 0.5 * np.cos(np.linspace(0.0, np.pi, n))
    return a + s[:, None] * (b - a)


def follow(plan: np.ndarray, lag: int, s: Session) -> None:
    """Send every sample; the arm is ``lag`` samples behind the command."""
    for k in range(len(plan)):
        s.check_deviation(plan, plan[max(0, k - lag)], k)
    for _ in range(lag):  # the final hold until the arm arrives
        s.check_deviation(plan, plan[-1], len(plan) - 1)


A = np.array([0.0, -1.5, 1.5, -1.5, -1.6, 0.0])
B = A + np.array([0.4, 0.3, -0.5, 0.2, 0.1, 0.6])


@pytest.mark.parametrize("hold", [0, 10, 500])
def test_leaving_the_way_it_came_after_a_hold_is_on_the_plan(hold):
    """Arrive, hold (the pre-heat), leave back along the arrival: the part demo's lead-in
    after its pre-heat, which a match that stepped back step by step called 0.05 rad."""
    # the resampled hold creeps on by rounding, away from an arm still closing in on it
    still = B + np.linspace(0.0, 1e-9, hold)[:, None] * (B - A)
    plan = np.concatenate([smooth_move(A, B, 600), still, smooth_move(B, A, 600)])
    s = session()
    follow(plan, lag=50, s=s)
    assert s.max_dev < 1e-9
    assert s.k_match == len(plan) - 1
    # an arm that rests a few tenths of a micro-radian short of the hold (a servo's
    # steady-state error): the end of the approach is then nearer than the hold itself,
    # and a match that took the strict minimum stayed there and lost the arm
    short = 3e-7 * (A - B) / np.max(np.abs(A - B))
    s = session()
    for k in range(len(plan)):
        s.check_deviation(plan, plan[max(0, k - 50)] + short, k)
    assert s.max_dev < 1e-6


@settings(max_examples=30, deadline=None)
@given(lag=st.integers(0, 50), n1=st.integers(50, 800), hold=st.integers(0, 600),
       n2=st.integers(50, 800), seed=st.integers(0, 2**16))  # fmt: skip
def test_an_arm_on_the_plan_with_the_servo_lag_is_never_off_it(lag, n1, hold, n2, seed):
    rng = np.random.default_rng(seed)
    C = B + rng.uniform(-0.5, 0.5, 6)
    plan = np.concatenate([smooth_move(A, B, n1), np.repeat(B[None], hold, axis=0),
                           smooth_move(B, C, n2)])  # fmt: skip
    s = session()
    follow(plan, lag, s)
    assert s.max_dev < 1e-9


def test_an_arm_that_leaves_the_plan_is_stopped():
    plan = smooth_move(A, B, 1000)
    s = session(limit=0.02)
    off = np.zeros(6)
    with pytest.raises(Stop) as stop:
        for k in range(len(plan)):
            off[1] = 0.0 if k < 400 else 1e-4 * (k - 400)  # joint 2 drifts away
            s.check_deviation(plan, plan[max(0, k - 30)] + off, k)
    assert stop.value.status == "deviation"
    # the match measures the distance to the path, which is at most the drift (the arm
    # may be nearer another sample): stopped once the drift passed the limit, before twice
    assert 600 <= k <= 800


def test_an_arm_that_stops_while_the_plan_goes_on_is_stopped():
    """On the path but stuck (the wire would dwell in the foam): the arm falls more than
    the window behind the command."""
    plan = smooth_move(A, B, 1000)
    s = session()
    with pytest.raises(Stop) as stop:
        for k in range(len(plan)):
            s.check_deviation(plan, plan[min(k, 300)], k)
    assert stop.value.status == "deviation" and "behind" in stop.value.message
    # once the window has passed and the plan has gone 5 mrad (a tenth of the limit) on
    assert 300 + WINDOW < k < 300 + WINDOW + 40


def test_an_arm_that_closes_in_on_a_rest_slowly_is_not_behind():
    """The servo filter's last micro-radians into a hold take long in samples, not in
    distance (the part demo's pre-heat after its approach): a first-order follower,
    time constants 20 to 80 ms, is never called behind or off the plan."""
    plan = np.concatenate([smooth_move(A, B, 300), np.repeat(B[None], 800, axis=0),
                           smooth_move(B, A, 300)])  # fmt: skip
    for tau in (0.02, 0.05, 0.08):
        s = session()
        arm = plan[0].copy()
        for k in range(len(plan)):
            arm += (plan[k] - arm) * (1.0 / 500.0) / tau
            s.check_deviation(plan, arm, k)
        assert s.max_dev < 0.02, tau


def test_a_path_run_is_matched_without_time():
    """moveL paths: the controller times the motion, every sample is 'sent' at once."""
    plan = smooth_move(A, B, 1000)
    s = session()
    for k in range(0, len(plan), 7):
        s.check_deviation(plan, plan[k], len(plan) - 1, timed=False)
    assert s.max_dev < 1e-9 and s.k_match >= len(plan) - 7


def test_the_stream_keeps_the_plans_schedule():
    s = session()
    dt = 1.0 / 500.0
    assert s.keep_schedule(10, 11 * dt, 1000) == 11  # on time
    assert s.keep_schedule(11, 12.9 * dt, 1000) == 12  # late within the period
    assert s.keep_schedule(12, 16.5 * dt, 1000) == 16  # three periods late: 13-15 skipped
    assert s.skipped == 3 and s.max_slip == pytest.approx(3.5 * dt)
    assert s.keep_schedule(997, 999.5 * dt, 1000) == 999  # the last sample is always sent
    assert s.keep_schedule(998, 1003 * dt, 1000) == 999
    with pytest.raises(Stop) as stop:
        s.keep_schedule(100, 101 * dt + 0.101, 1000)
    assert stop.value.status == "client_slow" and "101 ms late" in stop.value.message
