"""What holds the wire below its feed (wirecut.motion.feed_limit), on the demo's plan: the
joints' ratios to their limits measured here over the window around the slowest sample,
and the sentence's three cases — a joint at its speed limit, at its acceleration limit
(limits lowered here until they bind), or neither (the time law's feed bound)."""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest

from ruledrobot.robot.wire.cut import FeedMeasure
from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.job.load import job_document, parse_job
from ruledrobot.wirecut.motion.feed_limit import AT_LIMIT, WINDOW_S, feed_limit_reason
from ruledrobot.wirecut.plan import make_plan


@pytest.fixture(scope="module")
def plan():
    p = make_plan(parse_job(job_document(DEMO_JOB, "demo.toml"), "demo.toml"))
    assert p.motion is not None
    return p


def _slowest_in_cut(plan) -> int:
    mo = plan.motion
    feed = np.where(mo.surface & ~mo.timed.feed_limited, mo.wire.feed, np.inf)
    return int(np.argmin(feed))


def _fm(plan, k: int) -> FeedMeasure:
    lowest = float(plan.motion.wire.feed[k]) if k >= 0 else float("nan")
    return FeedMeasure("cut", 0.01, 0.05, 0.0101, lowest, 0, k)


def _window_ratios(plan, k: int, vmax: np.ndarray, amax: np.ndarray):
    t = plan.motion.timed.t
    dt = t[1] - t[0]
    near = np.abs(t - t[k]) <= WINDOW_S + 0.5 * dt
    v = np.abs(plan.motion.timed.qd[near]) / vmax
    a = np.abs(plan.motion.timed.qdd[near]) / amax
    return v.max(axis=0), a.max(axis=0)


def test_never_in_the_stock():
    class NoMotion:
        motion = None

    text = feed_limit_reason(NoMotion(), _fm_never())
    assert text == "the wire never holds the feed in the stock"


def _fm_never() -> FeedMeasure:
    return FeedMeasure("cut", 0.01, 0.05, float("nan"), float("nan"), -1, -1)


def test_the_joints_are_measured_over_the_window_and_the_feed_bound_named(plan):
    k = _slowest_in_cut(plan)
    model = plan.model
    v, a = _window_ratios(plan, k, np.asarray(model.max_velocity) * plan.job.robot.speed_scale,
                          np.asarray(model.max_acceleration))  # fmt: skip
    assert v.max() < AT_LIMIT and a.max() < AT_LIMIT  # the demo's joints idle in the cut
    text = feed_limit_reason(plan, _fm(plan, k))
    t = plan.motion.timed.t[k]
    feed = plan.motion.wire.feed[k] * 1e3
    assert text.startswith(f"slowest at t = {t:.2f} s (cut, {feed:.3g} mm/s): ")
    m = re.search(r"the joints are at most (\d+) % of their speed and (\d+) % of their "
                  r"acceleration limits there", text)  # fmt: skip
    assert m, text
    assert int(m[1]) == round(100 * v.max()) and int(m[2]) == round(100 * a.max())
    m = re.search(r"the time law's feed bound holds it back — the speed of the wire's "
                  r"fastest point per unit of path changes by (\d+) % between", text)  # fmt: skip
    assert m, text
    assert 0 <= int(m[1]) <= 100


def test_a_joint_at_its_speed_limit_sets_the_pace(plan):
    k = _slowest_in_cut(plan)
    vmax = np.asarray(plan.model.max_velocity)
    v, _ = _window_ratios(plan, k, vmax, np.asarray(plan.model.max_acceleration))
    scale = float(v.max()) / 1.2  # the joints' speeds at 120 % of the scaled limit
    robot = dataclasses.replace(plan.job.robot, speed_scale=scale)
    slowed = dataclasses.replace(plan, job=dataclasses.replace(plan.job, robot=robot))
    text = feed_limit_reason(slowed, _fm(slowed, k))
    j = int(np.argmax(v))
    assert text.endswith(f": joint {j + 1} at 120 % of its speed limit sets the pace"), text


def test_a_joint_at_its_acceleration_limit_sets_the_pace(plan):
    k = _slowest_in_cut(plan)
    amax = np.asarray(plan.model.max_acceleration)
    _, a = _window_ratios(plan, k, np.asarray(plan.model.max_velocity), amax)
    low = amax * float(a.max()) / 0.97  # the largest acceleration at 97 % of its limit
    weak = dataclasses.replace(plan, model=plan.model.with_limits(acceleration=low))
    text = feed_limit_reason(weak, _fm(weak, k))
    j = int(np.argmax(a))
    assert text.endswith(f": joint {j + 1} at 97 % of its acceleration limit sets the pace"), text
    # below the share, the joints do not set the pace
    weak = dataclasses.replace(plan, model=plan.model.with_limits(
        acceleration=amax * float(a.max()) / 0.9))  # fmt: skip
    assert "of their acceleration limits there" in feed_limit_reason(weak, _fm(weak, k))
