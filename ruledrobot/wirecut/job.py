"""Cut job files (TOML): what to cut, from what, with which robot and tool.

A job describes, in the robot base frame (metres, radians, seconds)::

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
    algorithm = "dh"           # projection | combined | dh
    scheme = "four_point"
    steps = 4                  # or: spacing = 0.002 (m, largest gap between refined rulings)

    [stock]                    # the block, a box
    centre = [0.5, 0.0, 0.3]
    size = [0.2, 0.2, 0.15]
    rotvec = [0.0, 0.0, 0.0]

    [robot]
    model = "ur5e"
    base = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    speed_scale = 1.0          # fraction of the catalogue joint speed limits
    acceleration = 1.4         # rad/s^2, one value or six
    # home = [3.14, -1.57, 1.57, -1.57, -1.57, 0.0]   # optional (rad): start and end here
    # calibration = "robot.calib.json"   # the robot's own kinematics (ruledrobot calibration fetch)

    [tool]                     # the hot-wire bow, in the flange frame
    wire_start = [-0.2, 0.0, 0.25]
    wire_end = [0.2, 0.0, 0.25]
    clearance = 0.02           # wire kept this far beyond the stock at each end
    mass = 1.0

    [cut]
    feed_speed = 0.01          # m/s, wire speed inside the stock
    lead_in = 0.02             # m before the first chord
    lead_out = 0.02
    approach_speed = 0.3       # fraction of joint speed limits for approach/retract
    kerf = 0.0008              # m, reported; the wire path is the surface itself
    wire_tolerance = 0.0005    # m, largest wire deviation from the rulings (a check)
    feed_tolerance = 0.05      # fraction: feed inside the stock within +-5 % (a check)

:func:`load_job` validates every field and raises ValueError naming the file,
the section and the field.
"""

from __future__ import annotations

import os
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..geometry import se3
from ..geometry.box import Box
from ..geometry.lines import Lines
from ..io.text import read_user_text
from ..subdivision.schemes import SCHEME_NAMES

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["CutSpec", "Job", "RobotSpec", "SurfaceSpec", "ToolSpec", "load_job", "parse_job"]

ALGORITHMS = ("projection", "combined", "dh")


@dataclass(frozen=True)
class SurfaceSpec:
    """Where the rulings come from and how they are refined."""

    builtin: str | None = None
    file: Path | None = None
    params: dict[str, Any] = field(default_factory=dict)
    u: tuple[float, float] | None = None
    rulings: int = 9
    pose: np.ndarray = field(default_factory=lambda: np.eye(4), repr=False)
    algorithm: str = "dh"
    scheme: str = "four_point"
    steps: int | None = 4
    spacing: float | None = None
    #: rulings read from a file of the field (gcode, airfoil, dxf, rhino) when the job
    #: names one (``file`` is then that file), as an open path, in the file's frame
    read_lines: Lines | None = field(default=None, repr=False)
    kind: str | None = None


@dataclass(frozen=True)
class RobotSpec:
    model: str = "ur5e"
    base: np.ndarray = field(default_factory=lambda: np.eye(4), repr=False)
    speed_scale: float = 1.0
    acceleration: np.ndarray | None = None
    home: np.ndarray | None = field(default=None, repr=False)
    calibration: Path | None = None


@dataclass(frozen=True)
class ToolSpec:
    """The bow: wire end points in the flange frame (m), clearance beyond the stock, mass."""

    wire_start: np.ndarray
    wire_end: np.ndarray
    clearance: float = 0.02
    mass: float = 1.0

    @property
    def wire_length(self) -> float:
        return float(np.linalg.norm(self.wire_end - self.wire_start))


@dataclass(frozen=True)
class CutSpec:
    feed_speed: float = 0.01
    lead_in: float = 0.02
    lead_out: float = 0.02
    approach_speed: float = 0.3
    kerf: float = 0.0008
    wire_tolerance: float = 0.0005
    feed_tolerance: float = 0.05


