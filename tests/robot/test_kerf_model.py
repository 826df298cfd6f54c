"""The kerf model (robot.wire.kerf) against its closed form and its inverse."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from ruledrobot.robot.wire.kerf import Material, wire_power

XPS = Material(kerf_base=0.0003, kerf_gain=4.0e-8, power_threshold=5.0, max_speed=1.0e-4)


def test_kerf_is_the_energy_balance():
    # 20 W/m at 2 mm/s: 0.3 mm + 4e-8 * 15 / 0.002 = 0.3 mm + 0.3 mm
    assert XPS.kerf(0.002, 20.0) == pytest.approx(0.0006, rel=1e-12)
    assert XPS.kerf(0.004, 20.0) == pytest.approx(0.00045, rel=1e-12)  # faster: narrower
    assert XPS.kerf(0.002, 4.0) == pytest.approx(0.0003)  # below the threshold: the wire alone


def test_a_still_hot_wire_burns_and_a_cold_one_does_not():
    w = XPS.kerf(np.array([0.0, 0.0]), np.array([20.0, 5.0]))
    assert np.isinf(w[0]) and w[1] == pytest.approx(0.0003)


@given(st.floats(0.0004, 0.003), st.floats(1e-4, 0.05))
def test_power_for_kerf_inverts_kerf(w, v):
    p = XPS.power_for_kerf(w, v)
    assert XPS.kerf(v, p) == pytest.approx(w, rel=1e-9)


def test_no_power_melts_less_than_the_wire():
    with pytest.raises(ValueError, match="below the material's kerf_base"):
        XPS.power_for_kerf(0.0002, 0.01)


def test_speed_limit_and_bad_constants():
    assert XPS.speed_limit(25.0) == pytest.approx(0.002)
    assert np.isinf(Material(0.0003, 4e-8).speed_limit(25.0))
    with pytest.raises(ValueError, match=r"material\.kerf_gain"):
        Material(0.0003, 0.0)


def test_wire_power_is_the_set_point_delayed():
    t = np.linspace(0.0, 2.0, 201)
    setpoint = np.where(t >= 1.0, 10.0, 0.0)
    p = wire_power(t, setpoint, 0.5)
    assert p[t < 1.49].max() < 10.0 and np.all(p[t >= 1.5 + 1e-9] == 10.0)
    np.testing.assert_array_equal(wire_power(t, setpoint, 0.0), setpoint)
