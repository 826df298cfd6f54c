"""The cell file of ``ruledrobot carve``: the part, and the block, robot, tool and cut defaults.

A cell file is a job file (docs/wirecut.md) with a ``[part]`` table instead of cuts::

    [part]
    file = "column.stl"          # STL (ASCII or binary), OBJ, PLY or 3DM; relative paths
                                 # are taken from the cell file's folder
    units = "mm"                 # the file's length unit: m, cm, mm, in (a 3DM says its own)
    pose = [0.5, 0.0, 0.3, 0.0, 0.0, 0.0]   # the part's frame in the robot base frame
                                 # (UR pose vector: metres, rotation vector in radians)
    tolerance = 0.0005           # m: how far an exact cut may lie from the part's surface
    rough_cuts = 4               # roughing loops where the surface is not ruled (0: none)
    repair = false               # true: merge vertices within tolerance / 100 and turn
                                 # facets to agree with their neighbours (noted)
    turns = true                 # a face the arm cannot make: try the block turned a
                                 # quarter turn and offer the turn that lets it (up to a
                                 # minute more; false: only name the face)

    [stock]   ...                # as in a job: the block
    [robot]   ...
    [tool]    ...
    [cut]     ...                # feed, kerf, leads: the defaults of every cut made

Every field is checked; errors name the file, the table and the field, as the job
parser's do (``cell.toml: [part] units: unknown length unit 'ft'; expected one of m,
cm, mm, in``).  The ``[stock]``, ``[robot]``, ``[tool]`` and ``[cut]`` tables are checked
by the job parser itself (:func:`ruledrobot.wirecut.parse_job`) on a job made of them.
"""

from __future__ import annotations

import copy
import os
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..geometry import se3
from ..geometry.box import Box
from ..geometry.checks import FloatArray
from ..io.paths import input_path, missing_file
from ..io.text import read_user_text
from ..io.units import unit_name, unit_scale

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["MESH_SUFFIXES", "Cell", "PartSpec", "load_cell", "parse_cell"]

#: the part files read (:mod:`.readers`)
MESH_SUFFIXES = (".stl", ".obj", ".ply", ".3dm")
_PART_FIELDS = ("file", "units", "pose", "tolerance", "rough_cuts", "repair", "turns")
_SECTIONS = ("part", "stock", "robot", "tool", "cut")


@dataclass(frozen=True)
class PartSpec:
    """The ``[part]`` table.

    ``file`` (resolved), ``units`` (m, cm, mm, in), ``pose`` (4, 4) the part frame in the robot
    base frame, ``tolerance`` [m], ``rough_cuts``, ``repair`` (mend the mesh as CAD exported
    it: :mod:`.repair`), ``turns`` (offer a turn of the block for a face the arm cannot
    make: :func:`.robotcheck.next_best`)."""

    file: Path
    units: str
    pose: FloatArray = field(repr=False)
    tolerance: float = 0.0005
    rough_cuts: int = 4
    repair: bool = False
    turns: bool = True

    @property
    def scale(self) -> float:
        """Metres per unit of the part file."""
        return unit_scale(self.units, "units")


@dataclass(frozen=True)
class Cell:
    """A parsed cell file.

    The part, the block (:class:`~ruledrobot.geometry.box.Box`, base frame), and the job tables
    as the user wrote them (``tables``: ``stock``, ``robot``, ``tool``, ``cut``; checked), for
    the jobs carve writes. ``source``: the cell file."""

    part: PartSpec
    stock: Box
    tables: dict[str, Any] = field(repr=False)
    source: Path | None = None
    where: str = "cell"


def _fail(where: str, key: str, msg: str) -> ValueError:
    return ValueError(f"{where}: [part] {key}: {msg}")


def _number(raw: dict, key: str, where: str, default: float, lo: float) -> float:
    v = raw.get(key, default)
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v):
        raise _fail(where, key, f"expected a finite number, got {v!r}")
    if v <= lo:
        raise _fail(where, key, f"expected a number > {lo:g}, got {v!r}")
    return float(v)