@dataclass(frozen=True)
class Job:
    """A validated cut job (see the module doc for the file format)."""

    surface: SurfaceSpec
    stock: Box
    robot: RobotSpec
    tool: ToolSpec
    cut: CutSpec
    source: Path | None = None

    def robot_model(self):
        """The job's robot: the catalogue model with its calibration (if the job names
        one) and its base; the arm every stage plans and checks with."""
        from ..robot import load

        return load(self.robot.model).with_calibration(self.robot.calibration).with_base(
            self.robot.base
        )

    def input_lines(self) -> Lines:
        """The input rulings in the robot base frame."""
        s = self.surface
        if s.read_lines is not None:
            lines = s.read_lines
        elif s.file is not None:
            from ..io.lines import load_lines

            lines = load_lines(s.file)
        else:
            from ..geometry.surfaces import sample_surface

            lo, hi = s.u if s.u is not None else (None, None)
            lines = sample_surface(s.builtin, n=s.rulings, start=lo, stop=hi, **s.params).lines
        return lines.transform(s.pose)


class _Section:
    """Typed access to one TOML table with errors naming file, section and field."""

    def __init__(self, doc: dict, name: str, where: str, required: bool = True) -> None:
        self.where = where
        self.name = name
        raw = doc.get(name)
        if raw is None:
            if required:
                raise ValueError(f"{where}: missing section [{name}]")
            raw = {}
        if not isinstance(raw, dict):
            raise ValueError(f"{where}: [{name}] must be a table")
        self.raw = raw
        self.used: set[str] = set()

    def fail(self, key: str, msg: str) -> ValueError:
        return ValueError(f"{self.where}: [{self.name}] {key}: {msg}")

    def get(self, key: str, default: Any = None) -> Any:
        self.used.add(key)
        return self.raw.get(key, default)

    def number(
        self,
        key: str,
        default: float | None = None,
        lo: float | None = None,
        hi: float | None = None,
        strict_lo: bool = False,
    ) -> float:
        v = self.get(key, default)
        if v is None:
            raise self.fail(key, "missing; expected a number")
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v):
            raise self.fail(key, f"expected a finite number, got {v!r}")
        if lo is not None and (v < lo or (strict_lo and v == lo)):
            rel = ">" if strict_lo else ">="
            raise self.fail(key, f"expected a number {rel} {lo:g}, got {v!r}")
        if hi is not None and v > hi:
            raise self.fail(key, f"expected a number <= {hi:g}, got {v!r}")
        return float(v)

    def vector(self, key: str, n: int, default: Any = None) -> np.ndarray:
        v = self.get(key, default)
        if v is None:
            raise self.fail(key, f"missing; expected a list of {n} numbers")
        if (
            not isinstance(v, list)
            or len(v) != n
            or any(isinstance(x, bool) or not isinstance(x, (int, float)) for x in v)
        ):
            raise self.fail(key, f"expected a list of {n} numbers, got {v!r}")
        arr = np.asarray(v, dtype=np.float64)
        if not np.all(np.isfinite(arr)):
            raise self.fail(key, "contains NaN or infinity")
        return arr

    def choice(self, key: str, options: tuple[str, ...], default: str) -> str:
        v = self.get(key, default)
        if v not in options:
            raise self.fail(key, f"expected one of {', '.join(options)}, got {v!r}")
        return str(v)

    def done(self) -> None:
        extra = sorted(set(self.raw) - self.used)
        if extra:
            raise ValueError(
                f"{self.where}: [{self.name}] unknown field(s) {', '.join(extra)}; "
                f"expected some of {', '.join(sorted(self.used))}"
            )


