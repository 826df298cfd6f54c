"""A plan's outcome (wirecut.report.outcome): report.json and the verdict from the demo's
plan, unverified and with a verification made up here (the simulated wire on the planned
one, then a collision), and from a job out of reach.  The report's figures are checked
against the plan's own arrays and against each other."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.job.load import job_document, parse_job
from ruledrobot.wirecut.plan import make_plan
from ruledrobot.wirecut.report.outcome import REPORT_FORMAT, plan_outcome
from ruledrobot.wirecut.verify import Verification
from tests.wirecut.reach_jobs import demo_at


def _plan(text: str):
    return make_plan(parse_job(job_document(text, "job.toml"), "job.toml"))


@pytest.fixture(scope="module")
def plan():
    p = _plan(DEMO_JOB)
    assert p.motion is not None
    return p


def _verification(plan, collisions=(), sentences=()) -> Verification:
    sim = {"joint_torque": {"max_ratio": 0.4}, "tcp_position_error_mm": {"max": 0.3},
           "realtime_factor": 7.5}  # fmt: skip
    return Verification(None, sim, plan.measured.deviation.copy(), tuple(collisions),
                        tuple(sentences), 1.5)  # fmt: skip


def test_an_unverified_plan_fails_what_only_the_simulation_measures(plan):
    report, verdict = plan_outcome(plan, None)
    assert {c.name for c in verdict.failed} == {"verified", "wire_deviation", "joint_torque"}
    assert report["feasible"] is False and report["verdict"] == verdict.as_dict()
    assert json.loads(json.dumps(report)) == report  # plain JSON
    assert report["format"] == REPORT_FORMAT and report["robot"] == "ur5e"
    assert report["job"] is None  # built in memory: no file to name
    assert report["max_joint_torque_ratio"] is None and report["max_wire_deviation_mm"] is None
    assert "simulation_realtime_factor" not in report


def test_the_reports_figures_are_the_plans(plan):
    report, verdict = plan_outcome(plan, None)
    mo, me = plan.motion, plan.measured
    assert report["duration_s"] == mo.timed.t[-1] and report["samples"] == mo.timed.t.size
    assert report["path_rulings"] == sum(len(cp.frames) for cp in plan.passes)
    assert report["rulings_in_stock"] == sum(int(cp.motion.hit.sum()) for cp in plan.passes)
    (cut,) = report["cuts"]
    assert cut["name"] == "cut" and cut["passes"] == len(plan.passes) == 1
    assert cut["feed_speed_mm_s"] == pytest.approx(10.0) and cut["kerf_mm"] == pytest.approx(0.8)
    assert cut["keep"] is None and cut["kerf_compensated"] is False
    assert cut["max_kept_surface_error_mm"] is None
    rows = mo.surface
    assert cut["max_planned_wire_deviation_mm"] == pytest.approx(me.deviation[rows].max() * 1e3)
    cutting = mo.pass_of >= 0
    t_cut = mo.timed.t[cutting]
    assert report["cut_duration_s"] == pytest.approx(t_cut[-1] - t_cut[0])
    held = rows & ~mo.timed.feed_limited
    assert cut["feed_within_1pct_fraction"] == pytest.approx(
        np.mean(np.abs(me.feed[held] / 0.01 - 1.0) <= 0.01))
    m0 = plan.passes[0].motion
    assert cut["roll_deg"] == pytest.approx(np.degrees(m0.roll[0]))
    assert cut["constant_roll"] == bool(np.ptp(m0.roll) < 1e-12)
    assert cut["slide_m"] == m0.slide[0] and cut["wire_reversed"] == bool(m0.reverse)
    # the whole job's figures are its only cut's
    for key in ("max_feed_speed_mm_s", "min_feed_speed_mm_s", "feed_within_1pct_fraction",
                "max_planned_wire_deviation_mm", "roll_deg", "kerf_mm"):  # fmt: skip
        assert report[key] == cut[key], key
    # and the verdict's
    assert verdict["feed_max"].value == report["max_feed_speed_mm_s"]
    assert verdict["feed_min"].value == report["min_feed_speed_mm_s"]
    assert verdict["planned_wire_deviation"].value == report["max_planned_wire_deviation_mm"]
    assert verdict["joint_speed"].value == report["max_joint_speed_ratio"]
    assert report["max_feed_speed_mm_s"] >= report["min_feed_speed_mm_s"] > 0
    assert report["heat"] is None


def test_a_verification_on_the_planned_wire_passes(plan):
    report, verdict = plan_outcome(plan, _verification(plan))
    assert verdict.ok, verdict.summary()
    assert report["feasible"] is True
    assert report["max_wire_deviation_mm"] == report["max_planned_wire_deviation_mm"]
    assert report["max_joint_torque_ratio"] == 0.4
    assert report["max_tcp_tracking_error_mm"] == 0.3
    assert report["simulation_realtime_factor"] == 7.5
    assert report["timings"]["simulation_s"] == 1.5


def test_a_simulated_collision_fails_the_plan_and_is_reported(plan):
    hit = {"geom1": "stock", "body1": "world", "geom2": "bow", "body2": "tool", "phase": "cut"}
    report, verdict = plan_outcome(
        plan, _verification(plan, [hit], ["bow of tool hits the stock, 1.0 mm deep"]))
    assert [c.name for c in verdict.failed] == ["collisions"]
    assert verdict["collisions"].value == 1
    assert "bow of tool hits the stock" in verdict["collisions"].detail
    assert report["collisions"] == [hit]


def test_a_job_out_of_reach_says_why_and_where_to_move():
    plan = _plan(demo_at(1.25, steps=2))
    assert plan.motion is None
    report, verdict = plan_outcome(plan, None)
    assert [c.name for c in verdict.checks] == ["reach"] and not verdict.ok
    assert report["feasible"] is False and report["verdict"] == verdict.as_dict()
    assert report["reasons"][: len(plan.reasons)] == list(plan.reasons)
    assert len(report["reasons"]) > len(plan.reasons)  # the reach explanations added
    assert any("moving the block" in r for r in report["reasons"])
    assert verdict["reach"].detail == "; ".join(report["reasons"])
    assert report["path_rulings"] == sum(len(cp.frames) for cp in plan.passes)
    assert "duration_s" not in report and "cuts" not in report
