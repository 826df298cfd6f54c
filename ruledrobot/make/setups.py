"""The setups carve wrote, and what the operator does by hand before each.

carve writes one ``job.toml`` (one setup) or ``setupN/job.toml`` (several: the open cuts
and the first closed loop, then one loop each; docs/carve.md, "Order and setups").  Every
setup plans on the same block where the cell puts it: carve never turns the block.  A
loop that keeps its inside frees the part, so between setups the operator puts the freed
piece back in its place in the block, its offcuts taped round it, and the next loop cuts
the block whole again.  :func:`hand_steps` says this per setup, with the block's place in
millimetres in the robot base frame.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..carve import CarveResult, Cell

__all__ = ["Setup", "hand_steps", "setups_of"]


@dataclass(frozen=True)
class Setup:
    """Setup ``number`` (1-based): its job file, its cuts in order and their kinds.

    The job file as carve wrote it (``job``), the names of its cuts in order, and each cut's
    kind (``exact`` / ``rough``) and closedness.
    """

    number: int
    job: Path
    cuts: tuple[str, ...]
    kinds: tuple[str, ...]
    closed: tuple[bool, ...]

    @property
    def folder_name(self) -> str:
        """The setup's folder in the make folder (``setup1``, ...)."""
        return f"setup{self.number}"


def setups_of(carved: CarveResult) -> list[Setup]:
    """The setups of a carve, in order (none when carve made no cut)."""
    numbered = {int(k[3:] or 1): p for k, p in carved.files.items()
                if k == "job" or (k.startswith("job") and k[3:].isdigit())}  # fmt: skip
    jobs = [numbered[k] for k in sorted(numbered)]
    cuts = carved.report["cuts"]
    out = []
    for k, job in enumerate(jobs, start=1):
        mine = [c for c in cuts if c.get("setup") == k]
        out.append(Setup(k, job, tuple(c["name"] for c in mine), tuple(c["kind"] for c in mine),
                         tuple(bool(c["closed"]) for c in mine)))  # fmt: skip
    return out


def _mm(v: Any) -> str:
    return "(" + ", ".join(f"{1e3 * float(x):.0f}" for x in v) + ") mm"


def block_place(cell: Cell) -> str:
    """Where the block goes, in words: its size, its centre and its turn (base frame)."""
    box = cell.stock
    size = " x ".join(f"{1e3 * float(x):.0f}" for x in box.size)
    rotvec = cell.tables.get("stock", {}).get("rotvec", [0.0, 0.0, 0.0])
    if np.allclose(box.rotation, np.eye(3), atol=1e-9):
        turn = "its edges along the robot's x, y and z axes"
    else:
        turn = ("turned by the rotation vector [" + ", ".join(f"{float(x):g}" for x in rotvec)
                + "] rad of [stock] rotvec")  # fmt: skip
    return (f"the {size} mm block with its centre at {_mm(box.centre)} in the robot base frame, "
            f"{turn}")  # fmt: skip


def _cuts(setup: Setup) -> str:
    named = ", ".join(f"{n} ({k}{', closed' if c else ''})"
                      for n, k, c in zip(setup.cuts, setup.kinds, setup.closed, strict=True))
    return f"cut{'s' if len(setup.cuts) != 1 else ''}: {named}"


def _run(setup: Setup, program: str | None) -> str:
    if program:
        return f"Run {setup.folder_name}/{program} ({_cuts(setup)})."
    return (f"Stream {setup.folder_name}/trajectory.csv (ruledrobot run "
            f"{setup.folder_name}/trajectory.csv --host ROBOT; no pendant program, make.json "
            f"says why) ({_cuts(setup)}).")  # fmt: skip


def hand_steps(setups: list[Setup], cell: Cell, programs: dict[int, str | None] | None = None,
               blocked: str = "") -> list[str]:  # fmt: skip
    """What the operator does before each setup (one paragraph per setup).

    ``programs``: each setup's program file name, None when it has none (default
    ``cut.script``); ``blocked``: why there is nothing to run (a failed make), said instead."""
    out = []
    for s in setups:
        run = (f"Nothing to run: {blocked} ({_cuts(s)})." if blocked
               else _run(s, (programs or {}).get(s.number, "cut.script")))  # fmt: skip
        if s.number == 1:
            out.append(f"Setup 1: clamp {block_place(cell)}. {run}")
            continue
        prev = setups[s.number - 2]
        loop = next((n for n, c in zip(reversed(prev.cuts), reversed(prev.closed), strict=True)
                     if c), prev.cuts[-1])  # fmt: skip
        out.append(f"Setup {s.number}: leave the block clamped where it is, not turned (every "
                   f"setup cuts the same block in the same place). Take out the piece that "
                   f"setup {prev.number}'s loop {loop} freed and put it back in its place in "
                   "the block, its offcuts taped round it, so that the block is whole again. "
                   f"{run}")  # fmt: skip
    return out
