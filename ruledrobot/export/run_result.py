"""What a run is about to do and what it did: :class:`RunPlan` (shown before motion, given
to the confirmation) and :class:`RunResult`; :class:`RunMode`, :class:`ControllerError`."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
from pathlib import Path
from typing import TYPE_CHECKING

from ..robot.motion.trajectory import KinematicsRef, Trajectory
from ..robot.verdict import Check, Verdict
from .run_plan import Entry, StopPlace

if TYPE_CHECKING:
    from .run_verdict import RunMeasures
    from .verify_program import ProgramCheck

__all__ = ["ControllerError", "RunMode", "RunPlan", "RunResult"]


class RunMode(str, Enum):
    """How the motion is sent.

    Forwarded ahead of time to a program that plays it on the controller's clock
    (:mod:`.forward`, the default), one servoJ per controller period streamed on this
    computer's clock, or the plan's path program (UR moves at the plan's speeds, verified
    before motion: :mod:`.run_program`)."""

    forward = "forward"
    servoj = "servoj"
    stream = "stream"  #: servoj's other name
    path = "path"


class ControllerError(RuntimeError):
    """The controller cannot be asked (not reachable, no answer): nothing was checked."""


@dataclass(frozen=True)
class RunPlan:
    """What a run will do, shown before it moves: the checks and the entry move."""

    verdict: Verdict
    entry: Entry | None
    host: str | None
    mode: str
    trajectory: Trajectory
    approach_speed: float
    speed_scale: float

    def describe(self) -> list[str]:
        """The approach move in words (one line each)."""
        e = self.entry
        if e is None:
            return ["approach move: not known (the controller was not contacted)"]
        lines = [f"entry: {e.kind} — {e.note}"]
        if e.distance < 1e-4:
            lines.append(f"approach move: none (the arm is at sample {e.sample})")
        else:
            lines.append(
                f"approach move: moveJ to sample {e.sample}, leading joint q{e.joint} "
                f"{e.distance:.4f} rad at {self.approach_speed:g} rad/s, about "
                f"{e.approach_time:.1f} s"
            )
        if e.replay_time > 0:
            lines.append(
                f"replay of the kerf: samples {e.sample}..{e.requested} "
                f"({e.replay_time / self.speed_scale:.1f} s) before the cut goes on"
            )
        traj = self.trajectory
        rest = (traj.t[-1] - traj.t[e.sample]) / self.speed_scale
        lines.append(f"motion: samples {e.sample}..{traj.n - 1} ({rest:.1f} s, mode {self.mode})")
        return lines


@dataclass
class RunResult:
    """What :func:`run_trajectory` did.

    ``status``: ``"completed"``, ``"dry_run"``, ``"refused"`` (a check failed;
    nothing moved), ``"cancelled"`` (not confirmed), or why the motion stopped:
    ``"deviation"``, ``"protective_stop"``, ``"emergency_stop"``,
    ``"connection_lost"``, ``"controller_slow"``, ``"client_slow"``, ``"buffer_dry"`` (a
    forwarded run's samples ran short: the controller stopped along the path),
    ``"program_stopped"``,
    ``"command_failed"``, ``"interrupted"``, ``"client_error"`` (an error the ur_rtde
    process did not expect: a defect; it stopped the arm as on any stop and says the
    error and where), ``"client_died"`` (the ur_rtde process crashed), ``"client_hung"``
    (it stopped answering and was killed).
    ``start_index``: the first sample streamed (the entry), ``requested_index``:
    the sample asked for; ``stop_index``: the input sample the arm reached
    (``n_samples`` when completed) — resume with it; ``stop``: where, in words
    (time, phase, wire in the stock); ``verdict``: the checks before motion;
    ``entry``: how the run entered; ``actual``/``actual_path``: the recording
    and its file (``<stem>.run-NNN.csv``); ``client``: how the ur_rtde process
    ended and the tail of its output, when it did not end normally;
    ``timeline``: (``time.monotonic()``, event) of the supervised steps;
    ``run_verdict``: after motion, what the robot did to the cut (the motion, the feed
    and the wire in the block, samples skipped in the stock: :mod:`.run_verdict`), with
    its figures in ``measures``; ``ok``: the run holds (completed, or a dry run, and
    every check of both verdicts holds); ``priority``: the scheduling the streaming
    process got (``realtime``: SCHED_RR).
    """

    status: str
    message: str
    n_samples: int
    start_index: int = 0
    stop_index: int = 0
    stop_time: float = 0.0
    samples_sent: int = 0
    max_deviation: float = 0.0
    actual: Trajectory | None = None
    actual_path: Path | None = None
    verdict: Verdict | None = None
    #: the controller's kinematics as read before motion (the recording's frame)
    controller_kinematics: KinematicsRef | None = None
    entry: Entry | None = None
    requested_index: int = 0
    stop: StopPlace | None = None
    client: str = ""
    timeline: list[tuple[float, str]] = field(default_factory=list)
    #: the controller's clock [s] at the recording's first sample (its t = 0), when known
    recording_t0: float | None = None
    #: servoJ streams: samples skipped to keep the plan's schedule, and the longest the
    #: stream was behind it [s] (``Session.keep_schedule``)
    samples_skipped: int = 0
    max_slip: float = 0.0
    #: after motion: the run's verdict from the recording, and its figures
    run_verdict: Verdict | None = None
    measures: RunMeasures | None = None
    #: the streaming process's scheduling, in words, and whether it is real-time
    priority: str = ""
    realtime: bool = False
    #: mode path: the program's motion (generated at the control period) measured against
    #: the plan before motion (:mod:`.run_program`)
    program_check: ProgramCheck | None = None

    @property
    def completed(self) -> bool:
        """Whether the run went to its end (``completed``) or was a dry run."""
        return self.status in ("completed", "dry_run")

    @property
    def ok(self) -> bool:
        """Completed (or a dry run) with every check before motion and of the executed cut holding.

        What exit code 0 means."""
        return (self.completed and (self.verdict is None or self.verdict.ok)
                and (self.run_verdict is None or self.run_verdict.ok))  # fmt: skip

    @property
    def moved(self) -> bool:
        """Whether motion was started (not a dry run, refusal or cancellation)."""
        return self.status not in ("dry_run", "refused", "cancelled")

    @property
    def approach_distance(self) -> float:
        """The leading joint's distance [rad] from the arm's pose to the first sample streamed.

        The entry's; 0 before an entry is chosen.
        """
        return 0.0 if self.entry is None else self.entry.distance

    @property
    def checks(self) -> tuple[Check, ...]:
        """The checks before motion (empty before the verdict)."""
        return () if self.verdict is None else self.verdict.checks

    @property
    def resume_index(self) -> int | None:
        """The sample to resume from (``--resume``), None when completed or nothing moved."""
        return self.stop_index if self.moved and self.status != "completed" else None

    def __str__(self) -> str:
        text = f"{self.status}: {self.message}"
        if self.moved:
            text += (
                f" (samples {self.start_index}..{self.stop_index} of {self.n_samples}, max "
                f"deviation {self.max_deviation:.4f} rad)"
            )
        if self.run_verdict is not None and not self.run_verdict.ok:
            text += f"; the executed cut fails: {self.run_verdict.summary()}"
        return text
