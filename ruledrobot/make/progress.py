"""How a make run shows itself on a terminal: two rich progress bars.

The first counts the steps (carve, then plan, program and viewer per setup: the total
grows once carve has said how many setups); the second is the step under way, with the
words of its own progress (the carve's and the planner's stages) and its time.  Each step
that ends leaves a line (``plan setup 1: PASS (41.2 s)``).
"""

from __future__ import annotations

import time
from typing import Any

from .steps import Step

__all__ = ["MakeBars"]


class MakeBars:
    """Progress of a make run on ``console`` (a rich Console).

    Call it with every :class:`~.steps.Step`; use as a context manager (the bars stop on
    leaving)."""

    def __init__(self, console: Any = None) -> None:
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            SpinnerColumn,
            TextColumn,
            TimeElapsedColumn,
        )

        self.progress = Progress(SpinnerColumn(), TextColumn("{task.description:<18}"),
                                 BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                                 TextColumn("{task.fields[text]}"), console=console,
                                 transient=True)  # fmt: skip
        self.steps = self.progress.add_task("make", total=1, text="")
        self.step = self.progress.add_task("", total=None, text="", visible=False)
        self._started = time.perf_counter()

    def __enter__(self) -> MakeBars:
        self.progress.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.progress.stop()

    def __call__(self, s: Step) -> None:
        from rich.text import Text

        self.progress.update(self.steps, total=s.total, completed=s.index - (not s.done),
                             text=f"step {s.index} of {s.total}")  # fmt: skip
        if s.done:
            took = time.perf_counter() - self._started
            style = {"PASS": "green", "FAIL": "bold red", "refused": "bold red",
                     "none": "yellow"}.get(s.message, "")  # fmt: skip
            self.progress.console.print(Text(f"{s.name}: {s.message or 'done'}", style=style)
                                        + Text(f"  ({took:.1f} s)", style="dim"))  # fmt: skip
            self.progress.update(self.step, visible=False)
            return
        if not s.message:  # a new step
            self._started = time.perf_counter()
            self.progress.reset(self.step, total=None, description=s.name, text="",
                                visible=True)  # fmt: skip
        else:
            self.progress.update(self.step, text=s.message)
