"""MJCF generation of robot arms from their DH tables and inertial data.

:func:`robot_mjcf` writes a MuJoCo model of any :class:`~ruledrobot.robot.RobotModel`
(the UR catalogue or a custom DH arm) from its DH table and inertial data,
with primitive geometry only (cylinders and capsules, no meshes).
:func:`build_robot` builds the same element tree for callers that add to it
(the cell scene, :mod:`ruledrobot.sim.scene`); :class:`ServoGains`,
:func:`default_armature`, :func:`default_damping` and :func:`physics_timestep`
are the parameters shared with the playback and the inverse dynamics.
The serial chain whose joint axes are a sequence of lines (the paper's view of
a discrete ruled surface as a robot) is :func:`ruledrobot.sim.chain.chain_mjcf`.

Frames and names of the robot model (see ``docs/sim.md``):

* body ``base`` sits at ``model.base`` in the world; its frame is DH frame 0;
* body ``link{i}`` (i = 1..J) carries hinge ``joint{i}`` about its local z
  axis through its origin; at ``q = 0`` its frame is DH frame i-1 turned by
  ``theta_offset_i`` about z, so it moves with ``Rz(q_i)`` exactly as the DH
  link ``A_i = Rz(q_i + theta_offset_i) Tz(d_i) Tx(a_i) Rx(alpha_i)``;
* site ``flange`` = DH frame J (UR ``tool0``), site ``tcp`` = flange @ ``model.tool``;
* actuators ``pos{i}``, ``vel{i}``, ``ff{i}`` (control vector
  ``[q_ref (J), qd_ref (J), tau_ff (J)]``): a position servo, a velocity servo
  and a torque feed-forward on each joint, summed and clamped to the torque
  limit by the joint's ``actuatorfrcrange``; gravity is compensated by the
  actuators (``gravcomp`` on every moving body, ``actuatorgravcomp`` on every
  joint), so it counts against the torque limit too;
* sensors ``torque{i}`` (``jointactuatorfrc``: servo + feed-forward + gravity
  compensation, the joint torque), ``tcp_pos``, ``tcp_quat``.

The compiled model's kinematics equal ``model.fk`` to rounding (tested to 1e-9).
"""

from __future__ import annotations

import dataclasses
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..geometry.checks import FloatArray, as_per_joint
from ..robot.arm.model import RobotModel
from ..robot.arm.shape import Segment, dh_tail, link_radii, link_segments, rot_z
from ._xml import placed, sub, to_string

__all__ = [
    "ServoGains",
    "default_armature",
    "default_damping",
    "robot_mjcf",
]

#: Largest physics step [s]: the e-Series servo period.  Slower controllers
#: (CB3, 8 ms) are simulated with substeps of at most this size.
MAX_TIMESTEP = 0.002

# colours (UR-like: light grey links, blue joint caps, dark base)
_RGBA = {
    "link": "0.78 0.80 0.82 1",
    "joint": "0.25 0.50 0.72 1",
    "base": "0.22 0.23 0.25 1",
    "flange": "0.45 0.47 0.50 1",
}


# ---------------------------------------------------------------------------------------
# parameters shared by the MJCF writer, the playback and the inverse dynamics
# ---------------------------------------------------------------------------------------


def physics_timestep(control_period: float) -> float:
    """MuJoCo timestep [s] for a controller period [s].

    The control period itself when it is at most 2 ms (e-Series: the physics
    steps at the 500 Hz servo rate, one reference sample per step); otherwise
    the period divided into the fewest equal substeps of at most 2 ms (CB3:
    8 ms -> 4 x 2 ms), because the stiff joint servos need a 2 ms step to be
    integrated accurately.
    """
    period = float(control_period)
    if not period > 0.0:
        raise ValueError(f"control_period: must be positive, got {period}")
    n = max(1, math.ceil(period / MAX_TIMESTEP - 1e-9))
    return period / n


