"""The one joint-trajectory type of the project, with everything a controller needs.

A :class:`Trajectory` is what the planner writes and what export, run and
simulate read: samples ``t`` (M,) s, joint positions ``q`` (M, 6) rad and the
TCP pose in the **robot base frame** ``tcp`` (M, 6) as UR pose vectors
``[x, y, z, rx, ry, rz]`` (m, rad), plus :class:`TrajectoryMeta`:

* ``robot`` — the catalogue model it was planned for (``"ur5e"``);
* ``control_period`` — the controller period it is sampled at [s];
* ``tcp_offset`` — the TCP in the flange frame (4, 4): UR's "TCP offset", what
  ``set_tcp`` must be set to so that the controller's TCP is the ``tcp`` column;
* ``payload`` — mass [kg] and centre of gravity in the flange frame [m]
  (``set_payload``);
* ``kinematics`` — the DH table it was planned with and its checksum;
* ``base`` — the robot base in the job's world frame (information: where the
  simulation puts the robot);
* ``phases`` — named sample ranges (approach, lead_in, cut, lead_out, retract,
  move) and ``in_stock`` — sample ranges with the wire inside the stock;
* ``job`` — the job file it came from (path and SHA-256), ``source`` — what
  produced it.

The invariant every consumer may rely on (and :meth:`Trajectory.tcp_error`
measures): ``tcp[k] = FK(q[k]) · tcp_offset`` with FK the model of
``kinematics`` and no base, i.e. the TCP column is what the controller reports
as ``actual_TCP_pose`` once its TCP is set to ``tcp_offset``.
"""

from __future__ import annotations

import dataclasses
import hashlib
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ...geometry.rotations import angle_between
from ...geometry.se3 import pose_from_ur_vector, ur_vector_from_pose
from .._checks import FloatArray, as_array, as_pose_or_vector, readonly
from ..arm.model import DEFAULT_ACCELERATION, RobotModel
from ..wire.cut import WireCut
from ..wire.in_stock import WireInStock
from .rates import finite_difference_rates

__all__ = [
    "CUTTING_PHASES",
    "HEATED_PHASES",
    "HEAT_MODES",
    "PHASE_COLOURS",
    "PHASE_NAMES",
    "Heat",
    "KinematicsRef",
    "Payload",
    "Phase",
    "Trajectory",
    "TrajectoryMeta",
    "kinematics_checksum",
    "model_for",
    "phases_from_labels",
]

#: Names of trajectory phases, in the order a cut meets them.
PHASE_NAMES = (
    "approach", "preheat", "lead_in", "cut", "lead_out", "retract", "transit", "move",
)
#: the phases in which the wire goes through the stock: it cuts (the simulation's and the
#: viewer's "cutting"; a touch of the block outside them is a collision)
CUTTING_PHASES = ("lead_in", "cut", "lead_out")
#: the phases with the wire hot: the cutting phases and the preheat before them (the
#: planner's heat windows; a path program keeps the TCP speed tight in them)
HEATED_PHASES = ("preheat", *CUTTING_PHASES)
#: the colour of each phase (hex RGB) in every picture of a plan: plots.png's 3-D path and
#: time bands, the viewer's trail; the moves with the wire cold share one
PHASE_COLOURS = {
    "approach": "#9467bd", "transit": "#9467bd", "retract": "#9467bd", "move": "#9467bd",
    "preheat": "#d62728", "lead_in": "#1f77b4", "cut": "#2ca02c", "lead_out": "#17becf",
}  # fmt: skip


def kinematics_checksum(dh: ArrayLike) -> str:
    """``"sha256:<hex>"`` of a DH table (J, 4) ``[theta_offset, a, d, alpha]`` per joint.

    The numbers are hashed as their shortest round-trip decimal text, so the same
    table read back from JSON gives the same checksum.
    """
    table = np.asarray(dh, dtype=np.float64)
    text = ";".join(",".join(repr(float(x)) for x in row) for row in table)
    return "sha256:" + hashlib.sha256(text.encode()).hexdigest()


