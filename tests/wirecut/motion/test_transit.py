"""Transits (wirecut.motion.transit) in the demo's cell: the wire measured here from the
tool's wire ends in the flange frame and the forward kinematics — a move straight through
the block is not clear, the route goes over it in legs whose every sample (sampled here
finer than the planner does) keeps the wire out of the block, and a lifted pose raises the flange
straight up until the bow and wire are above the block."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from ruledrobot.wirecut.cut.passes import cut_paths
from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.job.load import job_document, parse_job
from ruledrobot.wirecut.motion.transit import CLEAR, TransitPlanner


@pytest.fixture(scope="module")
def cell():
    job = parse_job(job_document(DEMO_JOB, "demo.toml"), "demo.toml")
    model = job.robot_model()
    (cp,) = cut_paths(job, None, model)
    return job, model, cp, TransitPlanner.of(job, model)


def _wire(job, model, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    P = model.fk(np.atleast_2d(q))
    ends = [P[:, :3, :3] @ np.asarray(e) + P[:, :3, 3] for e in (job.tool.wire_start,
                                                                 job.tool.wire_end)]  # fmt: skip
    return ends[0], ends[1]


def _wire_hits_block(job, model, q: np.ndarray) -> np.ndarray:
    a, b = _wire(job, model, q)
    return job.stock.segment_hits(a, b)


def _samples(qa, qb, step=0.0005):
    """The move qa -> qb every ``step`` rad (max norm), finer than the planner's own
    samples (at most 0.0014 rad apart in the demo's cell)."""
    n = max(2, int(np.ceil(np.abs(qb - qa).max() / step)) + 1)
    return qa + np.linspace(0.0, 1.0, n)[:, None] * (qb - qa)


def test_the_planner_knows_the_blocks_top(cell):
    _, _, _, tp = cell
    assert tp.top == pytest.approx(0.3 + 0.075)
    assert (tp.lower >= -2 * np.pi).all() and (tp.upper <= 2 * np.pi).all()
    assert tp.cell.self_collision  # the arm against itself too


def test_a_wire_in_the_block_is_not_free(cell):
    job, model, cp, tp = cell
    k = len(cp.frames) // 2
    q = cp.motion.q[k]
    assert _wire_hits_block(job, model, q).all()
    assert not tp.free(q).any()
    assert "wire in the stock" in tp.broken(q)
    q0 = cp.motion.q[0]  # the lead-in's first pose: the wire 2 cm off the block
    assert not _wire_hits_block(job, model, q0).any()
    assert tp.free(q0).all() and tp.broken(q0) == []


def test_through_the_block_is_not_clear_and_the_route_goes_over_it(cell):
    job, model, cp, tp = cell
    qa, qb = cp.motion.q[0], cp.motion.q[-1]  # either side of the block
    assert _wire_hits_block(job, model, _samples(qa, qb)).any()
    assert not tp.clear(qa, qb)
    notes: list[str] = []
    legs = tp.route(qa, qb, notes, "test")
    assert len(legs) >= 2
    np.testing.assert_array_equal(legs[0][0], qa)
    np.testing.assert_array_equal(legs[-1][1], qb)
    for (_, b), (c, _) in itertools.pairwise(legs):
        np.testing.assert_array_equal(b, c)  # the legs join
    for a, b in legs:
        assert not _wire_hits_block(job, model, _samples(a, b)).any()
        assert model.within_limits(_samples(a, b)).all()
    assert len(notes) == 1 and notes[0].startswith("transit test: ")
    assert "direct move would hit it" in notes[0]


def test_a_lifted_pose_is_straight_above_with_the_bow_clear(cell):
    job, model, cp, tp = cell
    q = cp.motion.q[len(cp.frames) // 2]
    up = tp.lifted(q)
    assert up is not None
    P, U = model.fk(q), model.fk(up)
    np.testing.assert_allclose(U[:3, :3], P[:3, :3], atol=1e-9)
    np.testing.assert_allclose(U[:2, 3], P[:2, 3], atol=1e-9)
    assert U[2, 3] > P[2, 3]
    a, b = _wire(job, model, up)
    assert min(a[0, 2], b[0, 2]) >= tp.top + CLEAR - 1e-9  # the wire at least CLEAR above
    assert np.abs(up - q).max() < np.pi  # the solution nearest q, not another branch
    np.testing.assert_allclose(tp.lifted(up), up, atol=1e-9)  # already clear: the same


def test_no_move_is_needed_between_equal_poses(cell):
    _, _, cp, tp = cell
    notes: list[str] = []
    assert tp.route(cp.motion.q[0], cp.motion.q[0].copy(), notes, "x") == [] and notes == []
