"""Wire lag (robot.wire.lag) against the taut string's closed forms."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.linalg import solve_banded

from ruledrobot.robot.wire.lag import corner_dwell, wire_bow


def test_a_fully_loaded_wire_bows_q_l2_over_8t():
    # 0.4 m wire, 20 N, drag 50 N/m per m/s at 10 mm/s: q = 0.5 N/m, 0.5*0.16/160 = 0.5 mm
    assert wire_bow(0.01, 0.4, 0.4, 20.0, 50.0) == pytest.approx(0.0005, rel=1e-12)


@given(st.floats(0.01, 0.4), st.floats(0.001, 0.05), st.floats(1.0, 100.0))
def test_the_bow_is_the_midspan_of_a_string_by_finite_differences(c, v, T):
    # independent truth: solve T y'' = -q(x) on [0, L] with y(0) = y(L) = 0 numerically
    L, drag = 0.4, 30.0
    x = np.linspace(0.0, L, 20001)
    h = x[1] - x[0]
    # the load per node: the loaded length of each node's cell (exact for a step load)
    cell_lo, cell_hi = np.maximum(x - h / 2, L / 2 - c / 2), np.minimum(x + h / 2, L / 2 + c / 2)
    q = drag * v * np.clip(cell_hi - cell_lo, 0.0, None) / h
    n = x.size - 2
    bands = np.vstack([np.ones(n), -2.0 * np.ones(n), np.ones(n)]) / h**2
    y = solve_banded((1, 1), bands, -q[1:-1] / T)
    assert wire_bow(v, c, L, T, drag) == pytest.approx(y[n // 2], rel=1e-4)


def test_the_corner_dwell_is_the_bow_over_the_speed():
    assert corner_dwell(0.0005, 0.01) == pytest.approx(0.05)
    assert corner_dwell(0.0, 0.0) == 0.0 and np.isinf(corner_dwell(1e-4, 0.0))


def test_bad_tension_is_named():
    with pytest.raises(ValueError, match="wire_tension"):
        wire_bow(0.01, 0.2, 0.4, 0.0, 1.0)
