"""How a batch shows itself on a terminal: a rich progress bar (jobs done, failed,
running, throughput, time left) and one line per job that comes back."""

from __future__ import annotations

from typing import Any

from .manifest import JobRecord
from .run import BatchProgress

__all__ = ["BatchBar", "job_line"]


def _clock(seconds: float | None) -> str:
    if seconds is None:
        return "-:--"
    s = round(seconds)
    h, rem = divmod(s, 3600)
    return f"{h}:{rem // 60:02d}:{rem % 60:02d}" if h else f"{rem // 60}:{rem % 60:02d}"


def job_line(r: JobRecord) -> str:
    """One line about a job's result.

    Name, status and why (failing checks, the bad input's message, the crash's last line), the
    plan's seconds."""
    lines = r.message.strip().splitlines()
    why = {"feasible": "", "infeasible": ", ".join(r.failed_checks),
           "bad_input": lines[0] if lines else "", "crashed": lines[-1] if lines else "",
           "pending": "not planned"}.get(r.status, "")  # fmt: skip
    took = f"  ({r.plan_s:.1f} s)" if r.plan_s is not None else ""
    return f"{r.name}: {r.status}{': ' + why if why else ''}{took}"


class BatchBar:
    """Progress of a batch on ``console`` (a rich Console).

    Call it with every :class:`~.run.BatchProgress`; :meth:`stop` when the batch ends."""

    def __init__(self, console: Any = None) -> None:
        self.console = console
        self.progress: Any = None
        self.task: Any = None

    def __call__(self, p: BatchProgress) -> None:
        from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

        if p.to_plan == 0:
            return  # every result kept: nothing to show
        if self.progress is None:
            self.progress = Progress(TextColumn("jobs"), BarColumn(),
                                     TextColumn("{task.fields[text]}"), TimeElapsedColumn(),
                                     console=self.console)  # fmt: skip
            self.progress.start()
            self.task = self.progress.add_task("jobs", total=max(p.to_plan, 1), text="")
        if p.last is not None:
            style = "green" if p.last.status == "feasible" else "red"
            from rich.text import Text

            self.progress.console.print(Text(job_line(p.last), style=style))
        rate = p.throughput
        rate_text = f"{rate * 60:.1f} jobs/min" if rate is not None else "- jobs/min"
        kept = f" · {p.kept} kept" if p.kept else ""
        workers = "" if p.workers is None else f" on {p.workers} workers"
        if p.workers == 0:
            workers = " · waiting for a worker"
        text = (f"{p.done}/{p.to_plan} done · {p.failed} failed · {p.running} running"
                f"{workers}{kept} · {rate_text} · {_clock(p.eta_s)} left")  # fmt: skip
        self.progress.update(self.task, completed=p.done, text=text)

    def stop(self) -> None:
        """Stop the progress display, if one was started (safe to call twice)."""
        if self.progress is not None:
            self.progress.stop()
            self.progress = None
