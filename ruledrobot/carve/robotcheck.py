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

**The next best** (:func:`next_best`)

When the robot check refuses a face's exact cut, carve asks it again
of the same cut with the block — and the part in it — turned a quarter turn about one of
the block's own horizontal axes through its centre (:data:`TURNS`), and names the first
turn under which the arm can make the face, with the ``[stock] rotvec`` and ``[part]
pose`` to write in the cell (:func:`next_best`).  One face is probed per carve, the
largest refused, when the arm can make some other cut of the part (else the block as a
whole is misplaced: ``ruledrobot place``); each turn is one more check of the robot, within
its :data:`MAX_CHECKS`.  The turn is an offer: the other faces are judged again
when the user makes the part turned.  Cells with a ``[robot] base`` are not probed (the
block's frame is then not the robot's).
"""

from __future__ import annotations

import dataclasses
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..geometry import se3
from ..geometry.box import Box
from ..geometry.checks import FloatArray
from ..io.atomic import atomic_write_text
from ..io.lines import save_lines
from .jobs import toml_text
from .model import CarveCut

__all__ = ["MAX_CHECKS", "TURNS", "TURN_SECONDS", "RobotCheck", "Turn", "next_best",
           "quarter_turns"]

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

    def __call__(self, cut: CarveCut, stock: dict[str, Any] | None = None) -> str:
        """Why the arm cannot make ``cut`` ("" when it can); ``stock``: another ``[stock]``
        table for this check (the block turned, :func:`next_best`)."""
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
        tables = self.tables if stock is None else {**self.tables, "stock": stock}
        job = load_job(atomic_write_text(folder / f"check{self.calls}.toml",
                                         toml_text(tables, [(cut, lines)], cut.name)))
        if self._model is None:
            self._model = job.robot_model()
        why = cut_reasons(job, self._model).get(cut.name, "")
        self.seconds += time.perf_counter() - t
        return why

    def close(self) -> None:
        """Remove the scratch folder."""
        self._dir.cleanup()


#: the turns tried, in order: (the block's own axis: 0 x, 1 y; degrees)
TURNS = ((0, 90.0), (0, -90.0), (1, 90.0), (1, -90.0))
#: time [s] past which no further turn is tried (a refused cut's search takes up to a
#: minute on a busy 2-core machine; a passing one seconds)
TURN_SECONDS = 30.0


@dataclass(frozen=True)
class Turn:
    """A quarter turn of the block and the part about the block's centre.

    ``T`` (4, 4) the motion in the robot base frame; ``stock`` the block turned; ``part_pose``
    (4, 4) the part's frame after it (base frame, m)."""

    axis: int
    degrees: float
    T: FloatArray
    stock: Box
    part_pose: FloatArray

    def words(self) -> str:
        """The turn and the cell's fields that make it, in words."""
        rv = se3.rotvec_from_matrix(self.stock.rotation)
        pose = se3.ur_vector_from_pose(self.part_pose)
        num = lambda v: "[" + ", ".join(f"{x:.6g}" for x in np.asarray(v) + 0.0) + "]"  # noqa: E731
        return (f"with the block turned {self.degrees:+g}° about its {'xy'[self.axis]} axis "
                f"the arm can make it: in the cell write [stock] rotvec = {num(rv)} and [part] "
                f"pose = {num(pose)}, and make again")  # fmt: skip


def quarter_turns(stock: Box, part_pose: FloatArray) -> list[Turn]:
    """The turns of :data:`TURNS` of ``stock`` with the part at ``part_pose`` (4, 4)."""
    out = []
    for axis, deg in TURNS:
        R = se3.rotation_about_axis(stock.rotation[:, axis], np.radians(deg))
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = R, stock.centre - R @ stock.centre
        out.append(Turn(axis, deg, T, stock.moved(T), T @ part_pose))
    return out


def _turned(cut: CarveCut, T: FloatArray) -> CarveCut:
    """``cut`` carried by the motion ``T`` (4, 4): its rulings and its kept point."""
    keep = cut.keep if isinstance(cut.keep, str) else T[:3, :3] @ cut.keep + T[:3, 3]
    return dataclasses.replace(cut, lines=cut.lines.transform(T), keep=keep)


def next_best(check: RobotCheck, cut: CarveCut, stock: Box, part_pose: FloatArray,
              tables: dict[str, Any]) -> str:  # fmt: skip
    """The first quarter turn under which the arm can make ``cut``, in words (module doc).

    Else the turns tried, in words; "" when none was tried (the cell has a ``[robot] base``,
    or the check's budget is spent).  Turns stop after :data:`TURN_SECONDS`."""
    import time

    base = tables.get("robot", {}).get("base")
    if base is not None and np.any(np.asarray(base, dtype=float) != 0.0):
        return ""
    t0, tried = time.perf_counter(), []
    for turn in quarter_turns(stock, part_pose):
        if check.exhausted or time.perf_counter() - t0 > TURN_SECONDS:
            break
        rv = se3.rotvec_from_matrix(turn.stock.rotation)
        table = {**tables.get("stock", {}), "rotvec": [float(x) for x in rv]}
        if not check(_turned(cut, turn.T), stock=table):
            return turn.words()
        tried.append(f"{turn.degrees:+g}° about {'xy'[turn.axis]}")
    if not tried:
        return ""
    return (f"the block turned {', '.join(tried)} does not let the arm make it either"
            + ("" if len(tried) == len(TURNS) else
               f" (the other turns not tried: {TURN_SECONDS:g} s spent)"))  # fmt: skip
