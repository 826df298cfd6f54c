"""What holds the wire below its feed, measured where it is slowest — the words of a
failing ``feed_min`` check (never a guess: every figure is measured on the plan).

At the sample of the lowest feed the joints' speeds and accelerations (the time law's
own, analytic) are compared with their limits over a window of
:data:`WINDOW_S` around it.  A joint at :data:`AT_LIMIT` of a limit or more sets the
pace there; otherwise the pace is set by the time law's feed bound — the speed factor
of the wire's fastest point in the block, which it holds at its largest value around
each ruling — and the sentence says by how much that factor changes between the
neighbouring rulings (the path's geometry: where the chord's end changes faces of the
block, or the rulings are sparse).
"""

from __future__ import annotations

import numpy as np

from ...robot.wire.cut import FeedMeasure
from ..cut.wire_geometry import speed_factor
from ..plan import Plan
from .assemble import feed_param

__all__ = ["AT_LIMIT", "WINDOW_S", "feed_limit_reason"]

#: s: the window around the slowest sample in which the joints are measured
WINDOW_S = 0.05
#: a joint at this share of its speed or acceleration limit sets the pace
AT_LIMIT = 0.95


def _ratios(plan: Plan, k: int) -> tuple[float, int, float, int]:
    timed, model = plan.motion.timed, plan.model
    dt = float(timed.t[1] - timed.t[0]) if timed.t.size > 1 else 1.0
    w = max(1, round(WINDOW_S / dt))
    rows = slice(max(0, k - w), min(timed.t.size, k + w + 1))
    vel = np.abs(timed.qd[rows]) / (np.asarray(model.max_velocity) * plan.job.robot.speed_scale)
    acc = np.abs(timed.qdd[rows]) / np.asarray(model.max_acceleration)
    jv, ja = int(np.argmax(vel.max(axis=0))), int(np.argmax(acc.max(axis=0)))
    return float(vel.max()), jv, float(acc.max()), ja


def _factor_change(plan: Plan, k: int) -> tuple[float, float] | None:
    """The relative change of the time law's speed factor between the rulings around
    sample ``k`` of its pass, and the path parameter there (None outside a pass)."""
    mo = plan.motion
    p = int(mo.pass_of[k])
    if p < 0:
        return None
    cp = plan.passes[p]
    s = cp.s
    bow = plan.bow if plan.bow is not None else plan.job.tool
    near = feed_param(plan.job, cp, cp.cut.feed_speed, plan.bow)[1]  # the time law's own reach
    sf = speed_factor(cp.motion.flange, s, bow, plan.job.stock, near)
    i = int(np.clip(np.searchsorted(s, mo.s[k]) - 1, 0, len(s) - 2))
    a, b = max(0, i - 1), min(len(s), i + 3)
    f = sf[a:b]
    if f.max() <= 0:
        return None
    return float((f.max() - f.min()) / f.max()), float(mo.s[k])


def feed_limit_reason(plan: Plan, fm: FeedMeasure) -> str:
    """One sentence: where the wire is slowest and what holds it back (module doc)."""
    k = fm.at_lowest
    if k < 0 or plan.motion is None:
        return "the wire never holds the feed in the stock"
    t = float(plan.motion.timed.t[k])
    where = f"slowest at t = {t:.2f} s ({plan.motion.labels[k]}, {fm.lowest * 1e3:.3g} mm/s)"
    v, jv, a, ja = _ratios(plan, k)
    if v >= AT_LIMIT:
        return f"{where}: joint {jv + 1} at {100 * v:.0f} % of its speed limit sets the pace"
    if a >= AT_LIMIT:
        return (f"{where}: joint {ja + 1} at {100 * a:.0f} % of its acceleration limit sets "
                "the pace")  # fmt: skip
    joints = (f"the joints are at most {100 * v:.0f} % of their speed and {100 * a:.0f} % of "
              "their acceleration limits there")  # fmt: skip
    ch = _factor_change(plan, k)
    if ch is None:
        return f"{where}: {joints}"
    return (f"{where}: {joints}; the time law's feed bound holds it back — the speed of the "
            f"wire's fastest point per unit of path changes by {100 * ch[0]:.0f} % between "
            "the rulings around it (the path's geometry: the chord's end changing faces of "
            "the block, or sparse rulings)")  # fmt: skip
