"""The value types of a cut job: surface, stock, robot, tool (with its heat), cuts.

Built and validated by :mod:`.load` from a job file; every other module reads them.
Units: metres, radians, seconds; poses in the robot base frame.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ...geometry.box import Box
from ...geometry.lines import Lines
from ...robot.arm.calibration import Calibration
from ...robot.motion.trajectory import HEAT_MODES
from ...robot.wire.cut import WIRE_TOLERANCE
from ...robot.wire.kerf import Material

__all__ = ["HEAT_MODES", "CutSpec", "HeatSpec", "Job", "RobotSpec", "SurfaceSpec", "ToolSpec"]

#: m: how far the predicted cut face may lie from the part's surface, by default
FACE_TOLERANCE = 1e-4


@dataclass(frozen=True)
class SurfaceSpec:
    """Where the rulings come from, the rulings themselves, and how they are refined.

    The job's loader (:func:`~.sections.parse_surface`) reads the file a surface names
    -- a lines file or a file of the field -- and samples a built-in surface, once, when
    the job is loaded: the surface carries its rulings (``read_lines``), and no later
    stage opens a file (docs/architecture.md, "The job is read whole, once").  ``file``
    and ``kind`` then only name where they came from, for messages and reports.

    ``closed``: None takes the lines file's own flag; a built-in surface is closed when
    it is periodic (hyperboloid, Möbius band) and no ``u`` range is given.
    """

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
    closed: bool | None = None
    #: the input rulings as loaded, in the surface's own frame (``pose`` not applied):
    #: read from ``file`` (a lines file, or a file of the field: gcode, airfoil, dxf,
    #: rhino) or the built-in surface sampled (:meth:`sample`); and whether they close.
    #: None only for a built-in surface made in memory (sampled when asked for)
    read_lines: Lines | None = field(default=None, repr=False)
    read_closed: bool = False
    #: the file's two planes its rulings end on (towers, a panel's faces, the profiles'
    #: planes; :class:`~ruledrobot.io.formats.rulings.Planes`), in the file's frame
    read_planes: Any = None
    kind: str | None = None

    def __post_init__(self) -> None:
        if self.file is not None and self.read_lines is None:
            raise ValueError(f"{self.file}: a surface named by a file carries the rulings read "
                             "from it (read_lines); load the job with load_job or parse_job, "
                             "which read every file it names")  # fmt: skip

    def document(self):
        """The input rulings in the robot base frame and whether they close.

        A :class:`~ruledrobot.io.lines.LinesDocument`; no file is read (the rulings were
        read when the job was loaded).
        """
        from ...io.lines import LinesDocument

        if self.read_lines is not None:
            lines, closed = self.read_lines, self.read_closed
        else:
            lines, closed = self.sample()
        if self.closed is not None:
            closed = self.closed
        return LinesDocument(lines.transform(self.pose), closed)

    def sample(self) -> tuple[Lines, bool]:
        """The built-in surface's rulings in its own frame, and whether they close.

        ``rulings`` of them over ``u``; closed: a periodic surface over its whole period.
        """
        from ...geometry.surfaces import sample_surface

        if self.builtin is None:
            raise ValueError(f"{self.label}: not a built-in surface; its rulings are read "
                             "from its file when the job is loaded")  # fmt: skip
        lo, hi = self.u if self.u is not None else (None, None)
        if self.whole_period:  # sampled without its repeated end (u + period is u)
            sample = sample_surface(self.builtin, n=self.rulings, start=lo, closed=True,
                                    **self.params)  # fmt: skip
        else:
            sample = sample_surface(self.builtin, n=self.rulings, start=lo, stop=hi,
                                    **self.params)  # fmt: skip
        return sample.lines, bool(sample.closed)

    @property
    def whole_period(self) -> bool:
        """Whether the surface is a closed periodic built-in over one whole period of ``u``.

        A periodic built-in surface, ``closed = true``, whose ``u`` range is one whole
        period (within 0.1 %: ``u = [0.0, 6.2832]`` for 2 pi): its ``rulings`` are spread
        over the period and the end, the start again, is not repeated.
        """
        if self.builtin is None or self.u is None or self.closed is not True:
            return False
        from ...geometry.surfaces import SURFACES

        period = SURFACES[self.builtin].period
        return period is not None and abs(self.u[1] - self.u[0] - period) <= 1e-3 * period

    def planes(self) -> tuple[np.ndarray, float] | None:
        """Return the file's planes ``z = 0`` and ``z = distance``, or None.

        As their frame (4, 4) in the robot base frame and the distance [m]; None: a file
        without, a built-in.
        """
        if self.read_planes is None:
            return None
        return self.pose @ self.read_planes.pose, float(self.read_planes.distance)

    def lines(self) -> Lines:
        """The input rulings in the robot base frame."""
        return self.document().lines

    @property
    def label(self) -> str:
        """What the rulings are, for messages: the file or the built-in surface's name."""
        if self.file is None:
            return str(self.builtin)
        return str(self.file) if self.kind in (None, "lines") else f"{self.kind} {self.file}"


