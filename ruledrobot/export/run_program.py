"""The runner's path mode: the part of the plan a run plays, as the path program an export
writes, verified the same way before anything is sent.

``ruledrobot run --mode path`` used to decimate the TCP path on its own and time each
move at the average speed of the samples it spanned: on the emulator the demo's block
was crossed in 19.7 s instead of 23.8 s, the wire at 9.55-9.79 mm/s against 8 mm/s ± 5 %
(issue 21).  Now the run's motion is :func:`~.urscript.path_program` of the samples it
plays (:func:`~.decimate.path_steps`: every phase, stock and heat boundary a waypoint,
``v`` the plan's speed over each move, free air as ``movej`` through the plan's joints,
dwells as sleeps) and :func:`~.verify_program.check_path_program` generates its motion
with the emulator's trajectory generator and measures it against the plan before the
run is confirmed: a program that would not cut as planned refuses the run (check
``path_program``, exit 1, nothing sent).

The child (:func:`~.run_motion.run_program`) plays the statements: the moves between two
sleeps as one ur_rtde path (``movePath``, each ``movel``/``movej`` with its own ``v``,
``a``, ``r``), a sleep as a monitored hold, a heat switch through RTDE IO — between two
paths at once, inside a path when the controller reports that the move after it has
begun (the move before it has no blend: the arm rests there, as in the exported program).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..robot.motion.trajectory import Trajectory
from ..robot.verdict import Check
from ..robot.wire.cut import FeedWindow, WireCut
from .settings import PATH_ACCELERATION, PATH_BLEND
from .urscript import path_program
from .verify_program import Move, Op, ProgramCheck, Sleep, Switch, check_path_program

__all__ = ["PathRun", "plan_path_run", "run_slice"]


def run_slice(traj: Trajectory, start: int, speed_scale: float = 1.0) -> Trajectory:
    """Return the samples a run plays, ``start`` to the end, with times from 0.

    Times divided by ``speed_scale``: phases, stock ranges, the cut's feed windows (their
    speeds times ``speed_scale``) and the heat windows carried to the slice's samples."""
    part = traj.sliced(start)
    meta = part.meta
    cut = meta.cut
    if cut is not None and speed_scale != 1.0:
        feeds = tuple(FeedWindow(w.name, w.start, w.stop, w.speed * speed_scale, w.tolerance,
                                 w.held, w.wire_tolerance) for w in cut.feeds)  # fmt: skip
        cut = WireCut(cut.stock, cut.wire_length, feeds)
    t = part.t / float(speed_scale)  # the heat windows: renumbered by Trajectory.sliced
    return part.with_samples(t, part.q, part.tcp, meta.replace(cut=cut))


def _move_samples(part: Trajectory, ops: tuple[Op, ...]) -> list[int]:
    """The sample of ``part`` each move goes to (its target is that sample's TCP or joints,
    copied; searched forward from the previous move's, so a path through its own poses
    is not confused)."""
    out = []
    k = 0
    for op in ops:
        if not isinstance(op, Move):
            continue
        rows = part.q if op.joint else part.tcp
        d = np.abs(rows[k:] - op.pose).max(axis=1)
        hit = np.flatnonzero(d <= 1e-12)
        if not hit.size:  # cannot happen: path_program's targets are the plan's rows
            raise ValueError(f"path program: a move's target is no sample after {k}")
        k += int(hit[0])
        out.append(k)
    return out


@dataclass(frozen=True)
class PathRun:
    """A run's path program, with the samples it plays and its measured motion.

    ``part`` (:func:`run_slice`: the samples from input sample ``start``), its statements
    ``ops`` (:func:`~.urscript.path_program`), the sample of ``part`` each move goes to
    (``samples``), and ``check``: the program's motion measured against ``part``
    (:func:`~.verify_program.check_path_program`)."""

    part: Trajectory = field(repr=False)
    start: int
    ops: tuple[Op, ...] = field(repr=False)
    samples: tuple[int, ...] = field(repr=False)
    check: ProgramCheck = field(repr=False)
    move: str = "movel"

    @property
    def ok(self) -> bool:
        """Whether the program's motion holds the plan's tolerances (``check.ok``)."""
        return self.check.ok

    def counts(self) -> str:
        """The program's statements in words."""
        lines = sum(1 for op in self.ops if isinstance(op, Move) and not op.joint)
        joints = sum(1 for op in self.ops if isinstance(op, Move) and op.joint)
        sleeps = sum(1 for op in self.ops if isinstance(op, Sleep))
        switches = sum(1 for op in self.ops if isinstance(op, Switch))
        text = f"{lines} {self.move}, {joints} movej, {sleeps} sleeps"
        return text + (f", {switches} heat switches" if switches else "")

    def verdict_check(self) -> Check:
        """The check before motion: the program's motion cuts as planned (gating)."""
        c = self.check
        label = (f"path program from sample {self.start} ({self.counts()}), its motion "
                 "generated and measured")  # fmt: skip
        detail = "" if c.ok else (
            "path program refused: its motion (UR's moves, blends and speeds, generated at "
            "the control period) would not cut as planned: " + "; ".join(c.failures())
            + ". Stream it (--mode servoj) or tighten the path (tolerance, blend)")  # fmt: skip
        limit = (
            "the plan's feed"
            + (", " if c.feeds else "; TCP ")
            + f"within {c.wire_tolerance * 1e3:.3g} mm"
        )
        return Check("path_program", label, c.summary(), limit, "", "", c.ok, True, detail)

    def child_ops(self, grid_of: Callable[[int], int]) -> list[tuple]:
        """Return the statements for the streaming child.

        ``("move", joint, target, v, a, r, grid, q_end)`` (``grid``: the controller-period grid
        sample of the move's end, ``grid_of(sample of part)``; ``q_end``: the plan's joints
        there), ``("sleep", seconds, grid)`` (grid: where the hold ends) and ``("heat", on,
        value)`` (value: an analog set-point of a scheduled power, or None)."""
        out: list[tuple] = []
        samples = iter(self.samples)
        k = 0
        q = self.part.q
        for op in self.ops:
            if isinstance(op, Move):
                k = next(samples)
                out.append(("move", bool(op.joint), [float(x) for x in op.pose], float(op.v),
                            float(op.a), float(op.r), int(grid_of(k)),
                            [float(x) for x in q[k]]))  # fmt: skip
            elif isinstance(op, Sleep):
                end = int(np.searchsorted(self.part.t, self.part.t[k] + op.seconds - 1e-9))
                out.append(("sleep", float(op.seconds), int(grid_of(min(end, q.shape[0] - 1)))))
            else:
                out.append(("heat", bool(op.on), op.value))
        return out


def plan_path_run(
    traj: Trajectory,
    start: int,
    *,
    speed_scale: float = 1.0,
    tolerance: float | None = None,
    blend: float = PATH_BLEND,
    acceleration: float = PATH_ACCELERATION,
    wire_tolerance: float,
) -> PathRun:
    """Return the path program of ``traj`` from sample ``start`` and its measured motion.

    At ``speed_scale`` (:func:`~.urscript.path_program`, the same program ``ruledrobot export
    --mode movel`` writes for these samples); its motion measured against these samples with
    ``wire_tolerance`` m (the plan's unless overridden)."""
    part = run_slice(traj, start, speed_scale)
    ops = tuple(path_program(part, tolerance=tolerance, blend=blend, acceleration=acceleration,
                             wire_tolerance=wire_tolerance))  # fmt: skip
    check = check_path_program(part, ops, wire_tolerance=wire_tolerance)
    return PathRun(part, start, ops, tuple(_move_samples(part, ops)), check)
