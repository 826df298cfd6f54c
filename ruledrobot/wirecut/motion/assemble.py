"""The whole motion of a job: approach, every pass with its lead-in and lead-out, the
transits between them, the retract — one timed joint trajectory with a label per sample.

Each pass (:class:`~..cut.cutpath.CutPath`) is timed at its cut's feed speed
(:func:`~.timing.time_path`), in pieces from rest to rest between the corners of its
path (:mod:`.corners`).  It is entered from a pose ``LIFT`` beyond its first
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

import dataclasses
from dataclasses import dataclass, field
from itertools import pairwise

import numpy as np

from ...geometry.angles import wrap_near
from ...geometry.checks import FloatArray
from ...robot.arm.model import RobotModel
from ...robot.arm.nearest import nearest_ik
from ...robot.motion.trajectory import HEATED_PHASES
from ...robot.tool import BowTool
from ...robot.wire.in_stock import WireInStock, flange_wire_ends, wire_gap, wire_in_stock
from ..cut.clearance import Cell
from ..cut.passes import CutPath
from ..cut.wire_geometry import speed_factor
from ..job.spec import Job
from .corners import CORNER_JOIN, corner_nodes, corner_stop_mask, time_between_corners
from .densify import densified, pass_deviation, pass_feed_error, uneven_intervals
from .timing import TimedPath, TimingFailure, concatenate, dwell, joint_move
from .transit import TransitPlanner

__all__ = ["LIFT", "Motion", "PassNotTimed", "assemble_motion"]

LIFT = 0.1  # m: approach from / retract to this far beyond the lead-in/out pose
#: rounds of adding rulings where the timed wire leaves the surface or its feed strays,
#: and the share of the cut's wire and feed tolerances that triggers it (:mod:`.densify`)
DENSIFY_ROUNDS = 3
DENSIFY_SHARE = 0.25
#: m: the time law bounds the speed of the wire's point nearest the block from this far
#: out (at least; 1.5 ruling intervals where they are longer: :func:`feed_param`), so
#: that its feed bound
#: meets the chord's without a jump where the wire enters and leaves
#: (:func:`ruledrobot.robot.wire.in_stock.feed_chord`)
FEED_NEAR = 0.002
#: s: the wire moves at its feed for at least this long before it enters the block (and
#: after it leaves), so that a servo following the plan has settled by then: ruledrobot's
#: streams filter with a 0.1 s look-ahead, and the part demo's wire entered its side cut
#: at 12.7 mm/s against 12 +- 5 % when the lead-in sped up until just before the block
SETTLE_S = 0.3


@dataclass(frozen=True, eq=False)
class Motion:
    """The timed motion of a job (M samples) and, per sample, what it belongs to.

    ``timed``: the trajectory.  ``labels`` (M,): the phase (module doc).  ``pass_of``
    (M,): the index of the pass a sample belongs to (-1 outside passes).  ``s`` (M,):
    the ruling parameter within its pass (NaN outside).  ``wire``: the one model of the
    wire against the block measured on the samples (:mod:`ruledrobot.robot.wire.in_stock`);
    ``in_stock`` (M,) is its ``inside``: the wire's chord in the block is at least
    ``TOUCH`` long.  ``ends`` (M, 2, 3): the chord ends as points of the wire in the
    flange frame (0 outside the stock).  A pass's lead-in ends where its wire first
    enters the block and its lead-out starts where it last leaves.
    ``heat`` (M,): the wire is hot (pre-heat, lead-in, cut, lead-out) when the tool
    switches heat, else all False.  ``notes``: what the assembly decided (transits).
    ``passes``: the passes as timed (with the rulings :mod:`.densify` added).
    ``surface`` (M,): the wire cuts the target surface (in the stock, phase ``cut``; not
    the slits of a closed cut, which cut waste): where the feed and the wire's deviation
    are checked.  ``corner_stop`` (M,): the wire slows to a stop at a corner of its path
    (:mod:`.corners`); the lowest feed is measured outside these samples.
    """

    timed: TimedPath = field(repr=False)
    labels: np.ndarray = field(repr=False)
    pass_of: np.ndarray = field(repr=False)
    s: FloatArray = field(repr=False)
    in_stock: np.ndarray = field(repr=False)
    ends: FloatArray = field(repr=False)
    heat: np.ndarray = field(repr=False)
    notes: tuple[str, ...] = ()
    passes: tuple[CutPath, ...] = field(default=(), repr=False)
    surface: np.ndarray | None = field(default=None, repr=False)
    corner_stop: np.ndarray | None = field(default=None, repr=False)
    wire: WireInStock | None = field(default=None, repr=False)


class PassNotTimed(RuntimeError):
    """The time law found no usable trajectory for a pass.

    Its :class:`TimingFailure` in ``failure``: ``name`` the cut, ``rulings`` (first, last)
    the pass's rulings (from 0) spanning the stretch where the time goes, of ``count``.
    """

    def __init__(self, cp: CutPath, failure: TimingFailure) -> None:
        s = np.asarray(cp.s, dtype=np.float64)
        s0, s1 = failure.s_range
        a = int(np.clip(np.searchsorted(s, s0, side="right") - 1, 0, len(s) - 1))
        b = int(np.clip(np.searchsorted(s, s1, side="left"), a, len(s) - 1))
        self.name, self.rulings, self.count, self.failure = cp.name, (a, b), len(s), failure
        super().__init__(self.sentence())

    def sentence(self) -> str:
        """The pass, the rulings, what the time law found and what binds there."""
        f, (a, b) = self.failure, self.rulings
        where = f"rulings {a}-{b} of {self.count}" if b > a else f"ruling {a} of {self.count}"
        bind = f.binding
        why = ("" if bind is None else f"; {bind.words()} holds the wire to "
               f"{1e3 * f.path_speed:.3g} mm/s there")  # fmt: skip
        if f.reason == "too_long":
            what = (f"its timed path would last {f.duration:.3g} s ({f.duration / 3600:.3g} h), "
                    f"{100 * f.share:.0f} % of it over {where}")  # fmt: skip
        elif f.reason == "stall":
            what = f"its path speed falls to zero over {where}"
        elif f.reason == "limits":
            what = f"its sampled joints still break a limit at {where} after every refinement"
        else:
            what = f"no finite path speed at {where}"
        return f"pass '{self.name}': {what}{why}"


def _backed_off(
    model: RobotModel, q: FloatArray, away: FloatArray, dist: float
) -> FloatArray | None:
    """Joints nearest ``q`` whose flange is ``dist`` further along ``away`` (unit, base
    frame); None if unreachable or out of limits."""
    P = model.fk(q)
    P[:3, 3] += dist * away
    return nearest_ik(model, P, q)


def _free_pose(
    transit: TransitPlanner, model: RobotModel, q: FloatArray, away: FloatArray
) -> FloatArray | None:
    """A pose near ``q`` clear of the stock, the table and the arm, to enter a pass from
    or leave it to: ``LIFT`` (then twice that) further along ``away``, else raised over
    the stock; None when none of them is free."""
    for cand in (_backed_off(model, q, away, LIFT), _backed_off(model, q, away, 2.0 * LIFT),
                 transit.lifted(q)):  # fmt: skip
        if cand is not None and transit.free(cand).all():
            return cand
    return None


def _legs(transit: TransitPlanner, here: FloatArray, entry: FloatArray | None,
          start: FloatArray, notes: list[str], what: str):  # fmt: skip
    """Joint moves from ``here`` through ``entry`` (if any) to the pass's first pose."""
    if entry is None:
        return transit.route(here, start, notes, what)
    return transit.route(here, entry, notes, what) + transit.route(entry, start, notes,
                                                                   what.replace("to ", "into "))


