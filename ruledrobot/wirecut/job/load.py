"""Cut job files (TOML): what to cut, from what, with which robot and tool.

A job holds one stock, one robot, one tool and one or more cuts.  A single cut
is written as ``[surface]`` and ``[cut]`` tables (in the robot base frame;
metres, radians, seconds)::

    [surface]                  # the ruled surface to cut
    builtin = "hyperbolic_paraboloid"   # or: file = "rulings.json" (lines file), or a file of
                               # the field: gcode = "wing.ngc", airfoil, dxf, rhino -- a path, or
                               # a table of the reader's options with the path under file
                               # (airfoil: root, tip): [surface.gcode] file = "wing.ngc"
                               # tower_distance = 0.8 (docs/formats.md)
    params = { c = 0.4 }       # parameters of the built-in surface
    u = [-0.12, 0.12]          # its parameter range
    rulings = 9                # input rulings sampled over u
    pose = [0.5, 0.0, 0.3, 0.0, 0.0, 0.0]   # surface frame in the base frame (UR pose vector)
    algorithm = "dh"           # projection | combined | dh (G-code: projection by default)
    scheme = "four_point"      # linear | chaikin | bspline3 | four_point | six_point | ...
    steps = 4                  # or: spacing = 0.002 (m, largest gap between refined rulings)
    # closed = true            # a closed sequence of rulings (a column, a band)

    [stock]                    # the block, a box
    centre = [0.5, 0.0, 0.3]
    size = [0.2, 0.2, 0.15]
    rotvec = [0.0, 0.0, 0.0]

    [robot]
    model = "ur5e"
    base = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]   # the cell in the simulation's world; plans ignore it
    speed_scale = 1.0          # fraction of the catalogue joint speed limits
    acceleration = 1.4         # rad/s^2, one value or six
    # home = [3.14, -1.57, 1.57, -1.57, -1.57, 0.0]   # optional (rad): start and end here
    # calibration = "robot.calib.json"   # the robot's own kinematics (ruledrobot calibration fetch)

    [tool]                     # the hot-wire bow, in the flange frame
    wire_start = [-0.2, 0.0, 0.25]
    wire_end = [0.2, 0.0, 0.25]
    clearance = 0.02           # wire kept this far beyond the stock at each end
    mass = 1.0
    # wire_tension = 60.0      # N (optional): with [material] drag, the wire's bow is reported
    # heat = { output = "standard:0", preheat = 2.0 }   # switch the wire's heat (robot IO)
    # heat = { output = "analog:0", mode = "constant_kerf", full_scale = 400.0, lag = 0.2 }
    #                          # the heat model (docs/kerf.md): mode = "on_off" (default) |
    #                          # "constant" (power = W/m) | "constant_kerf" (needs [material]);
    #                          # full_scale W/m at the analog output's 1.0; lag s

    # [material]               # the foam's kerf model (docs/kerf.md); without it every cut
    # kerf_base = 0.0003       # keeps its constant kerf. m: the wire's own width
    # kerf_gain = 1.5e-8       # m^2/s per W/m: w = kerf_base + kerf_gain (p - p0) / v
    # power_threshold = 20.0   # W/m: p0, what the wire loses without cutting
    # max_speed = 0.002        # (m/s) per W/m above p0: faster, the wire drags (optional)
    # drag = 2.0              # N/m per m/s: the foam's drag on the wire (optional, the bow)

    [cut]
    feed_speed = 0.01          # m/s, wire speed inside the stock
    lead_in = 0.02             # m before the first chord
    lead_out = 0.02
    approach_speed = 0.3       # fraction of joint speed limits for approach/retract/transit
    kerf = 0.0008              # m, the width of the slot the wire melts
    # keep = [0.5, 0.0, 0.2]   # a point of the part (or "inside"/"outside" for a closed
    #                          # surface): the wire runs kerf/2 off the surface, in the waste
    wire_tolerance = 0.0005    # m, largest wire deviation from the rulings (a check)
    feed_tolerance = 0.05      # fraction: feed inside the stock within +-5 % (a check)
    # extend = true            # an open surface that stops short of the block is cut on
    #                          # through it along its extrapolation (noted); default: refused
    tolerance = 0.0001         # m, the predicted cut face within this of the part (face_error)

A part with several cuts lists them in order as ``[[cut]]`` tables, each with a
``name`` and its own ``[cut.surface]`` table (the fields of ``[surface]``), and
the ``[cut]`` fields above; there is then no top-level ``[surface]``::

    [[cut]]
    name = "top"
    keep = [0.5, 0.0, 0.2]
    [cut.surface]
    builtin = "hyperbolic_paraboloid"
    ...

:func:`load_job` validates every field and raises ValueError naming the file,
the section and the field.
"""

