"""How a run shows itself on a terminal: the progress bar and the resume command."""

from __future__ import annotations

import shlex
from pathlib import Path
from typing import Any

from ..robot.motion.trajectory import Trajectory
from .run_plan import inside_mask

__all__ = ["RunProgress", "resume_command"]


class RunProgress:
    """A rich progress bar.

    The phase (``*``: the wire inside the stock), the sample, the trajectory time; started on
    the first :meth:`update` (after the confirmation)."""

    def __init__(self, traj: Trajectory, console: Any = None) -> None:
        self.traj = traj
        self.console = console
        self.progress: Any = None
        self.task: Any = None
        self._inside = inside_mask(traj)

    def update(self, k: int, n: int) -> None:
        """Show sample ``k`` of ``n`` (clipped to ``n``), its phase and trajectory time [s].

        The first call starts the bar.
        """
        from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

        traj = self.traj
        k = min(int(k), n)
        kk = min(k, n - 1)
        if self.progress is None:
            self.progress = Progress(
                TextColumn("{task.description:<10}"),
                BarColumn(),
                TextColumn("sample {task.completed:>6.0f}/{task.total:.0f}"),
                TextColumn("t {task.fields[t]:7.2f}/{task.fields[T]:.2f} s"),
                TimeElapsedColumn(),
                console=self.console,
            )
            self.progress.start()
            self.task = self.progress.add_task("", total=n, t=0.0, T=float(traj.t[-1]))
        phase = traj.phase_at(kk) + (" *" if self._inside[kk] else "")
        self.progress.update(self.task, completed=k, description=phase, t=float(traj.t[kk]))

    def stop(self) -> None:
        """Stop the bar, if started (a later :meth:`update` starts a new one)."""
        if self.progress is not None:
            self.progress.stop()
            self.progress = None


def resume_command(trajectory: str | Path, host: str | None, mode: str, speed_scale: float,
                   sample: int | None) -> str:  # fmt: skip
    """The shell command that resumes a run at ``sample`` with the same options."""
    cmd = ["ruledrobot", "run", str(trajectory)]
    if host is not None:
        cmd += ["--host", host]
    if mode != "forward":  # the default
        cmd += ["--mode", mode]
    if speed_scale != 1.0:
        cmd += ["--speed-scale", f"{speed_scale:g}"]
    cmd += ["--resume", str(sample)]
    return shlex.join(cmd)
