"""A scheduled wire power (issue 33): the analog set-points of exported programs, of the
forwarded messages and of the recording follow the trajectory's heat_power column."""

from __future__ import annotations

import struct

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from ruledrobot.export import urscript_program
from ruledrobot.export.forward.program import (
    MICRO,
    WORDS,
    ForwardSettings,
    end_message,
    forward_program,
    sample_messages,
    stop_message,
)
from ruledrobot.export.heat import (
    HEAT_STEP,
    heat_levels,
    heat_power_from_outputs,
    servo_levels,
    written_levels,
)
from ruledrobot.export.settings import SERVO_GAIN, SERVO_LOOKAHEAD
from ruledrobot.robot import load
from ruledrobot.robot.motion.trajectory import Heat, Phase, Trajectory
from ruledrobot.ursim.script.interpreter import compile_script
from ruledrobot.ursim.script.program import parse_call
from tests.support.emulators import smooth_trajectory

FULL_SCALE = 120.0  # W/m at the analog output's 1.0
LAG = 0.05  # s


def _power(t: np.ndarray, duration: float) -> np.ndarray:
    """A schedule that follows the speed of smooth_trajectory (sin(2 pi t / T)) led by LAG:
    20 W/m plus 80 W/m at the top speed, 0 over the first and last 0.1 s."""
    p = 20.0 + 80.0 * np.abs(np.sin(2.0 * np.pi * (t + LAG) / duration))
    return np.where((t < 0.1) | (t > duration - 0.1), 0.0, p)


def _heated(mode: str = "constant_kerf", kind: str = "analog") -> Trajectory:
    base = smooth_trajectory(duration=1.2, amplitude=(0.09, -0.07, 0.08, 0.0, 0.0, 0.0))
    n = base.n
    heat = Heat(kind, 0, windows=((0, n),), mode=mode, full_scale=FULL_SCALE, lag=LAG)
    meta = base.meta.replace(heat=heat, phases=(Phase("cut", 0, n),))
    return Trajectory(base.t, base.q, base.tcp, meta, _power(base.t, 1.2))


def _body(text: str) -> list:
    lines = [ln.strip() for ln in text.splitlines()[1:-1]]
    return [parse_call(ln) for ln in lines if ln and not ln.startswith("#")]


def test_written_levels_stay_within_the_step_and_write_every_zero_crossing():
    x = np.r_[0.0, 0.0, np.linspace(0.001, 0.8, 500), 0.8, 0.0, 0.3]
    w = written_levels(x)
    assert np.max(np.abs(w - x)) < HEAT_STEP
    assert np.array_equal(w == 0.0, x == 0.0)
    writes = np.count_nonzero(np.diff(w)) + 1
    assert writes <= 0.8 / HEAT_STEP + 4 and writes < x.size


@given(st.lists(st.floats(0.0, 1.0), min_size=1, max_size=300))
def test_written_levels_property(values):
    x = np.asarray(values)
    w = written_levels(x)
    assert np.all(np.abs(w - x) < HEAT_STEP + 1e-15)
    assert np.all(w <= x)  # never hotter than planned (a stop a band hot would burn)
    assert np.array_equal(w == 0.0, x == 0.0)  # off and on as planned
    changed = np.r_[True, w[1:] != w[:-1]]  # each written value is one of the column's
    assert np.all(np.isin(w[changed], x))


def test_servoj_program_sets_the_analog_output_as_the_column_says():
    traj = _heated()
    body = _body(urscript_program(traj, mode="servoj"))
    level, seen = None, []
    for c in body:
        if c.name == "set_standard_analog_out":
            assert c.args[0] == 0
            level = float(c.args[1])
        elif c.name == "servoj":
            seen.append(level)
    assert len(seen) == traj.n and body[-2].name == "set_standard_analog_out"
    assert body[-2].args[1] == 0.0  # off at the end
    # the formula (independent of the program's code), as the arm reaches each sample: the
    # servo law (tests/robot/test_servo.py holds it to the emulator's arm)
    want = servo_levels(_power(traj.t, 1.2) / FULL_SCALE, traj.period, SERVO_LOOKAHEAD,
                        SERVO_GAIN)  # fmt: skip
    got = np.asarray(seen, dtype=float)
    assert np.max(np.abs(got - want)) < HEAT_STEP + 1e-6  # the written value has 6 digits
    assert np.array_equal(got == 0.0, want == 0.0)
    # a monotone stretch of range R is written at most R / HEAT_STEP + 1 times: the
    # schedule's total variation bounds the statements (6 monotone stretches, 4 jumps)
    sets = sum(c.name == "set_standard_analog_out" for c in body)
    assert 20 < sets <= np.abs(np.diff(want)).sum() / HEAT_STEP + 12