@dataclass
class _Builder:
    """Collects timed parts with their labels and pass indices."""

    dt: float
    parts: list[TimedPath] = field(default_factory=list)
    kinds: list[tuple[str, int]] = field(default_factory=list)  # (label or "pass", pass index)

    def add(self, part: TimedPath, label: str, pass_index: int = -1) -> None:
        self.parts.append(part)
        self.kinds.append((label, pass_index))


def _across(p: FloatArray, o: FloatArray, z: FloatArray) -> FloatArray:
    """Distance (K, P) of points p (K, P, 3) from the lines (o, z) (K, 3): the wire's
    travel across itself.  Not a chord end's own travel: where the wire leaves the
    stock at a grazing angle that end runs along the wire, many times faster than the
    wire moves, and would stretch the parameter there."""
    d = p - o[:, None]
    return np.linalg.norm(d - (d * z[:, None]).sum(-1, keepdims=True) * z[:, None], axis=-1)


def feed_param(
    job: Job, cp: CutPath, feed_speed: float, bow: BowTool | None = None
) -> tuple[FloatArray, float]:
    """(M,) the path parameter the feed is held in, and ``near`` (m).

    The distance [m] travelled across the wire by the part of it nearest the block — the
    chord's ends inside it — as the speed factor measures it
    (:func:`~..cut.wire_geometry.speed_factor`, the one model); ``near``: how far out of the
    block the time law bounds that part's speed: :data:`FEED_NEAR`, or farther so that the
    bound reaches three rulings beyond every entry and exit and the wire moves at the feed for
    :data:`SETTLE_S` before it.

    First the frame origins' travel across the wire ``s0``; then each interval's length
    is the mean speed factor at its ends (per unit of ``s0``) times its ``s0`` length,
    so that the speed factor in the new parameter is about 1 everywhere, through the
    wire's entry and exit too.  The time law bounds the feed with the largest speed
    factor around each node, so uneven spacing — a subdivided polygon, a slit meeting
    a loop, a parameter that changes its measure where the wire enters — would hold
    the feed below the set value by the unevenness (a parameter that switched from
    chord-end to frame-origin travel at the block's face held the wire of a helicoid
    to 58 % of its feed there, a conoid's to 63 %).  ``bow``: the job's bow when the caller
    built it (:meth:`~ruledrobot.robot.tool.BowTool.from_spec` of ``job.tool``)."""
    F = cp.frames
    o, z = F[:, :3, 3], F[:, :3, 2]
    step0 = np.maximum(_across(o[:-1, None], o[1:], z[1:]),
                       _across(o[1:, None], o[:-1], z[:-1]))[:, 0]  # fmt: skip
    step0 = np.maximum(step0, 1e-9)  # strictly increasing, also where the wire holds still
    s0 = np.r_[0.0, np.cumsum(step0)]
    bow = BowTool.of(job.tool if bow is None else bow)
    ends = flange_wire_ends(cp.motion.flange, bow)
    step = np.empty_like(step0)
    cuts = [0, *(int(c) for c in corner_nodes(F, 0.5 * job.tool.wire_length)), len(F) - 1]
    for a, b in pairwise(cuts):  # between corners: differences never reach across one
        sf0 = speed_factor(cp.motion.flange[a : b + 1], s0[a : b + 1], bow, job.stock,
                           np.inf)  # fmt: skip
        step[a:b] = 0.5 * (sf0[:-1] + sf0[1:]) * step0[a:b]
    step = np.maximum(step, 1e-9)
    gap = wire_gap(ends, job.stock)
    inside = gap == 0.0
    edges = np.flatnonzero(np.diff(inside.astype(np.int8)))  # node before each change
    beyond = np.r_[edges - 3, edges + 4].clip(0, len(gap) - 1)
    near = max(FEED_NEAR, feed_speed * SETTLE_S, float(gap[beyond].max(initial=0.0)) * 1.01)
    return np.r_[0.0, np.cumsum(step)], near


