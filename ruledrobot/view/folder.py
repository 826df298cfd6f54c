"""Reading a plan folder (what ``ruledrobot plan JOB --out DIR`` writes) for the viewer.

:func:`read_plan_folder` gathers what the viewer shows and nothing it would
have to compute by planning again:

* ``report.json`` (required: it is what makes a folder a plan folder) — the
  verdict, its checks, collisions and reasons;
* ``job.toml`` (required) — the cell: robot, base, bow, stock;
* ``trajectory.csv`` + ``trajectory.json`` — the motion (absent when the plan
  fails: the viewer then shows the cell without motion and says why);
* ``refined.json`` — the refined rulings; ``surface*.stl`` — the cut surface
  inside the stock; ``part.stl`` / ``removed.stl`` when a plan writes them
  (multi-cut parts);
* ``simulation/report.json`` — the MuJoCo playback report (collisions).

Errors: :class:`NotAPlanFolder` (a ValueError) names the folder and what is
missing; a damaged file raises ValueError naming the file and field.
"""

from __future__ import annotations

import os
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..geometry.lines import Lines
from ..geometry.mesh import Mesh
from ..io.lines import read_lines_document
from ..io.mesh import read_stl
from ..io.outdir import read_manifest
from ..io.paths import input_path
from ..io.text import json_object, read_user_text
from ..robot.motion.trajectory import Trajectory
from ..robot.verdict import Check

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["REPORT_FORMAT", "NotAPlanFolder", "PlanFolder", "read_plan_folder"]

#: ``format`` of a plan's ``report.json``.
REPORT_FORMAT = "ruledrobot.plan-report/1"


class NotAPlanFolder(ValueError):
    """The path is not a folder written by ``ruledrobot plan`` (the message says why)."""


@dataclass(frozen=True, eq=False)
class PlanFolder:
    """The files of a plan folder, read and checked (see the module doc).

    ``job`` is a :class:`ruledrobot.wirecut.job.load.Job`; ``trajectory`` the planned
    motion or None; ``rulings`` the refined rulings (``Lines``, robot base frame)
    or None; ``meshes`` name -> :class:`~ruledrobot.geometry.mesh.Mesh` (m, robot
    base frame) of ``surface*``, ``part``, ``removed``; ``simulation`` the
    playback report or None; ``notes`` what the reader had to work around.
    """

    path: Path
    report: dict[str, Any] = field(repr=False)
    job: Any = field(repr=False)
    trajectory: Trajectory | None = field(default=None, repr=False)
    rulings: Lines | None = field(default=None, repr=False)
    meshes: dict[str, Mesh] = field(default_factory=dict, repr=False)
    simulation: dict[str, Any] | None = field(default=None, repr=False)
    manifest: dict[str, Any] | None = field(default=None, repr=False)
    notes: tuple[str, ...] = ()

    @property
    def feasible(self) -> bool:
        """The plan's verdict holds (``report["feasible"]``)."""
        return bool(self.report.get("feasible", False))

    @property
    def checks(self) -> tuple[Check, ...]:
        """The verdict's table of checks, as the planner wrote it."""
        verdict = self.report.get("verdict") or {}
        return tuple(Check(**c) for c in verdict.get("checks", ()))

    @property
    def summary(self) -> str:
        """``"PASS — all 12 checks hold"`` / ``"FAIL — ..."``."""
        verdict = self.report.get("verdict") or {}
        word = "PASS" if verdict.get("ok") else "FAIL"
        return f"{word} — {verdict.get('summary', 'no verdict in report.json')}"


def _json(path: Path, kind: str) -> dict[str, Any]:
    p, text = read_user_text(path, kind)
    return json_object(text, str(p))


