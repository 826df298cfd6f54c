"""Redundancy search: roll, slide, wire direction and IK branch along a cut."""

from __future__ import annotations

import numpy as np
import pytest

import ruledrobot as rr
from ruledrobot.wirecut.cut import wire_pose as red
from ruledrobot.wirecut.cut.clearance import Cell
from ruledrobot.wirecut.job.load import load_job

from ..job.test_job import EXAMPLE


@pytest.fixture(scope="module")
def setup(tmp_path_factory):
    p = tmp_path_factory.mktemp("job") / "job.toml"
    p.write_text(EXAMPLE.replace("rotvec = [0.0, 0.0, 0.1]", "rotvec = [0.0, 0.0, 0.0]"))
    job = load_job(p)
    res = rr.refine(job.input_lines(), "dh", "four_point", 3)
    return job, res.frames, rr.robot.load("ur5e")


def test_solution_puts_the_wire_on_every_ruling_and_covers_every_chord(setup):
    job, F, model = setup
    r = red.solve_redundancy(F, job.stock, job.tool, model)
    assert r.feasible and r.constant_slide
    np.testing.assert_allclose(r.roll, r.roll[0])  # a constant offset on the DH frame motion
    # forward kinematics of the chosen joints reproduce the flange poses
    np.testing.assert_allclose(model.fk(r.q), r.flange, atol=1e-9)
    a = np.einsum("mij,j->mi", r.flange[:, :3, :3], job.tool.wire_start) + r.flange[:, :3, 3]
    b = np.einsum("mij,j->mi", r.flange[:, :3, :3], job.tool.wire_end) + r.flange[:, :3, 3]
    o, z = F[:, :3, 3], F[:, :3, 2]
    for w in (a, b):
        assert np.linalg.norm(np.cross(w - o, z), axis=1).max() < 1e-9  # on the ruling
    ta, tb = np.einsum("mi,mi->m", a - o, z), np.einsum("mi,mi->m", b - o, z)
    lo, hi = np.minimum(ta, tb), np.maximum(ta, tb)
    c0, c1 = r.chord[:, 0], r.chord[:, 1]
    h = r.hit
    assert np.all(lo[h] <= c0[h] - job.tool.clearance + 1e-9)
    assert np.all(hi[h] >= c1[h] + job.tool.clearance - 1e-9)
    assert r.max_step < 0.05  # rad between consecutive refined rulings: continuous branch
    assert r.min_measure >= 0.02


def test_search_solves_a_job_where_the_plain_dh_motion_fails(setup):
    job, F, model = setup
    m = len(F)
    cell = Cell.of(model, job.tool, job.stock, 0.0, 0.005, 0.02, None)
    _, _, ok, lost = red._evaluate(cell, F, np.zeros(m), np.zeros(m), False, 0.5)
    assert not ok and sum(lost.values()) > 0  # the plain DH motion (roll 0) fails here
    r = red.solve_redundancy(F, job.stock, job.tool, model)
    assert r.feasible and abs(r.roll[0]) > 0.1


def test_impossible_jobs_are_reported(setup):
    job, F, model = setup
    far = F.copy()
    far[:, 0, 3] += 3.0  # 3 m further out than a UR5e reaches
    from ruledrobot.geometry.box import Box

    stock_far = Box(job.stock.centre + np.array([3.0, 0.0, 0.0]), job.stock.size)
    r = red.solve_redundancy(far, stock_far, job.tool, model)
    assert not r.feasible
    assert "no constant or varying roll works" in r.reasons[-1]
    assert f"no continuous IK solution at rulings 0-{len(F) - 1}" in r.reasons[-1]
    big = Box(job.stock.centre, [0.2, 0.6, 0.6])
    r = red.solve_redundancy(F, big, job.tool, model)
    assert not r.feasible and "longer than the wire allows" in r.reasons[0]
    with pytest.raises(ValueError, match="none of them crosses the stock"):
        red.solve_redundancy(F, Box([5.0, 5.0, 5.0], [0.1, 0.1, 0.1]), job.tool, model)


def test_varying_roll_by_dynamic_programming(setup):
    job, F, model = setup
    r = red.solve_redundancy(F, job.stock, job.tool, model, strategy="varying")
    assert r.feasible
    np.testing.assert_allclose(model.fk(r.q), r.flange, atol=1e-9)
    assert r.max_step < 0.05 and r.min_measure >= 0.02
    # the roll is smooth: no jumps between consecutive rulings
    assert np.abs(np.diff(np.unwrap(r.roll))).max() < 0.02
    with pytest.raises(ValueError, match="strategy"):
        red.solve_redundancy(F, job.stock, job.tool, model, strategy="greedy")