def measure_wire(
    job: Job, model: RobotModel, t: FloatArray, q: FloatArray, bow: BowTool | None = None
) -> WireInStock:
    """Return the one model of the wire against the job's block along joints ``q``.

    Joints ``q`` (M, 6) at times ``t`` (M,) (``model``: the planner's, flange without tool,
    base frame; ``bow``: the job's, when the caller built it).
    """
    bow = BowTool.of(job.tool if bow is None else bow)
    ends = flange_wire_ends(model.fk(q), bow)
    return wire_in_stock(t, ends, job.stock)


def _chord_in_flange(bow: BowTool, wire: WireInStock) -> FloatArray:
    """(M, 2, 3) the chord ends as points of the wire in the flange frame (0 outside).

    The fractions are NaN outside the stock: the points there are zeroed, not the
    fractions (a fraction 0 is the wire's start point, ``W`` origin ``- L / 2``)."""
    W = bow.wire_frame()
    ends = W[:3, 3] + (wire.fractions() - 0.5)[:, :, None] * bow.wire_length * W[:3, 2]
    return np.where(wire.inside[:, None, None], ends, 0.0)


def _pass_timing(
    job: Job, model: RobotModel, cp: CutPath, vel: FloatArray, acc: FloatArray, dt: float,
    bow: BowTool,
) -> tuple[CutPath, TimedPath, np.ndarray]:
    """The pass timed at its feed, with rulings added where the timed wire leaves the
    surface between them or its feed strays (:mod:`.densify`); returns the (denser)
    pass too and the samples where the wire stops at a corner (:mod:`.corners`)."""
    cut = cp.cut
    param, near = feed_param(job, cp, cut.feed_speed, bow)
    cp = dataclasses.replace(cp, param=param)
    for attempt in range(DENSIFY_ROUNDS + 1):
        m = cp.motion
        s = cp.s
        corners = corner_nodes(cp.frames, 0.5 * job.tool.wire_length)

        def sf(a: int, b: int, m=m, s=s) -> FloatArray:  # one piece between corners
            return speed_factor(m.flange[a : b + 1], s[a : b + 1], bow, job.stock, near)

        try:
            timed = time_between_corners(s, m.q, sf, cut.feed_speed, vel, acc, dt, corners)
        except TimingFailure as exc:  # no usable time law: the plan fails, named
            raise PassNotTimed(cp, exc) from None
        if attempt == DENSIFY_ROUNDS:
            break
        wire = measure_wire(job, model, timed.t, timed.q, bow)
        dev = pass_deviation(cp, timed, wire)
        feed = pass_feed_error(cp, timed, wire, cut.feed_speed)
        bad = np.flatnonzero((dev > DENSIFY_SHARE * cut.wire_tolerance)
                             | (feed > DENSIFY_SHARE * cut.feed_tolerance))  # fmt: skip
        bad = np.union1d(bad, uneven_intervals(cp, DENSIFY_SHARE * cut.feed_tolerance))
        if not bad.size:
            break
        cp = densified(cp, bad, model, bow, job.stock)
    return cp, timed, corner_stop_mask(timed, s[corners], int(CORNER_JOIN / dt))