def _job(folder: Path, report: dict[str, Any], notes: list[str]) -> Any:
    """The job of the plan, from the folder's ``job.toml``.

    Relative paths in the job (a lines file, a calibration) are resolved next to
    the job file the plan was made from (``report["job"]["path"]``) when it still
    exists, else in the folder.  The viewer does not refine, so a lines file that
    cannot be found any more is replaced by the plan's own ``refined.json`` (noted).
    """
    from ..wirecut.job.load import file_fields, parse_job

    p, text = read_user_text(folder / "job.toml", "job file")
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{p}: not valid TOML ({exc})") from None
    origin = (report.get("job") or {}).get("path")
    base_dir = Path(origin).parent if origin and Path(origin).parent.is_dir() else folder
    surface = doc.get("surface")
    for loc, named in file_fields(doc):  # the surface's file of any format (issue 22)
        if loc[0] != "surface" or not isinstance(surface, dict):
            continue
        lines_file = input_path(named, base_dir)
        if not lines_file.exists() and (folder / "refined.json").exists():
            surface.pop(loc[1], None)  # the one source of the surface: file, gcode, ...
            surface["file"] = str(folder / "refined.json")
            notes.append(f"the job's {loc[1] if loc[1] != 'file' else 'lines'} file "
                         f"{lines_file} is not found; not needed to view")  # fmt: skip
            break
    robot = doc.get("robot")
    if isinstance(robot, dict) and isinstance(robot.get("calibration"), str):
        cal = input_path(robot["calibration"], base_dir)
        if not cal.exists():
            del robot["calibration"]
            notes.append(f"the job's calibration {cal} is gone: the arm is drawn with the "
                         "trajectory's kinematics (nominal ones without a trajectory)")
    return parse_job(doc, str(p), base_dir=base_dir)


def read_plan_folder(folder: str | os.PathLike[str]) -> PlanFolder:
    """Read a plan folder (see the module doc); never plans anything.

    Raises :class:`NotAPlanFolder` when ``folder`` is missing, not a folder, or
    holds no plan report or job; ValueError naming the file for damaged files.
    """
    path = Path(folder)
    hint = "a plan folder is what `ruledrobot plan JOB --out DIR` writes"
    if not path.exists():
        raise NotAPlanFolder(f"{path}: no such folder ({hint})")
    if not path.is_dir():
        raise NotAPlanFolder(f"{path}: not a folder ({hint})")
    if not (path / "report.json").is_file():
        raise NotAPlanFolder(f"{path}: not a plan folder: no report.json ({hint})")
    report = _json(path / "report.json", "plan report")
    if report.get("format") != REPORT_FORMAT:
        raise NotAPlanFolder(
            f"{path / 'report.json'}: field 'format': expected {REPORT_FORMAT!r}, got "
            f"{report.get('format')!r} ({hint})"
        )
    if not (path / "job.toml").is_file():
        raise NotAPlanFolder(f"{path}: no job.toml beside report.json: the cell (robot, bow, "
                             f"stock) is unknown ({hint})")  # fmt: skip
    notes: list[str] = []
    manifest = read_manifest(path)
    if manifest is None:
        notes.append("no manifest.json: the folder may be incomplete or edited")
    job = _job(path, report, notes)

    trajectory = None
    if (path / "trajectory.csv").is_file():
        from ..io.trajectory import read_trajectory

        trajectory = read_trajectory(path / "trajectory.csv")
    rulings = None
    if (path / "refined.json").is_file():
        rulings = read_lines_document(path / "refined.json").lines
    meshes: dict[str, Mesh] = {}
    for p in [*sorted(path.glob("surface*.stl")), path / "part.stl", path / "removed.stl"]:
        if p.is_file():
            m = read_stl(p)
            meshes[p.stem] = Mesh(m.vertices, m.faces)
    simulation = None
    if (path / "simulation" / "report.json").is_file():
        simulation = _json(path / "simulation" / "report.json", "simulation report")
    return PlanFolder(path, report, job, trajectory, rulings, meshes, simulation, manifest,
                      tuple(notes))  # fmt: skip