from __future__ import annotations

import dataclasses
import os
import sys
from pathlib import Path

import numpy as np

from ...io.text import read_user_bytes, user_text
from .sections import (
    FOREIGN_KINDS,
    Section,
    parse_heat,
    parse_material,
    parse_robot,
    parse_stock,
    parse_surface,
)
from .spec import CutSpec, HeatSpec, Job, RobotSpec, SurfaceSpec, ToolSpec

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = [
    "CutSpec",
    "HeatSpec",
    "Job",
    "RobotSpec",
    "SurfaceSpec",
    "ToolSpec",
    "file_fields",
    "job_document",
    "load_job",
    "parse_job",
]


def _tool(t: Section) -> ToolSpec:
    w0, w1 = t.vector("wire_start", 3), t.vector("wire_end", 3)
    length = float(np.linalg.norm(w1 - w0))
    if length < 1e-3:
        raise t.fail("wire_end", f"wire must be at least 1 mm long, got {length * 1e3:.3g} mm")
    heat = None
    if t.get("heat") is not None:
        heat = parse_heat(Section(t.raw, "heat", t.where, title=f"{t.title}.heat"))
    tension = None if t.get("wire_tension") is None else t.number("wire_tension", lo=0.0,
                                                                    strict_lo=True)
    tool = ToolSpec(w0, w1, clearance=t.number("clearance", ToolSpec.clearance, lo=0.0),
                    mass=t.number("mass", ToolSpec.mass, lo=0.0), heat=heat,
                    wire_tension=tension)  # fmt: skip
    if 2 * tool.clearance >= length:
        raise t.fail(
            "clearance",
            f"2 x clearance ({2 * tool.clearance:g} m) must be shorter "
            f"than the wire ({length:g} m)",
        )
    t.done()
    return tool


def _keep(c: Section, closed: bool | None) -> str | np.ndarray | None:
    value = c.get("keep")
    if value is None:
        return None
    if isinstance(value, str):
        if value not in ("inside", "outside"):
            raise c.fail("keep",
                         f'expected "inside", "outside" or a point [x, y, z], got {value!r}')
        if closed is False:
            raise c.fail("keep", f'"{value}" needs a closed surface; give a point [x, y, z] of '
                         "the part instead")  # fmt: skip
        return value
    return c.vector("keep", 3)


