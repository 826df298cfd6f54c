"""Parsing the tables of a job file: typed fields, errors naming file, section and field.

Each ``parse_*`` function reads one table (a TOML dict) into a value type of
:mod:`.load`.  Every error is a ``ValueError`` whose message starts with the file
and the section, then the field and what was expected, e.g.
``job.toml: [cut 'top'] feed_speed: expected a number > 0, got -1``.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ...geometry import se3
from ...geometry.box import Box
from ...io.fields import FieldReader
from ...io.paths import input_path, missing_file
from ...robot.arm.calibration import Calibration
from ...robot.wire.kerf import Material
from ...subdivision.schemes import SCHEME_NAMES
from .spec import HEAT_MODES, HeatSpec, RobotSpec, SurfaceSpec

if TYPE_CHECKING:  # the readers of the field's files are imported when a job names one
    from ...io.formats import ReadSpec, Rulings

__all__ = ["Section", "parse_heat", "parse_material", "parse_robot", "parse_stock",
           "parse_surface"]

ALGORITHMS = ("projection", "combined", "dh")
#: the files of the field a surface can be read from (:mod:`ruledrobot.io.formats`)
FOREIGN_KINDS = ("gcode", "airfoil", "dxf", "rhino")
#: where the wire's heat is switched: UR standard, configurable and tool digital outputs,
#: and the standard analog outputs (a current or voltage set as a fraction of the range)
HEAT_OUTPUTS = {"standard": 8, "configurable": 8, "tool": 2, "analog": 2}


class Section(FieldReader):
    """Typed access to one TOML table with errors naming file, section and field."""

    def __init__(
        self, doc: dict, name: str, where: str, required: bool = True, title: str | None = None
    ) -> None:
        self.where = where
        self.name = name
        self.title = title or name
        raw = doc.get(name) if isinstance(doc, dict) else None
        if raw is None:
            if required:
                raise ValueError(f"{where}: missing section [{self.title}]")
            raw = {}
        if not isinstance(raw, dict):
            raise ValueError(f"{where}: [{self.title}] must be a table")
        self.raw = raw
        self.used: set[str] = set()

    @classmethod
    def of(cls, raw: dict, title: str, where: str) -> Section:
        """A section over an already extracted table (``[[cut]]`` entries)."""
        return cls({"_": raw}, "_", where, title=title)

    def fail(self, key: str, msg: str) -> ValueError:
        """The error (returned, not raised) for field ``key``: file, section, field, ``msg``."""
        return ValueError(f"{self.where}: [{self.title}] {key}: {msg}")

    def get(self, key: str, default: Any = None) -> Any:
        """The raw value of ``key`` (``default`` when absent), marking the field as read."""
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
        """Field ``key`` as a finite number within the given bounds.

        Parameters
        ----------
        key : str
            The field's name.
        default : float or None
            The value when the field is absent; None: the field is required.
        lo, hi : float or None
            Lower and upper bounds, inclusive (None: unbounded); the field's unit.
        strict_lo : bool
            Whether ``lo`` itself is refused (the value must be ``> lo``).

        Returns
        -------
        value : float
            The field's value.

        Raises
        ------
        ValueError
            When the field is missing without a default, is not a finite number, or
            is out of bounds (the message names file, section and field).
        """
        v = self.get(key, default)
        if v is None:
            raise self.fail(key, "missing; expected a number")
        self.finite(key, v)
        if lo is not None and (v < lo or (strict_lo and v == lo)):
            rel = ">" if strict_lo else ">="
            raise self.fail(key, f"expected a number {rel} {lo:g}, got {v!r}")
        if hi is not None and v > hi:
            raise self.fail(key, f"expected a number <= {hi:g}, got {v!r}")
        return float(v)

    def vector(self, key: str, n: int, default: Any = None) -> np.ndarray:
        """Field ``key``, a list of ``n`` finite numbers, as an ndarray of shape (n,).

        Raises
        ------
        ValueError
            When the field is missing without a default, or is not a list of ``n``
            finite numbers.
        """
        v = self.get(key, default)
        if v is None:
            raise self.fail(key, f"missing; expected a list of {n} numbers")
        return self.numbers(key, v, n, (list,))

    def choice(self, key: str, options: tuple[str, ...], default: str) -> str:
        """Field ``key``, one of ``options`` (``default`` when absent).

        Raises
        ------
        ValueError
            When the value is not one of ``options``.
        """
        v = self.get(key, default)
        if v not in options:
            raise self.fail(key, f"expected one of {', '.join(options)}, got {v!r}")
        return str(v)

    flag = FieldReader.boolean  # ``key`` as true or false (``default`` when absent)

    def done(self) -> None:
        """Check that every field of the table was read.

        Raises
        ------
        ValueError
            When the table has fields no accessor asked for (a misspelt or unknown
            field), naming them and the fields expected.
        """
        extra = sorted(set(self.raw) - self.used)
        if extra:
            raise ValueError(
                f"{self.where}: [{self.title}] unknown field(s) {', '.join(extra)}; "
                f"expected some of {', '.join(sorted(self.used))}"
            )


def pose(sec: Section, key: str) -> np.ndarray:
    """A UR pose vector field ``[x, y, z, rx, ry, rz]`` as a 4x4 pose (identity if absent)."""
    return se3.pose_from_ur_vector(sec.vector(key, 6, [0.0] * 6))


def parse_surface(s: Section, base_dir: Path | None) -> SurfaceSpec:
    """``[surface]`` (or a cut's ``surface`` table) -> :class:`.spec.SurfaceSpec`."""
    builtin, file = s.get("builtin"), s.get("file")
    foreign = [k for k in FOREIGN_KINDS if s.get(k) is not None]
    if (builtin is not None) + (file is not None) + len(foreign) != 1:
        raise s.fail("builtin/file/gcode/airfoil/dxf/rhino",
                     'give exactly one of builtin = "name", file = "path" (a lines file), or '
                     'gcode/airfoil/dxf/rhino = "path" (or a table of options; '
                     "docs/formats.md)")  # fmt: skip
    read = None
    if foreign:
        from ...io.formats import parse_read_spec

        kind = foreign[0]
        spec = parse_read_spec(kind, s.get(kind), f"{s.where}: [{s.title}.{kind}]", base_dir)
        read = _read_file(s, kind, spec)
        file = str(spec.path)
    params = s.get("params", {})
    if not isinstance(params, dict):
        raise s.fail("params", f"expected a table of parameters, got {params!r}")
    u = None
    path = None
    if builtin is not None:
        from ...geometry.surfaces import SURFACES

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
        if foreign:  # resolved and checked by the format's options (parse_read_spec)
            path = Path(file)
        else:
            path = input_path(file, base_dir)
            missing = missing_file(path, "lines")
            if missing:
                raise s.fail("file", missing)
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
    closed = s.get("closed")
    if closed is not None and not isinstance(closed, bool):
        raise s.fail("closed", f"expected true or false, got {closed!r}")
    if path is not None and read is None:  # a lines file: read now, as the field's files
        from ...io.formats import ReadSpec

        read = _read_file(s, "file", ReadSpec("lines", path))
    # a foam cutter's moves: the projection algorithm by default, whose geodesic
    # midpoints keep the towers' straight moves (the dh frames swing round a corner
    # of parallel rulings); refined between its corners (docs/formats.md)
    polyline = bool(foreign) and foreign[0] == "gcode"
    surface = SurfaceSpec(
        builtin=builtin,
        file=path,
        params=dict(params),
        u=u,
        rulings=int(rulings),
        pose=pose(s, "pose"),
        algorithm=s.choice("algorithm", ALGORITHMS, "projection" if polyline else "dh"),
        scheme=s.choice("scheme", SCHEME_NAMES, "four_point"),
        steps=steps,
        spacing=spacing,
        closed=closed,
        read_lines=None if read is None else read.lines,
        read_closed=False if read is None else bool(read.closed),
        read_planes=None if read is None else read.planes,
        kind=foreign[0] if foreign else ("lines" if file is not None else None),
    )
    s.done()
    if read is None:  # a built-in surface: sampled once, here, as a file is read
        try:
            sampled, ends_meet = surface.sample()
        except ValueError as exc:
            raise s.fail("builtin", str(exc)) from None
        surface = dataclasses.replace(surface, read_lines=sampled, read_closed=ends_meet)
    return surface


def _read_file(s: Section, key: str, spec: ReadSpec) -> Rulings:
    """The rulings of the file ``spec`` names, read once when the job is loaded; a missing,
    unreadable or malformed file is a ValueError naming the job file, the table, the field
    ``key``, then the file and its line (:func:`~ruledrobot.io.formats.read_rulings`)."""
    from ...io.formats import read_rulings

    try:
        return read_rulings(spec)
    except (OSError, ValueError) as exc:
        raise s.fail(key, str(exc)) from None


def parse_stock(st: Section) -> Box:
    """``[stock]``: the block, an oriented box."""
    centre, size = st.vector("centre", 3), st.vector("size", 3)
    for k in range(3):
        if size[k] <= 0:
            raise st.fail("size", f"edge {k} must be positive, got {float(size[k])!r}")
    rot = se3.pose_from_rotvec(st.vector("rotvec", 3, [0.0, 0.0, 0.0]))[:3, :3]
    stock = Box(centre, size, rot)
    st.done()
    return stock


def parse_robot(r: Section, base_dir: Path | None) -> RobotSpec:
    """``[robot]`` -> :class:`.spec.RobotSpec` (the calibration file read and checked)."""
    from ...robot import MODEL_NAMES
    from ...robot.arm.ur_tables import canonical_name

    raw = r.get("model", "ur5e")
    try:
        model = canonical_name(raw)  # case-insensitive: "UR5e" is "ur5e"
    except ValueError:
        raise r.fail("model", f"unknown robot {raw!r}; expected one of {', '.join(MODEL_NAMES)} "
                     "(any case)") from None  # fmt: skip
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
        base=pose(r, "base"),
        speed_scale=r.number("speed_scale", 1.0, lo=0.0, hi=1.0, strict_lo=True),
        acceleration=acceleration,
        home=r.vector("home", 6) if r.get("home") is not None else None,
        calibration=_calibration(r, model, base_dir),
    )
    r.done()
    return robot


