"""The reachability map (issue 13) agrees with the planner, checked independently: the
IK, the planner's clearance rules and the planner's own path."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from ruledrobot.cli import app
from ruledrobot.wirecut.cut.clearance import clearance
from ruledrobot.wirecut.cut.passes import cut_paths
from ruledrobot.wirecut.cut.wire_geometry import flange_poses, wire_poses
from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.reach.map import job_cell, reach_map
from ruledrobot.wirecut.reach.margins import DEFAULT_RULES, Reason

from ..reach_jobs import demo_at

runner = CliRunner()


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    path = tmp_path_factory.mktemp("reach") / "job.toml"
    path.write_text(demo_at(0.5))
    job = load_job(path)
    model = job.robot_model()
    passes = cut_paths(job, job.cut, model)
    return job, model, passes, reach_map(job, model, rulings=40, rolls=36, passes=passes,
                                         slides=2)


def _cell_poses(pm, frames, W):
    D, K, R = pm.margin.shape
    shape = (D, K, R)
    roll = np.broadcast_to(pm.rolls[None, :, None], shape)
    # each cell's own slide: the planner's (index 0) or another of the chord's freedom
    slide = np.take_along_axis(pm.slides, pm.slide_index.reshape(-1, R), axis=0).reshape(shape)
    rev = np.broadcast_to(np.array([False, True])[:, None, None], shape)
    return flange_poses(wire_poses(frames[pm.idx], roll, slide, rev), W)


def test_every_reachable_cell_has_a_solution_the_planner_accepts(demo):
    job, model, passes, rm = demo
    pm, cp = rm.passes[0], passes[0]
    cell = job_cell(job, model, DEFAULT_RULES)
    P = _cell_poses(pm, cp.frames, cell.W)
    ok = pm.margin >= 0
    assert 0.1 < ok.mean() < 0.9  # the map has both kinds of cells
    assert (pm.slide_index[ok] == 1).any() and (pm.slides[0] == pm.slide).all()
    q = pm.q[ok]
    np.testing.assert_allclose(model.fk(q), P[ok], atol=1e-9)  # a solution of the cell's pose
    assert model.within_limits(q).all()
    assert model.singularity_measure(q).min() >= DEFAULT_RULES.singular_min
    checks = clearance(cell, q, P[ok])  # the planner's own rules, at its margin
    assert not any(v.any() for v in checks.values()), {k: int(v.sum()) for k, v in checks.items()}
    # and where the map says out of reach, no IK branch has a solution
    out = pm.reason == Reason.OUT_OF_REACH
    assert out.any() and np.isnan(model.ik(P[out])[..., 0]).all()


def test_the_planned_path_lies_in_the_reachable_region(demo):
    job, model, passes, rm = demo
    pm, cp = rm.passes[0], passes[0]
    assert cp.feasible and pm.chosen_roll is not None
    np.testing.assert_allclose(pm.chosen_roll, cp.motion.roll[pm.idx])
    assert (pm.path_margin >= 0).all()  # the map's rules at the planner's own roll
    # the nearest cell of the roll grid is reachable too, for every sampled ruling
    d = int(cp.motion.reverse)
    gap = np.angle(np.exp(1j * (pm.rolls[:, None] - pm.chosen_roll[None, :])))
    nearest = np.abs(gap).argmin(axis=0)
    assert (pm.margin[d, nearest, np.arange(pm.idx.size)] >= 0).all()
    # and the planner's joints there keep the rules
    cell = job_cell(job, model, DEFAULT_RULES)
    q, P = cp.motion.q[pm.idx], cp.motion.flange[pm.idx]
    assert not any(v.any() for v in clearance(cell, q, P).values())


def test_reach_command_writes_the_map(tmp_path):
    job = tmp_path / "job.toml"
    job.write_text(demo_at(1.25))
    res = runner.invoke(app, ["reach", str(job), "--out", str(tmp_path / "far"),
                              "--rulings", "40", "--rolls", "24"])  # fmt: skip
    assert res.exit_code == 1, res.output  # no feasible path
    text = " ".join(res.output.split())
    assert "no feasible path" in text and "no roll works at rulings" in text
    doc = json.loads((tmp_path / "far" / "reach.json").read_text())
    p = doc["passes"][0]
    margin = np.array(p["margin_mm"])
    assert margin.shape == (2, 24, len(p["sampled_rulings"])) and p["planned"] is None
    assert (np.array(p["reason"]) == int(Reason.OUT_OF_REACH)).mean() > 0.5
    assert (tmp_path / "far" / "reach.png").stat().st_size > 10_000
    res = runner.invoke(app, ["reach", str(tmp_path / "missing.toml")])
    assert res.exit_code == 2


def test_a_failed_plan_says_how_far_and_where_to_move(tmp_path):
    job = tmp_path / "job.toml"
    job.write_text(demo_at(1.25))
    res = runner.invoke(app, ["plan", str(job), "--out", str(tmp_path / "p")])
    assert res.exit_code == 1
    reasons = json.loads((tmp_path / "p" / "report.json").read_text())["reasons"]
    text = " ".join(reasons)
    assert "out of reach at every roll of the wire" in text
    assert "out of reach by up to" in text and "mm, the wrist too far from the shoulder" in text
    assert "moving the block" in text and "towards the robot" in text
