"""A run's verdict judges the cut face from the recorded motion and the recorded heat
(issue 33): face_error on the recording, the power from the recorded analog output."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from ruledrobot.export.heat import motion_power
from ruledrobot.export.run_verdict import measure_run
from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.plan import make_plan
from tests.wirecut.kerf.panel import write_corner, write_panel

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
    # the face decides; the feed window informs (as in the plan's verdict)
    assert not m.verdict["feed_min"].gating and not m.verdict["feed_max"].gating


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
    np.testing.assert_array_equal(motion_power(corner, idx, None, on), corner.heat_power)
    off = motion_power(corner, idx, None, np.zeros(corner.n, dtype=bool))
    assert not off.any()
    cold = _verdict(corner, None, np.zeros(corner.n, dtype=bool)).verdict["face_error"]
    assert not cold.ok  # a cold wire melts only its own width: the face stays proud



def _path_check(traj, value=None):
    """The movel program of ``traj`` measured (its motion generated), with every heat-on
    set-point replaced by ``value`` when given."""
    from ruledrobot.export.urscript import path_program
    from ruledrobot.export.verify_program import Switch, check_path_program

    ops = path_program(traj)
    assert any(isinstance(op, Switch) and op.value for op in ops)
    if value is not None:
        ops = [dataclasses.replace(op, value=value) if isinstance(op, Switch) and op.on
               else op for op in ops]  # fmt: skip
    return check_path_program(traj, ops, wire_tolerance=0.0005)


def test_a_path_program_is_verified_with_the_set_points_it_writes(tmp_path_factory):
    """The tapered panel (no stop in the block): its movel program, one set-point for its
    blended run, cuts the face within tolerance; the same program with its output at a
    fifth of that set-point leaves the face proud (only the wire's own width melted)."""
    job = write_panel(tmp_path_factory.mktemp("panel"), HEAT)
    traj = make_plan(load_job(job)).trajectory
    good = _path_check(traj)
    (fe,) = good.faces
    assert good.ok and fe.ok and "cut face within" in good.summary()
    assert fe.worst == pytest.approx(traj.face_errors()["cut"].worst, abs=5e-5)
    cold = _path_check(traj, 0.2 * max(traj.heat_power) / 200.0)
    assert not cold.ok and not cold.faces[0].ok
    assert any("from the part" in f for f in cold.failures())


def test_a_path_program_that_holds_the_power_through_a_corner_stop_is_refused(corner):
    """A statement between blended moves would stop the arm, so a path program holds one
    set-point per blended run: into the corner stop it holds the run's mean, the wire
    stands hot at the stop and the verification refuses the program (stream it)."""
    check = _path_check(corner)
    assert not check.ok and check.faces[0].burn
    assert any("burns" in f for f in check.failures())