def _part(raw: object, where: str, base_dir: Path | None) -> PartSpec:
    if raw is None:
        raise ValueError(f"{where}: missing section [part] (the part to carve: file, units, "
                         "pose, tolerance)")  # fmt: skip
    if not isinstance(raw, dict):
        raise ValueError(f"{where}: [part] must be a table")
    extra = sorted(set(raw) - set(_PART_FIELDS))
    if extra:
        raise ValueError(f"{where}: [part] unknown field(s) {', '.join(extra)}; expected some "
                         f"of {', '.join(_PART_FIELDS)}")  # fmt: skip
    name = raw.get("file")
    if not isinstance(name, str) or not name.strip():
        raise _fail(where, "file", f"expected a path string, got {name!r}")
    path = input_path(name, base_dir)
    if path.suffix.lower() not in MESH_SUFFIXES:
        got = path.suffix or "no suffix"
        raise _fail(where, "file", f"{path}: expected a mesh or model file "
                    f"({', '.join(MESH_SUFFIXES)}), got {got!r}")  # fmt: skip
    missing = missing_file(path, "part file")
    if missing:
        raise _fail(where, "file", missing)
    if "units" not in raw and path.suffix.lower() != ".3dm":
        raise _fail(where, "units", "missing; expected the file's length unit: m, cm, mm or in "
                    "(a mesh file does not say its own)")  # fmt: skip
    try:
        units = unit_name(raw.get("units", "mm"), f"{where}: [part] units")
    except ValueError as exc:
        raise ValueError(str(exc)) from None
    pose_raw = raw.get("pose", [0.0] * 6)
    if (not isinstance(pose_raw, list) or len(pose_raw) != 6
            or any(isinstance(x, bool) or not isinstance(x, (int, float)) for x in pose_raw)
            or not np.all(np.isfinite(pose_raw))):  # fmt: skip
        raise _fail(where, "pose", "expected [x, y, z, rx, ry, rz] (m, rotation vector in rad), "
                    f"got {pose_raw!r}")  # fmt: skip
    rough = raw.get("rough_cuts", 4)
    if isinstance(rough, bool) or not isinstance(rough, int) or not 0 <= rough <= 12:
        raise _fail(where, "rough_cuts",
                    f"expected an integer 0 <= rough_cuts <= 12, got {rough!r}")  # fmt: skip
    flags = {key: raw.get(key, default) for key, default in (("repair", False), ("turns", True))}
    for key, v in flags.items():
        if not isinstance(v, bool):
            raise _fail(where, key, f"expected true or false, got {v!r}")
    return PartSpec(file=path, units=units, pose=se3.pose_from_ur_vector(pose_raw),
                    tolerance=_number(raw, "tolerance", where, 0.0005, 0.0),
                    rough_cuts=int(rough), **flags)  # fmt: skip


def absolute_paths(tables: dict[str, Any], base_dir: Path | None) -> dict[str, Any]:
    """Return the job tables with the files they name made absolute.

    The files named by ``[robot] calibration``, so that a job written in another folder
    names the same files.
    """
    out = copy.deepcopy(tables)
    robot = out.get("robot")
    if isinstance(robot, dict) and isinstance(robot.get("calibration"), str):
        robot["calibration"] = str(input_path(robot["calibration"], base_dir))
    return out


def parse_cell(doc: dict, where: str = "cell", base_dir: Path | None = None) -> Cell:
    """Check a cell file's document (see the module doc).

    ValueError naming the file, the table and the field."""
    from ..wirecut import parse_job

    extra = sorted(set(doc) - set(_SECTIONS))
    if extra:
        raise ValueError(f"{where}: unknown section(s) {', '.join(extra)}; expected "
                         f"{', '.join(_SECTIONS)} (a cell names its part, not its "
                         "cuts)")  # fmt: skip
    if isinstance(doc.get("cut"), list):
        raise ValueError(f"{where}: [[cut]]: a cell file has one [cut] table (the defaults of "
                         "every cut carve makes), not a list of cuts")  # fmt: skip
    cut = doc.get("cut", {})
    if isinstance(cut, dict) and "keep" in cut:
        raise ValueError(f"{where}: [cut] keep: carve decides each cut's kept side; leave it out")
    part = _part(doc.get("part"), where, base_dir)
    tables = {k: doc[k] for k in ("stock", "robot", "tool", "cut") if k in doc}
    # the job parser checks the tables (a stand-in surface: carve writes the real ones)
    probe = {**copy.deepcopy(tables), "surface": {"builtin": "hyperbolic_paraboloid"}}
    job = parse_job(probe, where, base_dir)
    return Cell(part=part, stock=job.stock, tables=absolute_paths(tables, base_dir),
                where=where)  # fmt: skip


def load_cell(path: str | os.PathLike[str]) -> Cell:
    """Read and check a cell file (TOML); ValueError names the file, table and field."""
    p, text = read_user_text(path, "cell file")
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{p}: not valid TOML ({exc})") from None
    cell = parse_cell(doc, str(p), base_dir=p.parent)
    return Cell(cell.part, cell.stock, cell.tables, source=p, where=str(p))