def _cut(c: Section, name: str, surface: SurfaceSpec) -> CutSpec:
    # the rulings (read or sampled when the surface was parsed) decide when the table
    # does not: a closed file, a periodic built-in surface
    closed = surface.closed if surface.closed is not None else surface.read_closed
    cut = CutSpec(
        name=name,
        surface=surface,
        # the defaults are CutSpec's own (one home: a job built in memory plans the same)
        feed_speed=c.number("feed_speed", CutSpec.feed_speed, lo=0.0, hi=1.0, strict_lo=True),
        lead_in=c.number("lead_in", CutSpec.lead_in, lo=0.0),
        lead_out=c.number("lead_out", CutSpec.lead_out, lo=0.0),
        approach_speed=c.number("approach_speed", CutSpec.approach_speed, lo=0.0, hi=1.0,
                                strict_lo=True),
        kerf=c.number("kerf", CutSpec.kerf, lo=0.0),
        keep=_keep(c, closed),
        wire_tolerance=c.number("wire_tolerance", CutSpec.wire_tolerance, lo=0.0,
                                strict_lo=True),
        feed_tolerance=c.number("feed_tolerance", CutSpec.feed_tolerance, lo=0.0, hi=1.0,
                                strict_lo=True),
        extend=c.flag("extend", CutSpec.extend),
        tolerance=c.number("tolerance", CutSpec.tolerance, lo=0.0, strict_lo=True),
    )
    if cut.extend and closed:
        raise c.fail("extend", "only for an open surface (a closed one is entered through a "
                     "slit, never extended)")  # fmt: skip
    c.done()
    return cut


def _cuts(doc: dict, where: str, base_dir: Path | None) -> tuple[CutSpec, ...]:
    raw = doc.get("cut")
    if isinstance(raw, list):  # [[cut]]: a part with several cuts
        if "surface" in doc:
            raise ValueError(f"{where}: [surface] with [[cut]] tables: give each cut its own "
                             "[cut.surface] table and no top-level [surface]")  # fmt: skip
        if not raw:
            raise ValueError(f"{where}: [[cut]] is empty; expected at least one cut")
        cuts: list[CutSpec] = []
        for i, entry in enumerate(raw):
            if not isinstance(entry, dict):
                raise ValueError(f"{where}: [[cut]] entry {i + 1} must be a table")
            name = entry.get("name", f"cut{i + 1}")
            if not isinstance(name, str) or not name.strip():
                raise ValueError(f"{where}: [[cut]] entry {i + 1}: name: expected a non-empty "
                                 f"string, got {name!r}")  # fmt: skip
            if name in [c.name for c in cuts]:
                raise ValueError(f"{where}: [[cut]] entry {i + 1}: name {name!r} is used by an "
                                 "earlier cut; names must be unique")  # fmt: skip
            title = f"cut '{name}'"
            c = Section.of(entry, title, where)
            c.get("name")
            surface = parse_surface(Section(entry, "surface", where, title=f"{title}.surface"),
                                    base_dir)  # fmt: skip
            c.get("surface")
            cuts.append(_cut(c, name, surface))
        return tuple(cuts)
    surface = parse_surface(Section(doc, "surface", where), base_dir)
    c = Section(doc, "cut", where, required=False)
    return (_cut(c, "cut", surface),)


def parse_job(doc: dict, where: str = "job", base_dir: Path | None = None) -> Job:
    """Validate a job given as a TOML-like dict and read every file it names.

    The fields are the module doc's; relative paths are taken from ``base_dir``.  Every
    file's data goes into the job (the cut stage gets data, not paths), and a bad file is
    refused here, naming ``where``, the table and the field, then the file and its line.
    """
    known = {"surface", "stock", "robot", "tool", "cut", "material"}
    extra = sorted(set(doc) - known)
    if extra:
        raise ValueError(
            f"{where}: unknown section(s) {', '.join(extra)}; expected {sorted(known)}"
        )
    cuts = _cuts(doc, where, base_dir)
    stock = parse_stock(Section(doc, "stock", where))
    robot = parse_robot(Section(doc, "robot", where), base_dir)
    tool = _tool(Section(doc, "tool", where))
    material = None
    if doc.get("material") is not None:
        material = parse_material(Section(doc, "material", where))
    _check_heat_model(tool, cuts, material, where)
    return Job(cuts, stock, robot, tool, material=material)