def default_armature(model: RobotModel) -> FloatArray:
    """Reflected rotor inertia per joint [kg m^2] (J,): ``1e-3 s^2 * tau_max``.

    UR do not publish rotor inertias.  Rotor inertia times the squared gear
    ratio grows with the drive size, i.e. with the torque limit; this rule
    gives 0.15 kg m^2 (UR5e shoulder) and 0.028 kg m^2 (UR5e wrists), close
    to MuJoCo Menagerie's 0.1 kg m^2.  Unlimited torque: 0.1 kg m^2.
    """
    tau = model.max_torque
    return np.where(np.isfinite(tau), 1e-3 * np.where(np.isfinite(tau), tau, 0.0), 0.1)


def default_damping(model: RobotModel) -> FloatArray:
    """Viscous joint friction [N m s/rad] (J,): ``0.02 s * tau_max`` (UR5e 3 / 0.56).

    Unknown for real UR drives; of the order of Menagerie's UR10e values
    (10 / 5 / 2).  The inverse-dynamics feed-forward compensates it.
    Unlimited torque: 1 N m s/rad.
    """
    tau = model.max_torque
    return np.where(np.isfinite(tau), 0.02 * np.where(np.isfinite(tau), tau, 0.0), 1.0)


@dataclass(frozen=True)
class ServoGains:
    """Joint servo gains: ``tau = kp (q_ref - q) + kv (qd_ref - qd) + tau_ff`` (+ gravity).

    ``kp`` (J,) [N m/rad], ``kv`` (J,) [N m s/rad].  :meth:`default` scales
    them with the drive size (the torque limit).
    """

    kp: FloatArray
    kv: FloatArray

    def __post_init__(self) -> None:
        for name in ("kp", "kv"):
            v = np.array(getattr(self, name), dtype=np.float64).reshape(-1)
            if not np.all(np.isfinite(v)) or np.any(v < 0.0):
                k = int(np.flatnonzero(~(np.isfinite(v) & (v >= 0.0)))[0])
                raise ValueError(f"servo gains {name}[{k}]: expected a finite value >= 0")
            v.setflags(write=False)
            object.__setattr__(self, name, v)
        if self.kp.shape != self.kv.shape:
            raise ValueError(f"servo gains: kp {self.kp.shape} and kv {self.kv.shape} differ")

    @classmethod
    def default(cls, model: RobotModel) -> ServoGains:
        """Return the default servo gains, proportional to each joint's torque limit.

        ``kp = 100 /rad * tau_max``, ``kv = 4 s/rad * tau_max`` (UR5e: 15000 / 600 on the
        big joints, 2800 / 112 on the wrists); unlimited torque: as for 150 N m.

        With the armature of :func:`default_armature` the wrist servo has a
        natural frequency ``sqrt(kp / armature) = 316 rad/s`` and is
        overdamped; the physics step of 2 ms resolves it (``omega dt = 0.63``)
        and ``implicitfast`` integrates the velocity gain implicitly.
        """
        tau = np.where(np.isfinite(model.max_torque), model.max_torque, 150.0)
        return cls(kp=100.0 * tau, kv=4.0 * tau)

    def for_joints(self, n: int) -> ServoGains:
        """Broadcast scalar gains to n joints (ValueError on a length mismatch)."""
        try:
            kp = np.broadcast_to(self.kp, (n,)).copy()
            kv = np.broadcast_to(self.kv, (n,)).copy()
        except ValueError:
            raise ValueError(
                f"servo gains: expected 1 or {n} values, "
                f"got {self.kp.size} (kp), {self.kv.size} (kv)"
            ) from None
        return ServoGains(kp, kv)


def _per_joint(value: ArrayLike | None, default: FloatArray, name: str) -> FloatArray:
    """``value`` per joint (a scalar or one per joint, each >= 0), ``default`` if None."""
    if value is None:
        return default
    return as_per_joint(value, name, default.shape[0], minimum=0.0)


# ---------------------------------------------------------------------------------------
# robot geometry
# ---------------------------------------------------------------------------------------


def _cylinder_inertia(mass: float, radius: float, length: float, axis: int) -> FloatArray:
    """Diagonal inertia (3,) of a solid cylinder about its centre, axis along ``axis``."""
    axial = 0.5 * mass * radius**2
    trans = mass * (3.0 * radius**2 + length**2) / 12.0
    out = np.full(3, trans)
    out[axis] = axial
    return out


