"""The steps of a make run as it reports them: carve, then per setup plan, program, viewer.

:class:`Step` is what :func:`ruledrobot.make.make` hands its ``progress`` callback at the
start of each step, at each message of the step's own progress (the carve's and the
planner's words), and at its end; :class:`StepCounter` numbers the steps as they come (the
number of setups, hence of steps, is known once carve is done).  The command line shows
them as progress bars (:mod:`.progress`); the package itself prints nothing.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

__all__ = ["STEPS_PER_SETUP", "Step", "StepCounter"]

#: plan, program, viewer
STEPS_PER_SETUP = 3


@dataclass(frozen=True)
class Step:
    """One report of progress.

    Step ``index`` (1-based) of ``total`` known so far, its ``name`` (``carve``, ``plan setup
    1``, ...), the current ``message`` within it, whether it is ``done``, and the seconds since
    the run started (``elapsed_s``)."""

    index: int
    total: int
    name: str
    message: str = ""
    done: bool = False
    elapsed_s: float = 0.0


class StepCounter:
    """Numbers the steps of a run and forwards them to ``progress`` (or nowhere)."""

    def __init__(self, progress: Callable[[Step], None] | None, total: int) -> None:
        self._progress = progress or (lambda step: None)
        self.total = total
        self.index = 0
        self.name = ""
        self._t0 = time.perf_counter()

    def _say(self, message: str, done: bool = False) -> None:
        self._progress(Step(self.index, self.total, self.name, message, done,
                            time.perf_counter() - self._t0))  # fmt: skip

    def start(self, name: str) -> Callable[[str], None]:
        """Begin the next step; returns the callback for its messages."""
        self.index += 1
        self.total = max(self.total, self.index)
        self.name = name
        self._say("")
        return self._say

    def done(self, message: str = "") -> None:
        """End the current step."""
        self._say(message, done=True)