def _calibration(sec: Section, model: str, base_dir: Path | None) -> Calibration | None:
    """``[robot] calibration``: a calibration file of this robot, read and checked."""
    value = sec.get("calibration")
    if value is None:
        return None
    if not isinstance(value, str):
        raise sec.fail("calibration", f"expected a path string, got {value!r}")
    path = input_path(value, base_dir)
    from ...io.calibration import load_calibration

    try:
        cal = load_calibration(path)
    except (OSError, ValueError) as exc:
        raise sec.fail("calibration", str(exc)) from None
    if cal.model != model:
        raise sec.fail("calibration", f"{path} is a calibration of a {cal.model}, the job's "
                       f"robot is a {model}")  # fmt: skip
    return cal


def parse_material(m: Section) -> Material:
    """Parse ``[material]`` into a :class:`~ruledrobot.robot.wire.kerf.Material`.

    See docs/kerf.md: ``kerf_base`` m, ``kerf_gain`` m^2/s per W/m, ``power_threshold`` W/m
    (default 0), ``max_speed`` (m/s) per W/m (optional), ``drag`` N/m per m/s (optional:
    the wire's bow, information).
    """
    for key in ("kerf_base", "kerf_gain", "power_threshold", "max_speed", "drag"):
        m.get(key)
    m.done()  # a misspelt field is named as such, not as the one it stands for missing
    top, drag = m.get("max_speed"), m.get("drag")
    material = Material(
        kerf_base=m.number("kerf_base", lo=0.0),
        kerf_gain=m.number("kerf_gain", lo=0.0, strict_lo=True),
        power_threshold=m.number("power_threshold", 0.0, lo=0.0),
        max_speed=None if top is None else m.number("max_speed", lo=0.0, strict_lo=True),
        drag=None if drag is None else m.number("drag", lo=0.0),
    )
    return material


