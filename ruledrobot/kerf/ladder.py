"""The calibration ladder: straight test cuts at several speeds and powers in the user's block.

``write_ladder(job_file, out, speeds, powers)`` keeps the job's robot, tool and block and
writes, for each power, a job of straight cuts (``DIR/powerN/job.toml``, one cut per
speed), the sheet saying what to measure (``DIR/ladder.md``, :mod:`.sheet`) and the
template of the measurements (``DIR/measured.csv``), into one staged folder.

**One job per power.** The wire's power is a property of the job's ``[tool] heat``; the job
format has no per-cut power, so each power is its own job (run them one after the other,
in the same block).  The power is set on the analog output: ``mode = "constant"`` with
``power`` and ``full_scale`` (docs/kerf.md).  A digital output only switches a supply set
by hand, so the robot cannot set the ladder's powers: refused.

**The cuts** are planes through the whole block, normal to its horizontal axis along
which it is longest (of the two the wire can span); the wire lies along the other
horizontal axis and goes down through the block, so each slot is a vertical slit whose
two sides stand where they are after the cut and can be measured with calipers at the
top.  Cuts are ``spacing`` apart (default the block's length over the number of cuts plus
one, at most :data:`SPACING_MAX`; at least :data:`SPACING_MIN`, so that kerfs of a few mm
cannot merge and the slices stand), centred in the block, power by power, each power's
speeds slowest first.  Every cut has no ``keep``: the wire runs on the plane itself.
Units: m, m/s, W/m.
"""

from __future__ import annotations

import os
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..geometry import se3
from ..geometry.lines import Lines
from ..io.atomic import atomic_write_text
from ..io.lines import save_lines
from ..io.outdir import StagedFolder
from ..io.toml_text import toml_table
from ..wirecut import load_job
from .sheet import measured_template, sheet_text

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = [
    "RULING_SPACING",
    "SPACING_MAX",
    "SPACING_MIN",
    "Ladder",
    "LadderCut",
    "write_ladder",
]  # fmt: skip

#: closest and farthest default spacing [m] of the test cuts
SPACING_MIN = 0.005
SPACING_MAX = 0.02
#: largest gap [m] between the planner's refined rulings of a test cut
RULING_SPACING = 0.005
#: input rulings of a test cut (parallel lines, top to bottom)
RULINGS = 5
#: default speeds: these fractions of the job's first feed
SPEED_FACTORS = (0.5, 0.75, 1.0, 1.5)
#: default powers: these fractions of the job's constant heat power, when it has one (the
#: spread of powers sets how well kerf_gain is known: 1.9 % standard error with these and
#: 0.02 mm scatter per slot, 4.8 % with 0.8 and 1.2; docs/kerf.md)
POWER_FACTORS = (0.6, 1.0, 1.4)
_AXES = "xyz"


@dataclass(frozen=True)
class LadderCut:
    """One test cut of a ladder.

    ``name``, its job folder ``job`` (``"power1"``), ``speed`` [m/s],
    ``power`` [W/m] and ``offset`` [m] of its plane from the block's centre along the
    spacing axis (``+`` towards the block's ``+axis`` face)."""

    name: str
    job: str
    speed: float
    power: float
    offset: float


@dataclass(frozen=True)
class Ladder:
    """What :func:`write_ladder` wrote.

    ``out`` (the folder), ``jobs`` (the job files),
    ``cuts``, ``spacing`` [m], the block's ``wire_axis`` and ``spacing_axis`` (``"x"``,
    ``"y"`` or ``"z"`` of the block's own frame), ``size`` (3,) [m] and ``heat`` (how the
    power is set, in words)."""

    out: Path
    jobs: tuple[Path, ...]
    cuts: tuple[LadderCut, ...]
    spacing: float
    wire_axis: str
    spacing_axis: str
    size: np.ndarray
    heat: str


def _axes(job: Any, where: str) -> tuple[int, int, int]:
    """(up, wire, spacing) axes of the block's frame (module doc)."""
    R, size = job.stock.rotation, job.stock.size
    up = int(np.argmax(np.abs(R[2])))
    flat = [k for k in range(3) if k != up]
    reach = job.tool.wire_length - 2.0 * job.tool.clearance
    fits = [k for k in flat if size[k] <= reach + 1e-12]
    if not fits:
        raise ValueError(f"{where}: [tool] the wire spans {reach * 1e3:.1f} mm inside its "
                         f"clearances; the block is {size[flat[0]] * 1e3:.1f} and "
                         f"{size[flat[1]] * 1e3:.1f} mm across: no straight cut goes through "
                         "it")  # fmt: skip
    wire = min(fits, key=lambda k: (size[k], k != 1))
    return up, wire, next(k for k in flat if k != wire)


