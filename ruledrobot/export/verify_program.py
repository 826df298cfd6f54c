"""What a movel/movep program will cut, measured before it is written.

A path program (:func:`~.urscript.urscript_program` with ``mode="movel"`` or ``"movep"``)
replaces the plan's samples by linear moves with UR's speed, acceleration and blend
semantics.  Before the program is written its motion is generated, one setpoint per
control period, by the same trajectory generator the emulator runs
(:mod:`ruledrobot.robot.motion.ur_motion`: trapezoidal profiles, blends, IK nearest the
previous sample, with :class:`~ruledrobot.robot.motion.arm_kinematics.ArmKinematics` of the
trajectory's robot and TCP) and measured with the one model of the wire against the
block (:meth:`WireCut.measure <ruledrobot.robot.wire.cut.WireCut.measure>`,
:func:`~ruledrobot.robot.wire.cut.feed_measures`):

* **feed** per cut: the highest cutting speed in the stock and the lowest where the
  plan holds the feed, against the plan's ``speed · (1 ± tolerance)``; the plan's feed
  windows (sample ranges) are carried over to the program's samples through the
  matching below;
* **wire deviation**: each program sample is matched to the plan sample whose wire is
  nearest (both wire ends, within :data:`MATCH_WINDOW` s of the same time on the plan's
  clock: the program's time carried by the drift measured so far, ``_match``); the
  deviation is the largest distance of the program's chord ends (the wire's part in the
  block) from the matched plan sample's wire line, over the samples with the wire in
  the stock, against ``wire_tolerance``.  Its resolution is half the plan's step along
  the path (0.01 mm at 10 mm/s and 500 Hz).

* **face error** (issue 33), for cuts that name the part's face: the predicted cut face
  of the program's wire (:func:`~ruledrobot.robot.wire.face.face_errors`, the plan's own
  check) with the power the program sets — its analog set-points times the full scale
  where the heat schedules the power, else the plan's ``heat_power`` where the program
  has the heat on (:func:`~.heat.motion_power`), delayed by the heat's lag — against
  each cut's ``tolerance``.

A program that breaks any is refused (:class:`ProgramRefused`, with the numbers); a cut
whose face error is measured is judged by its face, its feed is information (the time
law's target), as in the plan's verdict.
A trajectory without a cut (``meta.cut`` None: no block, no feed) is measured on its
TCP alone: the TCP's distance from the nearest plan TCP, against ``wire_tolerance``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ..geometry.ranges import runs_of
from ..robot.motion.arm_kinematics import ArmKinematics
from ..robot.motion.trajectory import Trajectory, model_for
from ..robot.motion.ur_motion import PathMotion, Segment, joint_segment, linear_segment
from ..robot.wire.cut import WIRE_TOLERANCE, FeedMeasure, FeedWindow, WireCut, feed_measures
from ..robot.wire.face import FaceError, FaceTarget, face_errors
from ..robot.wire.in_stock import WireInStock, largest_line_distance, wire_ends
from ..robot.wire.kerf import wire_power
from .heat import motion_power

__all__ = [
    "MATCH_WINDOW",
    "Move",
    "ProgramCheck",
    "ProgramRefused",
    "Sleep",
    "Switch",
    "carried_faces",
    "check_path_program",
    "measure_motion",
    "refuse_unless_ok",
    "simulate_path_program",
]

#: s: a program sample is matched to plan samples at most this far from its own time
MATCH_WINDOW = 1.0
#: m/s: the time gap's weight in the match, against the wires' distance (m): it only
#: breaks ties between equal poses (1 um per second of gap)
TIE_SPEED = 1e-6


@dataclass(frozen=True)
class Move:
    """A ``movel``/``movep`` (or, with ``joint``, ``movej``) statement of a path program.

    ``movel``/``movep`` to UR pose vector ``pose`` with ``a`` m/s^2, ``v`` m/s, ``r`` m;
    with ``joint`` a ``movej`` to the joints ``pose`` (rad/s^2, rad/s, r m)."""

    pose: np.ndarray
    a: float
    v: float
    r: float
    joint: bool = False


@dataclass(frozen=True)
class Sleep:
    """``sleep(seconds)``: the arm holds still."""

    seconds: float


@dataclass(frozen=True)
class Switch:
    """The heat output switched on or off (takes no time).

    ``value``: an analog output's set-point (a fraction of its range) when the plan
    schedules the wire's power."""

    on: bool
    value: float | None = None


Op = Move | Sleep | Switch


class ProgramRefused(ValueError):
    """A path program would not cut as planned (feed or wire beyond the plan's tolerances).

    Not written.  ``check`` holds the numbers.  The CLI exits 1 (a check fails), not 2: the
    trajectory is valid, this program of it is not."""

    def __init__(self, message: str, check: ProgramCheck) -> None:
        super().__init__(message)
        self.check = check