@dataclass(frozen=True)
class RobotSpec:
    """The job's robot: its model, place in the cell, speed and acceleration limits.

    Attributes
    ----------
    model : str
        The catalogue model's canonical name (``"ur5e"``, ...).
    base : ndarray, shape (4, 4)
        Pose of the robot base in the world frame (the simulation's cell); plans,
        all given in the base frame, ignore it.
    speed_scale : float
        Fraction in (0, 1] of the catalogue joint speed limits the motion uses
        (dimensionless).
    acceleration : ndarray, shape (6,), or None
        Joint acceleration limits [rad/s^2] replacing the catalogue's (None: the
        catalogue's).
    home : ndarray, shape (6,), or None
        Joint positions [rad] the motion starts and ends at (None: no home).
    calibration : Calibration or None
        The robot's own kinematics, read from the job's calibration file (None: the
        catalogue's nominal kinematics).
    """

    model: str = "ur5e"
    base: np.ndarray = field(default_factory=lambda: np.eye(4), repr=False)
    speed_scale: float = 1.0
    acceleration: np.ndarray | None = None
    home: np.ndarray | None = field(default=None, repr=False)
    calibration: Calibration | None = None  #: read from the job's calibration file


@dataclass(frozen=True)
class HeatSpec:
    """Where the wire's heat is switched (robot IO) and how long it heats before a cut.

    ``kind``: ``"standard"``, ``"configurable"`` or ``"tool"`` digital output, or
    ``"analog"`` (standard analog output ``index`` set to ``value``, a fraction of its
    range: the wire's current); ``preheat``: seconds the wire heats, still, at the
    start of each lead-in before it moves into the stock.

    The heat model (docs/kerf.md): ``mode`` one of :data:`HEAT_MODES`; ``power`` [W/m]
    the wire's power while on (required by ``"constant"``; ``"on_off"`` without it: the
    power that melts the cut's kerf at its feed); ``full_scale`` [W/m] the power at an
    analog output's 1.0; ``lag`` [s] the wire's thermal delay the set-points lead by.
    """

    kind: str
    index: int
    preheat: float = 2.0
    value: float = 1.0
    mode: str = "on_off"
    power: float | None = None
    full_scale: float | None = None
    lag: float = 0.0

    @property
    def output(self) -> str:
        """The output as ``"KIND:INDEX"`` (``"standard:0"``), as the job file writes it."""
        return f"{self.kind}:{self.index}"


@dataclass(frozen=True)
class ToolSpec:
    """The bow: wire ends, clearance, mass, the wire's heat output and tension.

    Wire end points in the flange frame (m), clearance beyond the stock, mass, the wire's
    heat output (None: the heat is not switched by the robot) and the wire's tension [N]
    (None: not given; with ``[material] drag`` it predicts the wire's bow).
    """

    wire_start: np.ndarray
    wire_end: np.ndarray
    clearance: float = 0.02
    mass: float = 1.0
    heat: HeatSpec | None = None
    wire_tension: float | None = None

    @property
    def wire_length(self) -> float:
        """Length of the wire between its end points [m]."""
        return float(np.linalg.norm(self.wire_end - self.wire_start))


@dataclass(frozen=True)
class CutSpec:
    """One cut of a part: its surface and how it is cut.

    ``keep``: which side of the surface is the part — a point of the part (3,) in the
    base frame, ``"inside"`` / ``"outside"`` for a closed surface, or None (the wire
    runs on the surface itself and the kerf is not compensated).  ``extend``: an open
    surface that stops short of the block is cut on through it along the extrapolated
    frame motion (noted) instead of being refused (:func:`..cut.passes.cut_paths`).
    """

    name: str
    surface: SurfaceSpec
    feed_speed: float = 0.01
    lead_in: float = 0.02
    lead_out: float = 0.02
    approach_speed: float = 0.3
    kerf: float = 0.0008
    keep: str | np.ndarray | None = field(default=None, repr=False)
    wire_tolerance: float = WIRE_TOLERANCE
    feed_tolerance: float = 0.05
    extend: bool = False
    #: m: how far the predicted cut face may lie from the part's surface (``face_error``)
    tolerance: float = FACE_TOLERANCE


@dataclass(frozen=True)
class Job:
    """A validated cut job: one stock, robot and tool, and the cuts in the order they are made.

    See the module doc for the file format.

    ``source``: the job file, as the reports name it; ``source_bytes``: its bytes as
    loaded (:func:`~.load.load_job` reads them once; a batch worker, a copy's): the
    reports hash them and ``job.toml`` is written from them, the job file is never read
    again (None: a job made in memory, without a file)."""

    cuts: tuple[CutSpec, ...]
    stock: Box
    robot: RobotSpec
    tool: ToolSpec
    source: Path | None = None
    source_bytes: bytes | None = field(default=None, repr=False)
    material: Material | None = None

    @property
    def cut(self) -> CutSpec:
        """The first cut (the only one of a single-cut job)."""
        return self.cuts[0]

    @property
    def surface(self) -> SurfaceSpec:
        """The first cut's surface (the only one of a single-cut job)."""
        return self.cuts[0].surface

    def robot_model(self):
        """Return the job's robot in its own base frame: the arm every stage plans and checks with.

        The catalogue model with its calibration (if the job names one) and its joint
        acceleration limits, in its own base frame (``base`` the identity) -- the frame of
        every pose of the job.
        """
        from ...robot import load

        model = load(self.robot.model).with_calibration(self.robot.calibration)
        if self.robot.acceleration is not None:
            model = model.with_limits(acceleration=self.robot.acceleration)
        return model

    def cell_robot(self):
        """Return :meth:`robot_model` placed in the world at ``[robot] base``.

        The arm of the MuJoCo scene and the viewer, which place the stock and table at
        ``base @ pose`` with it (so ``[robot] base`` moves the whole cell, never the plan).
        """
        return self.robot_model().with_base(self.robot.base)

    def input_lines(self) -> Lines:
        """The first cut's input rulings in the robot base frame."""
        return self.surface.lines()
