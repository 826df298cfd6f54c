"""What holds the wire below its feed, measured where it is slowest — the words of a
failing ``feed_min`` check.  Every figure in the sentence is measured on the plan; none
is advice (issue 32: "sparse rulings" was said where the rulings were not the cause,
and refining them as it advised made the cut slower).

At the sample of the lowest feed:

1. **The joints.**  Their speeds and accelerations (the time law's own, analytic) are
   compared with their limits over :data:`WINDOW_S` around it.  A joint at
   :data:`AT_LIMIT` of a limit or more sets the pace: the sentence names the joint, its
   share of which limit, and the samples (times, rulings of the pass) over which it
   stays at that share.
2. **Otherwise the time law's feed bound, or its model.**  The time law's own feed
   there (its model of the wire: the speed factor between the rulings) tells whether
   the law slowed the wire, or held the feed while the wire measured on the sampled
   joints moves slower.
3. **The path there**, in both cases, measured around the ruling interval of that
   sample: how much the wire's travel per joint distance changes from one ruling
   interval to the next (what the time law's feed bound follows: a jump there is a
   jump of the bound), how far the joint path turns at those rulings against the
   pass's median turn (a kink, such as a loop's exit slit meeting the loop, or a
   joint-space detour of the wire-pose search, against an even bend), and the block
   faces the chord's ends lie on when they change there.
"""

from __future__ import annotations

import numpy as np

from ...robot.wire.cut import FeedMeasure
from ..plan import Plan
from .timing import FEED_HOLD_TOL

__all__ = ["AT_LIMIT", "WINDOW_S", "feed_limit_reason"]

#: s: the window around the slowest sample in which the joints are measured
WINDOW_S = 0.05
#: a joint at this share of its speed or acceleration limit sets the pace
AT_LIMIT = 0.95
#: the block's faces, as the chord's ends are named
_FACES = ("-x", "+x", "-y", "+y", "-z", "+z")


def _ratios(plan: Plan, k: int) -> tuple[np.ndarray, np.ndarray, slice]:
    """Joint speed and acceleration ratios (W, J) over the window around sample ``k``,
    and the window's rows."""
    timed, model = plan.motion.timed, plan.model
    dt = float(timed.t[1] - timed.t[0]) if timed.t.size > 1 else 1.0
    w = max(1, round(WINDOW_S / dt))
    rows = slice(max(0, k - w), min(timed.t.size, k + w + 1))
    vel = np.abs(timed.qd[rows]) / (np.asarray(model.max_velocity) * plan.job.robot.speed_scale)
    acc = np.abs(timed.qdd[rows]) / np.asarray(model.max_acceleration)
    return vel, acc, rows


def _ruling_of(plan: Plan, k: int) -> tuple[int, int, int] | None:
    """(pass, ruling interval i (between rulings i and i+1), rulings in the pass) of
    sample ``k``; None outside a pass."""
    mo = plan.motion
    p = int(mo.pass_of[k])
    if p < 0 or not np.isfinite(mo.s[k]):
        return None
    s = plan.passes[p].s
    i = int(np.clip(np.searchsorted(s, mo.s[k], side="right") - 1, 0, len(s) - 2))
    return p, i, len(s)


def _rulings_words(plan: Plan, rows: np.ndarray) -> str:
    """``"rulings 512-515 of 'face0'"`` for the samples ``rows`` (of one pass)."""
    got = [r for r in (_ruling_of(plan, int(k)) for k in (rows[0], rows[-1])) if r is not None]
    if not got:
        return ""
    p = got[0][0]
    a, b = got[0][1], got[-1][1] + 1
    return f", between rulings {a} and {b} of '{plan.passes[p].name}'"


def _at_limit(plan: Plan, k: int, ratio: np.ndarray, rows: slice, j: int, kind: str) -> str:
    """A joint at its limit: its largest share in the window, and the samples around
    ``k`` where it stays at :data:`AT_LIMIT` of the limit or more (the whole run, which
    may reach beyond the window)."""
    timed, model = plan.motion.timed, plan.model
    if kind == "speed":
        full = np.abs(timed.qd[:, j]) / (float(model.max_velocity[j]) * plan.job.robot.speed_scale)
    else:
        full = np.abs(timed.qdd[:, j]) / float(model.max_acceleration[j])
    idx = np.arange(rows.start, rows.stop)
    near = idx[ratio[:, j] >= AT_LIMIT]
    c = int(near[np.argmin(np.abs(near - k))])  # the sample at the limit nearest k
    at = full >= AT_LIMIT
    a = c - int(np.argmin(at[c::-1])) + 1 if not at[: c + 1].all() else 0
    b = c + int(np.argmin(at[c:])) - 1 if not at[c:].all() else at.size - 1
    t = timed.t
    rul = _rulings_words(plan, np.array([a, b]))
    over = (f"at t = {t[a]:.3f} s (sample {a}{rul})" if a == b else
            f"over t = {t[a]:.3f}-{t[b]:.3f} s (samples {a}-{b}{rul})")  # fmt: skip
    return (f"joint {j + 1} at {100 * float(ratio[:, j].max()):.0f} % of its {kind} limit sets "
            f"the pace {over}")  # fmt: skip


