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
import math
import time
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from ..geometry.checks import FloatArray, as_float_array
from ..geometry.interp import interp_hermite
from ..robot.arm.model import RobotModel
from ._mujoco import mujoco
from .contacts import Collision, ProgressCallback, _detect_collisions, _geom_reach, _wire
from .mjcf import ServoGains, physics_timestep, robot_mjcf
from .result import REPORT_FORMAT, PlaybackResult
from .scene import Scene

__all__ = [
    "REPORT_FORMAT",
    "Collision",
    "PlaybackResult",
    "ProgressCallback",
    "play",
]


Feedforward = Literal["velocity", "torque"]



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