def test_a_digital_output_keeps_switching_on_and_off():
    traj = _heated(mode="on_off", kind="standard")
    names = [c.name for c in _body(urscript_program(traj, mode="servoj"))]
    assert "set_standard_analog_out" not in names
    assert names.count("set_standard_digital_out") == 3  # off first, on, off at the end


def test_an_analog_output_on_off_switches_to_its_value():
    """mode on_off: the column is the power the plan assumes; the output goes to value."""
    traj = _heated(mode="on_off")
    sets = [c for c in _body(urscript_program(traj, mode="servoj"))
            if c.name == "set_standard_analog_out"]  # fmt: skip
    assert [c.args[1] for c in sets] == [0.0, 1.0, 0.0]
    assert heat_levels(traj) is None


@pytest.mark.parametrize("mode", ["movel", "movep"])
def test_a_path_program_sets_each_blended_run_to_its_mean(mode):
    traj = _heated()
    body = _body(urscript_program(traj, mode=mode, verify=False))
    moves = [c for c in body if c.name in (mode, "movej")]
    assert moves
    ratio = heat_levels(traj)
    for i, c in enumerate(body):
        if c.name != "set_standard_analog_out" or i < 4:
            continue
        before = [b for b in body[:i] if b.name == mode]
        if before:  # a statement between blended moves would stop the arm
            assert before[-1].kwargs["r"] == 0.0
        assert 0.0 <= c.args[1] <= ratio.max() + 1e-9
    values = [c.args[1] for c in body if c.name == "set_standard_analog_out"]
    assert values[0] == 0.0 and values[-1] == 0.0 and max(values) > 0.1


def test_forward_messages_carry_the_level():
    q = np.array([[0.1, -1.2, 1.3, -0.4, 1.5, 2.6], [0.2, -1.1, 1.2, -0.3, 1.4, 2.5]])
    raw = sample_messages(q, np.array([False, True]), 7, np.array([0.0, 0.4375]))
    words = np.frombuffer(raw, dtype=">i4").reshape(2, WORDS)
    assert words[:, 0].tolist() == [1, 2] and words[:, 1].tolist() == [7, 8]
    assert words[:, 2].tolist() == [0, round(0.4375 * MICRO)]
    np.testing.assert_allclose(words[:, 3:] / MICRO, q, atol=1e-6)
    assert len(end_message(9)) == len(stop_message()) == 4 * WORDS == 36
    assert struct.unpack(">9i", end_message(9))[:2] == (3, 9)
    no = np.frombuffer(sample_messages(q, None, 0), dtype=">i4").reshape(2, WORDS)
    assert not no[:, 2].any()


@pytest.mark.parametrize("levels", [False, True])
def test_the_forwarding_program_compiles(levels):
    heat = Heat("analog", 1, full_scale=FULL_SCALE)
    text = forward_program("127.0.0.1", 50002, ForwardSettings(0.002), heat, 2.0, levels)
    compile_script(text)
    assert ("set_standard_analog_out(1, v)" in text) is levels
    assert "socket_read_binary_integer(9," in text


def test_recorded_outputs_give_the_power():
    heat = Heat("analog", 1, full_scale=FULL_SCALE)
    outs = np.array([[0.0, 0.9, 0.25], [0.0, 0.0, np.nan], [3.0, 0.0, 1.0]])
    np.testing.assert_allclose(heat_power_from_outputs(heat, outs), [30.0, 0.0, FULL_SCALE])
    assert heat_power_from_outputs(Heat("standard", 0), outs) is None
    assert heat_power_from_outputs(Heat("analog", 0), outs) is None  # no full scale


def test_heat_levels_only_for_an_analog_schedule():
    traj = _heated()
    np.testing.assert_allclose(heat_levels(traj), traj.heat_power / FULL_SCALE)
    assert heat_levels(_heated(kind="standard")) is None
    plain = smooth_trajectory()
    assert heat_levels(plain) is None
    assert load("ur5e") is not None


def test_a_path_run_sends_the_set_points_to_the_child():
    from ruledrobot.export.run_program import plan_path_run

    traj = _heated()
    ops = plan_path_run(traj, 0, wire_tolerance=0.0005).child_ops(lambda k: k)
    heat = [op for op in ops if op[0] == "heat"]
    assert heat and all(len(op) == 3 and op[1] == (op[2] > 0.0) for op in heat)
    assert max(op[2] for op in heat) > 0.1 and heat[-1][2] == 0.0