@dataclass(frozen=True, eq=False)
class KinematicsRef:
    """The kinematics a trajectory was planned with.

    ``dh`` (J, 4): per joint ``[theta_offset, a, d, alpha]`` (standard DH, m and
    rad); ``source``: ``"nominal"`` (the catalogue table) or where a calibration
    came from; ``checksum``: :func:`kinematics_checksum` of ``dh``;
    ``controller_checksum``: the controller's six per-joint checksums of that
    calibration (KinematicsInfo), when known — what the runner compares.
    """

    dh: FloatArray
    source: str = "nominal"
    checksum: str = ""
    controller_checksum: tuple[int, ...] | None = None

    def __post_init__(self) -> None:
        dh = as_array(self.dh, "kinematics.dh", (4,))
        if dh.ndim != 2:
            raise ValueError(f"kinematics.dh: expected (J, 4), got shape {dh.shape}")
        object.__setattr__(self, "dh", readonly(dh))
        expected = kinematics_checksum(dh)
        if self.checksum and self.checksum != expected:
            raise ValueError(
                f"kinematics.checksum: {self.checksum} does not match its DH table ({expected})"
            )
        object.__setattr__(self, "checksum", expected)

    @classmethod
    def of(cls, model: RobotModel) -> KinematicsRef:
        """The kinematics of ``model``: nominal, or its calibration (source, checksums)."""
        dh = np.stack([model.theta_offset, model.a, model.d, model.alpha], axis=1)
        cal = getattr(model, "calibration", None)
        if cal is None or cal.is_nominal:
            return cls(dh, "nominal")
        return cls(dh, cal.source or "calibration", "", cal.checksum)


@dataclass(frozen=True, eq=False)
class Payload:
    """The tool's mass [kg] and centre of gravity (3,) in the flange frame [m]."""

    mass: float = 0.0
    cog: FloatArray = field(default_factory=lambda: readonly(np.zeros(3)))

    def __post_init__(self) -> None:
        mass = float(as_array(self.mass, "payload.mass"))
        if not mass >= 0.0:
            raise ValueError(f"payload.mass: expected a mass >= 0 kg, got {mass}")
        object.__setattr__(self, "mass", mass)
        object.__setattr__(self, "cog", readonly(as_array(self.cog, "payload.cog", (3,))))


@dataclass(frozen=True)
class Phase:
    """Samples ``start <= k < stop`` of a trajectory are in phase ``name``."""

    name: str
    start: int
    stop: int

    def __post_init__(self) -> None:
        if self.name not in PHASE_NAMES:
            raise ValueError(f"phase name: expected one of {', '.join(PHASE_NAMES)}, "
                             f"got {self.name!r}")  # fmt: skip
        if not 0 <= self.start < self.stop:
            raise ValueError(f"phase {self.name}: expected 0 <= start < stop, got "
                             f"{self.start}, {self.stop}")  # fmt: skip


#: heat output kinds and how many outputs of each a UR controller has
HEAT_OUTPUT_KINDS = {"standard": 8, "configurable": 8, "tool": 2, "analog": 2}
#: how the wire's power is scheduled (docs/kerf.md): switched on and off, held at a power,
#: or following the speed so that the kerf stays the cut's
HEAT_MODES = ("on_off", "constant", "constant_kerf")


def _seconds_or_watts(name: str, value: object, positive: bool = False) -> float:
    """``value`` as a finite float ``>= 0`` (``> 0`` when ``positive``), else ValueError."""
    x = float(value)  # type: ignore[arg-type]
    if not np.isfinite(x) or x < 0.0 or (positive and x == 0.0):
        raise ValueError(f"heat.{name}: expected a finite number {'> 0' if positive else '>= 0'}"
                         f", got {value!r}")  # fmt: skip
    return x


