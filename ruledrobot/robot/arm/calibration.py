r"""A robot's factory calibration as data: effective DH table, checksums, plausibility checks.

Every UR leaves the factory with its own kinematics: the nominal DH table of
its model plus per-robot corrections.  The controller reports the result on its
primary interface (KinematicsInfo, :mod:`ruledrobot.protocol.primary`): six
``uint32`` checksums (one per joint), the *effective* ``dh_theta``, ``dh_a``,
``dh_d``, ``dh_alpha`` and a calibration status.  A :class:`Calibration` holds
exactly that, plus the model it belongs to and where it came from.

The corrections are small in the arm's geometry (joint axes moved by a fraction
of a millimetre, tilted by milliradians; the flange a few millimetres away from
the nominal FK) but **not** in the DH numbers: joints 2, 3 and 4 of a UR are
nearly parallel, and the DH frames of nearly parallel axes sit at their common
normal, far away.  Real calibrations move ``d2``, ``d3``, ``d4`` by metres to
hundreds of metres with values that nearly cancel (``d2 + d3 + d4`` stays within
a millimetre or two of the nominal), turn ``theta2..4`` by up to a few radians
(their sum stays within 1e-4 rad, modulo 2 pi) and change ``a2``, ``a3`` by
centimetres to decimetres.  The checks here therefore bound what is physical:

* the parameters a calibration does not mix (``d1, d5, d6``, ``a1, a4, a5, a6``,
  every ``alpha``, ``theta1, theta5, theta6``), each against its nominal value;
* the sums ``d2 + d3 + d4`` and ``theta2 + theta3 + theta4`` (mod 2 pi);
* the geometry at ``q = 0``: every joint axis (its tilt from the nominal axis,
  the distance of the nominal axis point from it) and the flange frame;
* ``|d|`` and ``|a|`` below 10 km (beyond, rounding in the FK exceeds 1e-12 m).

The bounds (:class:`CalibrationBounds`) are 2.5-10 times the largest deviation
in the real calibrations collected in ``docs/robot.md`` ("Calibration").

Files (``ruledrobot.calibration/1``) are read and written by
:mod:`ruledrobot.io.calibration`; seeded random calibrations of realistic size are
made by :mod:`.calibration_random`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ...geometry.angles import wrap_angle
from ...geometry.rotations import angle_between
from .._checks import FloatArray, readonly
from .ur_tables import MODEL_NAMES, NominalDH, nominal_dh

if TYPE_CHECKING:
    from ...protocol.primary import KinematicsInfo

__all__ = [
    "DEFAULT_BOUNDS",
    "STATUS_TEXT",
    "Calibration",
    "CalibrationBounds",
    "CalibrationError",
    "calibration_deviations",
    "zero_frames",
]

#: The calibration status codes of a UR controller (its ``calibration.conf``:
#: ``0 == notInitialized / 1 == notLinearised / 2 == Linearised``).
STATUS_TEXT = {0: "not initialized", 1: "not linearised", 2: "linearised"}
_COLUMNS = ("theta_offset", "a", "d", "alpha")


class CalibrationError(ValueError):
    """A calibration that is malformed, of another model or implausible (names the field)."""


@dataclass(frozen=True)
class CalibrationBounds:
    """Largest accepted deviation of a calibration from its model's nominal table.

    The real calibrations in ``docs/robot.md`` reach: 0.9 mm on the direct lengths,
    0.0135 rad on alpha, 7.5e-5 rad on theta 1/5/6, 1.5 mm on ``d2 + d3 + d4``,
    7e-5 rad on ``theta2 + theta3 + theta4``, axes tilted 20.5 mrad and moved
    4.1 mm, the flange at ``q = 0`` 6.3 mm and 0.020 rad away.
    """

    length: float = 0.005  #: d1, d5, d6, a1, a4, a5, a6 [m]
    angle: float = 0.05  #: every alpha; theta1, theta5, theta6 [rad]
    d_sum: float = 0.005  #: d2 + d3 + d4 [m]
    theta_sum: float = 0.05  #: theta2 + theta3 + theta4, modulo 2 pi [rad]
    axis_tilt: float = 0.05  #: joint axis direction at q = 0 [rad]
    axis_offset: float = 0.02  #: distance of the nominal axis point from the axis [m]
    flange_position: float = 0.025  #: flange origin at q = 0 [m]
    flange_rotation: float = 0.05  #: flange orientation at q = 0 [rad]
    magnitude: float = 10_000.0  #: |d| and |a| of any joint [m]


DEFAULT_BOUNDS = CalibrationBounds()

_JOINT_NAMES = ("base", "shoulder", "elbow", "wrist 1", "wrist 2", "wrist 3")


def _joint(i: int) -> str:
    return f"joint {i + 1} ({_JOINT_NAMES[i]})"


def _column(value: ArrayLike, name: str) -> FloatArray:
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise CalibrationError(f"{name}: expected 6 numbers, got {value!r}") from None
    if arr.shape != (6,):
        raise CalibrationError(f"{name}: expected 6 numbers (one per joint), got shape {arr.shape}")
    bad = ~np.isfinite(arr)
    if bad.any():
        i = int(np.argmax(bad))
        raise CalibrationError(f"{name}[{i}] ({_joint(i)}): not a finite number ({arr[i]})")
    return readonly(arr)


def _nominal_model(model: str) -> NominalDH:
    key = model.strip().lower() if isinstance(model, str) else None
    if key not in MODEL_NAMES:
        raise CalibrationError(
            f"model: {model!r} is not a catalogue model; valid names: {', '.join(MODEL_NAMES)}"
        )
    return nominal_dh(key)


@dataclass(frozen=True, eq=False)
class Calibration:
    """The effective kinematics of one robot: its model's DH table with the factory corrections.

    Attributes
    ----------
    model : catalogue model name (``"ur5e"``).
    theta_offset, a, d, alpha : (6,) effective standard-DH parameters [rad, m, m, rad],
        ``A_i = Rz(q_i + theta_offset_i) Tz(d_i) Tx(a_i) Rx(alpha_i)`` (what the
        controller reports as ``dh_theta``, ``dh_a``, ``dh_d``, ``dh_alpha``).
    checksum : the controller's six per-joint ``uint32`` checksums, or None.
    source : where it came from (``"controller 192.168.1.10"``, a file path,
        ``"seeded random (seed 3)"``, ``"nominal"``).
    status : the controller's calibration status (:data:`STATUS_TEXT`), or None.

    Construction checks everything: shapes and finite values, the model name, and
    the deviations from the nominal table against ``bounds``
    (:class:`CalibrationBounds`).  A :class:`CalibrationError` (a ``ValueError``)
    names the joint and the parameter.
    """

    model: str
    theta_offset: FloatArray
    a: FloatArray
    d: FloatArray
    alpha: FloatArray
    checksum: tuple[int, ...] | None = None
    source: str = ""
    status: int | None = None
    bounds: CalibrationBounds = field(default=DEFAULT_BOUNDS, repr=False)

    def __post_init__(self) -> None:
        put = object.__setattr__
        nominal = _nominal_model(self.model)
        put(self, "model", nominal.name)
        for name in _COLUMNS:
            put(self, name, _column(getattr(self, name), name))
        if self.checksum is not None:
            put(self, "checksum", _checksums(self.checksum))
        if not isinstance(self.source, str):
            raise CalibrationError(f"source: expected a string, got {self.source!r}")
        if self.status is not None:
            if isinstance(self.status, bool) or not isinstance(self.status, (int, np.integer)):
                raise CalibrationError(f"status: expected an integer or None, got {self.status!r}")
            if not 0 <= int(self.status) < 2**32:
                raise CalibrationError(f"status: expected a uint32, got {self.status}")
            put(self, "status", int(self.status))
        if not isinstance(self.bounds, CalibrationBounds):
            raise CalibrationError(f"bounds: expected CalibrationBounds, got {self.bounds!r}")
        _check_plausible(self, nominal)

    # ------------------------------------------------------------------ construction

    @classmethod
    def from_dh(
        cls,
        model: str,
        dh: ArrayLike,
        *,
        checksum: tuple[int, ...] | None = None,
        source: str = "",
        status: int | None = None,
        bounds: CalibrationBounds = DEFAULT_BOUNDS,
    ) -> Calibration:
        """From a (6, 4) table, per joint ``[theta_offset, a, d, alpha]`` (ruledrobot's order)."""
        table = np.asarray(dh, dtype=np.float64)
        if table.shape != (6, 4):
            raise CalibrationError(f"dh: expected shape (6, 4), got {table.shape}")
        return cls(model, table[:, 0], table[:, 1], table[:, 2], table[:, 3],
                   checksum=checksum, source=source, status=status, bounds=bounds)  # fmt: skip

    @classmethod
    def from_kinematics_info(
        cls, info: KinematicsInfo, model: str, source: str = "controller"
    ) -> Calibration:
        """From a controller's KinematicsInfo (:mod:`ruledrobot.protocol.primary`).

        The primary interface does not say which model the robot is: pass it.
        """
        return cls(model, info.theta, info.a, info.d, info.alpha,
                   checksum=tuple(int(c) for c in info.checksum), source=source,
                   status=int(info.calibration_status))  # fmt: skip

    @classmethod
    def nominal(cls, model: str) -> Calibration:
        """The uncalibrated table of ``model`` (what an emulator without calibration reports)."""
        m = _nominal_model(model)
        return cls(m.name, m.theta_offset, m.a, m.d, m.alpha, source="nominal")

    # ------------------------------------------------------------------ views

    def dh(self) -> FloatArray:
        """Return the DH table (6, 4): per joint ``[theta_offset, a, d, alpha]``.

        The column order of :class:`ruledrobot.robot.KinematicsRef`.
        """
        return np.stack([self.theta_offset, self.a, self.d, self.alpha], axis=1)

    def deltas(self) -> FloatArray:
        """(6, 4) effective minus nominal ``[theta_offset, a, d, alpha]`` (angles not wrapped).

        What a controller's ``calibration.conf`` calls ``delta_theta`` ... ``delta_alpha``."""
        m = _nominal_model(self.model)
        return self.dh() - np.stack([m.theta_offset, m.a, m.d, m.alpha], axis=1)

    @property
    def is_nominal(self) -> bool:
        """True when the effective table equals the catalogue's nominal table exactly."""
        return bool(np.all(self.deltas() == 0.0))

    @property
    def status_text(self) -> str:
        """The calibration status in words (``"linearised"``), ``"unknown"`` when not set."""
        if self.status is None:
            return "unknown"
        return STATUS_TEXT.get(self.status, f"code {self.status}")

    def kinematics_info(self) -> KinematicsInfo:
        """Return this calibration as the primary interface's KinematicsInfo.

        Checksums 0 if unknown, status 2 "linearised" if unknown.
        """
        from ...protocol.primary import KinematicsInfo

        return KinematicsInfo(
            checksum=self.checksum if self.checksum is not None else (0,) * 6,
            theta=np.array(self.theta_offset), a=np.array(self.a), d=np.array(self.d),
            alpha=np.array(self.alpha),
            calibration_status=2 if self.status is None else self.status,
        )  # fmt: skip


    def __repr__(self) -> str:
        kind = "nominal" if self.is_nominal else "calibrated"
        src = f", source={self.source!r}" if self.source else ""
        return f"Calibration({self.model!r}, {kind}{src}, status={self.status_text})"


def _checksums(value: Any) -> tuple[int, ...]:
    try:
        items = list(value)
    except TypeError:
        raise CalibrationError(f"checksum: expected 6 integers, got {value!r}") from None
    if len(items) != 6:
        raise CalibrationError(f"checksum: expected 6 integers (one per joint), got {len(items)}")
    out = []
    for i, c in enumerate(items):
        if isinstance(c, str):
            try:
                c = int(c, 0)
            except ValueError:
                raise CalibrationError(f"checksum[{i}]: expected an integer, got {c!r}") from None
        if isinstance(c, bool) or not isinstance(c, (int, np.integer)) or not 0 <= c < 2**32:
            raise CalibrationError(f"checksum[{i}] ({_joint(i)}): expected a uint32, got {c!r}")
        out.append(int(c))
    return tuple(out)


# ---------------------------------------------------------------------- geometry


def zero_frames(
    theta_offset: ArrayLike, a: ArrayLike, d: ArrayLike, alpha: ArrayLike
) -> FloatArray:
    """The DH frames 0..J at ``q = 0``: (J + 1, 4, 4), frame 0 the identity.

    Joint ``i`` (1-based) turns about the z axis of frame ``i - 1``.
    """
    th, aa, dd, al = (np.asarray(v, dtype=np.float64) for v in (theta_offset, a, d, alpha))
    out = np.empty((th.shape[0] + 1, 4, 4))
    out[0] = np.eye(4)
    for i in range(th.shape[0]):
        ct, st, ca, sa = math.cos(th[i]), math.sin(th[i]), math.cos(al[i]), math.sin(al[i])
        A = np.array([[ct, -st * ca, st * sa, aa[i] * ct],
                      [st, ct * ca, -ct * sa, aa[i] * st],
                      [0.0, sa, ca, dd[i]],
                      [0.0, 0.0, 0.0, 1.0]])  # fmt: skip
        out[i + 1] = out[i] @ A
    return out


def calibration_deviations(cal: Calibration) -> dict[str, Any]:
    """The physical deviations of ``cal`` from its nominal table (what the bounds check).

    Keys: ``"length"`` (6, 4) per joint and column the effective-minus-nominal value
    (angles wrapped), ``"d_sum"`` [m], ``"theta_sum"`` [rad], ``"axis_tilt"`` (6,) rad,
    ``"axis_offset"`` (6,) m, ``"flange_position"`` m, ``"flange_rotation"`` rad.
    """
    m = _nominal_model(cal.model)
    nominal = np.stack([m.theta_offset, m.a, m.d, m.alpha], axis=1)
    delta = cal.dh() - nominal
    delta[:, 0] = wrap_angle(delta[:, 0])
    delta[:, 3] = wrap_angle(delta[:, 3])
    Fn = zero_frames(m.theta_offset, m.a, m.d, m.alpha)
    Fc = zero_frames(cal.theta_offset, cal.a, cal.d, cal.alpha)
    tilt, offset = np.zeros(6), np.zeros(6)
    for i in range(6):
        zn, zc = Fn[i, :3, 2], Fc[i, :3, 2]
        tilt[i] = math.atan2(float(np.linalg.norm(np.cross(zn, zc))), float(zn @ zc))
        offset[i] = float(np.linalg.norm(np.cross(Fn[i, :3, 3] - Fc[i, :3, 3], zc)))
    rot = float(angle_between(Fn[6], Fc[6]))
    return {
        "delta": delta,
        "d_sum": float(delta[1:4, 2].sum()),
        "theta_sum": float(wrap_angle(delta[1:4, 0].sum())),
        "axis_tilt": tilt,
        "axis_offset": offset,
        "flange_position": float(np.linalg.norm(Fn[6, :3, 3] - Fc[6, :3, 3])),
        "flange_rotation": rot,
    }


def _check_plausible(cal: Calibration, nominal: NominalDH) -> None:
    b = cal.bounds
    table = cal.dh()
    for i in range(6):
        for k, col in ((1, "a"), (2, "d")):
            v = float(table[i, k])
            if abs(v) > b.magnitude:
                raise CalibrationError(
                    f"{_joint(i)}: {col} = {v:.6g} m is beyond {b.magnitude:g} m (numerically "
                    "meaningless: FK rounding grows as |d| x 1e-16)"
                )
    dev = calibration_deviations(cal)
    delta = dev["delta"]
    nom = np.stack([nominal.theta_offset, nominal.a, nominal.d, nominal.alpha], axis=1)
    checks: list[tuple[int, int, str, float, str]] = []
    for i in (0, 4, 5):
        checks.append((i, 2, "d", b.length, "m"))
        checks.append((i, 0, "theta_offset", b.angle, "rad"))
    for i in (0, 3, 4, 5):
        checks.append((i, 1, "a", b.length, "m"))
    for i in range(6):
        checks.append((i, 3, "alpha", b.angle, "rad"))
    for i, k, col, bound, unit in checks:
        if abs(delta[i, k]) > bound:
            raise CalibrationError(
                f"{_joint(i)}: {col} = {table[i, k]:.9g} {unit} differs from the nominal "
                f"{nom[i, k]:.9g} {unit} of the {cal.model} by {delta[i, k]:+.3g} {unit} "
                f"(bound {bound:g} {unit})"
            )
    if abs(dev["d_sum"]) > b.d_sum:
        raise CalibrationError(
            f"joints 2-4: d2 + d3 + d4 = {table[1:4, 2].sum():.6g} m differs from the nominal "
            f"{nom[1:4, 2].sum():.6g} m by {dev['d_sum'] * 1e3:+.3g} mm "
            f"(bound {b.d_sum * 1e3:g} mm)"
        )
    if abs(dev["theta_sum"]) > b.theta_sum:
        raise CalibrationError(
            f"joints 2-4: theta_offset2 + theta_offset3 + theta_offset4 differs from the nominal "
            f"sum by {dev['theta_sum']:+.3g} rad modulo 2 pi (bound {b.theta_sum:g} rad)"
        )
    for i in range(6):
        if dev["axis_tilt"][i] > b.axis_tilt:
            raise CalibrationError(
                f"{_joint(i)}: axis tilted {dev['axis_tilt'][i]:.3g} rad from its nominal "
                f"direction at q = 0 (bound {b.axis_tilt:g} rad; check alpha and theta_offset "
                f"of joints 1-{i})"
            )
        if dev["axis_offset"][i] > b.axis_offset:
            raise CalibrationError(
                f"{_joint(i)}: axis {dev['axis_offset'][i] * 1e3:.3g} mm from its nominal position "
                f"at q = 0 (bound {b.axis_offset * 1e3:g} mm; check a, d and theta_offset of "
                f"joints 1-{i})"
            )
    if dev["flange_position"] > b.flange_position:
        raise CalibrationError(
            f"flange: {dev['flange_position'] * 1e3:.3g} mm from its nominal position at q = 0 "
            f"(bound {b.flange_position * 1e3:g} mm)"
        )
    if dev["flange_rotation"] > b.flange_rotation:
        raise CalibrationError(
            f"flange: turned {dev['flange_rotation']:.3g} rad from its nominal orientation at "
            f"q = 0 (bound {b.flange_rotation:g} rad)"
        )