def _body_frames(model: RobotModel) -> list[FloatArray]:
    """Poses (4, 4) of the link bodies at q = 0 in the base frame (body k: DH frame k-1
    turned by the joint's zero offset)."""
    out, T = [], np.eye(4)
    for k in range(model.n_joints):
        B = T @ rot_z(float(model.theta_offset[k]))
        out.append(B)
        T = B @ dh_tail(float(model.d[k]), float(model.a[k]), float(model.alpha[k]))
    return out


def _body_corrections(model: RobotModel, shape: RobotModel) -> list[FloatArray]:
    """Per body the constant pose of ``shape``'s body frame in ``model``'s (identity for an
    uncalibrated arm): both frames are fixed to the same link, so the map holds for every q."""
    if shape is model:
        return [np.eye(4)] * model.n_joints
    return [np.linalg.inv(c) @ s for c, s in zip(_body_frames(model), _body_frames(shape),
                                                    strict=True)]  # fmt: skip


def _moved(seg: Segment, C: FloatArray) -> Segment:
    R, t = C[:3, :3], C[:3, 3]
    return dataclasses.replace(seg, a=R @ seg.a + t, b=R @ seg.b + t)


def _link_inertial(model: RobotModel, k: int, radius: float) -> tuple[FloatArray, FloatArray]:
    """COM (3,) in the body frame and diagonal inertia (3,) of link k (0-based).

    UR publish masses and COMs but (except UR20/UR30) no inertia tensors; the
    inertia is that of a solid cylinder of the link's mass, with the tube's
    radius (0.8 x housing radius), along the link's longer DH offset
    (``a`` along x, else ``d`` along z) and at least 2 radii long, taken
    about the published COM with its axes along the body frame -- the same
    approximation as the cylinders of UR's ROS description.
    """
    d, a, alpha = float(model.d[k]), float(model.a[k]), float(model.alpha[k])
    tail = dh_tail(d, a, alpha)
    com = tail[:3, :3] @ model.link_com[k] + tail[:3, 3]
    tube = 0.8 * radius
    if abs(a) >= abs(d) and abs(a) > 0.0:
        axis, length = 0, abs(a)
    else:
        axis, length = 2, abs(d)
    length = max(length, 2.0 * tube)
    return com, _cylinder_inertia(float(model.link_mass[k]), tube, length, axis)


def _add_segment(body: ET.Element, name: str, seg: Segment, **attrs: object) -> None:
    sub(
        body,
        "geom",
        name=name,
        type=seg.kind,
        size=seg.radius,
        fromto=np.concatenate([seg.a, seg.b]),
        rgba=_RGBA[seg.part],
        **attrs,
    )  # type: ignore[arg-type]


# ---------------------------------------------------------------------------------------
# the robot writer (shared with the scene builder)
# ---------------------------------------------------------------------------------------


@dataclass
class _RobotTree:
    root: ET.Element
    worldbody: ET.Element
    last_body: ET.Element
    contact: ET.Element
    actuator: ET.Element
    sensor: ET.Element
    link_names: list[str]
    flange: FloatArray  # DH frame J in the last link body's frame


