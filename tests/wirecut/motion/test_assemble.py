"""The whole motion of a job (wirecut.motion.assemble) for the demo with the wire's heat
switched: the phases in order, the pre-heat held still for its time, the heat on from the
pre-heat to the lead-out, the pass's parameter, the samples evenly spaced and within the
joints' speed limits, and the wire in the block (measured here from the tool's wire ends
and the forward kinematics) only in the phase ``cut``."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from ruledrobot.wirecut.cut.passes import cut_paths
from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.job.load import job_document, parse_job
from ruledrobot.wirecut.motion.assemble import assemble_motion, feed_param

HEATED = DEMO_JOB.replace("mass = 1.0\n",
                          'mass = 1.0\nheat = { output = "standard:0", preheat = 0.5 }\n')


@pytest.fixture(scope="module")
def assembled():
    job = parse_job(job_document(HEATED, "heated.toml"), "heated.toml")
    assert job.tool.heat is not None
    model = job.robot_model()
    passes = cut_paths(job, None, model)
    return job, model, passes, assemble_motion(job, model, passes)


def _runs(labels) -> list[str]:
    return [k for k, _ in itertools.groupby(labels)]


def test_the_phases_follow_in_order(assembled):
    _, _, _, mo = assembled
    runs = _runs(mo.labels)
    assert runs[runs.index("preheat"):runs.index("preheat") + 4] == [
        "preheat", "lead_in", "cut", "lead_out"]
    assert runs[0] == "approach"
    assert set(runs[runs.index("lead_out") + 1 :]) <= {"retract"}
    assert runs.count("cut") == 1 and runs.count("preheat") == 1
    assert set(runs) <= {"approach", "preheat", "lead_in", "cut", "lead_out", "retract",
                         "transit"}  # fmt: skip


def test_the_preheat_holds_still_and_the_heat_is_on_while_cutting(assembled):
    job, _, _, mo = assembled
    t, q = mo.timed.t, mo.timed.q
    pre = mo.labels == "preheat"
    assert np.ptp(q[pre], axis=0).max() < 1e-12
    dt = t[1] - t[0]
    assert t[pre][-1] - t[pre][0] == pytest.approx(job.tool.heat.preheat, abs=2 * dt)
    hot = np.isin(mo.labels, ["preheat", "lead_in", "cut", "lead_out"])
    np.testing.assert_array_equal(mo.heat, hot)


def test_the_pass_samples_carry_its_index_and_parameter(assembled):
    _, _, _, mo = assembled
    in_pass = np.isin(mo.labels, ["lead_in", "cut", "lead_out"])
    np.testing.assert_array_equal(mo.pass_of[in_pass], 0)
    assert (mo.pass_of[np.isin(mo.labels, ["approach", "retract"])] == -1).all()
    s = mo.s[in_pass]
    assert not np.isnan(s).any() and (np.diff(s) >= -1e-12).all()
    cp = mo.passes[0]
    # the pass's first sample is its joining sample, dropped: s starts one step in
    assert cp.s[0] <= s[0] < cp.s[0] + 1e-4 and s[-1] == pytest.approx(cp.s[-1])
    assert np.isnan(mo.s[mo.labels == "approach"]).all()


def test_samples_are_evenly_spaced_and_within_the_speed_limits(assembled):
    job, model, _, mo = assembled
    t, q = mo.timed.t, mo.timed.q
    dt = float(model.control_period)
    np.testing.assert_allclose(np.diff(t), dt, rtol=1e-9)
    rate = np.abs(np.diff(q, axis=0)) / dt
    assert (rate <= np.asarray(model.max_velocity) * job.robot.speed_scale * (1 + 1e-6)).all()


def test_the_wire_is_in_the_block_exactly_while_cutting(assembled):
    job, model, _, mo = assembled
    P = model.fk(mo.timed.q)
    a = P[:, :3, :3] @ job.tool.wire_start + P[:, :3, 3]
    b = P[:, :3, :3] @ job.tool.wire_end + P[:, :3, 3]
    touches = job.stock.segment_hits(a, b)
    assert not (mo.in_stock & ~touches).any()  # in the stock: the wire's segment crosses it
    cut = mo.labels == "cut"
    np.testing.assert_array_equal(mo.in_stock[cut], True)
    # outside the cut the wire at most touches the block (the lead-in ends where it enters)
    assert not mo.in_stock[np.isin(mo.labels, ["approach", "preheat", "retract"])].any()
    assert not touches[np.isin(mo.labels, ["approach", "preheat", "retract"])].any()
    assert (mo.surface == (cut & mo.in_stock)).all()


def test_the_chord_ends_lie_on_the_wire_and_the_blocks_faces(assembled):
    job, model, _, mo = assembled
    k = np.flatnonzero(mo.in_stock)[::50]
    P = model.fk(mo.timed.q[k])
    ends = mo.ends[k]  # (K, 2, 3) in the flange frame
    a, b = np.asarray(job.tool.wire_start), np.asarray(job.tool.wire_end)
    u = b - a
    off = np.cross(ends - a, u) / np.linalg.norm(u)
    np.testing.assert_allclose(off, 0.0, atol=1e-12)  # on the wire
    world = np.einsum("kij,knj->kni", P[:, :3, :3], ends) + P[:, None, :3, 3]
    local = np.abs(job.stock.to_box(world))
    half = 0.5 * job.stock.size
    assert (local <= half + 1e-7).all()
    on_face = (np.abs(local - half) < 1e-7).any(axis=-1)
    at_wire_end = np.minimum(np.linalg.norm(ends - a, axis=-1),
                             np.linalg.norm(ends - b, axis=-1)) < 1e-9  # fmt: skip
    assert (on_face | at_wire_end).all()


def test_the_chord_ends_are_zero_outside_the_stock_as_documented(assembled):
    _, _, _, mo = assembled
    np.testing.assert_array_equal(mo.ends[~mo.in_stock], 0.0)


def test_the_feed_parameter_increases_from_zero(assembled):
    job, _, passes, _ = assembled
    param, near = feed_param(job, passes[0], 0.01)
    assert param[0] == 0.0 and (np.diff(param) > 0).all()
    assert param.shape == (len(passes[0].frames),)
    assert near >= 0.002  # FEED_NEAR at least
