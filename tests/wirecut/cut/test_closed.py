"""Closed cuts (wirecut.cut.closed): the slit's direction on a circular column (the
circle's tangent), the loop going round and past its seam (turned after a flip), the slit
and exit moves, the turn rate; and the part demo's plug as one pass: slit in along the
tangent, the loop closing on its start, out the same way."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ruledrobot.geometry.box import Box
from ruledrobot.wirecut.cut.closed import (
    SLIT_STEP,
    _exit,
    _loop,
    _slit,
    _turn_rate,
    slit_direction,
)
from ruledrobot.wirecut.cut.passes import cut_paths
from ruledrobot.wirecut.cut.wire_geometry import chords
from ruledrobot.wirecut.job.demo import PART_JOB
from ruledrobot.wirecut.job.load import job_document, parse_job

RADIUS = 0.05
BOX = Box([0.0, 0.0, 0.0], [0.2, 0.2, 0.1])


def _column(m: int = 36) -> tuple[np.ndarray, np.ndarray]:
    """Vertical rulings round a circle of RADIUS (counter-clockwise seen from +z)."""
    th = 2 * np.pi * np.arange(m) / m
    F = np.tile(np.eye(4), (m, 1, 1))
    F[:, :3, 0] = np.c_[np.cos(th), np.sin(th), np.zeros(m)]
    F[:, :3, 1] = np.c_[-np.sin(th), np.cos(th), np.zeros(m)]
    F[:, :3, 3] = RADIUS * F[:, :3, 0]
    return F, th


@pytest.mark.parametrize("i", [0, 5, 17, 35])
def test_the_slit_runs_along_the_circles_tangent(i):
    F, th = _column()
    d = slit_direction(F, i, BOX)
    np.testing.assert_allclose(d, [-np.sin(th[i]), np.cos(th[i]), 0.0], atol=1e-12)
    tilted = F.copy()
    tilted[:, :3, 3] += 0.02 * tilted[:, :3, 2]  # same lines, other origins: same direction
    np.testing.assert_allclose(slit_direction(tilted, i, BOX), d, atol=1e-12)


def test_the_loop_goes_round_past_its_seam_and_turns_after_a_flip():
    F, _ = _column(8)
    out = _loop(F, False, 6, 1, 8)
    assert out.shape == (9, 4, 4)
    np.testing.assert_array_equal(out, F[[6, 7, 0, 1, 2, 3, 4, 5, 6]])
    back = _loop(F, False, 1, -1, 3)
    np.testing.assert_array_equal(back, F[[1, 0, 7, 6]])
    flipped = _loop(F, True, 6, 1, 8)
    np.testing.assert_array_equal(flipped[:2], F[[6, 7]])
    turned = flipped[2:]  # past the seam: the same rulings, the other way round
    np.testing.assert_array_equal(turned[..., :3, 3], F[[0, 1, 2, 3, 4, 5, 6], :3, 3])
    np.testing.assert_array_equal(turned[..., :3, 0], F[[0, 1, 2, 3, 4, 5, 6], :3, 0])
    np.testing.assert_array_equal(turned[..., :3, 1:3], -F[[0, 1, 2, 3, 4, 5, 6], :3, 1:3])


def test_the_slit_comes_straight_from_outside_the_grown_stock():
    F, _ = _column()
    frame, d, lead = F[9], slit_direction(F, 9, BOX), 0.02
    s = _slit(frame, d, BOX, lead)
    np.testing.assert_array_equal(s[-1], frame)
    step = np.diff(s[:, :3, 3], axis=0)
    np.testing.assert_allclose(step / np.linalg.norm(step, axis=1, keepdims=True),
                               np.tile(d, (len(step), 1)), atol=1e-12)  # fmt: skip
    assert np.linalg.norm(step, axis=1).max() <= SLIT_STEP + 1e-12
    np.testing.assert_array_equal(s[:, :3, :3], np.tile(frame[:3, :3], (len(s), 1, 1)))
    grown = Box(BOX.centre, BOX.size + 2 * lead)
    hit = chords(s, grown)[2]
    assert not hit[0] and hit[-1]
    # the first clear position is at most one step beyond the grown box
    nearer = s[:1].copy()
    nearer[0, :3, 3] += SLIT_STEP * d
    assert chords(nearer, grown)[2][0]
    e = _exit(frame, d, BOX, lead)
    np.testing.assert_array_equal(e[0], frame)
    assert not chords(e, grown)[2][-1]
    np.testing.assert_allclose(e[-1, :3, 3] - frame[:3, 3],
                               -(s[0, :3, 3] - frame[:3, 3]), atol=1e-12)  # fmt: skip


def test_a_turning_slit_meets_the_loop_at_its_rate_and_starts_still():
    F, _ = _column()
    frame, d = F[3], slit_direction(F, 3, BOX)
    w = np.array([0.0, 0.0, 2.0])  # rad per metre about z
    s = _slit(frame, d, BOX, 0.02, w)
    np.testing.assert_allclose(s[-1], frame, atol=1e-15)
    rel = Rotation.from_matrix(s[:, :3, :3] @ frame[:3, :3].T).as_rotvec()
    travel = np.linalg.norm(s[:, :3, 3] - s[0, :3, 3], axis=1)
    rate = np.gradient(rel[:, 2], travel)
    assert rate[-1] == pytest.approx(2.0, rel=0.05)  # the loop's rate where they meet
    assert abs(rate[0]) < 0.1  # still at the outer end
    assert np.all(np.diff(rate) >= -1e-9)


def test_the_turn_rate_is_the_rotation_per_metre():
    a = np.eye(4)
    b = np.eye(4)
    b[:3, :3] = Rotation.from_rotvec([0.0, 0.3, 0.0]).as_matrix()
    b[:3, 3] = [0.1, 0.0, 0.0]
    np.testing.assert_allclose(_turn_rate(a, b), [0.0, 3.0, 0.0], atol=1e-12)


@pytest.fixture(scope="module")
def plug():
    job = parse_job(job_document(PART_JOB, "part.toml"), "part.toml")
    cut = job.cuts[2]
    return job, cut, cut_paths(job, cut)


def test_the_plug_is_one_pass_slit_in_round_and_out(plug):
    job, cut, passes = plug
    assert len(passes) == 1
    cp = passes[0]
    assert cp.closed and cp.feasible and cp.compensated
    assert cp.notes[0].startswith("closed: one pass round the loop")
    a, b = cp.extended
    F = cp.frames
    loop = F[a : len(F) - b]
    np.testing.assert_allclose(loop[0], loop[-1], atol=1e-12)  # it closes on its start
    assert chords(loop, job.stock)[2].all()
    d = slit_direction(loop[:-1], 0, job.stock)
    for part in (F[: a + 1], F[len(F) - b - 1 :]):
        step = np.diff(part[:, :3, 3], axis=0)
        along = step @ d
        assert (along > 0).all()  # the wire moves on along the tangent, in and out
        np.testing.assert_allclose(np.linalg.norm(step, axis=1), along, rtol=1e-9)
    for end, lead in ((F[:1], cut.lead_in), (F[-1:], cut.lead_out)):
        grown = Box(job.stock.centre, job.stock.size + 2 * lead, job.stock.rotation)
        assert not chords(end, grown)[2][0]  # clear of the stock by the lead
    # the slits cut waste: their target is the wire itself, with no kerf error
    np.testing.assert_array_equal(cp.surface_frames[:a], F[:a])
    np.testing.assert_array_equal(cp.surface_frames[len(F) - b :], F[len(F) - b :])
    assert not cp.kerf_error[:a].any() and not cp.kerf_error[len(F) - b :].any()
    assert cp.kerf_error[a : len(F) - b].max() > 0