@dataclass(frozen=True)
class ProgramCheck:
    """The measured motion of a path program against its plan (module doc).

    ``feeds``: per cut the feed figures on the program's motion (empty without a cut);
    ``wire_deviation`` m (largest, in the stock; of the TCP without a cut) at program
    time ``at_deviation`` s; ``wire_tolerance`` m; ``duration`` / ``planned_duration`` s;
    ``samples`` of the program's motion; ``faces``: the face error per cut on it (empty
    when the plan names no face).
    """

    feeds: tuple[FeedMeasure, ...]
    wire_deviation: float
    at_deviation: float
    wire_tolerance: float
    duration: float
    planned_duration: float
    samples: int
    times: np.ndarray
    faces: tuple[FaceError, ...] = field(default=(), repr=False)

    @property
    def deviation_ok(self) -> bool:
        """Whether the largest wire deviation [m] is not above ``wire_tolerance``."""
        return not self.wire_deviation > self.wire_tolerance

    @property
    def ok(self) -> bool:
        """Whether the program passes every check within tolerance.

        The wire deviation, every cut's face (where the wire is on it) and the feed of every
        cut without a measured face, each within tolerance."""
        return (self.deviation_ok
                and all(f.max_ok and f.min_ok for f in self.feeds if f.name not in self._faced)
                and all(f.ok or np.isnan(f.worst) for f in self.faces))  # fmt: skip

    @property
    def _faced(self) -> set[str]:
        """The cuts whose face error is measured: their face decides, their feed informs
        (the time law's target), as in the plan's verdict."""
        return {f.name for f in self.faces if not np.isnan(f.worst)}

    def failures(self) -> list[str]:
        """What fails, in words with the numbers (empty when the program passes)."""
        out = []
        for f in self.feeds:
            if f.name in self._faced:
                continue
            what = f"cut {f.name!r} ({f.speed * 1e3:.4g} mm/s ± {f.tolerance * 100:.3g} %)"
            if not f.max_ok:
                out.append(f"{what}: feed {f.highest * 1e3:.2f} mm/s at t = "
                           f"{self._t(f.at_highest):.2f} s, above "
                           f"{f.speed * (1 + f.tolerance) * 1e3:.2f} mm/s")  # fmt: skip
            if not f.min_ok:
                out.append(f"{what}: feed {f.lowest * 1e3:.2f} mm/s at t = "
                           f"{self._t(f.at_lowest):.2f} s, below "
                           f"{f.speed * (1 - f.tolerance) * 1e3:.2f} mm/s")  # fmt: skip
        for f in self.faces:
            if not (f.ok or np.isnan(f.worst)):
                how = "burns" if f.burn else f"lies {f.worst * 1e3:.3f} mm from the part"
                out.append(f"cut {f.name!r}: the predicted face {how} at t = "
                           f"{self._t(f.at):.2f} s, beyond {f.tolerance * 1e3:.3g} mm")
        if not self.deviation_ok:
            what = "wire" if self.feeds else "TCP"
            out.append(f"{what} {self.wire_deviation * 1e3:.2f} mm from the plan's at t = "
                       f"{self.at_deviation:.2f} s, beyond "
                       f"{self.wire_tolerance * 1e3:.2f} mm")  # fmt: skip
        return out

    def _t(self, k: int) -> float:
        return float(self.times[k]) if 0 <= k < self.times.size else float("nan")

    def summary(self) -> str:
        """One line: the feeds, the wire, the duration."""
        parts = [f"{f.name} feed {f.lowest * 1e3:.2f}-{f.highest * 1e3:.2f} mm/s "
                 f"(plan {f.speed * 1e3:.4g} ± {f.tolerance * 100:.3g} %)"
                 for f in self.feeds]  # fmt: skip
        what = "wire" if self.feeds else "TCP"
        parts.append(f"{what} within {self.wire_deviation * 1e3:.3f} mm of the plan "
                     f"(<= {self.wire_tolerance * 1e3:.3g} mm)")  # fmt: skip
        parts += [f"{f.name} face within {f.worst * 1e3:.3f} mm of the part (<= "
                  f"{f.tolerance * 1e3:.3g} mm)" for f in self.faces if not np.isnan(f.worst)]
        parts.append(f"{self.duration:.2f} s (plan {self.planned_duration:.2f} s)")
        return "; ".join(parts)


