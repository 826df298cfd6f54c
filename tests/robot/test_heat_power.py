"""The heat_power column of a Trajectory and the heat model fields of its Heat."""

from __future__ import annotations

import numpy as np
import pytest

import ruledrobot as rr
from ruledrobot.robot.motion.trajectory import HEAT_MODES, Heat, Phase, Trajectory


def _traj(heat: Heat | None, power=None, n: int = 40) -> Trajectory:
    model = rr.robot.load("ur5e")
    t = np.arange(n) * 0.002
    q = np.array([0.3, -1.2, 1.4, -1.8, -1.57, 0.2]) + 0.1 * np.sin(np.outer(t, np.arange(1, 7)))
    tr = Trajectory.from_joints(t, q, model, heat=heat,
                                phases=(Phase("approach", 0, 10), Phase("cut", 10, n)))  # fmt: skip
    return tr if power is None else Trajectory(tr.t, tr.q, tr.tcp, tr.meta, power)


ANALOG = Heat("analog", 0, windows=((5, 35),), mode="constant_kerf", full_scale=80.0, lag=0.01)


def test_heat_defaults_are_todays_switching():
    h = Heat("standard", 2)
    assert (h.mode, h.full_scale, h.lag) == ("on_off", None, 0.0)
    assert set(HEAT_MODES) == {"on_off", "constant", "constant_kerf"}


@pytest.mark.parametrize("field, value, message", [
    ("mode", "pwm", "heat.mode"), ("full_scale", 0.0, "heat.full_scale"),
    ("full_scale", float("inf"), "heat.full_scale"), ("lag", -0.1, "heat.lag"),
    ("lag", float("nan"), "heat.lag"),
])  # fmt: skip
def test_bad_heat_fields_are_named(field, value, message):
    with pytest.raises(ValueError, match=message):
        Heat("analog", 0, **{field: value})


def test_heat_power_is_kept_read_only_and_sliced():
    p = np.linspace(0.0, 60.0, 40)
    tr = _traj(ANALOG, p)
    assert not tr.heat_power.flags.writeable
    part = tr.sliced(7, 30)
    np.testing.assert_array_equal(part.heat_power, p[7:30])
    assert part.meta.heat.windows == ((0, 23),) and part.meta.heat.full_scale == 80.0
    assert part.meta.heat.lag == 0.01 and part.meta.heat.mode == "constant_kerf"
    assert _traj(ANALOG).sliced(3).heat_power is None


def test_the_run_slice_keeps_heat_power():
    from ruledrobot.export.run_program import run_slice

    p = np.linspace(0.0, 60.0, 40)
    part = run_slice(_traj(ANALOG, p), 12, speed_scale=0.5)
    np.testing.assert_array_equal(part.heat_power, p[12:])
    np.testing.assert_allclose(part.t, (np.arange(28) * 0.002) / 0.5)


@pytest.mark.parametrize("power, message", [
    (np.r_[np.zeros(39), -1.0], r"heat_power\[39\].*>= 0"),
    (np.r_[np.nan, np.zeros(39)], r"heat_power\[0\]"),
    (np.zeros(39), r"heat_power.*\(40,\)"),
])  # fmt: skip
def test_bad_heat_power_is_named(power, message):
    with pytest.raises(ValueError, match=message):
        _traj(ANALOG, power)


@pytest.mark.parametrize("mode", ["constant", "constant_kerf"])
def test_an_analog_schedule_needs_a_full_scale_for_heat_power(mode):
    with pytest.raises(ValueError, match="full_scale"):
        _traj(Heat("analog", 1, mode=mode), np.ones(40))
    assert Heat("analog", 1, mode=mode).schedules_power


def test_a_switched_output_takes_heat_power_as_information():
    """on_off (any output) and digital outputs switch by the windows: no full scale needed."""
    for heat in (Heat("analog", 1), Heat("standard", 1, mode="constant"), None):
        assert _traj(heat, np.ones(40)).heat_power is not None
        assert heat is None or not heat.schedules_power


def test_ratio_is_power_over_full_scale_clipped():
    np.testing.assert_allclose(ANALOG.ratio([0.0, 40.0, 80.0, 120.0]), [0.0, 0.5, 1.0, 1.0])
    with pytest.raises(ValueError, match="full scale"):
        Heat("analog", 0).ratio(1.0)