def build_robot(
    model: RobotModel,
    *,
    gains: ServoGains | None,
    armature: ArrayLike | None,
    damping: ArrayLike | None,
    timestep: float | None,
    collisions: bool,
    payload: bool,
    keyframe: bool,
    comment_model: str,
    conaffinity: int = 1,
) -> _RobotTree:
    """Build the MJCF element tree of a robot arm (see the module docstring for names).

    Parameters are those of :func:`robot_mjcf`, plus ``payload`` (add the
    ``payload`` body of a tool mass), ``comment_model`` (the ``model``
    attribute of ``<mujoco>``) and ``conaffinity`` (of the arm's geoms, when
    ``collisions``).  Returns the root with handles to the world body, the last
    link body, the contact, actuator and sensor sections, the link body names
    and the flange pose (DH frame J) in the last link body's frame.
    """
    n = model.n_joints
    g = (gains or ServoGains.default(model)).for_joints(n)
    arm = _per_joint(armature, default_armature(model), "armature")
    damp = _per_joint(damping, default_damping(model), "damping")
    dt = physics_timestep(model.control_period) if timestep is None else float(timestep)
    if not dt > 0.0:
        raise ValueError(f"timestep: must be positive, got {dt}")
    radii = link_radii(model.nominal)
    # a calibrated arm: the bodies follow the calibrated chain (exact kinematics); the
    # links keep their nominal shape, carried by the calibrated frames (its DH numbers
    # run metres along the nearly parallel axes 2-4, the metal does not)
    shape = model.nominal
    geometry, base_h = link_segments(shape, radii)
    carry = _body_corrections(model, shape)

    root = ET.Element("mujoco", model=comment_model)
    sub(root, "compiler", angle="radian", autolimits="true", inertiafromgeom="auto")
    sub(root, "option", timestep=dt, integrator="implicitfast")
    visual = sub(root, "visual")
    sub(visual, "quality", offsamples=0)
    sub(visual, "map", znear=0.01)
    default = sub(root, "default")
    geom_default = (
        {"contype": 1, "conaffinity": conaffinity}
        if collisions
        else {"contype": 0, "conaffinity": 0}
    )
    sub(default, "geom", condim=3, **geom_default)  # type: ignore[arg-type]
    worldbody = sub(root, "worldbody")
    base = placed(worldbody, "body", model.base, name="base")
    z_base = (0.0, base_h) if model.d[0] >= 0.0 else (-base_h, 0.0)
    sub(
        base,
        "geom",
        name="base",
        type="cylinder",
        size=1.15 * float(radii[0]),
        fromto=[0.0, 0.0, z_base[0], 0.0, 0.0, z_base[1]],
        rgba=_RGBA["base"],
    )

    parent = base
    parent_tail = np.eye(4)  # pose of DH frame i-1 in the parent body's frame
    names = ["base"]
    for k in range(n):
        name = f"link{k + 1}"
        body = placed(
            parent, "body", parent_tail @ rot_z(float(model.theta_offset[k])), name=name, gravcomp=1
        )
        com, inertia = _link_inertial(shape, k, float(radii[k]))
        com = carry[k][:3, :3] @ com + carry[k][:3, 3]
        if model.link_mass[k] > 0.0:
            sub(body, "inertial", pos=com, mass=float(model.link_mass[k]), diaginertia=inertia)
        lo, hi = float(model.lower[k]), float(model.upper[k])
        limited = bool(np.isfinite(lo) and np.isfinite(hi))
        tau = float(model.max_torque[k])
        sub(
            body,
            "joint",
            name=f"joint{k + 1}",
            type="hinge",
            axis="0 0 1",
            limited=limited,
            range=[lo, hi] if limited else None,
            armature=float(arm[k]),
            damping=float(damp[k]),
            actuatorgravcomp=True,
            actuatorfrclimited=bool(np.isfinite(tau)),
            actuatorfrcrange=[-tau, tau] if np.isfinite(tau) else None,
        )
        for j, seg in enumerate(geometry[k]):
            _add_segment(body, f"{name}_g{j}", _moved(seg, carry[k]))
        names.append(name)
        parent = body
        parent_tail = dh_tail(float(model.d[k]), float(model.a[k]), float(model.alpha[k]))

    flange = parent_tail
    placed(parent, "site", flange, name="flange", size=0.01, rgba="0.1 0.1 0.1 0.3")
    placed(parent, "site", flange @ model.tool, name="tcp", size=0.008, rgba="0.9 0.1 0.1 0.5")
    if payload and model.tool_mass > 0.0:
        tool = placed(parent, "body", flange, name="payload", gravcomp=1)
        r = 0.05  # the payload as a 5 cm sphere about its COM
        sub(
            tool,
            "inertial",
            pos=model.tool_com,
            mass=model.tool_mass,
            diaginertia=np.full(3, 0.4 * model.tool_mass * r * r),
        )

    contact = sub(root, "contact")
    ur = model.has_analytic_ik
    # base-link1: the base is welded to the world, so MuJoCo's parent filter skips it
    pairs = (
        [(0, 1), (0, 2), (3, 5), (4, 6)] if ur else [(0, 1)] + [(i, i + 2) for i in range(n - 1)]
    )
    for i, j in pairs:
        if j <= n:
            sub(contact, "exclude", body1=names[i], body2=names[j])

    actuator = sub(root, "actuator")
    for k in range(n):
        sub(actuator, "position", name=f"pos{k + 1}", joint=f"joint{k + 1}", kp=float(g.kp[k]))
    for k in range(n):
        sub(actuator, "velocity", name=f"vel{k + 1}", joint=f"joint{k + 1}", kv=float(g.kv[k]))
    for k in range(n):
        sub(actuator, "motor", name=f"ff{k + 1}", joint=f"joint{k + 1}")
    sensor = sub(root, "sensor")
    for k in range(n):
        sub(sensor, "jointactuatorfrc", name=f"torque{k + 1}", joint=f"joint{k + 1}")
    sub(sensor, "framepos", name="tcp_pos", objtype="site", objname="tcp")
    sub(sensor, "framequat", name="tcp_quat", objtype="site", objname="tcp")
    if keyframe:
        home = _home(model)
        keyf = sub(root, "keyframe")
        sub(keyf, "key", name="home", qpos=home, ctrl=np.concatenate([home, np.zeros(2 * n)]))
    return _RobotTree(root, worldbody, parent, contact, actuator, sensor, names, flange)