def _heat(raw: dict, power: float, full_scale: float) -> dict:
    """The ``[tool] heat`` table of one power: ``mode = "constant"`` (module doc)."""
    table = {k: v for k, v in raw.items() if k in ("output", "preheat", "lag")}
    return {**table, "mode": "constant", "power": float(power), "full_scale": float(full_scale)}


def _rebased_robot(raw: dict, src: Path, out_job: Path) -> dict:
    robot = dict(raw)
    if isinstance(robot.get("calibration"), str):  # a path from the job's folder
        path = (src.parent / robot["calibration"]).resolve()
        robot["calibration"] = os.path.relpath(path, out_job.parent.resolve())
    return robot


def _has_measurements(out: Path) -> bool:
    """Whether ``out/measured.csv`` has a kerf filled in (never overwritten)."""
    from .measured import read_measured

    p = out / "measured.csv"
    if not p.is_file():
        return False
    try:
        return bool(np.any(np.isfinite(read_measured(p).kerf)))
    except ValueError as exc:  # an empty kerf_mm: the template as written
        return "kerf_mm: empty" not in str(exc)


def write_ladder(job_file: str | os.PathLike[str], out: str | os.PathLike[str],
                 speeds: Any = None, powers: Any = None, *, spacing: float | None = None,
                 full_scale: float | None = None) -> Ladder:  # fmt: skip
    """Write the ladder of ``job_file``'s cell into ``out`` (module doc).

    ``speeds`` (m/s;
    None: :data:`SPEED_FACTORS` of the first cut's feed) by ``powers`` (W/m; None:
    :data:`POWER_FACTORS` of the job's heat ``power``, when it gives one), cuts ``spacing``
    m apart (None: the default), ``full_scale`` the W/m at the analog output's 1.0 (None:
    the job's own).  ValueError names the file,
    table and field (or the option) of bad input; nothing is written then."""
    job_file = Path(job_file)
    job = load_job(job_file)
    where = str(job_file)
    heat = job.tool.heat
    if speeds is None:
        speeds = np.multiply(SPEED_FACTORS, job.cuts[0].feed_speed)
    if powers is None:
        if getattr(heat, "power", None) is None:
            raise ValueError(f"{where}: [tool] heat gives no power: give the ladder's powers "
                             "(--powers, W/m of wire)")  # fmt: skip
        powers = np.multiply(POWER_FACTORS, heat.power)
    v = np.sort(np.asarray(speeds, dtype=np.float64).ravel())
    p = np.sort(np.asarray(powers, dtype=np.float64).ravel())
    if v.size < 2 or np.unique(v).size != v.size or not np.all((v > 0) & (v <= 1.0)):
        raise ValueError(f"--speeds: expected two or more different speeds in (0, 1000] "
                         f"mm/s, got {', '.join(f'{x * 1e3:g}' for x in v)}")  # fmt: skip
    if p.size < 2 or np.unique(p).size != p.size or not np.all(np.isfinite(p) & (p > 0)):
        raise ValueError(f"--powers: expected two or more different powers > 0 W/m, got "
                         f"{', '.join(f'{x:g}' for x in p)}")  # fmt: skip
    if heat is None or heat.kind != "analog":
        got = "no heat output" if heat is None else f'output = "{heat.output}"'
        raise ValueError(f'{where}: [tool] heat: the ladder sets each power on an analog '
                         f'output (output = "analog:0", UR\'s standard analog output 0, '
                         f"driving the wire's supply), got {got}: a digital output only "
                         "switches a supply whose power the robot cannot set")  # fmt: skip
    full_scale = full_scale if full_scale is not None else getattr(heat, "full_scale", None)
    if full_scale is None or not np.isfinite(full_scale) or full_scale <= 0:
        raise ValueError(f"{where}: [tool] heat: give full_scale, the W/m of wire at the "
                         "analog output's 1.0 (--full-scale)")  # fmt: skip
    if p[-1] > full_scale:
        raise ValueError(f"--powers: {p[-1]:g} W/m is above the supply's full scale "
                         f"{full_scale:g} W/m")  # fmt: skip
    up, wire, across = _axes(job, where)
    size = job.stock.size
    n = v.size * p.size
    if spacing is None:
        spacing = float(np.clip(np.floor(size[across] / (n + 1) * 1e3) * 1e-3, SPACING_MIN,
                                SPACING_MAX))  # fmt: skip
    if spacing < SPACING_MIN:
        raise ValueError(f"--spacing: {spacing * 1e3:g} mm; expected at least "
                         f"{SPACING_MIN * 1e3:g} mm, so that kerfs do not merge and the "
                         "slices stand")  # fmt: skip
    if (n + 1) * spacing > size[across] + 1e-12:
        raise ValueError(f"{where}: [stock] size: {n} cuts {spacing * 1e3:g} mm apart need "
                         f"{(n + 1) * spacing * 1e3:g} mm along the block's {_AXES[across]}; "
                         f"it is {size[across] * 1e3:g} mm: fewer speeds or powers, a "
                         "smaller --spacing or a longer block")  # fmt: skip
    offsets = (np.arange(n) - 0.5 * (n - 1)) * spacing
    cuts = tuple(LadderCut(f"cut{k + 1}_{v[k % v.size] * 1e3:g}mm_s", f"power{k // v.size + 1}",
                           float(v[k % v.size]), float(p[k // v.size]), float(offsets[k]))
                 for k in range(n))  # fmt: skip
    R, c = job.stock.rotation, job.stock.centre
    e_up = R[:, up] * np.sign(R[2, up])
    doc = tomllib.loads(job_file.read_text(encoding="utf-8"))
    first = job.cuts[0]
    fields = {k: getattr(first, k) for k in ("lead_in", "lead_out", "approach_speed",
                                             "wire_tolerance", "feed_tolerance")}  # fmt: skip
    stock = {"centre": c, "size": size, "rotvec": se3.rotvec_from_matrix(R)}
    heat_words = (f'output = "{heat.output}", mode = "constant", power W/m, '
                  f"full_scale = {full_scale:g} W/m")
    jobs = []
    if _has_measurements(Path(out)):  # before the folder's own check: say what matters
        raise ValueError(f"{Path(out) / 'measured.csv'} holds measurements: copy it "
                         "elsewhere, or write the ladder into another folder")  # fmt: skip
    staged = StagedFolder(out)
    with staged:
        for i, power in enumerate(p):
            folder = staged.path / f"power{i + 1}"
            tool = {k: val for k, val in doc["tool"].items() if k != "heat"}
            tool["heat"] = _heat(doc["tool"]["heat"], power, full_scale)
            text = [f"# kerf ladder, power {i + 1} of {p.size}: {power:g} W/m, "
                    f"{v.size} straight cuts (written by ruledrobot kerf ladder from "
                    f"{job_file.name}; see ../ladder.md)", ""]  # fmt: skip
            text += toml_table("stock", stock)
            text += toml_table("robot", _rebased_robot(doc.get("robot", {}), job_file,
                                                       staged.target / f"power{i + 1}" /
                                                       "job.toml"))  # fmt: skip
            text += toml_table("tool", tool)
            for cut in cuts[i * v.size:(i + 1) * v.size]:
                base = c + cut.offset * R[:, across]
                h = 0.5 * size[up] + 0.001  # from just above the block to just below
                pts = base + np.outer(np.linspace(h, -h, RULINGS), e_up)
                lines = Lines.from_point_direction(pts, np.tile(R[:, wire], (RULINGS, 1)))
                save_lines(folder / f"{cut.name}.json", lines)
                text += toml_table("cut", {"name": cut.name, "feed_speed": cut.speed,
                                           **fields}, "[[{}]]")  # fmt: skip
                text += toml_table("cut.surface", {"file": f"{cut.name}.json",
                                                   "spacing": RULING_SPACING})  # fmt: skip
            jobs.append(atomic_write_text(folder / "job.toml", "\n".join(text)))
        ladder = Ladder(staged.target, tuple(staged.target / j.relative_to(staged.path)
                                             for j in jobs), cuts, float(spacing),
                        _AXES[wire], _AXES[across], size.copy(), heat_words)  # fmt: skip
        for j in jobs:  # the jobs read back as written: every speed, in the staged folder
            back = load_job(j)
            got = sorted(cut.feed_speed for cut in back.cuts)
            if not np.allclose(got, v):
                raise ValueError(f"{j}: the ladder job reads back with speeds {got}")
        atomic_write_text(staged.path / "ladder.md", sheet_text(ladder, job_file))
        atomic_write_text(staged.path / "measured.csv", measured_template(ladder))
        staged.commit({"command": "kerf ladder", "job": str(job_file)})
    return ladder
