r"""A robot's factory calibration as data: effective DH table, checksums, file format, checks.

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

File format (JSON, one object; lengths in metres, angles in radians)::

    {"format": "ruledrobot.calibration/1",
     "model": "ur5e",
     "source": "controller 192.168.1.10",
     "status": 2,
     "checksum": [3005486464, 2969637617, 688696456, 2832462165, 2830625259, 2832973731],
     "dh": {"theta_offset": [6 numbers], "a": [6], "d": [6], "alpha": [6]}}

``format``, ``model`` and ``dh`` are required; ``source`` defaults to the file's
path, ``status`` and ``checksum`` to null.  The DH values are the *effective*
ones (what the controller reports), written with 17 significant digits so that a
file read back gives the same table bit for bit.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ._checks import FloatArray, readonly

if TYPE_CHECKING:
    from ..protocol.primary import KinematicsInfo
    from .model import RobotModel

__all__ = [
    "CALIBRATION_FORMAT",
    "DEFAULT_BOUNDS",
    "STATUS_TEXT",
    "Calibration",
    "CalibrationBounds",
    "CalibrationError",
    "calibration_deviations",
    "dh_from_axes",
    "load_calibration",
    "random_calibration",
    "save_calibration",
    "zero_frames",
]

CALIBRATION_FORMAT = "ruledrobot.calibration/1"
#: The calibration status codes of a UR controller (its ``calibration.conf``:
#: ``0 == notInitialized / 1 == notLinearised / 2 == Linearised``).
STATUS_TEXT = {0: "not initialized", 1: "not linearised", 2: "linearised"}
_COLUMNS = ("theta_offset", "a", "d", "alpha")
_TWO_PI = 2.0 * math.pi


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


def _wrap(x: float) -> float:
    """``x`` modulo 2 pi in (-pi, pi]."""
    y = math.remainder(x, _TWO_PI)
    return math.pi if y == -math.pi else y


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


def _nominal_model(model: str) -> RobotModel:
    from .catalogue import MODEL_NAMES, load

    key = model.strip().lower() if isinstance(model, str) else None
    if key not in MODEL_NAMES:
        raise CalibrationError(
            f"model: {model!r} is not a catalogue model; valid names: {', '.join(MODEL_NAMES)}"
        )
    return load(key)


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
        """(6, 4) per joint ``[theta_offset, a, d, alpha]`` (the column order of
        :class:`ruledrobot.robot.KinematicsRef`)."""
        return np.stack([self.theta_offset, self.a, self.d, self.alpha], axis=1)

    def deltas(self) -> FloatArray:
        """(6, 4) effective minus nominal ``[theta_offset, a, d, alpha]`` (angles not
        wrapped): what a controller's ``calibration.conf`` calls ``delta_theta`` ...
        ``delta_alpha``."""
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
        """This calibration as the primary interface's KinematicsInfo (checksums 0 if unknown,
        status 2 "linearised" if unknown)."""
        from ..protocol.primary import KinematicsInfo

        return KinematicsInfo(
            checksum=self.checksum if self.checksum is not None else (0,) * 6,
            theta=np.array(self.theta_offset), a=np.array(self.a), d=np.array(self.d),
            alpha=np.array(self.alpha),
            calibration_status=2 if self.status is None else self.status,
        )  # fmt: skip

    def with_source(self, source: str) -> Calibration:
        """The same calibration with another ``source``."""
        return Calibration(self.model, self.theta_offset, self.a, self.d, self.alpha,
                           checksum=self.checksum, source=source, status=self.status,
                           bounds=self.bounds)  # fmt: skip

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


def _signed_angle(u: FloatArray, v: FloatArray, axis: FloatArray) -> float:
    """Angle turning ``u`` into ``v`` about ``axis`` (unit vectors, u and v normal to axis)."""
    return math.atan2(float(np.cross(u, v) @ axis), float(u @ v))


def dh_from_axes(
    points: ArrayLike,
    directions: ArrayLike,
    flange: ArrayLike,
    reference_x: ArrayLike | None = None,
) -> FloatArray:
    """The standard-DH table of a 6R arm given its joint axes at ``q = 0``.

    Parameters
    ----------
    points, directions : (6, 3) a point and the unit direction of each joint axis in
        the base frame; axis 1 must be the base z axis through the origin.
    flange : (4, 4) the flange frame at ``q = 0``; its z axis must lie on axis 6.
    reference_x : optional (6, 3) x axes of frames 1..6 the result should follow
        (a common normal has two directions; the one nearer the reference is taken,
        so that a perturbed UR keeps the signs of its nominal ``a`` and ``alpha``).

    Returns
    -------
    (6, 4) per joint ``[theta_offset, a, d, alpha]``.  Frame ``i`` sits at the foot on
    axis ``i + 1`` of the common normal of axes ``i`` and ``i + 1``; for parallel
    axes the foot of the previous frame's origin (so ``d_i = 0``).  Nearly parallel
    axes give the far-away common normal, hence the large ``d`` of real calibrations.
    """
    P = np.asarray(points, dtype=np.float64).reshape(6, 3)
    U = np.asarray(directions, dtype=np.float64).reshape(6, 3)
    F = np.asarray(flange, dtype=np.float64).reshape(4, 4)
    U = U / np.linalg.norm(U, axis=1, keepdims=True)
    o = np.zeros(3)
    x = np.array([1.0, 0.0, 0.0])
    z = U[0]
    if (
        np.linalg.norm(z - np.array([0.0, 0.0, 1.0])) > 1e-12
        or np.linalg.norm(np.cross(P[0], z)) > 1e-12
    ):
        raise ValueError("directions[0]: axis 1 must be the base z axis through the origin")
    out = np.zeros((6, 4))
    for i in range(5):
        v, p = U[i + 1], P[i + 1]
        n = np.cross(z, v)
        nn = float(np.linalg.norm(n))
        w = o - p
        if nn < 1e-14:  # parallel: foot of the previous origin
            t1 = 0.0
            foot2 = p + (w @ v) * v
            xi = foot2 - o
            length = float(np.linalg.norm(xi))
            xi = xi / length if length > 1e-15 else (x if reference_x is None else
                                                       np.asarray(reference_x)[i])  # fmt: skip
        else:
            b = float(z @ v)
            dz, ev = float(z @ w), float(v @ w)
            den = nn * nn
            t1 = (b * ev - dz) / den
            t2 = (ev - b * dz) / den
            foot2 = p + t2 * v
            xi = n / nn
        if reference_x is not None and xi @ np.asarray(reference_x, dtype=np.float64)[i] < 0.0:
            xi = -xi
        foot1 = o + t1 * z
        out[i] = (_signed_angle(x, xi, z), float((foot2 - foot1) @ xi), t1, _signed_angle(z, v, xi))
        o, x, z = foot2, xi, v
    # joint 6: the flange z lies on axis 6
    zf, of, xf = F[:3, 2], F[:3, 3], F[:3, 0]
    if np.linalg.norm(np.cross(z, zf)) > 1e-9 or np.linalg.norm(np.cross(of - o, z)) > 1e-9:
        raise ValueError("flange: its z axis must lie on axis 6")
    out[5] = (_signed_angle(x, xf, z), 0.0, float((of - o) @ z), 0.0)
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
    delta[:, 0] = [_wrap(v) for v in delta[:, 0]]
    delta[:, 3] = [_wrap(v) for v in delta[:, 3]]
    Fn = zero_frames(m.theta_offset, m.a, m.d, m.alpha)
    Fc = zero_frames(cal.theta_offset, cal.a, cal.d, cal.alpha)
    tilt, offset = np.zeros(6), np.zeros(6)
    for i in range(6):
        zn, zc = Fn[i, :3, 2], Fc[i, :3, 2]
        tilt[i] = math.atan2(float(np.linalg.norm(np.cross(zn, zc))), float(zn @ zc))
        offset[i] = float(np.linalg.norm(np.cross(Fn[i, :3, 3] - Fc[i, :3, 3], zc)))
    R = Fn[6, :3, :3].T @ Fc[6, :3, :3]
    rot = math.acos(max(-1.0, min(1.0, (float(np.trace(R)) - 1.0) / 2.0)))
    return {
        "delta": delta,
        "d_sum": float(delta[1:4, 2].sum()),
        "theta_sum": _wrap(float(delta[1:4, 0].sum())),
        "axis_tilt": tilt,
        "axis_offset": offset,
        "flange_position": float(np.linalg.norm(Fn[6, :3, 3] - Fc[6, :3, 3])),
        "flange_rotation": rot,
    }


def _check_plausible(cal: Calibration, nominal: RobotModel) -> None:
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


# ---------------------------------------------------------------------- random calibrations


def _small_rotation(rng: np.random.Generator, axis: FloatArray, sigma: float) -> FloatArray:
    """A rotation matrix by a random vector normal to ``axis`` (each component ~ N(0, sigma))."""
    w = rng.normal(0.0, sigma, 3)
    w -= (w @ axis) * axis
    angle = float(np.linalg.norm(w))
    if angle == 0.0:
        return np.eye(3)
    k = w / angle
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * (K @ K)


def random_calibration(
    model: str | RobotModel = "ur5e", seed: int = 0, *, scale: float = 1.0
) -> Calibration:
    """A seeded, realistic factory calibration of ``model`` (for tests and demos).

    Built the way a real one arises: the nominal joint axes at ``q = 0`` are tilted
    (each by a random rotation of about ``1.5e-3 * scale`` rad per component, normal to
    it) and moved (about ``0.3 mm * scale`` per component), the flange is moved along
    axis 6 and turned about it, each joint zero is offset by about ``3e-5 * scale`` rad,
    and the DH table is then read off the perturbed axes (:func:`dh_from_axes`).  As in
    real calibrations, the nearly parallel axes 2-4 get large, nearly cancelling
    ``d2..d4`` and ``theta2..4``.  Axis 1 stays the base z axis.  A draw the checks
    refuse (at ``scale`` 1 rarely: ``d`` beyond 10 km when two axes come out parallel
    to 1e-7 rad) is drawn again, up to 20 times; at ``scale`` 10 nearly all are
    refused and the last refusal is raised.
    """
    name = model if isinstance(model, str) else model.name
    nom = _nominal_model(name)
    rng = np.random.default_rng(seed)
    source = f"seeded random (seed {seed}" + (f", scale {scale:g})" if scale != 1.0 else ")")
    for attempt in range(_ATTEMPTS):
        try:
            return _random_attempt(nom, rng, scale, source)
        except CalibrationError:
            if attempt == _ATTEMPTS - 1:
                raise
    raise AssertionError("unreachable")  # pragma: no cover


_ATTEMPTS = 20


def _random_attempt(
    nom: RobotModel, rng: np.random.Generator, scale: float, source: str
) -> Calibration:
    F = zero_frames(nom.theta_offset, nom.a, nom.d, nom.alpha)
    points = F[:6, :3, 3].copy()
    dirs = F[:6, :3, 2].copy()
    tilt, shift = 1.5e-3 * scale, 3e-4 * scale
    for i in range(1, 6):
        dirs[i] = _small_rotation(rng, dirs[i], tilt) @ dirs[i]
        dirs[i] /= np.linalg.norm(dirs[i])
        dp = rng.normal(0.0, shift, 3)
        points[i] = points[i] + dp - (dp @ dirs[i]) * dirs[i]
    # flange: on the new axis 6, near the nominal flange origin, x turned about the axis
    z6 = dirs[5]
    of = points[5] + ((F[6, :3, 3] - points[5]) @ z6) * z6 + rng.normal(0.0, shift) * z6
    x6 = F[6, :3, 0] - (F[6, :3, 0] @ z6) * z6
    x6 /= np.linalg.norm(x6)
    turn = rng.normal(0.0, 1e-4 * scale)
    x6 = math.cos(turn) * x6 + math.sin(turn) * np.cross(z6, x6)
    flange = np.eye(4)
    flange[:3, 0], flange[:3, 1], flange[:3, 2], flange[:3, 3] = x6, np.cross(z6, x6), z6, of
    table = dh_from_axes(points, dirs, flange, reference_x=F[1:, :3, 0])
    table[:, 0] += rng.normal(0.0, 3e-5 * scale, 6)
    table[:, 0] = [_wrap(v) for v in table[:, 0]]
    checksum = tuple(int(c) for c in rng.integers(0, 2**32, 6))
    return Calibration.from_dh(nom.name, table, checksum=checksum, source=source, status=2)


# ---------------------------------------------------------------------- files


def _to_dict(cal: Calibration) -> dict[str, Any]:
    return {
        "format": CALIBRATION_FORMAT,
        "model": cal.model,
        "source": cal.source,
        "status": cal.status,
        "checksum": None if cal.checksum is None else list(cal.checksum),
        "dh": {name: [float(v) for v in getattr(cal, name)] for name in _COLUMNS},
    }


def save_calibration(path: str | os.PathLike[str], cal: Calibration) -> Path:
    """Write ``cal`` as a ``ruledrobot.calibration/1`` JSON file (atomically); returns the path."""
    if not isinstance(cal, Calibration):
        raise TypeError(f"save_calibration: expected a Calibration, got {type(cal).__name__}")
    target = Path(path)
    text = json.dumps(_to_dict(cal), indent=2) + "\n"
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, 0o644)
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise
    return target


def load_calibration(path: str | os.PathLike[str]) -> Calibration:
    """Read a ``ruledrobot.calibration/1`` JSON file.

    Every error is a :class:`CalibrationError` (a ``ValueError``) naming the file and
    the field, e.g. ``cal.json: dh.d[2] (joint 3 (elbow)): not a finite number`` or
    ``cal.json: joint 4 (wrist 1): alpha = ... differs from the nominal ...``.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise CalibrationError(f"{p}: no such calibration file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise CalibrationError(f"{p}: cannot read ({exc})") from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise CalibrationError(f"{p}: not JSON (line {exc.lineno}: {exc.msg})") from None
    if not isinstance(doc, dict):
        raise CalibrationError(f"{p}: expected a JSON object, got {type(doc).__name__}")
    fmt = doc.get("format")
    if fmt != CALIBRATION_FORMAT:
        raise CalibrationError(f"{p}: format: expected {CALIBRATION_FORMAT!r}, got {fmt!r}")
    for key in ("model", "dh"):
        if key not in doc:
            raise CalibrationError(f"{p}: {key}: missing")
    unknown = sorted(set(doc) - {"format", "model", "source", "status", "checksum", "dh"})
    if unknown:
        raise CalibrationError(f"{p}: {unknown[0]}: unknown field")
    dh = doc["dh"]
    if not isinstance(dh, dict):
        raise CalibrationError(f"{p}: dh: expected an object with {', '.join(_COLUMNS)}")
    cols = {}
    for name in _COLUMNS:
        if name not in dh:
            raise CalibrationError(f"{p}: dh.{name}: missing")
        values = dh[name]
        if not isinstance(values, list) or any(
            isinstance(v, bool) or not isinstance(v, (int, float)) for v in values
        ):
            raise CalibrationError(f"{p}: dh.{name}: expected a list of 6 numbers, got {values!r}")
        try:
            cols[name] = _column(values, f"dh.{name}")
        except CalibrationError as exc:
            raise CalibrationError(f"{p}: {exc}") from None
    extra = sorted(set(dh) - set(_COLUMNS))
    if extra:
        raise CalibrationError(f"{p}: dh.{extra[0]}: unknown field")
    if not isinstance(doc["model"], str):
        raise CalibrationError(f"{p}: model: expected a string, got {doc['model']!r}")
    source = doc.get("source")
    if source is None:
        source = str(p)
    try:
        return Calibration(doc["model"], cols["theta_offset"], cols["a"], cols["d"],
                           cols["alpha"], checksum=doc.get("checksum"), source=source,
                           status=doc.get("status"))  # fmt: skip
    except CalibrationError as exc:
        raise CalibrationError(f"{p}: {exc}") from None
