"""The arm behind the emulated controller: the backend interface and a kinematic arm.

The controller (``controller.py``) decides *what* the arm should do each
control period: follow a trajectory setpoint (moveJ/moveL/paths/stops, from
its own trajectory generator), servo to a streamed target (servoJ/servoL), or
run at a joint speed (speedJ/speedL).  A backend decides *how the arm moves*
and reports the actual joint state.  Anything with the methods of
:class:`ArmBackend` plugs in; :class:`KinematicBackend` is the built-in one
(ideal tracking within joint speed and acceleration limits).  A physics
backend (e.g. MuJoCo: PD torques on the setpoint, ``mj_step`` in
:meth:`~ArmBackend.step`, ``qpos``/``qvel`` as the actual state) implements
the same six methods; see ``docs/rtde.md``.

All vectors are (6,) float arrays, joint order base to wrist 3; units rad,
rad/s, rad/s^2, s.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from ...robot import RobotModel
from ...robot.motion.servo import servo_time_constant

__all__ = ["HARDWARE_ACCELERATION", "ArmBackend", "ArmState", "KinematicBackend"]

#: Joint acceleration ceiling [rad/s^2] of the kinematic arm: the largest
#: value ur_rtde lets a client request (``UR_JOINT_ACCELERATION_MAX``).  The
#: model's ``max_acceleration`` (1.4 rad/s^2 by default) is a planning
#: default, not what the hardware can do.
HARDWARE_ACCELERATION = 40.0


def _zeros() -> np.ndarray:
    return np.zeros(6)


@dataclass
class ArmState:
    """The arm's state after a step.

    ``q, qd, qdd``: actual joint positions, speeds, accelerations.
    ``target_q, target_qd, target_qdd``: the setpoint the joint servos track
    this period (after the backend's own filtering, e.g. servoJ smoothing).
    ``current``: joint currents [A] or motor torques [N m] when the backend
    knows them (zeros otherwise).  ``limited``: True when the backend had to
    clip the setpoint to its speed or acceleration limits this period.
    """

    q: np.ndarray = field(default_factory=_zeros)
    qd: np.ndarray = field(default_factory=_zeros)
    qdd: np.ndarray = field(default_factory=_zeros)
    target_q: np.ndarray = field(default_factory=_zeros)
    target_qd: np.ndarray = field(default_factory=_zeros)
    target_qdd: np.ndarray = field(default_factory=_zeros)
    current: np.ndarray = field(default_factory=_zeros)
    limited: bool = False


@runtime_checkable
class ArmBackend(Protocol):
    """What the controller needs from an arm (kinematic, physics, or real).

    The controller calls exactly one of :meth:`track`, :meth:`servo`,
    :meth:`speed`, :meth:`hold` to set the mode and target, then
    :meth:`step` once per control period, then reads :meth:`state`.  A mode
    stays in force until another mode call; the controller re-sends targets
    whenever they change (every period for trajectories).
    """

    def reset(self, q: ArrayLike) -> None:
        """Put the arm at rest at joint positions ``q``."""
        ...

    def track(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> None:
        """Trajectory mode: follow this setpoint (position, speed, acceleration) exactly."""
        ...

    def servo(self, q: ArrayLike, lookahead_time: float, gain: float) -> None:
        """Servo mode (servoJ): move towards ``q``, smoothed by ``lookahead_time`` [s], ``gain``."""
        ...

    def speed(self, qd: ArrayLike, acceleration: float) -> None:
        """Speed mode (speedJ): reach joint speeds ``qd`` with ``acceleration`` and keep them."""
        ...

    def hold(self) -> None:
        """Hold the current position (brake to rest within the acceleration limit)."""
        ...

    def step(self, dt: float) -> None:
        """Advance the arm by ``dt`` seconds."""
        ...

    def state(self) -> ArmState:
        """The state after the last step (arrays may be reused: copy to keep them)."""
        ...


class KinematicBackend:
    """An ideal arm: the joints follow the setpoint exactly within speed/acceleration limits.

    * ``track``: the setpoint is reproduced exactly when it respects the limits;
      otherwise each joint is clipped to ``max_velocity`` and ``max_acceleration``
      (``ArmState.limited`` tells).
    * ``servo``: the streamed target passes through a first-order filter of
      time constant ``tau = lookahead_time * clip(300 / gain, 0.2, 1)`` (UR's
      servoj follows with a lag of about the lookahead time; a higher gain
      shortens it), then through the limits.
    * ``speed``: joint speeds ramp to the target at the given acceleration
      (capped by the limit), positions integrate.
    * ``hold``: the position where hold started is the setpoint.

    Positions are clipped to the model's joint limits.
    """

    def __init__(
        self,
        model: RobotModel,
        *,
        max_velocity: ArrayLike | None = None,
        max_acceleration: ArrayLike | float = HARDWARE_ACCELERATION,
    ) -> None:
        self.model = model
        self.vmax = np.array(model.max_velocity if max_velocity is None else max_velocity, float)
        self.amax = np.broadcast_to(np.asarray(max_acceleration, dtype=float), (6,)).copy()
        self.lower = np.asarray(model.lower, dtype=float)
        self.upper = np.asarray(model.upper, dtype=float)
        self._state = ArmState()
        self._mode = "hold"
        self._ref = np.zeros(6)  # servo filter state / hold position
        self._goal = np.zeros(6)  # servo target / speed target / track position
        self._goal_qd = np.zeros(6)
        self._tau = 0.1
        self._speed_acc = 1.0
        self.reset(np.zeros(6))

    @property
    def mode(self) -> str:
        """The current mode: ``"track"``, ``"servo"``, ``"speed"`` or ``"hold"``."""
        return self._mode

    def reset(self, q: ArrayLike) -> None:
        """Put the arm at rest at joint positions ``q`` [rad], shape (6,), in hold mode.

        Actual and target state alike: zero speed and acceleration, ``limited`` cleared.
        """
        q = np.array(q, dtype=float).reshape(6)
        s = self._state
        s.q = q.copy()
        s.qd = np.zeros(6)
        s.qdd = np.zeros(6)
        s.target_q = q.copy()
        s.target_qd = np.zeros(6)
        s.target_qdd = np.zeros(6)
        s.limited = False
        self._mode = "hold"
        self._ref = q.copy()

    def track(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> None:
        """Trajectory mode: follow the setpoint ``q`` [rad] moving at ``qd`` [rad/s].

        ``qdd`` is not used (the acceleration follows from consecutive setpoints).  Exact when the
        step respects the speed and acceleration limits, else braked and clipped to them
        (``ArmState.limited``).
        """
        self._mode = "track"
        self._goal = np.asarray(q, dtype=float)
        self._goal_qd = np.asarray(qd, dtype=float)

    def servo(self, q: ArrayLike, lookahead_time: float, gain: float) -> None:
        """Servo mode (servoJ): approach ``q`` [rad] through a first-order filter.

        Time constant :func:`~ruledrobot.robot.motion.servo.servo_time_constant` [s]
        (``lookahead_time * clip(300 / gain, 0.2, 1)``).  Entering the mode starts the filter
        at the current setpoint.
        """
        if self._mode != "servo":
            self._ref = self._state.target_q.copy()
            self._mode = "servo"
        self._goal = np.asarray(q, dtype=float)
        self._tau = servo_time_constant(lookahead_time, gain)

    def speed(self, qd: ArrayLike, acceleration: float) -> None:
        """Speed mode (speedJ): ramp the joint speeds to ``qd`` [rad/s] and keep them.

        The ramp's acceleration is ``|acceleration|`` [rad/s^2] (1 when zero), capped by the limit;
        the target speeds are clipped to ``max_velocity`` (``ArmState.limited``).
        """
        self._mode = "speed"
        self._goal_qd = np.asarray(qd, dtype=float)
        self._speed_acc = abs(float(acceleration)) or 1.0

    def hold(self) -> None:
        """Hold mode: brake to rest, within the limits, on the setpoint where the hold began.

        Nothing changes when the arm already holds.
        """
        if self._mode != "hold":
            self._ref = self._state.target_q.copy()
            self._mode = "hold"

    def _follow(self, goal: np.ndarray, goal_qd: np.ndarray, dt: float) -> None:
        """Move the setpoint towards ``goal`` (moving at ``goal_qd``) within the limits.

        Exact when the step is feasible; otherwise time-optimal with braking:
        the speed that would still stop on the goal (relative to its motion),
        limited by the acceleration and speed limits.
        """
        s = self._state
        q, qd = s.target_q, s.target_qd
        want = (goal - q) / dt
        dv = self.amax * dt
        # (array methods, not np.all / np.clip / np.any: their wrappers cost more than the
        # arithmetic on 6 joints, 500 times a second)
        if (np.abs(want) <= self.vmax * (1 + 1e-9)).all() and (
            np.abs(want - qd) <= dv * (1 + 1e-9)
        ).all():
            s.limited = False
            self._advance(goal.copy(), want, dt)
            return
        e = goal - q
        brake = np.sqrt(np.maximum(2.0 * self.amax * np.abs(e) - (self.amax * dt) ** 2, 0.0))
        v_des = goal_qd + np.sign(e) * brake
        # never step past the goal in one period
        v_des = np.where(np.abs(v_des * dt) > np.abs(e + goal_qd * dt), want, v_des)
        new_qd = np.clip(np.clip(v_des, qd - dv, qd + dv), -self.vmax, self.vmax)
        s.limited = True
        self._advance(q + new_qd * dt, new_qd, dt)

    def _advance(self, q_new: np.ndarray, qd_new: np.ndarray, dt: float) -> None:
        s = self._state
        clipped = q_new.clip(self.lower, self.upper)
        if (clipped != q_new).any():
            s.limited = True
            qd_new = np.where(clipped != q_new, 0.0, qd_new)
        qdd = (qd_new - s.target_qd) / dt
        s.target_q, s.target_qd, s.target_qdd = clipped, qd_new, qdd
        # ideal arm: actual = setpoint
        s.q, s.qd, s.qdd = clipped, qd_new, qdd

    def step(self, dt: float) -> None:
        """Advance the setpoint, and the ideal arm with it, by ``dt`` [s] (none for ``dt <= 0``)."""
        if dt <= 0.0:
            return
        s = self._state
        if self._mode == "track":
            self._follow(self._goal, self._goal_qd, dt)
        elif self._mode == "servo":
            a = 1.0 if self._tau <= dt else dt / self._tau
            prev = self._ref
            self._ref = prev + a * (self._goal - prev)
            self._follow(self._ref, (self._ref - prev) / dt, dt)
        elif self._mode == "speed":
            acc = np.minimum(self._speed_acc, self.amax) * dt
            goal = np.clip(self._goal_qd, -self.vmax, self.vmax)
            new_qd = np.clip(goal, s.target_qd - acc, s.target_qd + acc)
            s.limited = bool(np.any(goal != self._goal_qd))
            self._advance(s.target_q + new_qd * dt, new_qd, dt)
        else:
            self._follow(self._ref, np.zeros(6), dt)

    def state(self) -> ArmState:
        """The state after the last step: the backend's own :class:`ArmState` (copy to keep it)."""
        return self._state
