"""The servo's tracking law (robot/motion/servo.py) against the emulator's arm stepping it,
and the heat set as the arm reaches each sample (export.heat.servo_levels,
written_levels)."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from ruledrobot.export.heat import HEAT_STEP, servo_levels, written_levels
from ruledrobot.robot import load
from ruledrobot.robot.motion.servo import servo_time_constant, servo_track
from ruledrobot.ursim.arm.backend import KinematicBackend


def test_servo_track_is_the_emulators_arm():
    """The backend stepped one period per command (its own loop: an independent oracle)."""
    model = load("ur5e")
    dt, n = 0.002, 400
    t = np.arange(n) * dt
    q0 = np.array([0.1, -1.2, 1.0, -1.4, -1.5, 0.2])
    q = q0 + 0.05 * np.sin(2.0 * t)[:, None] * np.linspace(1.0, 0.5, 6)
    q[200:] = q[199]  # the command stops: the arm creeps on
    arm = KinematicBackend(model)
    arm.reset(q[0])
    got = np.empty_like(q)
    for k in range(n):
        arm.servo(q[k], 0.1, 300.0)
        arm.step(dt)
        got[k] = arm.state().q
    np.testing.assert_allclose(servo_track(q, dt, servo_time_constant(0.1, 300.0)), got,
                               atol=1e-12)  # fmt: skip
    assert np.abs(got[250] - q[250]).max() > 1e-4  # the residual after the stop


@given(st.floats(0.03, 0.2), st.floats(100.0, 2000.0))
def test_time_constant_closed_form(lookahead, gain):
    tau = servo_time_constant(lookahead, gain)
    assert tau == lookahead  # the lag UR's arm shows at gains 300 and 1200 (servo.py)
    # at a steady speed the response trails the command by tau
    dt = 0.002
    x = np.arange(4000) * dt
    y = servo_track(x, dt, tau)
    assert abs((x[-1] - y[-1]) - (tau - dt)) < 1e-9  # the discrete law's lag: tau - dt


def test_written_levels_never_above_and_exact_where_they_hold():
    t = np.linspace(0.0, 1.0, 501)
    lv = np.r_[np.linspace(0.5, 0.1, 250), np.full(251, 0.1)]  # a ramp down to a threshold
    w = written_levels(lv)
    assert np.all(w <= lv) and np.all(lv - w < HEAT_STEP)
    assert np.all(w[250:] == 0.1)  # the threshold written exactly, not a band above
    assert np.count_nonzero(np.diff(w)) < 0.5 * t.size  # few statements
    off = written_levels(np.r_[0.0, 0.3, 0.3, 0.0])
    np.testing.assert_array_equal(off, [0.0, 0.3, 0.3, 0.0])


def test_servo_levels_follow_the_arm_and_rest_on_the_set_point():
    dt = 0.002
    lv = np.r_[np.full(100, 0.5), np.full(400, 0.1), np.full(100, 0.5)]
    y = servo_levels(lv, dt, 0.1, 300.0)
    tau = servo_time_constant(0.1, 300.0)
    # after the step down the output decays as the arm: e^-1 of the step after tau
    k = 100 + round(tau / dt) - 1
    assert abs((y[k] - 0.1) / 0.4 - np.exp(-1.0)) < 0.02
    assert y[499] == 0.1  # settled: the set-point itself, exactly
    assert np.all(y[:100] == 0.5) and y[510] < 0.5


@given(st.floats(0.0021, 2.0), st.sampled_from([0.002, 0.008]), st.integers(1, 3000),
       st.integers(0, 2**31))  # fmt: skip
def test_servo_track_is_scipys_first_order_filter(tau, dt, n, seed):
    """The block recursion against scipy.signal.lfilter (an independent implementation
    of the same recursion), any time constant above the period, any length."""
    from scipy.signal import lfilter

    rng = np.random.default_rng(seed)
    x = np.cumsum(rng.normal(size=(n, 3)), axis=0) * 0.01 + rng.normal(size=3)
    a = dt / tau
    want = lfilter([a], [1.0, a - 1.0], x - x[0], axis=0) + x[0]
    np.testing.assert_allclose(servo_track(x, dt, tau), want, rtol=0, atol=1e-12)