def _faces(plan: Plan, p: int, nodes: np.ndarray) -> list[str]:
    """The faces the chord's ends lie on at the rulings ``nodes`` of pass ``p``
    (``"-y/+z"``; ``"-"`` where the ruling misses the block)."""
    cp, stock = plan.passes[p], plan.job.stock
    c0, c1 = cp.motion.chord[nodes, 0], cp.motion.chord[nodes, 1]
    F = cp.frames[nodes]
    out = []
    for n, (a, b) in enumerate(zip(c0, c1, strict=True)):
        if not (np.isfinite(a) and np.isfinite(b)) or not cp.motion.hit[nodes[n]]:
            out.append("-")
            continue
        ends = F[n, :3, 3] + np.array([a, b])[:, None] * F[n, :3, 2]
        box = stock.to_box(ends) / (0.5 * np.asarray(stock.size))
        ax = np.argmax(np.abs(box), axis=1)
        names = [_FACES[2 * x + int(box[e, x] > 0)] for e, x in enumerate(ax)]
        out.append("/".join(names))
    return out


def _path_there(plan: Plan, k: int) -> str:
    """The path around the ruling interval of sample ``k``, measured (module doc)."""
    loc = _ruling_of(plan, k)
    if loc is None:
        return ""
    p, i, n = loc
    cp = plan.passes[p]
    q, s = cp.motion.q, np.asarray(cp.s, dtype=np.float64)
    dq = np.diff(q, axis=0)
    dsig = np.linalg.norm(dq, axis=1)
    per = np.diff(s) / np.maximum(dsig, 1e-12)  # wire travel per joint distance [m/rad]
    a, b = max(0, i - 1), min(n - 2, i + 1)  # the intervals before, at and after
    pair = [(j, j + 1) for j in range(a, b)]
    change = [(abs(per[y] - per[x]) / max(per[x], per[y], 1e-300), x, y) for x, y in pair]
    words = []
    if change:
        c, x, y = max(change)
        words.append(f"the wire's travel per joint distance changes by {100 * c:.1f} % from "
                     f"rulings {x}-{x + 1} to {y}-{y + 1}")  # fmt: skip
    cos = np.einsum("ij,ij->i", dq[:-1], dq[1:]) / np.maximum(dsig[:-1] * dsig[1:], 1e-300)
    turn = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))  # at rulings 1 .. n-2
    if turn.size:
        nodes = np.arange(max(1, i), min(n - 1, i + 2))
        at = nodes[np.argmax(turn[nodes - 1])]
        words.append(f"the joint path turns {turn[at - 1]:.2f}° at ruling {at} (median over "
                     f"the pass {np.median(turn):.2f}°)")  # fmt: skip
    nodes = np.arange(max(0, i - 1), min(n, i + 3))
    faces = _faces(plan, p, nodes)
    if len(set(faces)) > 1:
        words.append("the chord's ends change faces of the block there (" + ", ".join(
            f"ruling {r}: {f}" for r, f in zip(nodes, faces, strict=True)) + ")")  # fmt: skip
    return f"; around rulings {i}-{i + 1} (of {n}, pass '{cp.name}'): " + "; ".join(words)


def feed_limit_reason(plan: Plan, fm: FeedMeasure) -> str:
    """One sentence: where the wire is slowest and what holds it back (module doc)."""
    k = fm.at_lowest
    if k < 0 or plan.motion is None:
        return "the wire never holds the feed in the stock"
    mo = plan.motion
    t = float(mo.timed.t[k])
    where = f"slowest at t = {t:.2f} s ({mo.labels[k]}, {fm.lowest * 1e3:.3g} mm/s)"
    vel, acc, rows = _ratios(plan, k)
    v, a = float(vel.max()), float(acc.max())
    if v >= AT_LIMIT or a >= AT_LIMIT:
        ratio, kind = (vel, "speed") if v >= AT_LIMIT else (acc, "acceleration")
        pace = _at_limit(plan, k, ratio, rows, int(np.argmax(ratio.max(axis=0))), kind)
        return f"{where}: {pace}{_path_there(plan, k)}"
    joints = (f"the joints are at most {100 * v:.0f} % of their speed and {100 * a:.0f} % of "
              f"their acceleration limits within {WINDOW_S:g} s")  # fmt: skip
    law = float(mo.timed.feed[k])
    if law < (1.0 - FEED_HOLD_TOL) * fm.speed:
        what = f"the time law slowed the wire to {law * 1e3:.3g} mm/s there (its feed bound)"
    else:
        what = (f"the time law held {law * 1e3:.3g} mm/s there (its model: the speed factor "
                f"between the rulings); the wire measured on the sampled joints moves "
                f"{fm.lowest * 1e3:.3g} mm/s")  # fmt: skip
    return f"{where}: {joints}; {what}{_path_there(plan, k)}"
