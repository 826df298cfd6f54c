"""Cuts chosen with the robot: the planner's own reach and clearance model on carve's cuts.

:class:`RobotCheck` writes one cut as the job carve would write (the cell's ``[stock]``,
``[robot]``, ``[tool]`` and ``[cut]`` tables, :func:`.jobs.toml_text`) into a scratch
folder, loads it as the planner does and runs the planner's first stage on it
(:func:`ruledrobot.wirecut.cut_reasons`: the refinement, the kerf, the wire-pose search —
reach, IK continuity with the joint steps between rulings, singularity, the clearance of
arm, bow and wire against block, table and arm).  carve asks it of every exact cut and of
each roughing loop before choosing it (:func:`.plan_cuts.find_cuts`): a cut the arm cannot
make where the block stands is never written; a face that loses its exact cut is roughed
and named with why.  The feed (the time law) is judged by the plan only.
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Any

from ..io.atomic import atomic_write_text
from ..io.lines import save_lines
from .jobs import toml_text
from .model import CarveCut

__all__ = ["MAX_CHECKS", "RobotCheck"]

#: most cuts one carve checks (each takes the planner's wire-pose search, seconds): past
#: it the loops are chosen by geometry alone, and carve.json says so
MAX_CHECKS = 24


class RobotCheck:
    """The planner's wire-pose search on one cut at a time, in the cell of ``tables``.

    ``check(cut)``: "" when the planner's wire-pose search finds a motion for every pass
    of ``cut`` in the cell of ``tables`` (the cell file's job tables), else why (module
    doc).  ``calls``: the cuts checked; ``seconds``: their time; ``unchecked``: the cuts let
    through unchecked once :data:`MAX_CHECKS` were checked."""

    def __init__(self, tables: dict[str, Any]) -> None:
        self.tables = tables
        self._dir = tempfile.TemporaryDirectory(prefix="ruledrobot-carve-check-")
        self._model = None
        self.calls = 0
        self.unchecked = 0
        self.seconds = 0.0

    @property
    def exhausted(self) -> bool:
        """Whether :data:`MAX_CHECKS` cuts were checked."""
        return self.calls >= MAX_CHECKS

    def __call__(self, cut: CarveCut) -> str:
        import time

        from ..wirecut import cut_reasons, load_job

        if self.exhausted:
            self.unchecked += 1
            return ""
        t = time.perf_counter()
        self.calls += 1
        folder = Path(self._dir.name)
        lines = f"check{self.calls}.json"
        save_lines(folder / lines, cut.lines, closed=cut.closed)
        job = load_job(atomic_write_text(folder / f"check{self.calls}.toml",
                                         toml_text(self.tables, [(cut, lines)], cut.name)))
        if self._model is None:
            self._model = job.robot_model()
        why = cut_reasons(job, self._model).get(cut.name, "")
        self.seconds += time.perf_counter() - t
        return why

    def close(self) -> None:
        """Remove the scratch folder."""
        self._dir.cleanup()
