"""A setup's robot program: ``cut.script``, as ``ruledrobot export`` writes it.

A **movep** path program first: a few hundred UR moves (the demo's 193), the size a
pendant loads safely, its motion generated at the control period and measured against the
plan (feed, wire) before it is written (docs/rtde.md, "Path programs").  When that program
is refused (it would not cut as planned), the plan's own samples as a **servoj** program,
if it is within the safe size (20,000 motion lines, 2 MB); else no program, with both
reasons.  The ``program`` check is information, not a gate: a setup whose plan passes can
be made without a pendant program, by streaming its trajectory (``ruledrobot run
setupN/trajectory.csv``, the route docs/rtde.md recommends for long cuts), and the summary
says so.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..robot.motion.trajectory import Trajectory
from ..robot.verdict import Check

__all__ = ["PROGRAM", "ProgramOutcome", "no_program", "program_check", "write_program"]

#: the program's file name in a setup's folder (an export name: ``cut.*``)
PROGRAM = "cut.script"


@dataclass(frozen=True)
class ProgramOutcome:
    """The program written, its mode, what it holds in words and the ``program`` check.

    ``path`` (None when none could be written), ``mode``, ``what`` (the verification's
    figures, or why none was written) and the ``program`` check (information).
    """

    path: Path | None
    mode: str
    what: str
    check: Check


def _verified(path: Path) -> str:
    for line in path.read_text(encoding="utf-8").splitlines()[:12]:
        if line.strip().startswith("# verified"):
            return line.strip()[2:]
    return ""


def program_check(value: str, detail: str = "") -> Check:
    """The ``program`` check (information): the mode written, or ``none`` and why."""
    return Check.info("program", "pendant program (movep verified against the plan, else "
                      "servoj; none: stream the trajectory)", value, detail=detail)  # fmt: skip


def no_program(why: str) -> ProgramOutcome:
    """No program, and why."""
    return ProgramOutcome(None, "", why, program_check("none", why))


def write_program(trajectory: Trajectory, folder: Path) -> ProgramOutcome:
    """Write ``folder/cut.script`` for ``trajectory`` (module doc)."""
    from ..export import export_trajectory

    target = folder / PROGRAM
    try:
        path = export_trajectory(trajectory, target, mode="movep")
        return ProgramOutcome(path, "movep", _verified(path), program_check("movep"))
    except ValueError as exc:  # ProgramRefused, or a trajectory beyond a limit
        movep_why = str(exc)
    try:
        path = export_trajectory(trajectory, target, mode="servoj")
    except ValueError as exc:
        return no_program(f"movep: {movep_why}; servoj: {exc}")
    what = (f"servoj, the plan's {trajectory.n:,} samples (the movep program was refused: "
            f"{movep_why})")  # fmt: skip
    return ProgramOutcome(path, "servoj", what, program_check("servoj"))
