"""A run's verdict judges the cut face from the recorded motion and the recorded heat
(issue 33): face_error on the recording, the power from the recorded analog output."""

from __future__ import annotations

import numpy as np
import pytest

from ruledrobot.export.run_verdict import measure_run, recorded_power
from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.plan import make_plan
from tests.wirecut.kerf.panel import write_corner

HEAT = ('heat = { output = "analog:0", mode = "constant_kerf", full_scale = 200.0, '
        "lag = 0.05, preheat = 0.3 }")


@pytest.fixture(scope="module")
def corner(tmp_path_factory):
    """The corner cut (a stop in the block) with its power scheduled on analog output 0."""
    plan = make_plan(load_job(write_corner(tmp_path_factory.mktemp("corner"), HEAT)))
    assert plan.trajectory is not None, plan.reasons
    assert plan.motion.corner_stop.any()
    return plan.trajectory


def _verdict(traj, power, hot=None):
    """measure_run of a recording that is the plan itself (every sample matched to itself)
    with the recorded analog output ``power`` [W/m]."""
    idx = np.arange(traj.n)
    return measure_run(traj, traj, idx, status="completed", message="", power=power, hot=hot)


def test_a_recording_with_the_planned_power_passes_as_the_plan_does(corner):
    m = _verdict(corner, corner.heat_power)
    check = m.verdict["face_error"]
    plan = corner.face_errors()["cut"]
    assert check.gating and check.ok and plan.ok
    assert check.value == pytest.approx(1e3 * plan.worst, rel=1e-9)
    (fe,) = m.faces
    assert m.as_dict()["face_errors"][0]["max_mm"] == pytest.approx(1e3 * fe.worst)


def test_an_output_held_at_the_cut_power_burns_at_the_corner_stop(corner):
    """The controller's output stuck at the top set-point: the wire stands hot at the stop."""
    held = np.where(corner.heat_power > 0.0, corner.heat_power.max(), 0.0)
    check = _verdict(corner, held).verdict["face_error"]
    assert check.gating and not check.ok and check.value == float("inf")
    assert check.detail.startswith("burn at plan sample")


def test_without_a_recorded_output_the_planned_power_counts_where_the_output_was_on(corner):
    """No analog reading: the plan's power where the recorded heat was on, 0 elsewhere."""
    idx = np.arange(corner.n)
    on = corner.heat_power > 0.0
    np.testing.assert_array_equal(recorded_power(corner, idx, None, on), corner.heat_power)
    off = recorded_power(corner, idx, None, np.zeros(corner.n, dtype=bool))
    assert not off.any()
    cold = _verdict(corner, None, np.zeros(corner.n, dtype=bool)).verdict["face_error"]
    assert not cold.ok  # a cold wire melts only its own width: the face stays proud