def simulate_path_program(
    traj: Trajectory, ops: Sequence[Op], q0: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Return the joint setpoints ``(t, q)`` a controller generates for a path program.

    The path program's ``ops`` on ``traj``'s robot with its TCP, one setpoint per control
    period from rest at ``q0`` (default the first sample), as the controller generates them:
    consecutive moves with ``r > 0`` form one blended path
    (:class:`~ruledrobot.robot.motion.ur_motion.PathMotion`), a move with ``r = 0`` or any
    other statement ends it; a sleep holds for whole periods."""
    t, q, _ = _simulate(traj, ops, q0)
    return t, q


def _simulate(traj: Trajectory, ops: Sequence[Op], q0: np.ndarray | None = None
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """:func:`simulate_path_program` and the heat at each setpoint (N,): the analog
    set-point of the last :class:`Switch` with a value, else 1.0 / 0.0 for on / off (0
    before the first)."""
    model = model_for(traj.meta)
    kin = ArmKinematics(model)
    period = float(model.control_period)
    q = np.asarray(traj.q[0] if q0 is None else q0, dtype=float).copy()
    out = [q.copy()]
    level, levels = 0.0, [0.0]
    n = 0
    while n < len(ops):
        levels.extend([level] * (len(out) - len(levels)))
        op = ops[n]
        if isinstance(op, Move):
            segs: list[Segment] = []
            qs = q
            while n < len(ops) and isinstance(ops[n], Move):
                mv = ops[n]
                n += 1
                make = joint_segment if mv.joint else linear_segment  # type: ignore[union-attr]
                seg = make(qs, mv.pose, mv.v, mv.a, mv.r, kin)  # type: ignore[union-attr]
                segs.append(seg)
                qs = seg.q_end
                if mv.r <= 0.0:  # type: ignore[union-attr]
                    break
            motion = PathMotion(q, segs)
            while (sp := motion.next(period)) is not None:
                out.append(sp[0])
            q = out[-1].copy()
            continue
        n += 1
        if isinstance(op, Sleep):
            ticks = max(1, math.ceil(op.seconds / period - 1e-9))
            out.extend([q.copy()] * ticks)
        elif isinstance(op, Switch):
            level = op.value if op.value is not None else (1.0 if op.on else 0.0)
    levels.extend([level] * (len(out) - len(levels)))
    qa = np.asarray(out)
    return period * np.arange(qa.shape[0]), qa, np.asarray(levels)


def _match(plan_t: np.ndarray, plan_x: np.ndarray, t: np.ndarray, x: np.ndarray,
           window: float) -> np.ndarray:  # fmt: skip
    """(N,) the plan sample nearest each program sample (features ``x`` (N, F) against
    ``plan_x`` (M, F)) among those within ``window`` s of its time on the plan's clock.

    The clocks drift apart over a long program (its free-air ``movej`` transits run
    faster or slower than the plan's: 4.9 s over the wedge's 273 s), so the program's
    time is carried to the plan's by the drift measured so far: after each chunk of
    samples, the median of (plan time - program time) over its matches (equal poses, as in
    a dwell, matched nearest in time: :data:`TIE_SPEED`).  The window
    then bounds only the error of that estimate within one chunk (half a second at
    500 Hz), and still keeps a loop's start from matching its end."""
    out = np.empty(t.size, dtype=np.int64)
    chunk = 256
    drift = 0.0
    for j0 in range(0, t.size, chunk):
        j1 = min(j0 + chunk, t.size)
        tc = t[j0:j1] + drift
        lo = int(np.searchsorted(plan_t, tc[0] - window))
        hi = int(np.searchsorted(plan_t, tc[-1] + window, side="right"))
        lo, hi = min(lo, plan_t.size - 1), max(hi, lo + 1)
        xs, ps = x[j0:j1] - plan_x[lo], plan_x[lo:hi] - plan_x[lo]  # small numbers: exact
        d = (xs * xs).sum(1)[:, None] + (ps * ps).sum(1)[None, :] - 2.0 * (xs @ ps.T)
        gap = np.abs(tc[:, None] - plan_t[None, lo:hi])
        d += (TIE_SPEED * gap) ** 2  # equal poses (a dwell): the one nearest in time
        d[gap > window] = np.inf
        k = np.argmin(d, axis=1)
        # a sample with no plan sample in its window (the program ran long): nearest in time
        none = ~np.isfinite(d[np.arange(j1 - j0), k])
        k[none] = np.clip(np.searchsorted(plan_t, tc[none]), 0, plan_t.size - 1) - lo
        out[j0:j1] = lo + k
        if (~none).any():
            drift = float(np.median(plan_t[out[j0:j1]][~none] - t[j0:j1][~none]))
    return out


def carried_faces(faces: tuple[FaceTarget, ...], match: np.ndarray) -> tuple[FaceTarget, ...]:
    """The face targets carried to the samples of another motion.

    Each range becomes the runs of samples whose plan sample ``match`` (N,) lies in it."""
    return tuple(dataclasses.replace(f, ranges=tuple(
        r for a, b in f.ranges for r in runs_of((match >= a) & (match < b))))
        for f in faces)  # fmt: skip


def _carried(cut: WireCut, match: np.ndarray) -> WireCut:
    """The plan's feed windows carried to the program's samples by ``match``."""
    feeds = []
    for w in cut.feeds:
        inwin = (match >= w.start) & (match < w.stop)
        k = np.flatnonzero(inwin)
        if not k.size:
            continue
        held = np.zeros(match.size, dtype=bool)
        for a, b in w.held:
            held |= (match >= a) & (match < b)
        feeds.append(FeedWindow(w.name, int(k[0]), int(k[-1]) + 1, w.speed, w.tolerance,
                                runs_of(held & inwin)))  # fmt: skip
    return WireCut(cut.stock, cut.wire_length, tuple(feeds))


def measure_motion(
    traj: Trajectory,
    t: np.ndarray,
    q: np.ndarray,
    *,
    wire_tolerance: float = WIRE_TOLERANCE,
    window: float = MATCH_WINDOW,
    level: np.ndarray | None = None,
) -> ProgramCheck:
    """Measure a joint motion ``(t, q)`` of ``traj``'s robot and TCP against the plan.

    A program's generated motion, or what a controller recorded, ``t`` from the start of
    the plan's first sample, measured against the plan (module doc); ``level`` (N,): the
    heat output at each sample (an analog fraction, or 1 / 0 for on / off; None: the plan's
    power)."""
    t = np.asarray(t, dtype=float)
    robot = model_for(traj.meta)
    poses = robot.fk(np.asarray(q, dtype=float))
    plan_poses = traj.tcp_poses()
    plan_t = traj.t - traj.t[0]
    cut = traj.meta.cut
    length = cut.wire_length if cut is not None else 0.0
    ends = wire_ends(poses, length)
    plan_ends = wire_ends(plan_poses, length)
    match = _match(plan_t, plan_ends.reshape(-1, 6), t, ends.reshape(-1, 6), window)
    if cut is None:
        dev = np.linalg.norm(poses[:, :3, 3] - plan_poses[match, :3, 3], axis=1)
        feeds: tuple[FeedMeasure, ...] = ()
    else:
        wis = cut.measure(t, poses)
        feeds = feed_measures(wis, _carried(cut, match))
        dev = np.zeros(t.size)
        inside = wis.inside
        if inside.any():
            chord = wis.chord_points()[inside]
            m = match[inside]
            a, b = plan_ends[m, 0], plan_ends[m, 1]
            dev[inside] = largest_line_distance(chord, a, b - a)
    k = int(np.argmax(dev))
    faces = () if cut is None else _faces(traj, wis, match, level)
    return ProgramCheck(feeds, float(dev[k]), float(t[k]), float(wire_tolerance),
                        float(t[-1] - t[0]), float(plan_t[-1]), int(t.size), t,
                        faces)  # fmt: skip


def _faces(traj: Trajectory, wis: WireInStock, match: np.ndarray,
           level: np.ndarray | None) -> tuple[FaceError, ...]:  # fmt: skip
    """The face error per cut of a motion (module doc)."""
    cut, heat = traj.meta.cut, traj.meta.heat
    if cut is None or not cut.faces:
        return ()
    full = None if heat is None or heat.full_scale is None or level is None else heat.full_scale
    p = motion_power(traj, match, None if full is None else level * full,
                     None if level is None else level > 0.0)  # fmt: skip
    lag = 0.0 if heat is None else heat.lag
    power = None if p is None else wire_power(wis.t, p, lag)
    return tuple(face_errors(wis, power, cut.material, carried_faces(cut.faces, match)).values())


def check_path_program(
    traj: Trajectory,
    ops: Sequence[Op],
    *,
    wire_tolerance: float = WIRE_TOLERANCE,
    window: float = MATCH_WINDOW,
) -> ProgramCheck:
    """Generate the motion of ``ops`` and measure it against ``traj``.

    :func:`simulate_path_program`, then :func:`measure_motion`.  Returns the figures; raises
    nothing (see :meth:`ProgramCheck.failures`)."""
    t, q, level = _simulate(traj, ops)
    return measure_motion(traj, t, q, wire_tolerance=wire_tolerance, window=window,
                          level=level)  # fmt: skip


def refuse_unless_ok(check: ProgramCheck, mode: str) -> None:
    """Raise :class:`ProgramRefused` with the numbers when ``check`` fails."""
    if check.ok:
        return
    raise ProgramRefused(
        f"{mode} program refused: its motion (UR's moves, blends and speeds, generated at "
        f"the control period) would not cut as planned: " + "; ".join(check.failures())
        + ". Export servoj, stream it (ruledrobot run), or tighten the path (tolerance, "
        "blend)", check)  # fmt: skip