def assemble_motion(
    job: Job, model: RobotModel, passes: list[CutPath], cell: Cell | None = None
) -> Motion:
    """Time the passes and join them with approach, pre-heat, transits and retract.

    ``Motion.passes`` are the passes as timed.  ``cell``: the plan's clearance cell (its
    bow; the transits' cell is the same under their rules), built once by the caller
    (default: built here).
    """
    passes = list(passes)
    dt = float(model.control_period)
    vel = model.max_velocity * job.robot.speed_scale
    acc = model.max_acceleration  # the job's [robot] acceleration when it names one
    if cell is None:
        cell = Cell.of(model, job.tool, job.stock, 0.0, 0.005, 0.0, None)
    bow = BowTool.of(job.tool if cell.bow is None else cell.bow)
    W = bow.wire_frame()
    transit = TransitPlanner.of(job, model, cell=cell)
    b = _Builder(dt)
    notes: list[str] = []
    timed_passes = []
    for k, cp in enumerate(passes):
        passes[k], *timing = _pass_timing(job, model, cp, vel, acc, dt, bow)
        timed_passes.append(tuple(timing))
    here: FloatArray | None = None
    if job.robot.home is not None:
        here = np.asarray(job.robot.home, dtype=np.float64)
    for k, (cp, (timed, *_)) in enumerate(zip(passes, timed_passes, strict=True)):
        slow = cp.cut.approach_speed
        m = cp.motion
        start, end = m.q[0], m.q[-1]
        mids = (m.flange @ W)[[0, -1], :3, 3]
        away = mids - job.stock.centre
        away /= np.linalg.norm(away, axis=1, keepdims=True)
        label = "approach" if k == 0 else "transit"
        entry = _free_pose(transit, model, start, away[0])
        if here is None:  # no home: the trajectory starts clear of the stock, near the cut
            here = start if entry is None else entry
        elif k == 0:  # home: the whole turns nearest the first pass
            here = wrap_near(here, start if entry is None else entry)
        for qa, qb in _legs(transit, here, entry, start, notes, f"to {cp.name}"):
            b.add(joint_move(qa, qb, vel, acc, dt, slow), label)
        if job.tool.heat is not None and job.tool.heat.preheat > 0:
            b.add(dwell(start, job.tool.heat.preheat, vel, acc, dt), "preheat", k)
        b.add(timed, "pass", k)
        leave = _free_pose(transit, model, end, away[1])
        last = k == len(passes) - 1
        if leave is not None:
            for qa, qb in transit.route(end, leave, notes, f"from {cp.name}"):
                b.add(joint_move(qa, qb, vel, acc, dt, slow), "retract" if last else "transit")
        here = end if leave is None else leave
    if job.robot.home is not None and here is not None:
        home = wrap_near(job.robot.home, here)
        for qa, qb in transit.route(here, home, notes, "home"):
            b.add(joint_move(qa, qb, vel, acc, dt, job.cuts[-1].approach_speed), "retract")
    whole = concatenate(b.parts, dt) if len(b.parts) > 1 else b.parts[0]
    return _label(job, model, bow, whole, b, passes, timed_passes, notes)


