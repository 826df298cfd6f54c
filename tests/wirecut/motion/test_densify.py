"""Denser rulings (wirecut.motion.densify) on the demo's pass: the target between rulings
(the screw geodesic: a straight slide for frames that only translate), the wire's
deviation measured at the rulings (zero on the pass's own joints, the hand-measured
distance from the ruling where one joint is moved), uneven intervals (a jump in the
wire's travel per joint travel), and the added rulings (halfway, on the wire's line,
their joints an IK solution of the mean roll and slide)."""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import numpy as np
import pytest

from ruledrobot.wirecut.cut.passes import cut_paths
from ruledrobot.wirecut.cut.wire_geometry import flange_poses, wire_frame, wire_poses
from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.job.load import job_document, parse_job
from ruledrobot.wirecut.motion.assemble import measure_wire
from ruledrobot.wirecut.motion.densify import (
    MIN_INTERVAL,
    densified,
    pass_deviation,
    pass_feed_error,
    target_frames,
    uneven_intervals,
)


@pytest.fixture(scope="module")
def demo():
    job = parse_job(job_document(DEMO_JOB, "demo.toml"), "demo.toml")
    model = job.robot_model()
    (cp,) = cut_paths(job, None, model)
    assert cp.feasible
    return job, model, cp


def _line_distance(p: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Distance of points p (..., 3) from the z-axis lines of frames F (..., 4, 4)."""
    return np.linalg.norm(np.cross(p - F[..., :3, 3], F[..., :3, 2]), axis=-1)


def test_target_frames_slide_between_translated_rulings(demo):
    _, _, cp = demo
    F = np.tile(np.eye(4), (4, 1, 1))
    F[:, :3, 3] = [[0, 0, 0], [1, 0, 0], [1, 2, 0], [1, 2, 3]]
    flat = dataclasses.replace(cp, frames=F, param=np.array([0.0, 1.0, 3.0, 6.0]))
    i0, T = target_frames(flat, np.array([0.0, 0.5, 2.0, 4.5, 6.0]))
    np.testing.assert_array_equal(i0, [0, 0, 1, 2, 2])
    np.testing.assert_allclose(T[:, :3, 3], [[0, 0, 0], [0.5, 0, 0], [1, 1, 0], [1, 2, 1.5],
                                             [1, 2, 3]], atol=1e-12)  # fmt: skip
    np.testing.assert_allclose(T[:, :3, :3], np.tile(np.eye(3), (5, 1, 1)), atol=1e-12)
    # at the pass's own rulings the target is the ruling
    i0, T = target_frames(cp, cp.s)
    np.testing.assert_allclose(T, cp.frames, atol=1e-12)


def _at_rulings(job, model, cp, q):
    """A "timed" pass that is at ruling k at sample k, and its wire."""
    t = np.arange(len(q), dtype=float)
    return SimpleNamespace(s_of_t=cp.s, feed_limited=np.zeros(len(q), bool)), measure_wire(
        job, model, t, q
    )


def test_the_wire_on_the_rulings_joints_does_not_deviate_and_a_moved_joint_does(demo):
    job, model, cp = demo
    timed, wire = _at_rulings(job, model, cp, cp.motion.q)
    assert wire.inside.sum() > 50
    np.testing.assert_allclose(pass_deviation(cp, timed, wire), 0.0, atol=1e-9)
    k = int(np.flatnonzero(wire.inside)[len(np.flatnonzero(wire.inside)) // 2])
    q = cp.motion.q.copy()
    q[k, 5] += 0.01  # the wrist turns the bow: the wire leaves the ruling's line
    timed, moved = _at_rulings(job, model, cp, q)
    dev = pass_deviation(cp, timed, moved)
    expect = _line_distance(moved.chord_points()[k], cp.frames[k]).max()
    assert expect > 1e-4
    assert dev[k] == pytest.approx(expect, rel=1e-9)
    others = np.delete(dev, k)
    np.testing.assert_allclose(others, 0.0, atol=1e-9)


def test_feed_error_is_the_largest_relative_error_where_the_feed_is_held(demo):
    job, model, cp = demo
    timed, wire = _at_rulings(job, model, cp, cp.motion.q)
    held = wire.inside.copy()
    feed = float(np.nanmedian(wire.feed[held]))
    err = pass_feed_error(cp, timed, wire, feed)
    expect = np.zeros(len(cp.frames) - 1)
    for k in np.flatnonzero(held):
        i = min(k, len(cp.frames) - 2)
        expect[i] = max(expect[i], abs(wire.feed[k] / feed - 1.0))
    np.testing.assert_allclose(err, expect, rtol=1e-12)
    timed.feed_limited[:] = True  # the joints set the pace everywhere: nothing is held
    assert not pass_feed_error(cp, timed, wire, feed).any()


def test_uneven_intervals_are_the_two_around_a_jump(demo):
    _, _, cp = demo
    m = 12
    q = np.zeros((m, 6))
    q[:, 0] = np.arange(m) * 0.01  # even: 1 m of path per 0.01 rad
    q[7:, 0] += np.arange(1, m - 6) * 0.01  # from interval 6 on twice the joint travel
    motion = SimpleNamespace(q=q, hit=np.ones(m, bool))
    cp2 = dataclasses.replace(cp, frames=np.tile(np.eye(4), (m, 1, 1)), motion=motion,
                              param=None)  # fmt: skip
    np.testing.assert_array_equal(uneven_intervals(cp2, 0.25), [5, 6])
    assert uneven_intervals(cp2, 0.6).size == 0  # the jump is 50 %
    motion.hit[6] = False  # out of the stock: not counted
    assert uneven_intervals(cp2, 0.25).size == 0


def test_densified_adds_the_rulings_halfway(demo):
    job, model, cp = demo
    a, b = cp.extended
    M = len(cp.frames)
    idx = np.array([a - 1, 40, 41, M - 2])  # one in the lead-in, two in the cut, one out
    out = densified(cp, idx, model, job.tool, job.stock)
    assert len(out.frames) == M + 4
    assert out.extended == (a + 1, b + 1)
    new = np.array([a, 42, 44, M + 2])  # where they land
    old = np.setdiff1d(np.arange(M + 4), new)
    np.testing.assert_array_equal(out.frames[old], cp.frames)
    np.testing.assert_array_equal(out.motion.q[old], cp.motion.q)
    np.testing.assert_allclose(out.s[new], 0.5 * (cp.s[idx] + cp.s[idx + 1]))
    assert np.all(np.diff(out.s) > 0)
    m = cp.motion
    np.testing.assert_allclose(out.motion.roll[new], 0.5 * (m.roll[idx] + m.roll[idx + 1]))
    np.testing.assert_allclose(out.motion.slide[new], 0.5 * (m.slide[idx] + m.slide[idx + 1]))
    # the new ruling passes through the neighbours' mean point on the screw between them
    mid_o = 0.5 * (cp.frames[idx, :3, 3] + cp.frames[idx + 1, :3, 3])
    assert _line_distance(mid_o, out.frames[new]).max() < 1e-4
    # their joints put the wire on the new ruling, and stay near the neighbours
    W = wire_frame(job.tool)
    P = flange_poses(wire_poses(out.frames[new], out.motion.roll[new], out.motion.slide[new],
                                m.reverse), W)  # fmt: skip
    np.testing.assert_allclose(model.fk(out.motion.q[new]), P, atol=1e-9)
    wire_axis = (model.fk(out.motion.q[new]) @ W)[:, :3, :]
    assert _line_distance(wire_axis[:, :, 3], out.frames[new]).max() < 1e-9
    ref = 0.5 * (m.q[idx] + m.q[idx + 1])
    assert np.abs(out.motion.q[new] - ref).max() < 0.05
    assert out.kerf_error[new] == pytest.approx(np.maximum(cp.kerf_error[idx],
                                                           cp.kerf_error[idx + 1]))  # fmt: skip


def test_short_intervals_are_not_split(demo):
    job, model, cp = demo
    short = dataclasses.replace(cp, param=np.arange(len(cp.frames)) * MIN_INTERVAL)
    assert densified(short, np.array([10, 20]), model, job.tool, job.stock) is short
