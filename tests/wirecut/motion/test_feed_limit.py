"""What holds the wire below its feed (wirecut.motion.feed_limit), on the demo's plan: the
joints' ratios to their limits measured here over the window around the slowest sample,
and the sentence's three cases — a joint at its speed limit, at its acceleration limit
(limits lowered here until they bind; the samples and rulings over which it stays there
named), or neither (the time law's own feed there and the path around the sample's
rulings, measured: never advice such as "sparse rulings", issue 32)."""

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


def _says_where(plan, text: str, j: int, v_limit=None, a_limit=None) -> None:
    """The samples the sentence names are those around the slowest one where joint ``j``
    stays at ``AT_LIMIT`` of the named limit or more, and the rulings are theirs."""
    m = re.search(r"(?:over t = ([\d.]+)-([\d.]+) s \(samples (\d+)-(\d+)|at t = ([\d.]+) s "
                  r"\(sample (\d+))", text)  # fmt: skip
    assert m, text
    a, b = (int(m[3]), int(m[4])) if m[3] else (int(m[6]), int(m[6]))
    timed = plan.motion.timed
    r = (np.abs(timed.qd[:, j]) / v_limit[j] if v_limit is not None
         else np.abs(timed.qdd[:, j]) / a_limit[j])  # fmt: skip
    assert (r[a : b + 1] >= AT_LIMIT).all()
    assert (a == 0 or r[a - 1] < AT_LIMIT) and (b == r.size - 1 or r[b + 1] < AT_LIMIT)
    cp = plan.passes[0]
    ra = int(np.searchsorted(cp.s, plan.motion.s[a], side="right") - 1)
    rb = int(np.searchsorted(cp.s, plan.motion.s[b], side="right") - 1) + 1
    assert f"between rulings {ra} and {rb} of 'cut'" in text, text


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
                  r"acceleration limits within 0.05 s", text)  # fmt: skip
    assert m, text
    assert int(m[1]) == round(100 * v.max()) and int(m[2]) == round(100 * a.max())
    # the time law's own feed there, and the path measured around the sample's rulings
    law = plan.motion.timed.feed[k] * 1e3
    assert (f"the time law slowed the wire to {law:.3g} mm/s there" in text
            or f"the time law held {law:.3g} mm/s there" in text), text  # fmt: skip
    cp = plan.passes[0]
    i = int(np.searchsorted(cp.s, plan.motion.s[k], side="right") - 1)
    assert f"around rulings {i}-{i + 1} (of {len(cp.s)}, pass 'cut')" in text, text
    m = re.search(r"the wire's travel per joint distance changes by ([\d.]+) % from rulings "
                  r"(\d+)-(\d+) to (\d+)-(\d+)", text)  # fmt: skip
    assert m, text
    dq = np.diff(cp.motion.q, axis=0)
    per = np.diff(cp.s) / np.linalg.norm(dq, axis=1)
    x, y = int(m[2]), int(m[4])
    assert abs(i - x) <= 1 and y == x + 1
    assert float(m[1]) == pytest.approx(100 * abs(per[y] - per[x]) / max(per[x], per[y]),
                                        abs=0.05)  # fmt: skip
    assert re.search(r"the joint path turns [\d.]+° at ruling \d+ \(median over the pass "
                     r"[\d.]+°\)", text), text  # fmt: skip
    # no advice: what was measured only
    assert "sparse" not in text and "refine" not in text


def test_a_joint_at_its_speed_limit_sets_the_pace(plan):
    k = _slowest_in_cut(plan)
    vmax = np.asarray(plan.model.max_velocity)
    v, _ = _window_ratios(plan, k, vmax, np.asarray(plan.model.max_acceleration))
    scale = float(v.max()) / 1.2  # the joints' speeds at 120 % of the scaled limit
    robot = dataclasses.replace(plan.job.robot, speed_scale=scale)
    slowed = dataclasses.replace(plan, job=dataclasses.replace(plan.job, robot=robot))
    text = feed_limit_reason(slowed, _fm(slowed, k))
    j = int(np.argmax(v))
    assert f": joint {j + 1} at 120 % of its speed limit sets the pace over t = " in text, text
    _says_where(slowed, text, v_limit=np.asarray(plan.model.max_velocity) * scale, j=j)


def test_a_joint_at_its_acceleration_limit_sets_the_pace(plan):
    k = _slowest_in_cut(plan)
    amax = np.asarray(plan.model.max_acceleration)
    _, a = _window_ratios(plan, k, np.asarray(plan.model.max_velocity), amax)
    low = amax * float(a.max()) / 0.97  # the largest acceleration at 97 % of its limit
    weak = dataclasses.replace(plan, model=plan.model.with_limits(acceleration=low))
    text = feed_limit_reason(weak, _fm(weak, k))
    j = int(np.argmax(a))
    assert f": joint {j + 1} at 97 % of its acceleration limit sets the pace " in text, text
    _says_where(weak, text, a_limit=low, j=j)
    # below the share, the joints do not set the pace
    weak = dataclasses.replace(plan, model=plan.model.with_limits(
        acceleration=amax * float(a.max()) / 0.9))  # fmt: skip
    assert "of their acceleration limits within" in feed_limit_reason(weak, _fm(weak, k))