def _calibration(sec: _Section, model: str, base_dir: Path | None) -> Path | None:
    """``[robot] calibration``: a calibration file of this robot (checked on reading)."""
    value = sec.get("calibration")
    if value is None:
        return None
    if not isinstance(value, str):
        raise sec.fail("calibration", f"expected a path string, got {value!r}")
    path = Path(value)
    if not path.is_absolute() and base_dir is not None:
        path = base_dir / path
    from ..robot.calibration import load_calibration

    try:
        cal = load_calibration(path)
    except (OSError, ValueError) as exc:
        raise sec.fail("calibration", str(exc)) from None
    if cal.model != model:
        raise sec.fail("calibration", f"{path} is a calibration of a {cal.model}, the job's "
                       f"robot is a {model}")  # fmt: skip
    return path


def _pose(sec: _Section, key: str) -> np.ndarray:
    v = sec.vector(key, 6, [0.0] * 6)
    return se3.pose_from_ur_vector(v)


def parse_job(doc: dict, where: str = "job", base_dir: Path | None = None) -> Job:
    """Validate a job given as a TOML-like dict (see the module doc)."""
    known = {"surface", "stock", "robot", "tool", "cut"}
    extra = sorted(set(doc) - known)
    if extra:
        raise ValueError(
            f"{where}: unknown section(s) {', '.join(extra)}; expected {sorted(known)}"
        )

    s = _Section(doc, "surface", where)
    builtin, file = s.get("builtin"), s.get("file")
    from ..io.formats import parse_read_spec, read_rulings

    foreign = [k for k in ("gcode", "airfoil", "dxf", "rhino") if s.get(k) is not None]
    if (builtin is not None) + (file is not None) + len(foreign) != 1:
        raise s.fail("builtin/file/gcode/airfoil/dxf/rhino",
                     'give exactly one of builtin = "name", file = "path" (a lines file), or '
                     'gcode/airfoil/dxf/rhino = "path" (or a table of options; docs/formats.md)')
    read_lines = None
    if foreign:
        kind = foreign[0]
        spec = parse_read_spec(kind, s.get(kind), f"{where}: [surface.{kind}]", base_dir)
        try:
            read_lines = read_rulings(spec).path_lines()
        except ValueError as exc:
            raise s.fail(kind, str(exc)) from None
        file = str(spec.path)
    params = s.get("params", {})
    if not isinstance(params, dict):
        raise s.fail("params", f"expected a table of parameters, got {params!r}")
    u = None
    path = None
    if builtin is not None:
        from ..geometry.surfaces import SURFACES

        if builtin not in SURFACES:
            raise s.fail(
                "builtin",
                f"unknown surface {builtin!r}; expected one of {', '.join(sorted(SURFACES))}",
            )
        try:
            SURFACES[builtin].params(**params)
        except ValueError as exc:
            raise s.fail("params", str(exc)) from None
        if s.get("u") is not None:
            uu = s.vector("u", 2)
            if not uu[1] > uu[0]:
                raise s.fail("u", f"expected [start, stop] with stop > start, got {uu.tolist()}")
            u = (float(uu[0]), float(uu[1]))
    else:
        if not isinstance(file, str):
            raise s.fail("file", f"expected a path string, got {file!r}")
        path = Path(file)
        if not path.is_absolute() and base_dir is not None:
            path = base_dir / path
        if not path.exists():
            raise s.fail("file", f"no such lines file: {path}")
        if "u" in s.raw:
            raise s.fail("u", "only for a builtin surface")
        if params:
            raise s.fail("params", "only for a builtin surface")
    rulings = s.get("rulings", 9)
    if isinstance(rulings, bool) or not isinstance(rulings, int) or not 4 <= rulings <= 10_000:
        raise s.fail("rulings", f"expected an integer 4 <= rulings <= 10000, got {rulings!r}")
    steps = s.get("steps")
    spacing = s.get("spacing")
    if steps is not None and spacing is not None:
        raise s.fail("steps/spacing", "give steps or spacing, not both")
    if spacing is not None:
        spacing = s.number("spacing", lo=0.0, strict_lo=True)
    elif steps is None:
        steps = 4
    if steps is not None and (
        isinstance(steps, bool) or not isinstance(steps, int) or not 0 <= steps <= 12
    ):
        raise s.fail("steps", f"expected an integer 0 <= steps <= 12, got {steps!r}")
    surface = SurfaceSpec(
        builtin=builtin,
        file=path,
        params=dict(params),
        u=u,
        rulings=int(rulings),
        pose=_pose(s, "pose"),
        algorithm=s.choice("algorithm", ALGORITHMS, "dh"),
        scheme=s.choice("scheme", SCHEME_NAMES, "four_point"),
        steps=steps,
        spacing=spacing,
        read_lines=read_lines,
        kind=foreign[0] if foreign else ("lines" if file is not None else None),
    )
    s.done()

    st = _Section(doc, "stock", where)
    centre, size = st.vector("centre", 3), st.vector("size", 3)
    for k in range(3):
        if size[k] <= 0:
            raise st.fail("size", f"edge {k} must be positive, got {size[k]!r}")
    rot = se3.pose_from_rotvec(st.vector("rotvec", 3, [0.0, 0.0, 0.0]))[:3, :3]
    stock = Box(centre, size, rot)
    st.done()

    r = _Section(doc, "robot", where)
    model = r.get("model", "ur5e")
    from ..robot import MODEL_NAMES

    if model not in MODEL_NAMES:
        raise r.fail("model", f"unknown robot {model!r}; expected one of {', '.join(MODEL_NAMES)}")
    acc = r.get("acceleration")
    acceleration = None
    if acc is not None:
        if isinstance(acc, list):
            acceleration = r.vector("acceleration", 6)
        else:
            acceleration = np.full(6, r.number("acceleration"))
        if np.any(acceleration <= 0):
            raise r.fail("acceleration", "expected positive values (rad/s^2)")
    robot = RobotSpec(
        model=model,
        base=_pose(r, "base"),
        speed_scale=r.number("speed_scale", 1.0, lo=0.0, hi=1.0, strict_lo=True),
        acceleration=acceleration,
        home=r.vector("home", 6) if r.get("home") is not None else None,
        calibration=_calibration(r, model, base_dir),
    )
    r.done()

    t = _Section(doc, "tool", where)
    w0, w1 = t.vector("wire_start", 3), t.vector("wire_end", 3)
    length = float(np.linalg.norm(w1 - w0))
    if length < 1e-3:
        raise t.fail("wire_end", f"wire must be at least 1 mm long, got {length * 1e3:.3g} mm")
    tool = ToolSpec(
        w0, w1, clearance=t.number("clearance", 0.02, lo=0.0), mass=t.number("mass", 1.0, lo=0.0)
    )
    if 2 * tool.clearance >= length:
        raise t.fail(
            "clearance",
            f"2 x clearance ({2 * tool.clearance:g} m) must be shorter "
            f"than the wire ({length:g} m)",
        )
    t.done()

    c = _Section(doc, "cut", where)
    cut = CutSpec(
        feed_speed=c.number("feed_speed", 0.01, lo=0.0, hi=1.0, strict_lo=True),
        lead_in=c.number("lead_in", 0.02, lo=0.0),
        lead_out=c.number("lead_out", 0.02, lo=0.0),
        approach_speed=c.number("approach_speed", 0.3, lo=0.0, hi=1.0, strict_lo=True),
        kerf=c.number("kerf", 0.0008, lo=0.0),
        wire_tolerance=c.number("wire_tolerance", 0.0005, lo=0.0, strict_lo=True),
        feed_tolerance=c.number("feed_tolerance", 0.05, lo=0.0, hi=1.0, strict_lo=True),
    )
    c.done()
    return Job(surface, stock, robot, tool, cut)


def load_job(path: str | os.PathLike[str]) -> Job:
    """Read and validate a TOML job file; ValueError names the file, section and field."""
    p, text = read_user_text(path, "job file")
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{p}: not valid TOML ({exc})") from None
    job = parse_job(doc, str(p), base_dir=p.parent)
    return Job(job.surface, job.stock, job.robot, job.tool, job.cut, source=p)
