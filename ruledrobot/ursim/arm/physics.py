"""A MuJoCo-backed arm for the controller emulator.

The kinematic arm (:class:`~.backend.KinematicBackend`) stays the setpoint
generator — moves, servoJ filtering, speed ramps, limits — and a MuJoCo model
of the robot (:func:`ruledrobot.sim.mjcf.robot_mjcf`: the same servo model as
playback, position + velocity actuators with gravity compensation and torque
limits) tracks that setpoint with real dynamics.  The controller reports
MuJoCo's joint positions, speeds and joint torques as the actual state, so
what a client reads (and what the runner monitors) includes real tracking lag.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ...robot import RobotModel
from .backend import ArmState, KinematicBackend

__all__ = ["MujocoBackend"]


class MujocoBackend(KinematicBackend):
    """The kinematic setpoint tracked by the MuJoCo servo model of ``model``."""

    def __init__(self, model: RobotModel, **kwargs: object) -> None:
        from ...sim._mujoco import mujoco
        from ...sim.mjcf import physics_timestep, robot_mjcf

        self._mj = mj = mujoco()
        self._m = mj.MjModel.from_xml_string(robot_mjcf(model, collisions=False))
        self._m.opt.timestep = physics_timestep(model.control_period)
        self._m.opt.disableflags |= int(mj.mjtDisableBit.mjDSBL_CONTACT)
        self._d = mj.MjData(self._m)
        self._J = model.n_joints
        self._phys = ArmState()
        super().__init__(model, **kwargs)  # calls reset(), which needs the model above

    def reset(self, q: ArrayLike) -> None:
        """Put the kinematic setpoint and the MuJoCo arm at rest at ``q`` [rad], shape (6,)."""
        super().reset(q)
        J = self._J
        self._d.qpos[:J] = np.asarray(q, dtype=float)
        self._d.qvel[:] = 0.0
        self._d.ctrl[:] = np.concatenate([self._d.qpos[:J], np.zeros(2 * J)])
        self._mj.mj_forward(self._m, self._d)
        self._phys = ArmState(q=self._d.qpos[:J].copy(), target_q=self._d.qpos[:J].copy())

    def step(self, dt: float) -> None:
        """Advance the setpoint by ``dt`` [s], then the MuJoCo arm tracking it for ``dt``.

        The actuators get the setpoint's positions and speeds; ``round(dt / timestep)`` physics
        steps (at least one) follow.  The actual state is then MuJoCo's ``qpos`` and ``qvel``, their
        finite-difference acceleration and the joint torque sensors [N m] (zeros without them).
        """
        super().step(dt)  # the setpoint of this period
        sp = super().state()
        J, d = self._J, self._d
        qd_before = d.qvel[:J].copy()
        d.ctrl[:] = np.concatenate([sp.q, sp.qd, np.zeros(J)])
        for _ in range(max(1, round(dt / self._m.opt.timestep))):
            self._mj.mj_step(self._m, d)
        qd = d.qvel[:J].copy()
        self._phys = ArmState(
            q=d.qpos[:J].copy(), qd=qd, qdd=(qd - qd_before) / dt,
            target_q=sp.q.copy(), target_qd=sp.qd.copy(), target_qdd=sp.qdd.copy(),
            current=d.sensordata[:J].copy() if self._m.nsensordata >= J else np.zeros(J),
            limited=sp.limited,
        )  # fmt: skip

    def state(self) -> ArmState:
        """The simulated arm's state after the last step (target: the kinematic setpoint)."""
        return self._phys