@dataclass(frozen=True)
class Heat:
    """When the wire is hot: the output that switches it and the sample ranges it is on.

    ``kind`` ``"standard"``, ``"configurable"`` or ``"tool"`` (a digital output, on =
    True) or ``"analog"`` (standard analog output ``index`` at ``value``, a fraction of
    its range; off = 0); ``windows``: half-open sample ranges ``(start, stop)`` with the
    heat on — from the start of a pre-heat dwell to the end of a lead-out; ``preheat``:
    the seconds the wire heats before it moves into the stock (a run resumed inside a
    window heats that long before it moves).

    The heat model (docs/kerf.md): ``mode`` one of :data:`HEAT_MODES` (``"on_off"`` by
    default: today's switching); ``full_scale`` the wire power [W/m] at an analog output's
    1.0 (required for an analog output in the modes ``constant`` and ``constant_kerf``
    when the trajectory carries ``heat_power``: its set-points are written as
    ``heat_power / full_scale``); ``lag`` [s] the wire's thermal delay, by which the
    ``heat_power`` set-points already lead the motion.
    """

    kind: str
    index: int
    value: float = 1.0
    windows: tuple[tuple[int, int], ...] = ()
    preheat: float = 0.0
    mode: str = "on_off"
    full_scale: float | None = None
    lag: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in HEAT_OUTPUT_KINDS:
            raise ValueError(f"heat.kind: expected one of {', '.join(HEAT_OUTPUT_KINDS)}, "
                             f"got {self.kind!r}")  # fmt: skip
        n = HEAT_OUTPUT_KINDS[self.kind]
        index = self.index
        if isinstance(index, bool) or not isinstance(index, int) or not 0 <= index < n:
            raise ValueError(f"heat.index: {self.kind} outputs are numbered 0..{n - 1}, got "
                             f"{self.index!r}")  # fmt: skip
        if not 0.0 <= float(self.value) <= 1.0:
            raise ValueError(f"heat.value: expected a fraction in [0, 1], got {self.value!r}")
        object.__setattr__(self, "value", float(self.value))
        if not float(self.preheat) >= 0.0:
            raise ValueError(f"heat.preheat: expected seconds >= 0, got {self.preheat!r}")
        object.__setattr__(self, "preheat", float(self.preheat))
        wins = tuple((int(a), int(b)) for a, b in self.windows)
        for a, b in wins:
            if not 0 <= a < b:
                raise ValueError(
                    f"heat.windows: expected ranges 0 <= start < stop, got [{a}, {b}]"
                )
        object.__setattr__(self, "windows", wins)
        if self.mode not in HEAT_MODES:
            raise ValueError(f"heat.mode: expected one of {', '.join(HEAT_MODES)}, got "
                             f"{self.mode!r}")  # fmt: skip
        if self.full_scale is not None:
            fs = _seconds_or_watts("full_scale", self.full_scale, positive=True)
            object.__setattr__(self, "full_scale", fs)
        object.__setattr__(self, "lag", _seconds_or_watts("lag", self.lag))

    def ratio(self, power: ArrayLike) -> FloatArray:
        """The analog set-point (broadcast shape) in [0, 1] for wire ``power`` [W/m].

        ``power / full_scale``, clipped to the output's range."""
        if self.full_scale is None:
            raise ValueError(f"heat.full_scale: the {self.output} output has no full scale "
                             "(W/m at 1.0) to turn a power into a set-point")  # fmt: skip
        return np.clip(np.asarray(power, dtype=np.float64) / self.full_scale, 0.0, 1.0)

    @property
    def schedules_power(self) -> bool:
        """Whether the output follows a trajectory's ``heat_power``.

        It does on an analog output in mode ``constant`` or ``constant_kerf``; otherwise it
        switches on (at ``value``) and off by ``windows``, and a ``heat_power`` column is the
        power that assumes."""
        return self.kind == "analog" and self.mode != "on_off"

    @property
    def output(self) -> str:
        """The switched output as ``"kind:index"`` (``"standard:3"``), for messages and reports."""
        return f"{self.kind}:{self.index}"

    def on(self, n: int) -> np.ndarray:
        """(n,) bool: the heat is on at sample k."""
        m = np.zeros(n, dtype=bool)
        for a, b in self.windows:
            m[a:b] = True
        return m


