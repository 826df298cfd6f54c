"""Trajectory playback in MuJoCo: servo tracking, torques, collisions, and a report.

:func:`play` runs a joint trajectory through the MuJoCo model of an arm (or of
the whole hot-wire cell, :class:`~ruledrobot.sim.scene.Scene`) at the
physics step of the controller (:func:`~ruledrobot.sim.mjcf.physics_timestep`,
2 ms), with the joint servos of :func:`~ruledrobot.sim.mjcf.robot_mjcf`:

``tau = kp (q_ref - q) + kv (qd_ref - qd) + tau_ff + gravity``, clamped to the torque limit,

where ``qd_ref`` is the trajectory's velocity (central finite differences of
``q`` when it is not given) and ``tau_ff`` is zero (``feedforward="velocity"``,
the default) or the inverse dynamics of the reference without gravity
(``feedforward="torque"``, computed torque).  It records the actual joint
positions and velocities, the joint torques (the actuators' total force,
gravity compensation included), the TCP poses and, in a scene, the wire
ends, and checks every sample for contacts.

Contacts are **detected, not simulated**: the dynamics run with contacts
off (a position-controlled UR stops on a collision -- a protective stop --
it does not push through), and every ``collision_stride``-th sample of the
actual motion goes through MuJoCo's collision detection.  The wire never
collides with the stock (see :mod:`ruledrobot.sim.scene`); the time it spends
inside the stock is reported separately.

:meth:`PlaybackResult.report` gives a JSON-ready dict (keys in
``docs/sim.md``); :meth:`PlaybackResult.write` writes ``report.json``,
``tracking.png``, ``limits.png`` and the actual trajectory as CSV.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from ..geometry import se3
from ..geometry._arrays import FloatArray, as_float_array
from ..geometry.box import Box
from ..geometry.interp import interp_hermite
from ..io.atomic import atomic_open, atomic_write_text
from ..robot.model import RobotModel
from ..robot.verdict import Check, Verdict
from ._mujoco import mujoco
from .mjcf import ServoGains, physics_timestep, robot_mjcf
from .scene import BowTool, Scene

__all__ = [
    "REPORT_FORMAT",
    "Collision",
    "PlaybackResult",
    "ProgressCallback",
    "play",
]

REPORT_FORMAT = "ruledrobot.playback/1"

#: ``progress(fraction, stage)``: fraction of the work done in [0, 1], stage name.
ProgressCallback = Callable[[float, str], None]

Feedforward = Literal["velocity", "torque"]


@dataclass(frozen=True)
class Collision:
    """A contact event: two geoms touching over ``[start, end]`` (s, sample times).

    ``depth`` is the deepest penetration seen [m] (>= 0).  Bodies are the
    MuJoCo bodies of the geoms (``link3``, ``bow``, ``world`` for the table and
    the stock).
    """

    start: float
    end: float
    geom1: str
    geom2: str
    body1: str
    body2: str
    depth: float

    def as_dict(self) -> dict[str, Any]:
        return {
            "start_s": self.start,
            "end_s": self.end,
            "geom1": self.geom1,
            "geom2": self.geom2,
            "body1": self.body1,
            "body2": self.body2,
            "max_depth_mm": self.depth * 1e3,
        }


@dataclass(frozen=True, eq=False)
class PlaybackResult:
    """What :func:`play` recorded, at the physics step (M samples, J joints).

    Attributes
    ----------
    robot : the arm (its ``base`` and ``tool`` define the world and TCP frames).
    t : (M,) sample times [s]: the physics grid ``t[0] + k dt`` of the input times.
    q_ref, qd_ref : (M, J) the reference [rad, rad/s] (resampled to the step).
    q, qd : (M, J) the simulated joint positions and velocities.
    torque : (M, J) joint torques [N m] (servo + feed-forward + gravity
        compensation, after the torque limit).
    tcp_ref, tcp : (M, 4, 4) reference and simulated TCP poses in the world.
    wire : (M, 2, 3) simulated wire ends (start, end) in the robot base frame, or
        None without a bow (for the wire's deviation from the target rulings).
    wire_inside : (M,) length of wire inside the stock [m], or None.
    collisions : contact events.
    timestep : physics step [s]; feedforward : the servo's feed-forward.
    gains : the servo gains used.
    wall_time : seconds :func:`play` took; physics_time : seconds of it spent
        stepping the dynamics.
    """

    robot: RobotModel
    t: FloatArray
    q_ref: FloatArray = field(repr=False)
    qd_ref: FloatArray = field(repr=False)
    q: FloatArray = field(repr=False)
    qd: FloatArray = field(repr=False)
    torque: FloatArray = field(repr=False)
    tcp_ref: FloatArray = field(repr=False)
    tcp: FloatArray = field(repr=False)
    wire: FloatArray | None = field(repr=False)
    wire_inside: FloatArray | None = field(repr=False)
    collisions: tuple[Collision, ...]
    timestep: float
    feedforward: str
    gains: ServoGains = field(repr=False)
    wall_time: float
    physics_time: float
    scene: Scene | None = field(default=None, repr=False)

    # ------------------------------------------------------------------ metrics

    @property
    def duration(self) -> float:
        """Simulated time [s]."""
        return float(self.t[-1] - self.t[0]) if self.t.size > 1 else 0.0

    @property
    def realtime_factor(self) -> float:
        """Simulated seconds per wall-clock second of the whole :func:`play` call."""
        return self.duration / self.wall_time if self.wall_time > 0 else math.inf

    def joint_error(self) -> FloatArray:
        """(M, J) ``q - q_ref`` [rad]."""
        return self.q - self.q_ref

    def tcp_position_error(self) -> FloatArray:
        """(M,) distance between simulated and reference TCP [m]."""
        return np.linalg.norm(self.tcp[:, :3, 3] - self.tcp_ref[:, :3, 3], axis=-1)

    def tcp_orientation_error(self) -> FloatArray:
        """(M,) rotation angle between simulated and reference TCP frames [rad]."""
        R = np.einsum("nji,njk->nik", self.tcp_ref[:, :3, :3], self.tcp[:, :3, :3])
        return np.linalg.norm(se3.rotvec_from_matrix(R), axis=-1)

    def verdict(self) -> Verdict:
        """The playback's checks: collisions, joint positions, speeds and torques of the
        simulated arm against the robot's limits (gating); TCP error (information)."""
        rep = self.report()
        names = [f"{c['geom1']}/{c['geom2']} {c['max_depth_mm']:.1f} mm at {c['start_s']:.2f} s"
                 for c in rep["collisions"]]  # fmt: skip
        pos = rep["joint_position"]
        return Verdict((
            Check("collisions", "collisions in the simulation", len(names), 0, relation="<=",
                  ok=not names, detail="\n".join(names[:8])),
            Check("joint_position", "simulated joints within their ranges",
                  "yes" if pos["within_limits"] else "no", "yes", relation="==",
                  ok=bool(pos["within_limits"]), detail="a joint leaves its position range"),
            Check.at_most("joint_speed", "simulated joint speed / limit",
                          rep["joint_speed"]["max_ratio"], 1.0 + 1e-9),
            Check.at_most("joint_torque", "simulated joint torque / limit",
                          rep["joint_torque"]["max_ratio"], 1.0 + 1e-9,
                          detail="a joint needs more torque than it has"),
            Check.info("tcp_error", "TCP position error (simulated vs reference)",
                       rep["tcp_position_error_mm"]["max"], "mm"),
        ))  # fmt: skip

    def report(self) -> dict[str, Any]:
        """The playback report as a JSON-ready dict (keys documented in ``docs/sim.md``)."""
        r = self.robot
        e = self.joint_error()
        pe = self.tcp_position_error()
        oe = self.tcp_orientation_error()
        speed = np.abs(self.qd).max(axis=0)
        speed_ref = np.abs(self.qd_ref).max(axis=0)
        tau = np.abs(self.torque).max(axis=0)
        tau_ratio = tau / r.max_torque
        speed_ratio = speed / r.max_velocity
        within = bool(np.all(r.within_limits(self.q)))
        within_ref = bool(np.all(r.within_limits(self.q_ref)))
        acc = (
            np.abs(np.gradient(self.qd_ref, self.timestep, axis=0)).max(axis=0)
            if self.t.size > 2
            else np.zeros(r.n_joints)
        )
        acc_ratio = acc / r.max_acceleration

        def stats(x: FloatArray, scale: float) -> dict[str, float]:
            return {
                "max": float(np.max(np.abs(x)) * scale),
                "rms": float(np.sqrt(np.mean(x * x)) * scale),
            }

        wire: dict[str, Any] | None = None
        if self.wire_inside is not None:
            inside = self.wire_inside > 0.0
            idx = np.flatnonzero(inside)
            wire = {
                "in_stock_s": float(inside.sum() * self.timestep),
                "in_stock_fraction": float(inside.mean()),
                "first_in_stock_s": float(self.t[idx[0]]) if idx.size else None,
                "last_in_stock_s": float(self.t[idx[-1]]) if idx.size else None,
                "max_length_in_stock_mm": float(self.wire_inside.max() * 1e3),
            }
        collisions = [c.as_dict() for c in self.collisions]
        ok = (
            not collisions
            and within
            and bool(np.all(tau_ratio <= 1.0 + 1e-9))
            and bool(np.all(speed_ratio <= 1.0 + 1e-9))
        )
        return {
            "format": REPORT_FORMAT,
            "robot": r.name,
            "duration_s": self.duration,
            "samples": int(self.t.size),
            "timestep_s": self.timestep,
            "control_period_s": r.control_period,
            "servo": {
                "feedforward": self.feedforward,
                "kp": self.gains.kp.tolist(),
                "kv": self.gains.kv.tolist(),
            },
            "joint_error_rad": {**stats(e, 1.0), "max_per_joint": np.abs(e).max(axis=0).tolist()},
            "tcp_position_error_mm": stats(pe, 1e3),
            "tcp_orientation_error_deg": stats(oe, 180.0 / np.pi),
            "joint_speed": {
                "peak_rad_s": speed.tolist(),
                "peak_reference_rad_s": speed_ref.tolist(),
                "limit_rad_s": r.max_velocity.tolist(),
                "ratio": speed_ratio.tolist(),
                "max_ratio": float(speed_ratio.max()),
            },
            "joint_torque": {
                "peak_nm": tau.tolist(),
                "limit_nm": [float(v) if np.isfinite(v) else None for v in r.max_torque],
                "ratio": [float(v) for v in tau_ratio],
                "max_ratio": float(tau_ratio.max()),
            },
            "joint_position": {
                "min_rad": self.q.min(axis=0).tolist(),
                "max_rad": self.q.max(axis=0).tolist(),
                "within_limits": within,
                "reference_within_limits": within_ref,
            },
            "joint_acceleration": {
                "peak_reference_rad_s2": acc.tolist(),
                "limit_rad_s2": r.max_acceleration.tolist(),
                "ratio": acc_ratio.tolist(),
                "max_ratio": float(acc_ratio.max()),
            },
            "collisions": collisions,
            "collision_count": len(collisions),
            "wire": wire,
            "realtime_factor": self.realtime_factor,
            "physics_realtime_factor": (
                self.duration / self.physics_time if self.physics_time > 0 else None
            ),
            "wall_time_s": self.wall_time,
            "ok": ok,
        }

    # ------------------------------------------------------------------ output

    def write(
        self, out_dir: str | os.PathLike[str], *, plots: bool = True, trajectory: bool = True
    ) -> dict[str, Path]:
        """Write ``report.json``, ``tracking.png``, ``limits.png`` and ``simulated.csv``
        (the simulated trajectory with its sidecar, ``ruledrobot.io.trajectory``) into ``out_dir``;
        returns ``{name: path}``.  Every file is written atomically."""
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        paths: dict[str, Path] = {}
        rep = self.report()
        rep["verdict"] = self.verdict().as_dict()
        paths["report"] = atomic_write_text(out / "report.json", json.dumps(rep, indent=2) + "\n")
        if plots:
            paths.update(self.plot(out))
        if trajectory and self.robot.n_joints == 6:
            from ..io.trajectory import write_trajectory
            from ..robot.trajectory import Trajectory, TrajectoryMeta

            base_inv = se3.inverse(np.asarray(self.robot.base))
            meta = TrajectoryMeta.for_model(
                self.robot, source="simulated by ruledrobot.sim.playback (MuJoCo)"
            )
            paths["simulated"] = write_trajectory(
                out / "simulated.csv", Trajectory(self.t, self.q, base_inv @ self.tcp, meta)
            )
        return paths

    def plot(self, out_dir: str | os.PathLike[str]) -> dict[str, Path]:
        """``tracking.png`` (joint, TCP position and orientation errors over time) and
        ``limits.png`` (|torque| / limit and |speed| / limit per joint); matplotlib Agg."""
        import matplotlib

        matplotlib.use("Agg", force=False)
        from matplotlib.figure import Figure

        out = Path(out_dir)
        t = self.t
        J = self.robot.n_joints
        labels = [f"q{i + 1}" for i in range(J)]

        fig = Figure(figsize=(9, 8), constrained_layout=True)
        ax = fig.subplots(3, 1, sharex=True)
        ax[0].plot(t, self.joint_error() * 1e3, lw=0.8)
        ax[0].set_ylabel("joint error [mrad]")
        ax[0].legend(labels, ncol=J, fontsize=7, loc="upper right")
        ax[1].plot(t, self.tcp_position_error() * 1e3, lw=0.8, color="C3")
        ax[1].set_ylabel("TCP position error [mm]")
        ax[2].plot(t, np.degrees(self.tcp_orientation_error()), lw=0.8, color="C4")
        ax[2].set_ylabel("TCP orientation error [deg]")
        ax[2].set_xlabel("time [s]")
        for c in self.collisions:
            for a in ax:
                a.axvspan(c.start, max(c.end, c.start + self.timestep), color="red", alpha=0.15)
        fig.suptitle(f"{self.robot.name}: tracking ({self.feedforward} feed-forward)")
        paths = {"tracking_plot": _save_fig(fig, out / "tracking.png")}

        fig = Figure(figsize=(9, 6), constrained_layout=True)
        ax = fig.subplots(2, 1, sharex=True)
        lim_t = np.where(np.isfinite(self.robot.max_torque), self.robot.max_torque, np.inf)
        ax[0].plot(t, np.abs(self.torque) / lim_t, lw=0.8)
        ax[0].axhline(1.0, color="k", ls="--", lw=0.8)
        ax[0].set_ylabel("|torque| / limit")
        ax[0].legend(labels, ncol=J, fontsize=7, loc="upper right")
        ax[1].plot(t, np.abs(self.qd) / self.robot.max_velocity, lw=0.8)
        ax[1].axhline(1.0, color="k", ls="--", lw=0.8)
        ax[1].set_ylabel("|speed| / limit")
        ax[1].set_xlabel("time [s]")
        fig.suptitle(f"{self.robot.name}: joint torques and speeds against their limits")
        paths["limits_plot"] = _save_fig(fig, out / "limits.png")
        return paths


def _save_fig(fig: Any, path: Path) -> Path:
    with atomic_open(path, "wb") as fh:
        fig.savefig(fh, format="png", dpi=100)
    return path


# ---------------------------------------------------------------------------------------
# reference
# ---------------------------------------------------------------------------------------


def _reference(
    t: FloatArray, q: FloatArray, qd: FloatArray | None, dt: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Reference on the physics grid ``t0 + k dt``: times, positions, velocities.

    Samples already on the grid are used as they are; otherwise cubic
    Hermite interpolation of ``(q, qd)`` (``qd`` from finite differences when
    absent).
    """
    if qd is None:
        qd = (
            np.gradient(q, t, axis=0, edge_order=2)
            if t.size > 2
            else (np.repeat(np.diff(q, axis=0) / np.diff(t)[:, None], 2, axis=0)[: t.size])
        )
    steps = np.diff(t)
    if np.allclose(steps, dt, rtol=1e-6, atol=1e-9):
        return t.copy(), q.copy(), np.asarray(qd, dtype=np.float64).copy()
    n = math.floor((t[-1] - t[0]) / dt + 1e-9) + 1
    ts = t[0] + dt * np.arange(n)
    qs, vs = interp_hermite(ts, t, q, qd)
    return ts, qs, vs


def _check_trajectory(
    robot: RobotModel, t: ArrayLike, q: ArrayLike, qd: ArrayLike | None
) -> tuple[FloatArray, FloatArray, FloatArray | None]:
    J = robot.n_joints
    t = as_float_array(t, "t")
    q = as_float_array(q, "q")
    if t.ndim != 1 or t.size < 2:
        raise ValueError(f"t: expected at least 2 sample times (M,), got shape {t.shape}")
    if q.shape != (t.size, J):
        raise ValueError(f"q: expected shape ({t.size}, {J}) (one row per time), got {q.shape}")
    bad = np.flatnonzero(np.diff(t) <= 0.0)
    if bad.size:
        raise ValueError(f"t[{bad[0] + 1}]: times must increase strictly")
    if qd is not None:
        qd = as_float_array(qd, "qd")
        if qd.shape != q.shape:
            raise ValueError(f"qd: expected shape {q.shape} like q, got {qd.shape}")
    return t, q, qd


# ---------------------------------------------------------------------------------------
# the run
# ---------------------------------------------------------------------------------------


def _resolve(
    model_or_scene: RobotModel | Scene, gains: ServoGains | None
) -> tuple[RobotModel, Scene | None, str, ServoGains]:
    if isinstance(model_or_scene, Scene):
        scene = model_or_scene
        if gains is not None:
            scene = dataclasses.replace(scene, gains=gains)
        g = (scene.gains or ServoGains.default(scene.robot)).for_joints(scene.robot.n_joints)
        return scene.robot, scene, scene.mjcf(), g
    if isinstance(model_or_scene, RobotModel):
        robot = model_or_scene
        g = (gains or ServoGains.default(robot)).for_joints(robot.n_joints)
        return robot, None, robot_mjcf(robot, gains=g), g
    raise ValueError(
        f"model_or_scene: expected a RobotModel or a Scene, got {type(model_or_scene).__name__}"
    )


def play(
    model_or_scene: RobotModel | Scene,
    t: ArrayLike,
    q: ArrayLike,
    qd: ArrayLike | None = None,
    *,
    feedforward: Feedforward = "velocity",
    gains: ServoGains | None = None,
    collisions: bool = True,
    collision_stride: int = 10,
    progress: ProgressCallback | None = None,
) -> PlaybackResult:
    """Run a joint trajectory through MuJoCo and record what the arm does.

    Parameters
    ----------
    model_or_scene : a :class:`~ruledrobot.robot.RobotModel` (the arm alone,
        :func:`~ruledrobot.sim.mjcf.robot_mjcf`) or a
        :class:`~ruledrobot.sim.scene.Scene` (arm, bow, stock, table).
    t : (M,) strictly increasing sample times [s] (any spacing; resampled to
        the physics step by cubic Hermite interpolation when off its grid).
    q : (M, J) joint positions [rad].
    qd : (M, J) joint velocities [rad/s]; default central finite differences.
    feedforward : ``"velocity"`` (PD on position and velocity errors, gravity
        compensated) or ``"torque"`` (plus the reference's inverse-dynamics
        torque: computed-torque control, ~10x smaller tracking error).
    gains : servo gains; default the scene's, else :meth:`ServoGains.default`.
    collisions : detect contacts at every sample (a coarse pass over every
        ``collision_stride``-th sample with a safety margin, then the samples
        near a contact one by one: exact at sample resolution, see
        :func:`_detect_collisions`).
    progress : called as ``progress(fraction, stage)`` while running.

    The arm starts on the trajectory (``q[0]``, ``qd[0]``).  Raises ValueError
    on malformed input (the message names the argument).
    """
    t_start = time.perf_counter()
    if feedforward not in ("velocity", "torque"):
        raise ValueError(f"feedforward: expected 'velocity' or 'torque', got {feedforward!r}")
    if not isinstance(collision_stride, (int, np.integer)) or collision_stride < 1:
        raise ValueError(f"collision_stride: expected an integer >= 1, got {collision_stride!r}")
    robot, scene, xml, g = _resolve(model_or_scene, gains)
    t_in, q_in, qd_in = _check_trajectory(robot, t, q, qd)
    mj = mujoco()
    m = mj.MjModel.from_xml_string(xml)
    dt = physics_timestep(robot.control_period)
    m.opt.timestep = dt
    ts, q_ref, qd_ref = _reference(t_in, q_in, qd_in, dt)
    n, J = q_ref.shape
    ff = np.zeros((n, J))
    if feedforward == "torque":
        ff = _inverse_dynamics(mj, m, q_ref, qd_ref, dt)
    ctrl = np.concatenate([q_ref, qd_ref, ff], axis=1)

    t_phys = time.perf_counter()
    q_act, qd_act, torque = _simulate(mj, m, q_ref[0], qd_ref[0], ctrl, progress)
    physics_time = time.perf_counter() - t_phys

    events: tuple[Collision, ...] = ()
    if collisions:
        events = _detect_collisions(
            mj, m, ts, q_act, collision_stride, _geom_reach(mj, m, robot), progress
        )

    tcp_ref = robot.fk(q_ref)
    tcp = robot.fk(q_act)
    wire = wire_inside = None
    if scene is not None and scene.tool is not None:
        wire, wire_inside = _wire(robot, scene.tool, scene.stock, q_act)
    if progress is not None:
        progress(1.0, "done")
    return PlaybackResult(
        robot=robot,
        t=ts,
        q_ref=q_ref,
        qd_ref=qd_ref,
        q=q_act,
        qd=qd_act,
        torque=torque,
        tcp_ref=tcp_ref,
        tcp=tcp,
        wire=wire,
        wire_inside=wire_inside,
        collisions=events,
        timestep=dt,
        feedforward=feedforward,
        gains=g,
        wall_time=time.perf_counter() - t_start,
        physics_time=physics_time,
        scene=scene,
    )


def _inverse_dynamics(mj: Any, m: Any, q: FloatArray, qd: FloatArray, dt: float) -> FloatArray:
    """Joint torques (M, J) that produce the reference motion, gravity excluded (the
    actuators' gravity compensation adds it), from MuJoCo's inverse dynamics."""
    qdd = np.gradient(qd, dt, axis=0, edge_order=2) if q.shape[0] > 2 else np.zeros_like(qd)
    d = mj.MjData(m)
    out = np.empty_like(q)
    m.opt.disableflags |= int(mj.mjtDisableBit.mjDSBL_CONTACT)
    for k in range(q.shape[0]):  # one inverse-dynamics call per simulation step
        d.qpos[:] = q[k]
        d.qvel[:] = qd[k]
        d.qacc[:] = qdd[k]
        mj.mj_inverse(m, d)
        out[k] = d.qfrc_inverse - d.qfrc_gravcomp
    return out


def _simulate(
    mj: Any,
    m: Any,
    q0: FloatArray,
    qd0: FloatArray,
    ctrl: FloatArray,
    progress: ProgressCallback | None,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Step the dynamics (contacts off) under the controls (M, 3J); returns the state at
    every sample time (the first is the initial state) and the joint torques there."""
    n, J = ctrl.shape[0], q0.shape[0]
    m.opt.disableflags |= int(mj.mjtDisableBit.mjDSBL_CONTACT)
    d = mj.MjData(m)
    d.qpos[:J] = q0
    d.qvel[:J] = qd0
    spec = int(mj.mjtState.mjSTATE_FULLPHYSICS)
    state = np.empty(mj.mj_stateSize(m, spec))
    mj.mj_getState(m, d, state, spec)
    nq = m.nq
    q_out = np.empty((n, J))
    qd_out = np.empty((n, J))
    tau = np.empty((n, J))
    chunk = max(500, -(-n // 20))
    try:
        from mujoco import rollout as _rollout
    except ImportError:  # pragma: no cover - old MuJoCo: plain Python loop
        _rollout = None
    # sensordata of step k is evaluated at the state before that step (time t_k);
    # the state output of step k is the state after it (time t_{k+1})
    q_out[0], qd_out[0] = q0, qd0
    for lo in range(0, n, chunk):
        hi = min(lo + chunk, n)
        if _rollout is not None:
            st, sd = _rollout.rollout(m, d, state[None], ctrl[None, lo:hi])
            st, sd = st[0], sd[0]
        else:  # pragma: no cover
            st = np.empty((hi - lo, state.size))
            sd = np.empty((hi - lo, m.nsensordata))
            mj.mj_setState(m, d, state, spec)
            for k in range(hi - lo):
                d.ctrl[:] = ctrl[lo + k]
                mj.mj_step(m, d)
                mj.mj_getState(m, d, st[k], spec)
                sd[k] = d.sensordata
        tau[lo:hi] = sd[:, :J]
        last = min(hi, n - 1)
        q_out[lo + 1 : last + 1] = st[: last - lo, 1 : 1 + J]
        qd_out[lo + 1 : last + 1] = st[: last - lo, 1 + nq : 1 + nq + J]
        state = st[-1].copy()
        if progress is not None:
            progress(0.8 * hi / n, "dynamics")
    return q_out, qd_out, tau


def _geom_reach(mj: Any, m: Any, robot: RobotModel) -> FloatArray:
    """(ngeom, J) upper bounds of the distance of each geom's points from joint j's axis
    [m]; 0 where joint j does not move the geom (static geoms: all 0).

    A geom of a body moved by joints 1..k lies within ``r_g`` (its distance
    from that body's origin plus its bounding radius) of the origin of link k,
    and link k's origin lies within ``sum_{i=j..k-1} |a_i| + |d_i|`` of joint
    j's axis.
    """
    J = robot.n_joints
    d = mj.MjData(m)
    mj.mj_kinematics(m, d)
    jbody = np.asarray(m.jnt_bodyid[:J])  # body of joint j
    link_of_body = np.full(m.nbody, -1)
    for b in range(1, m.nbody):  # walk up to the nearest body with a joint
        a = b
        while a > 0 and a not in jbody:
            a = int(m.body_parentid[a])
        link_of_body[b] = int(np.flatnonzero(jbody == a)[0]) if a > 0 else -1
    lengths = np.abs(robot.a) + np.abs(robot.d)
    csum = np.concatenate([[0.0], np.cumsum(lengths)])
    out = np.zeros((m.ngeom, J))
    for g in range(m.ngeom):
        k = link_of_body[int(m.geom_bodyid[g])]
        if k < 0:
            continue
        origin = d.xpos[jbody[k]]
        r_g = float(np.linalg.norm(d.geom_xpos[g] - origin) + m.geom_rbound[g])
        j = np.arange(k + 1)
        out[g, : k + 1] = csum[k] - csum[j] + r_g
    return out


def _detect_collisions(
    mj: Any,
    m: Any,
    t: FloatArray,
    q: FloatArray,
    stride: int,
    reach: FloatArray,
    progress: ProgressCallback | None,
) -> tuple[Collision, ...]:
    """Contact events of the motion q (M, J), exact at every sample.

    A coarse pass checks every ``stride``-th sample with each geom's margin
    set to twice the largest distance its points can travel between two
    checked samples (``sum_j |dq_j| R_gj``, R from :func:`_geom_reach`): a pair
    penetrating at some sample between two checks is then within the margin
    at one of them.  Only the samples next to such near contacts are checked
    again, with the model's margins, one by one.
    """
    n, J = q.shape
    m.opt.disableflags &= ~int(mj.mjtDisableBit.mjDSBL_CONTACT)
    d = mj.MjData(m)
    margin0 = m.geom_margin.copy()
    hits: list[tuple[int, int, int, float]] = []
    try:
        checks = np.unique(np.append(np.arange(0, n, stride), n - 1))
        if stride > 1 and checks.size > 1:
            path = np.concatenate([np.zeros((1, J)), np.cumsum(np.abs(np.diff(q, axis=0)), 0)])
            travel = path[checks[1:]] - path[checks[:-1]]  # (windows, J) joint travel
            disp = (travel @ reach.T).max(axis=0)  # (ngeom,) largest geom travel
            m.geom_margin[:] = np.maximum(margin0, 2.05 * disp + 1e-6 * (disp > 0))
            near = np.zeros(n, dtype=bool)
            for i, k in enumerate(checks):  # coarse pass over the simulation steps
                d.qpos[:J] = q[k]
                mj.mj_kinematics(m, d)
                mj.mj_collision(m, d)
                if d.ncon:
                    near[max(0, k - stride) : k + stride + 1] = True
                if progress is not None and i % 500 == 0:
                    progress(0.8 + 0.1 * i / checks.size, "collisions")
            m.geom_margin[:] = margin0
            samples = np.flatnonzero(near)
        else:
            samples = np.arange(n)
        for i, k in enumerate(samples):  # exact pass where something came near
            d.qpos[:J] = q[k]
            mj.mj_kinematics(m, d)
            mj.mj_collision(m, d)
            nc = d.ncon
            if nc:
                con = d.contact
                for g1, g2, dist in zip(con.geom1[:nc], con.geom2[:nc], con.dist[:nc], strict=True):
                    hits.append((int(k), int(g1), int(g2), float(dist)))
            if progress is not None and i % 2000 == 0:
                progress(0.9 + 0.1 * i / max(samples.size, 1), "collisions")
    finally:
        m.geom_margin[:] = margin0
    return _events(mj, m, t, hits, 1)


def _events(
    mj: Any, m: Any, t: FloatArray, hits: list[tuple[int, int, int, float]], stride: int
) -> tuple[Collision, ...]:
    """Merge per-sample contacts into events per geom pair (gaps of one check allowed)."""
    by_pair: dict[tuple[int, int], list[tuple[int, float]]] = {}
    for k, g1, g2, dist in hits:
        key = (min(g1, g2), max(g1, g2))
        by_pair.setdefault(key, []).append((k, dist))
    out: list[Collision] = []

    def name(obj: int, i: int) -> str:
        nm = mj.mj_id2name(m, obj, i)
        return nm if nm else f"#{i}"

    geom_t = int(mj.mjtObj.mjOBJ_GEOM)
    body_t = int(mj.mjtObj.mjOBJ_BODY)
    for (g1, g2), samples in by_pair.items():
        start = prev = samples[0][0]
        depth = max(0.0, -samples[0][1])
        spans: list[tuple[int, int, float]] = []
        for k, dist in samples[1:]:
            if k - prev > stride:
                spans.append((start, prev, depth))
                start, depth = k, 0.0
            prev = k
            depth = max(depth, -dist)
        spans.append((start, prev, depth))
        b1, b2 = int(m.geom_bodyid[g1]), int(m.geom_bodyid[g2])
        for k0, k1, dep in spans:
            out.append(
                Collision(
                    start=float(t[k0]),
                    end=float(t[k1]),
                    geom1=name(geom_t, g1),
                    geom2=name(geom_t, g2),
                    body1=name(body_t, b1),
                    body2=name(body_t, b2),
                    depth=dep,
                )
            )
    out.sort(key=lambda c: (c.start, c.geom1, c.geom2))
    return tuple(out)


def _wire(
    robot: RobotModel, tool: BowTool, stock: Box | None, q: FloatArray
) -> tuple[FloatArray, FloatArray | None]:
    """Wire ends (M, 2, 3) in the base frame and the wire length inside the stock (M,)."""
    flange = dataclasses.replace(robot, base=np.eye(4), tool=np.eye(4)).fk(q)
    ends = np.stack([tool.wire_start, tool.wire_end])  # (2, 3)
    wire = np.einsum("nij,kj->nki", flange[:, :3, :3], ends) + flange[:, None, :3, 3]
    if stock is None:
        return wire, None
    a, b = wire[:, 0], wire[:, 1]
    t_in, t_out, hit = stock.clip_lines(a, b - a)
    lo = np.where(hit, np.maximum(t_in, 0.0), 0.0)
    hi = np.where(hit, np.minimum(t_out, 1.0), 0.0)
    inside = np.maximum(hi - lo, 0.0) * tool.wire_length
    return wire, inside


# ---------------------------------------------------------------------------------------
# files
# ---------------------------------------------------------------------------------------