def _label(job: Job, model: RobotModel, bow: BowTool, whole: TimedPath, b: _Builder,
           passes: list[CutPath], timed_passes: list, notes: list[str]) -> Motion:  # fmt: skip
    M = whole.t.size
    labels = np.full(M, "move", dtype=object)
    pass_of = np.full(M, -1, dtype=np.int64)
    s = np.full(M, np.nan)
    wire = measure_wire(job, model, whole.t, whole.q, bow)
    in_stock = wire.inside
    seg = whole.segment
    stop = np.zeros(M, dtype=bool)
    for i, (label, k) in enumerate(b.kinds):
        rows = seg == i
        if not rows.any():
            continue
        if label != "pass":
            labels[rows] = label
            if label == "preheat":
                pass_of[rows] = k
            continue
        cp, (timed_k, stop_k) = passes[k], timed_passes[k]
        idx = np.flatnonzero(rows)
        # the pass's own parameter: its s_of_t starts at cp.s[0] (the part drops no first
        # sample when it is the first part; otherwise the dropped one is its start)
        s_k = whole.s_of_t[idx] - whole.s_of_t[idx[0]] + cp.s[0]
        if i > 0:
            s_k = s_k + (b.parts[i].s_of_t[1] - b.parts[i].s_of_t[0])
        s_k = np.clip(s_k, cp.s[0], cp.s[-1])
        pass_of[idx] = k
        s[idx] = s_k
        h = np.flatnonzero(in_stock[idx])
        lab = np.full(idx.size, "lead_in", dtype=object)
        if h.size:
            lab[h[0] : h[-1] + 1] = "cut"
            lab[h[-1] + 1 :] = "lead_out"
        if cp.closed:  # a closed cut's slits cut waste: they lead in and out
            a, z = cp.extended
            lab[s_k < cp.s[a]] = "lead_in"
            lab[s_k > cp.s[len(cp.s) - 1 - z]] = "lead_out"
        labels[idx] = lab
        stop[idx] = stop_k[timed_k.t.size - idx.size :]  # its first may be dropped
    surface = in_stock & (labels == "cut")
    heat = np.zeros(M, dtype=bool)
    if job.tool.heat is not None:
        heat = np.isin(labels.astype(str), HEATED_PHASES)
    return Motion(whole, labels, pass_of, s, in_stock, _chord_in_flange(bow, wire), heat,
                  tuple(notes), tuple(passes), surface, stop & surface, wire)