def _check_heat_model(tool: ToolSpec, cuts: tuple[CutSpec, ...], material, where: str) -> None:
    """Check the heat model's needs across tables (docs/kerf.md).

    ``constant_kerf`` needs ``[material]``; with ``[material]``, a ``power`` must lie above
    the material's ``power_threshold`` (at or below it the wire melts nothing), and every
    cut's ``kerf`` that sets the power (``constant_kerf``, or ``on_off`` without ``power``)
    must be at least the material's ``kerf_base`` (without a heat output too: ``on_off``)."""
    heat = tool.heat
    if heat is not None and heat.mode == "constant_kerf" and material is None:
        raise ValueError(f'{where}: [tool.heat] mode: "constant_kerf" needs a [material] '
                         "table (kerf_base, kerf_gain, power_threshold)")  # fmt: skip
    if material is None:
        return
    power = None if heat is None else heat.power
    if power is not None and power <= material.power_threshold:
        raise ValueError(f"{where}: [tool.heat] power: {power:g} W/m is at or below "
                         f"[material] power_threshold {material.power_threshold:g} W/m: the "
                         "wire melts nothing (expected a power above it)")  # fmt: skip
    if power is not None and heat.mode != "constant_kerf":
        return  # the power is given: the cuts' kerf does not set it
    for cut in cuts:
        if cut.kerf < material.kerf_base:
            title = "cut" if cut.name == "cut" and len(cuts) == 1 else f"cut '{cut.name}'"
            raise ValueError(f"{where}: [{title}] kerf: {cut.kerf * 1e3:g} mm is below "
                             f"[material] kerf_base {material.kerf_base * 1e3:g} mm: no heat "
                             "melts less than the wire (expected a kerf >= kerf_base)")  # fmt: skip


def job_document(text: str, where: str) -> dict:
    """Return the TOML document of a job file's text.

    ValueError naming ``where`` when it is not valid TOML (the fields are checked by
    :func:`parse_job`).
    """
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{where}: not valid TOML ({exc})") from None


#: the fields of a ``[surface]`` table that name a file: ``kind -> keys`` of its option
#: table (a plain string is the first key's path)
_SURFACE_FILES = {"file": ()} | {k: ("root", "tip") if k == "airfoil" else ("file",)
                                 for k in FOREIGN_KINDS}  # fmt: skip


def file_fields(doc: dict) -> list[tuple[tuple[str | int, ...], str]]:
    """Return every field of a job document that names an input file.

    As ``(location, path)``: ``location`` the keys from the document's root (``("cut", 0,
    "surface", "file")``), ``path`` as written (relative paths are taken from the job file's
    folder).  Fields of the wrong type are left out (:func:`parse_job` reports them).
    """
    found: list[tuple[tuple[str | int, ...], str]] = []
    surfaces: list[tuple[tuple[str | int, ...], object]] = [(("surface",), doc.get("surface"))]
    if isinstance(doc.get("cut"), list):
        surfaces += [(("cut", i, "surface"), c.get("surface"))
                     for i, c in enumerate(doc["cut"]) if isinstance(c, dict)]  # fmt: skip
    for where, table in surfaces:
        if not isinstance(table, dict):
            continue
        for kind, keys in _SURFACE_FILES.items():
            value = table.get(kind)
            if isinstance(value, str):
                found.append(((*where, kind), value))
            elif isinstance(value, dict):
                found += [((*where, kind, k), value[k]) for k in keys
                          if isinstance(value.get(k), str)]  # fmt: skip
    robot = doc.get("robot")
    if isinstance(robot, dict) and isinstance(robot.get("calibration"), str):
        found.append((("robot", "calibration"), robot["calibration"]))
    return found


def load_job(path: str | os.PathLike[str]) -> Job:
    """Read and validate a TOML job file and every file it names, once.

    The surfaces' rulings and the robot's calibration are read by :func:`parse_job`;
    ValueError names the job file, the table and the field, then the named file and its
    line.  The job carries the file's bytes (``Job.source_bytes``) and the data of every
    file it names: planning it opens no file.
    """
    p, data = read_user_bytes(path, "job file")
    doc = job_document(user_text(p, data), str(p))
    job = parse_job(doc, str(p), base_dir=p.parent)
    return dataclasses.replace(job, source=p, source_bytes=data)