@dataclass(frozen=True, eq=False)
class TrajectoryMeta:
    """Metadata of a :class:`Trajectory` (see the module doc)."""

    robot: str
    control_period: float
    tcp_offset: FloatArray
    payload: Payload
    kinematics: KinematicsRef
    base: FloatArray = field(default_factory=lambda: readonly(np.eye(4)))
    phases: tuple[Phase, ...] = ()
    in_stock: tuple[tuple[int, int], ...] = ()
    job: dict[str, str] | None = None
    source: str = ""
    heat: Heat | None = None
    #: the joint acceleration limits (J,) [rad/s^2] the trajectory was planned within, when
    #: they are not the catalogue's default (a job's ``[robot] acceleration``)
    max_acceleration: FloatArray | None = None
    #: what it cuts — the block, the wire, the passes' feeds — for measuring any motion
    #: of it with the one model of the wire against the block (:mod:`..wire.cut`)
    cut: WireCut | None = None

    def __post_init__(self) -> None:
        put = object.__setattr__
        if self.max_acceleration is not None:
            acc = as_array(self.max_acceleration, "max_acceleration")
            if acc.ndim != 1 or not np.all(acc > 0):
                raise ValueError(f"max_acceleration: expected positive limits per joint, got "
                                 f"{acc.tolist()}")  # fmt: skip
            put(self, "max_acceleration", readonly(acc))
        put(self, "tcp_offset", readonly(as_pose_or_vector(self.tcp_offset, "tcp_offset")))
        put(self, "base", readonly(as_pose_or_vector(self.base, "base")))
        period = float(self.control_period)
        if not (np.isfinite(period) and period > 0):
            raise ValueError(f"control_period: expected a positive period (s), got {period}")
        put(self, "control_period", period)
        put(self, "phases", tuple(self.phases))
        put(self, "in_stock", tuple((int(a), int(b)) for a, b in self.in_stock))
        for a, b in self.in_stock:
            if not 0 <= a < b:
                raise ValueError(f"in_stock: expected ranges 0 <= start < stop, got [{a}, {b}]")

    @classmethod
    def for_model(cls, model: RobotModel, **fields: object) -> TrajectoryMeta:
        """Return the metadata for a trajectory of ``model``.

        Its name, period, tool (as TCP offset), tool mass and COM (as payload) and nominal
        kinematics; ``fields`` override any of them."""
        kw: dict[str, object] = {
            "robot": model.name,
            "control_period": model.control_period,
            "tcp_offset": model.tool,
            "payload": Payload(model.tool_mass, model.tool_com),
            "kinematics": KinematicsRef.of(model),
            "base": model.base,
        }
        if not np.allclose(model.max_acceleration, DEFAULT_ACCELERATION):
            kw["max_acceleration"] = model.max_acceleration
        kw.update(fields)
        return cls(**kw)  # type: ignore[arg-type]

    def replace(self, **changes: object) -> TrajectoryMeta:
        """A copy with the fields named in ``changes`` replaced (validated again)."""
        return dataclasses.replace(self, **changes)  # type: ignore[arg-type]


def model_for(meta: TrajectoryMeta) -> RobotModel:
    """Return the robot a trajectory was planned for.

    The catalogue model ``meta.robot`` with the trajectory's kinematics, its TCP offset as
    tool, its payload and the joint acceleration limits it was planned within; no base (the
    trajectory's poses are in the robot base frame)."""
    from ..arm.catalogue import load

    model = load(meta.robot)
    dh = meta.kinematics.dh
    if dh.shape != (model.n_joints, 4):
        raise ValueError(f"kinematics.dh: {meta.robot} has {model.n_joints} joints, the "
                         f"trajectory's table has shape {dh.shape}")  # fmt: skip
    nominal = KinematicsRef.of(model)
    if meta.kinematics.checksum != nominal.checksum:
        from ..arm.calibration import Calibration

        cal = Calibration.from_dh(meta.robot, dh, checksum=meta.kinematics.controller_checksum,
                                  source=meta.kinematics.source)  # fmt: skip
        model = model.with_calibration(cal)
    if abs(meta.control_period - model.control_period) > 1e-12:
        raise ValueError(f"control_period: {meta.control_period} s, but a {meta.robot} runs at "
                         f"{model.control_period} s")  # fmt: skip
    if meta.max_acceleration is not None:
        if meta.max_acceleration.shape != (model.n_joints,):
            raise ValueError(f"max_acceleration: {meta.robot} has {model.n_joints} joints, got "
                             f"{meta.max_acceleration.shape[0]} limits")  # fmt: skip
        model = model.with_limits(acceleration=meta.max_acceleration)
    return dataclasses.replace(
        model, tool=meta.tcp_offset, tool_mass=meta.payload.mass, tool_com=meta.payload.cog
    )


