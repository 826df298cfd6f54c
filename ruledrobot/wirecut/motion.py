"""The whole motion of a job: approach, every pass with its lead-in and lead-out, the
transits between them, the retract — one timed joint trajectory with a label per sample.

Each pass (:class:`~.path.CutPath`) is timed at its cut's feed speed
(:func:`~.timing.time_path`).  It is entered from a pose ``LIFT`` beyond its first
ruling (away from the stock centre) and left to a pose ``LIFT`` beyond its last.
Between passes the arm moves in joint space from one lifted pose to the next
(:mod:`.transit` checks that the bow and the arm stay clear of the whole stock —
what earlier cuts cut off may still lie there — and goes over the top when the
direct move does not).  With ``[tool] heat`` the arm holds still at the start of
each lead-in for the pre-heat time (phase ``preheat``).

Labels: ``approach`` (before the first pass), ``preheat``, ``lead_in``, ``cut``
(the wire in the stock), ``lead_out``, ``transit`` (between passes, including the
moves to and from the lifted poses), ``retract`` (after the last pass).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..geometry.angles import wrap_near
from ..geometry.checks import FloatArray
from ..geometry.interp import interp_linear
from .path import CutPath, chord_ends_in_flange
from .spec import Job
from .timing import TimedPath, concatenate, dwell, joint_move, time_path
from .toolpath import speed_factor, wire_frame
from .transit import TransitPlanner

__all__ = ["LIFT", "Motion", "assemble_motion"]

LIFT = 0.1  # m: approach from / retract to this far beyond the lead-in/out pose


@dataclass(frozen=True, eq=False)
class Motion:
    """The timed motion of a job (M samples) and, per sample, what it belongs to.

    ``timed``: the trajectory.  ``labels`` (M,): the phase (module doc).  ``pass_of``
    (M,): the index of the pass a sample belongs to (-1 outside passes).  ``s`` (M,):
    the ruling parameter within its pass (NaN outside).  ``in_stock`` (M,): the wire
    crosses the stock (both neighbouring rulings of its pass do).  ``ends`` (M, 2, 3):
    the chord ends as points of the wire in the flange frame (0 outside the stock).
    ``heat`` (M,): the wire is hot (pre-heat, lead-in, cut, lead-out) when the tool
    switches heat, else all False.  ``notes``: what the assembly decided (transits).
    """

    timed: TimedPath = field(repr=False)
    labels: np.ndarray = field(repr=False)
    pass_of: np.ndarray = field(repr=False)
    s: FloatArray = field(repr=False)
    in_stock: np.ndarray = field(repr=False)
    ends: FloatArray = field(repr=False)
    heat: np.ndarray = field(repr=False)
    notes: tuple[str, ...] = ()


def _fill_nearest(values: FloatArray, valid: np.ndarray) -> FloatArray:
    """Rows of ``values`` where ``valid`` is False replaced by the nearest valid row."""
    idx = np.flatnonzero(valid)
    pos = np.clip(np.searchsorted(idx, np.arange(len(values))), 0, len(idx) - 1)
    left = idx[np.clip(pos - 1, 0, len(idx) - 1)]
    right = idx[pos]
    k = np.arange(len(values))
    nearest = np.where(np.abs(k - left) <= np.abs(right - k), left, right)
    return values[nearest]


def _backed_off(model, q: FloatArray, away: FloatArray, dist: float) -> FloatArray | None:
    """Joints nearest ``q`` whose flange is ``dist`` further along ``away`` (unit, base
    frame); None if unreachable or out of limits."""
    P = model.fk(q)
    P[:3, 3] += dist * away
    sols = model.ik(P)
    sols = sols[~np.isnan(sols).any(axis=1)]
    if not len(sols):
        return None
    sols = wrap_near(sols, q)
    best = sols[np.argmin(np.abs(sols - q).max(axis=1))]
    return best if model.within_limits(best) else None


@dataclass
class _Builder:
    """Collects timed parts with their labels and pass indices."""

    dt: float
    parts: list[TimedPath] = field(default_factory=list)
    kinds: list[tuple[str, int]] = field(default_factory=list)  # (label or "pass", pass index)

    def add(self, part: TimedPath, label: str, pass_index: int = -1) -> None:
        self.parts.append(part)
        self.kinds.append((label, pass_index))


def _pass_timing(job: Job, model, cp: CutPath, vel, acc, dt) -> tuple[TimedPath, FloatArray]:
    cut = next(c for c in job.cuts if c.name == cp.name)
    m = cp.motion
    s = np.arange(len(cp.frames), dtype=np.float64)
    ends = chord_ends_in_flange(cp)
    sf = speed_factor(m.flange, s, ends, m.hit)
    return time_path(s, m.q, sf, cut.feed_speed, vel, acc, dt), ends


def assemble_motion(job: Job, model, passes: list[CutPath]) -> Motion:
    """Time the passes and join them with approach, pre-heat, transits and retract."""
    dt = float(model.control_period)
    vel = model.max_velocity * job.robot.speed_scale
    acc = model.max_acceleration if job.robot.acceleration is None else job.robot.acceleration
    W = wire_frame(job.tool)
    transit = TransitPlanner.of(job, model)
    b = _Builder(dt)
    notes: list[str] = []
    timed_passes = []
    for cp in passes:
        timed_passes.append(_pass_timing(job, model, cp, vel, acc, dt))
    here: FloatArray | None = None
    if job.robot.home is not None:
        here = np.asarray(job.robot.home, dtype=np.float64)
    for k, (cp, (timed, _)) in enumerate(zip(passes, timed_passes, strict=True)):
        cut = next(c for c in job.cuts if c.name == cp.name)
        slow = cut.approach_speed
        m = cp.motion
        start, end = m.q[0], m.q[-1]
        mids = (m.flange @ W)[[0, -1], :3, 3]
        away = mids - job.stock.centre
        away /= np.linalg.norm(away, axis=1, keepdims=True)
        above_start = _backed_off(model, start, away[0], LIFT)
        label = "approach" if k == 0 else "transit"
        entry = start if above_start is None else above_start
        if here is not None:
            if k == 0:  # home: the whole turns nearest the first pass
                here = wrap_near(here, entry)
            for qa, qb in transit.route(here, entry, notes, f"to {cp.name}"):
                b.add(joint_move(qa, qb, vel, acc, dt, slow), label)
        if above_start is not None:
            b.add(joint_move(above_start, start, vel, acc, dt, slow), label)
        if job.tool.heat is not None and job.tool.heat.preheat > 0:
            b.add(dwell(start, job.tool.heat.preheat, vel, acc, dt), "preheat", k)
        b.add(timed, "pass", k)
        above_end = _backed_off(model, end, away[1], LIFT)
        last = k == len(passes) - 1
        if above_end is not None:
            b.add(joint_move(end, above_end, vel, acc, dt, slow), "retract" if last else "transit")
        here = end if above_end is None else above_end
    if job.robot.home is not None and here is not None:
        home = wrap_near(job.robot.home, here)
        for qa, qb in transit.route(here, home, notes, "home"):
            b.add(joint_move(qa, qb, vel, acc, dt, job.cuts[-1].approach_speed), "retract")
    whole = concatenate(b.parts, dt) if len(b.parts) > 1 else b.parts[0]
    return _label(job, whole, b, passes, timed_passes, notes)


def _label(job, whole: TimedPath, b: _Builder, passes, timed_passes, notes) -> Motion:
    M = whole.t.size
    labels = np.full(M, "move", dtype=object)
    pass_of = np.full(M, -1, dtype=np.int64)
    s = np.full(M, np.nan)
    in_stock = np.zeros(M, dtype=bool)
    ends = np.zeros((M, 2, 3))
    seg = whole.segment
    for i, (label, k) in enumerate(b.kinds):
        rows = seg == i
        if not rows.any():
            continue
        if label != "pass":
            labels[rows] = label
            if label == "preheat":
                pass_of[rows] = k
            continue
        cp, (_, cp_ends) = passes[k], timed_passes[k]
        idx = np.flatnonzero(rows)
        # the pass's own parameter: its s_of_t restarts at 0 (the part drops no first
        # sample when it is the first part; otherwise the dropped one is its s = 0)
        s_k = whole.s_of_t[idx] - whole.s_of_t[idx[0]]
        if i > 0:
            s_k = s_k + (b.parts[i].s_of_t[1] - b.parts[i].s_of_t[0])
        n = len(cp.frames)
        s_k = np.clip(s_k, 0.0, n - 1.0)
        i0 = np.clip(np.floor(s_k).astype(int), 0, n - 2)
        hit = cp.motion.hit[i0] & cp.motion.hit[i0 + 1]
        pass_of[idx] = k
        s[idx] = s_k
        in_stock[idx] = hit
        ends[idx] = interp_linear(s_k, np.arange(n, dtype=float),
                                  _fill_nearest(cp_ends, cp.motion.hit))  # fmt: skip
        h = np.flatnonzero(hit)
        lab = np.full(idx.size, "lead_in", dtype=object)
        if h.size:
            lab[h[0] : h[-1] + 1] = "cut"
            lab[h[-1] + 1 :] = "lead_out"
        labels[idx] = lab
    heat = np.zeros(M, dtype=bool)
    if job.tool.heat is not None:
        heat = np.isin(labels.astype(str), ("preheat", "lead_in", "cut", "lead_out"))
    return Motion(whole, labels, pass_of, s, in_stock, ends, heat, tuple(notes))