def _home(model: RobotModel) -> FloatArray:
    """A keyframe posture: the UR "home" (elbow up, wrist down) within limits, else zeros."""
    n = model.n_joints
    if model.has_analytic_ik:
        q = np.array([0.0, -np.pi / 2, np.pi / 2, -np.pi / 2, -np.pi / 2, 0.0])
    else:
        q = np.zeros(n)
    return np.clip(q, model.lower, model.upper)


def robot_mjcf(
    model: RobotModel,
    *,
    gains: ServoGains | None = None,
    armature: ArrayLike | None = None,
    damping: ArrayLike | None = None,
    timestep: float | None = None,
    collisions: bool = True,
    keyframe: bool = True,
) -> str:
    """MJCF text of a robot arm built from its DH table and inertial data.

    Parameters
    ----------
    model : any :class:`~ruledrobot.robot.RobotModel` (catalogue or ``from_dh``).
        ``model.base`` places the base body in the world; ``model.tool`` is
        the ``tcp`` site in the flange frame; a ``tool_mass`` > 0 adds a
        ``payload`` body (mass at ``tool_com``, flange frame).
    gains : joint servo gains; default :meth:`ServoGains.default`.
    armature, damping : (J,) or scalar, kg m^2 and N m s/rad; defaults
        :func:`default_armature`, :func:`default_damping`.
    timestep : physics step [s]; default :func:`physics_timestep` of the
        model's control period (2 ms on every catalogue arm).
    collisions : geoms collide (``contype = conaffinity = 1``; the joint
        neighbours, base-link1 and, on UR arms, the pairs base-link2,
        link3-link5, link4-link6 that the real arm cannot bring together are
        excluded; other arms exclude every link i, i+2 pair);
        ``False`` makes every geom visual only.
    keyframe : add the keyframe ``home`` (UR: ``[0, -pi/2, pi/2, -pi/2, -pi/2, 0]``).

    Joint limits are the model's (an infinite limit, UR3/UR3e wrist 3, makes
    the joint unlimited); joint torque limits are ``actuatorfrcrange``.  Angles
    are radians (``<compiler angle="radian">``), integrator ``implicitfast``.
    """
    if not isinstance(model, RobotModel):
        raise ValueError(f"model: expected a RobotModel, got {type(model).__name__}")
    tree = build_robot(
        model,
        gains=gains,
        armature=armature,
        damping=damping,
        timestep=timestep,
        collisions=collisions,
        payload=True,
        keyframe=keyframe,
        comment_model=model.name,
    )
    comment = (
        f"{model.name}: generated by ruledrobot.sim.mjcf.robot_mjcf from the DH table "
        "and inertial data of the robot catalogue; do not edit, regenerate with "
        "ruledrobot.sim.write_models()"
    )
    return to_string(tree.root, comment)