@dataclass(frozen=True, eq=False)
class Trajectory:
    """A sampled joint trajectory with its metadata (see the module doc).

    ``t`` (M,) s from the start, strictly increasing; ``q`` (M, 6) rad; ``tcp``
    (M, 6) UR pose vectors of the TCP in the robot base frame; ``meta``;
    ``heat_power`` (M,) W/m or None: the wire power set-point per sample (docs/kerf.md),
    already led by the heat's ``lag``; where the heat schedules it (``Heat.schedules_power``)
    it needs ``meta.heat.full_scale``.
    """

    t: FloatArray
    q: FloatArray = field(repr=False)
    tcp: FloatArray = field(repr=False)
    meta: TrajectoryMeta = field(repr=False)
    heat_power: FloatArray | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        t = as_array(self.t, "t")
        q = as_array(self.q, "q", (6,))
        tcp = np.asarray(self.tcp, dtype=np.float64)
        if tcp.shape[-2:] == (4, 4):
            tcp = ur_vector_from_pose(tcp)
        tcp = as_array(tcp, "tcp", (6,))
        if t.ndim != 1 or q.shape[0] != t.size or tcp.shape[0] != t.size or t.size < 1:
            raise ValueError(f"trajectory: t {t.shape}, q {q.shape} and tcp {tcp.shape} must "
                             "have the same (non-zero) length")  # fmt: skip
        if t.size > 1 and np.any(np.diff(t) <= 0):
            k = int(np.flatnonzero(np.diff(t) <= 0)[0]) + 1
            raise ValueError(f"t[{k}]: times must increase strictly")
        for name, arr in (("t", t), ("q", q), ("tcp", tcp)):
            object.__setattr__(self, name, readonly(arr))
        m = t.size
        for p in self.meta.phases:
            if p.stop > m:
                raise ValueError(f"phase {p.name}: stop {p.stop} beyond the {m} samples")
        for a, b in self.meta.in_stock:
            if b > m:
                raise ValueError(f"in_stock: range [{a}, {b}) beyond the {m} samples")
        if self.heat_power is not None:
            object.__setattr__(self, "heat_power", readonly(self._heat_power(m)))

    def _heat_power(self, m: int) -> FloatArray:
        """The validated ``heat_power`` column (M,): finite (``as_array``), >= 0, one per
        sample, with a full scale when the heat goes to an analog output."""
        p = as_array(self.heat_power, "heat_power")
        if p.shape != (m,):
            raise ValueError(f"heat_power: expected one set-point per sample ({m},), got "
                             f"shape {p.shape}")  # fmt: skip
        bad = np.flatnonzero(p < 0.0)
        if bad.size:
            raise ValueError(f"heat_power[{bad[0]}]: expected a finite power >= 0 W/m, got "
                             f"{p[bad[0]]}")  # fmt: skip
        heat = self.meta.heat
        if heat is not None and heat.schedules_power and heat.full_scale is None:
            raise ValueError(f"heat.full_scale: the heat_power column on {heat.output} "
                             f"({heat.mode}) needs the output's full scale (W/m at 1.0)")
        return p

    def with_samples(self, t: ArrayLike, q: ArrayLike, tcp: ArrayLike,
                     meta: TrajectoryMeta | None = None,
                     rows: ArrayLike | slice | None = None) -> Trajectory:  # fmt: skip
        """A trajectory of new samples with this one's ``heat_power`` at ``rows``.

        ``rows``: indices or a slice of this one's samples (default: all); ``meta``
        default: this one's.  What every method that re-cuts or re-times the samples
        returns."""
        power = self.heat_power
        if power is not None and rows is not None:
            power = power[rows]
        return Trajectory(t, q, tcp, self.meta if meta is None else meta, power)

    @classmethod
    def from_joints(
        cls, t: ArrayLike, q: ArrayLike, model: RobotModel, **meta_fields: object
    ) -> Trajectory:
        """Return the samples of ``model`` with the TCP column computed as FK(q) · tool.

        In the robot base frame (``model.base`` is recorded in the metadata, not applied)."""
        meta = TrajectoryMeta.for_model(model, **meta_fields)
        robot = model.with_base(np.eye(4))
        q = as_array(q, "q", (6,))
        return cls(as_array(t, "t"), q, ur_vector_from_pose(robot.fk(q)), meta)

    @property
    def n(self) -> int:
        """The number of samples M."""
        return int(self.t.size)

    @property
    def period(self) -> float:
        """The median sampling period (s)."""
        return float(np.median(np.diff(self.t))) if self.t.size > 1 else 0.0

    @property
    def duration(self) -> float:
        """Time from the first sample to the last [s] (0 for a single sample)."""
        return float(self.t[-1] - self.t[0])

    def tcp_poses(self) -> FloatArray:
        """TCP poses (M, 4, 4) in the robot base frame."""
        return pose_from_ur_vector(self.tcp)

    def rates(self) -> tuple[FloatArray, FloatArray]:
        """Finite-difference joint speeds (M-1, 6) and accelerations (M-2, 6)."""
        return finite_difference_rates(self.t, self.q)

    def inside_stock(self) -> np.ndarray:
        """(M,) bool: the wire is inside the stock at sample k."""
        mask = np.zeros(self.n, dtype=bool)
        for a, b in self.meta.in_stock:
            mask[a:b] = True
        return mask

    def wire_in_stock(self) -> WireInStock | None:
        """Return the wire against the block along these samples, or None.

        The one model, :mod:`..wire.in_stock`; None when the metadata names no cut."""
        if self.meta.cut is None:
            return None
        return self.meta.cut.measure(self.t, self.tcp_poses())

    def face_errors(
        self, wis: WireInStock | None = None, heat_power: ArrayLike | None = None
    ) -> dict:
        """Return ``face_error`` per cut (:func:`..wire.face.face_errors`) of a motion.

        Of this motion -- or of ``wis``, the wire of a motion measured against this
        trajectory's block (an exported program's, a run's recording) -- with the wire's power
        from ``heat_power`` (M,) W/m, recorded set-points (default: this trajectory's), delayed
        by the heat's lag; {} when the sidecar names no face."""
        from ..wire.face import face_errors

        cut = self.meta.cut
        if cut is None or not cut.faces:
            return {}
        wis = self.wire_in_stock() if wis is None else wis
        power = self.wire_power(wis.t, heat_power)
        return face_errors(wis, power, cut.material, cut.faces)

    def wire_power(
        self, t: ArrayLike | None = None, heat_power: ArrayLike | None = None
    ) -> FloatArray | None:
        """The wire's power (M,) [W/m]: the set-points delayed by the heat's lag.

        At times ``t`` (default: this trajectory's) of the set-points ``heat_power``
        (default: this trajectory's), by :func:`..wire.kerf.wire_power`: what
        :meth:`face_errors` judges the kerf with; None without set-points."""
        from ..wire.kerf import wire_power

        hp = self.heat_power if heat_power is None else heat_power
        if hp is None:
            return None
        lag = 0.0 if self.meta.heat is None else self.meta.heat.lag
        return wire_power(self.t if t is None else t, hp, lag)

    def phase_at(self, k: int) -> str:
        """The name of the phase sample ``k`` belongs to (``"move"`` if none is named)."""
        for p in self.meta.phases:
            if p.start <= k < p.stop:
                return p.name
        return "move"

    def tcp_error(self, model: RobotModel | None = None) -> tuple[float, float, int]:
        """Return the largest distance between the TCP column and FK(q) · tcp_offset.

        (metres, radians, the sample where the position error is largest).  ``model`` defaults
        to :func:`model_for` of the metadata."""
        robot = (model_for(self.meta) if model is None else model).with_base(np.eye(4))
        T = robot.fk(self.q)
        P = self.tcp_poses()
        dp = np.linalg.norm(T[:, :3, 3] - P[:, :3, 3], axis=1)
        ang = angle_between(T, P)
        k = int(np.argmax(dp))
        return float(dp[k]), float(ang.max()), k

    def sliced(self, start: int, stop: int | None = None) -> Trajectory:
        """Return samples ``start:stop`` with times from 0.

        Phases, ``in_stock`` ranges, the cut's feed windows and the heat's windows clipped and
        renumbered to them."""
        stop = self.n if stop is None else stop
        if not 0 <= start < stop <= self.n:
            raise ValueError(f"slice [{start}, {stop}) outside the {self.n} samples")

        def clip(a: int, b: int) -> tuple[int, int] | None:
            a, b = max(a, start) - start, min(b, stop) - start
            return (a, b) if a < b else None

        phases = tuple(
            Phase(p.name, *c) for p in self.meta.phases if (c := clip(p.start, p.stop))
        )
        stock = tuple(c for a, b in self.meta.in_stock if (c := clip(a, b)))
        cut = None if self.meta.cut is None else self.meta.cut.sliced(start, stop)
        heat = self.meta.heat
        if heat is not None:  # its windows renumbered too (they stayed the whole plan's)
            windows = tuple(c for a, b in heat.windows if (c := clip(a, b)))
            heat = dataclasses.replace(heat, windows=windows)
        meta = self.meta.replace(phases=phases, in_stock=stock, cut=cut, heat=heat)
        rows = slice(start, stop)
        return self.with_samples(self.t[rows] - self.t[start], self.q[rows], self.tcp[rows],
                                 meta, rows)  # fmt: skip


def phases_from_labels(labels: ArrayLike) -> tuple[Phase, ...]:
    """Runs of equal labels (M,) (phase names) as :class:`Phase` ranges."""
    lab = np.asarray(labels)
    if lab.size == 0:
        return ()
    cut = np.flatnonzero(lab[1:] != lab[:-1]) + 1
    starts = np.r_[0, cut]
    stops = np.r_[cut, lab.size]
    return tuple(Phase(str(lab[a]), int(a), int(b)) for a, b in zip(starts, stops, strict=True))