def parse_heat(h: Section) -> HeatSpec:
    """Parse ``[tool.heat]`` into a :class:`.spec.HeatSpec`.

    ``output = "standard:0"`` (kind:index), ``preheat`` (s), ``value`` (analog outputs: the
    fraction of the range), and the heat model (docs/kerf.md): ``mode``, ``power`` (W/m),
    ``full_scale`` (W/m at an analog output's 1.0), ``lag`` (s).  What needs ``[material]``
    is checked with the job.
    """
    out = h.get("output")
    if not isinstance(out, str) or ":" not in out:
        raise h.fail("output", 'expected "KIND:N" with KIND one of '
                     f"{', '.join(HEAT_OUTPUTS)} (e.g. \"standard:0\"), got {out!r}")  # fmt: skip
    kind, _, index = out.partition(":")
    if kind not in HEAT_OUTPUTS:
        raise h.fail("output", f"unknown output kind {kind!r}; expected one of "
                     f"{', '.join(HEAT_OUTPUTS)}")  # fmt: skip
    if not index.isdigit() or not 0 <= int(index) < HEAT_OUTPUTS[kind]:
        raise h.fail("output", f"{kind} outputs are numbered 0..{HEAT_OUTPUTS[kind] - 1}, "
                     f"got {index!r}")  # fmt: skip
    mode = h.choice("mode", HEAT_MODES, "on_off")
    power = None if h.get("power") is None else h.number("power", lo=0.0, strict_lo=True)
    full_scale = (None if h.get("full_scale") is None
                  else h.number("full_scale", lo=0.0, strict_lo=True))  # fmt: skip
    heat = HeatSpec(
        kind=kind,
        index=int(index),
        preheat=h.number("preheat", 2.0, lo=0.0, hi=60.0),
        value=h.number("value", 1.0, lo=0.0, hi=1.0) if kind == "analog" else 1.0,
        mode=mode, power=power, full_scale=full_scale,
        lag=h.number("lag", 0.0, lo=0.0, hi=10.0),
    )
    for key in ("value", "full_scale"):
        if kind != "analog" and key in h.raw:
            raise h.fail(key, f'only for an analog output, got output = "{out}"')
    if kind != "analog" and mode == "constant_kerf":
        raise h.fail("mode", f'"constant_kerf" sets the power as the wire\'s speed changes: '
                     f'it needs an analog output (output = "analog:0"), got output = "{out}"')
    if mode == "constant" and power is None:
        raise h.fail("power", 'missing; mode = "constant" needs the wire\'s power (W/m)')
    if kind == "analog" and mode != "on_off" and full_scale is None:
        raise h.fail("full_scale", f'missing; mode = "{mode}" on an analog output needs the '
                     "power (W/m) at the output's 1.0")  # fmt: skip
    if kind == "analog" and None not in (power, full_scale) and power > full_scale:
        raise h.fail("power", f"{power:g} W/m is above full_scale {full_scale:g} W/m: the "
                     "output cannot set it (expected a power <= full_scale)")
    if kind == "analog" and mode != "on_off" and "value" in h.raw:
        raise h.fail("value", f'not with mode = "{mode}": the power sets the output '
                     "(power / full_scale)")  # fmt: skip
    h.done()
    return heat
