"""ur_rtde's control script, re-implemented: the register handshake and its commands.

ur_rtde uploads ``rtde_control.script`` and talks to it through RTDE
registers (register indices below are relative to the offset, 0 or 24):

* ``input_int_register_0`` — command id (:class:`Command`); arguments in
  ``input_double_register_0..`` and ``input_int_register_1..``;
* ``output_int_register_0`` — 1 = ready for a command, 2 = done with it;
* ``output_int_register_1`` / ``output_double_register_0..`` — results;
* ``output_int_register_2`` — async progress word (bit 15 running, bits 0-14
  progress, bits 16-22 write counter, bits 24-30 operation id).

Each control period the script reads the command: real-time commands
(servo/speed/...) are applied and ``ready`` kept; ``0`` clears the
``executing`` latch and signals ready; any other command runs once per
0 -> N edge (the latch), blocking the loop until it completes, then signals
done.  :class:`ControlScript` does the same, one :meth:`~ControlScript.step`
per control period.

Commands whose effect the emulator cannot produce (:data:`NOT_EMULATED`:
force mode, contact detection, the force/torque sensor, teach and freedrive
mode, direct torque and the dynamics queries) are not acknowledged: they raise
a runtime error, the control script stops (runtime state STOPPED), as the
script does on a robot when a command fails, so the client's call returns
False (or raises, for calls that return a value).  Real-time commands
(forceMode, toolContact, ...) are never waited for by ur_rtde, so that very
call returns True in the client; the program has stopped by the next one.
Command ids the script does not know are acknowledged without effect, as the
script does.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from enum import IntEnum

import numpy as np

from ...geometry.se3 import pose_from_ur_vector, ur_vector_from_pose
from ...robot.motion.ur_motion import (
    MotionError,
    PathMotion,
    StopMotion,
    joint_segment,
    linear_segment,
)
from .host import ProgramHost
from .program import Program

__all__ = ["NOT_EMULATED", "RT_COMMANDS", "Command", "ControlScript", "NotEmulatedError"]

log = logging.getLogger("ruledrobot.ursim")


class Command(IntEnum):
    """Command ids of ur_rtde's control script (``rtde.h``, 1.6.5)."""

    NO_CMD = 0
    MOVEJ = 1
    MOVEJ_IK = 2
    MOVEL = 3
    MOVEL_FK = 4
    FORCE_MODE = 6
    FORCE_MODE_STOP = 7
    ZERO_FT_SENSOR = 8
    SPEEDJ = 9
    SPEEDL = 10
    SERVOJ = 11
    SERVOC = 12
    SET_STD_DIGITAL_OUT = 13
    SET_TOOL_DIGITAL_OUT = 14
    SPEED_STOP = 15
    SERVO_STOP = 16
    SET_PAYLOAD = 17
    TEACH_MODE = 18
    END_TEACH_MODE = 19
    FORCE_MODE_SET_DAMPING = 20
    FORCE_MODE_SET_GAIN_SCALING = 21
    SET_SPEED_SLIDER = 22
    SET_STD_ANALOG_OUT = 23
    SERVOL = 24
    TOOL_CONTACT = 25
    GET_STEPTIME = 26
    GET_ACTUAL_JOINT_POSITIONS_HISTORY = 27
    GET_TARGET_WAYPOINT = 28
    SET_TCP = 29
    GET_INVERSE_KINEMATICS_ARGS = 30
    PROTECTIVE_STOP = 31
    STOPL = 33
    STOPJ = 34
    SET_WATCHDOG = 35
    IS_POSE_WITHIN_SAFETY_LIMITS = 36
    IS_JOINTS_WITHIN_SAFETY_LIMITS = 37
    GET_JOINT_TORQUES = 38
    POSE_TRANS = 39
    GET_TCP_OFFSET = 40
    JOG_START = 41
    JOG_STOP = 42
    GET_FORWARD_KINEMATICS_DEFAULT = 43
    GET_FORWARD_KINEMATICS_ARGS = 44
    MOVE_PATH = 45
    GET_INVERSE_KINEMATICS_DEFAULT = 46
    IS_STEADY = 47
    SET_CONF_DIGITAL_OUT = 48
    SET_INPUT_INT_REGISTER = 49
    SET_INPUT_DOUBLE_REGISTER = 50
    MOVE_UNTIL_CONTACT = 51
    FREEDRIVE_MODE = 52
    END_FREEDRIVE_MODE = 53
    GET_FREEDRIVE_STATUS = 54
    SET_EXTERNAL_FORCE_TORQUE = 55
    FT_RTDE_INPUT_ENABLE = 56
    ENABLE_EXTERNAL_FT_SENSOR = 57
    GET_ACTUAL_TOOL_FLANGE_POSE = 58
    SET_GRAVITY = 59
    GET_INVERSE_KINEMATICS_HAS_SOLUTION_DEFAULT = 60
    GET_INVERSE_KINEMATICS_HAS_SOLUTION_ARGS = 61
    START_CONTACT_DETECTION = 62
    STOP_CONTACT_DETECTION = 63
    READ_CONTACT_DETECTION = 64
    SET_TARGET_PAYLOAD = 65
    DIRECT_TORQUE = 66
    GET_MASS_MATRIX = 67
    GET_CORIOLIS_AND_CENTRIFUGAL_TORQUES = 68
    GET_TARGET_JOINT_ACCELERATIONS = 69
    GET_JACOBIAN = 70
    GET_JACOBIAN_TIME_DERIVATIVE = 71
    WATCHDOG = 99
    STOP_SCRIPT = 255


#: Commands the script handles in its real-time branch (no latch, no "done"):
#: the 1.6.5 script's set plus SERVOC and SET_EXTERNAL_FORCE_TORQUE, which
#: the client sends without waiting for "done" either.
RT_COMMANDS = frozenset({24, 11, 9, 10, 6, 25, 26, 27, 38, 58, 66, 67, 68, 69, 70, 71, 12, 55})

#: ur_rtde commands the emulator cannot carry out, with the client method and the
#: URScript function behind them: a runtime error stops the control script.
NOT_EMULATED: dict[int, str] = {
    Command.FORCE_MODE: "forceMode (force_mode)",
    Command.FORCE_MODE_STOP: "forceModeStop (end_force_mode)",
    Command.ZERO_FT_SENSOR: "zeroFtSensor (zero_ftsensor)",
    Command.TEACH_MODE: "teachMode (teach_mode)",
    Command.END_TEACH_MODE: "endTeachMode (end_teach_mode)",
    Command.FORCE_MODE_SET_DAMPING: "forceModeSetDamping (force_mode_set_damping)",
    Command.FORCE_MODE_SET_GAIN_SCALING: "forceModeSetGainScaling (force_mode_set_gain_scaling)",
    Command.TOOL_CONTACT: "toolContact (tool_contact)",
    Command.MOVE_UNTIL_CONTACT: "moveUntilContact (tool_contact + speedl)",
    Command.FREEDRIVE_MODE: "freedriveMode (freedrive_mode)",
    Command.END_FREEDRIVE_MODE: "endFreedriveMode (end_freedrive_mode)",
    Command.GET_FREEDRIVE_STATUS: "getFreedriveStatus (get_freedrive_status)",
    Command.SET_EXTERNAL_FORCE_TORQUE: "setExternalForceTorque (external F/T input)",
    Command.FT_RTDE_INPUT_ENABLE: "ftRtdeInputEnable (ft_rtde_input_enable)",
    Command.ENABLE_EXTERNAL_FT_SENSOR: "enableExternalFtSensor (enable_external_ft_sensor)",
    Command.SET_GRAVITY: "setGravity (set_gravity)",
    Command.START_CONTACT_DETECTION: "startContactDetection (tool_contact)",
    Command.STOP_CONTACT_DETECTION: "stopContactDetection (tool_contact)",
    Command.READ_CONTACT_DETECTION: "readContactDetection (tool_contact)",
    Command.DIRECT_TORQUE: "directTorque (direct_torque)",
    Command.GET_MASS_MATRIX: "getMassMatrix (get_mass_matrix)",
    Command.GET_CORIOLIS_AND_CENTRIFUGAL_TORQUES: "getCoriolisAndCentrifugalTorques",
    Command.GET_JACOBIAN_TIME_DERIVATIVE: "getJacobianTimeDerivative",
}

READY = 1
DONE = 2


class NotEmulatedError(MotionError):
    """A command the emulator cannot carry out: a runtime error that stops the program."""

    def __init__(self, cmd: int) -> None:
        super().__init__(
            f"command {cmd}: {NOT_EMULATED[cmd]} is not emulated (the emulated arm has no "
            "force control, contact sensing, F/T sensor, hand guiding or dynamics model)"
        )


Waiter = Callable[[], bool]


class ControlScript:
    """The running ``rtde_control`` program: one :meth:`step` per control period."""

    def __init__(self, host: ProgramHost, program: Program) -> None:
        self.c = host
        self.kin = host.kin
        self.program = program
        self.off = program.register_offset
        self.executing = False
        self.waiting: Waiter | None = None
        self.async_wr_count = 0
        self.async_op_id = 0
        self.async_motion: PathMotion | StopMotion | None = None
        self.async_progress = -1
        self._servoc_target: tuple | None = None
        self._servol: tuple[tuple, np.ndarray] | None = None  # last servoL target, solution
        self._speedl: tuple[np.ndarray, float] | None = None
        self.out_int(0, READY)
        self.signal_async(-1)

    # ------------------------------------------------------------ registers

    def in_int(self, i: int) -> int:
        """Input integer register ``i`` of the script (RTDE register ``i`` + the offset)."""
        return self.c.in_int(i + self.off)

    def in_d(self, i: int) -> float:
        """Input double register ``i`` of the script (RTDE register ``i`` + the offset)."""
        return self.c.in_double(i + self.off)

    def in_vec(self, start: int, n: int = 6) -> np.ndarray:
        """``n`` consecutive input double registers from ``start`` (+ the offset), shape (n,)."""
        return np.array([self.in_d(start + k) for k in range(n)])

    def out_int(self, i: int, value: int) -> None:
        """Set output integer register ``i`` of the script (RTDE register ``i`` + the offset)."""
        self.c.set_out_int(i + self.off, value)

    def out_d(self, i: int, value: float) -> None:
        """Set output double register ``i`` of the script (RTDE register ``i`` + the offset)."""
        self.c.set_out_double(i + self.off, value)

    def out_vec(self, values, start: int = 0) -> None:
        """Write ``values`` to consecutive output double registers from ``start`` (+ the offset)."""
        for k, x in enumerate(values):
            self.out_d(start + k, float(x))

    def has_arg(self, name: str) -> bool:
        """True when the data package that carried the command had this register."""
        return name in self.c.last_input_names

    # ------------------------------------------------------------ async progress

    def signal_async(self, value: int) -> None:
        """``write_async_progress_register``: value >= 0 running with progress, < 0 finished."""
        self.async_wr_count = (self.async_wr_count + 1) % 128
        if value == 0:
            self.async_op_id = (self.async_op_id + 1) % 128
        reg = self.async_wr_count * 65536 + self.async_op_id * 16777216
        if value >= 0:
            reg += (value & 0x7FFF) + 32768
        self.async_progress = value
        self.out_int(2, reg)

    def _start_async(self, motion: PathMotion | StopMotion) -> None:
        self.async_motion = motion
        self.signal_async(0)

    def _track_async(self) -> None:
        m = self.async_motion
        if m is None:
            return
        if self.c.motion is not m:
            self.async_motion = None
            self.signal_async(-1)
            return
        if isinstance(m, PathMotion) and m.progress != self.async_progress:
            self.signal_async(m.progress)

    # ------------------------------------------------------------ main loop

    def step(self) -> None:
        """One control period of the script's main loop."""
        self._track_async()
        if self.waiting is not None:
            if not self.waiting():
                return
            self.waiting = None
            self.out_int(0, DONE)
            return
        cmd = self.in_int(0)
        if cmd in NOT_EMULATED and (cmd in RT_COMMANDS or not self.executing):
            self.executing = True
            raise NotEmulatedError(cmd)
        if cmd in RT_COMMANDS:
            self.realtime(cmd)
            self.out_int(0, READY)
        elif cmd == Command.NO_CMD:
            self.executing = False
            self.out_int(0, READY)
        elif not self.executing:
            self.executing = True
            if cmd == Command.STOP_SCRIPT:
                self.c.log("rtde_control: stop script requested")
                self.c.stop_program("stopScript", decelerate=True)
                return
            waiter = self.execute(cmd)
            if waiter is None:
                self.out_int(0, DONE)
            else:
                self.waiting = waiter

    # ------------------------------------------------------------ helpers

    def _motion_waiter(self, motion: PathMotion | StopMotion) -> Waiter:
        def done() -> bool:
            return self.c.motion is not motion

        return done

    def _move(self, motion: PathMotion, asynchronous: bool) -> Waiter | None:
        self.c.start_motion(motion)
        if asynchronous:
            self._start_async(motion)
            return None
        return self._motion_waiter(motion)

    def _q_now(self) -> np.ndarray:
        return self.c.arm_state().target_q.copy()

    def _ik(self, pose: np.ndarray, qnear: np.ndarray, what: str) -> np.ndarray:
        q = self.kin.ik_nearest(pose, qnear)
        if q is None:
            raise MotionError(
                f"{what}: no inverse kinematics solution for p{np.round(pose, 6).tolist()}"
            )
        return q

    def _stop(self, decel: float, asynchronous: bool) -> Waiter | None:
        stop = self.c.stop_motion(decel)
        if asynchronous:
            self._start_async(stop)
            return None
        return self._motion_waiter(stop)

    # ------------------------------------------------------------ real-time commands

    def realtime(self, cmd: int) -> None:
        """Carry out one real-time command (:data:`RT_COMMANDS`) this period: no latch, no done.

        servoJ and servoL set the servo target (servoL: the inverse kinematics solution nearest the
        setpoint, solved once per target); speedJ and speedL set joint speeds (speedL: the
        least-squares joint speeds of the Jacobian at the setpoint); servoC starts a linear move
        when its target changes or no motion runs.  The queries (step time [s], a past actual joint
        position [rad], joint torques, flange pose in the base frame, target joint accelerations
        [rad/s^2], Jacobian) write their answer to the output double registers.
        """
        c = self.c
        if cmd == Command.SERVOJ:
            q = self.in_vec(0)
            c.set_servo(q, self.in_d(9), self.in_d(10))
        elif cmd == Command.SERVOL:
            pose = self.in_vec(0)
            key = tuple(pose.tolist())
            if self._servol is not None and self._servol[0] == key:
                q = self._servol[1]  # the same target again: its solution (IK once per target)
            else:
                q = self.kin.ik_nearest(pose, self._q_now())
                if q is None:
                    raise MotionError(
                        f"servol: no inverse kinematics solution for p{pose.round(6).tolist()}"
                    )
                self._servol = (key, q)
            c.set_servo(q, self.in_d(9), self.in_d(10))
        elif cmd == Command.SPEEDJ:
            c.set_speed(self.in_vec(0), self.in_d(6))
        elif cmd == Command.SPEEDL:
            self._speedl = (self.in_vec(0), self.in_d(6))
            self._apply_speedl()
        elif cmd == Command.SERVOC:
            target = tuple(self.in_vec(0).round(9))
            if target != self._servoc_target or c.motion is None:
                self._servoc_target = target
                seg = linear_segment(self._q_now(), self.in_vec(0), self.in_d(6), self.in_d(7),
                                     self.in_d(8), self.kin)  # fmt: skip
                c.start_motion(PathMotion(seg.q_start, [seg]))
        elif cmd == Command.GET_STEPTIME:
            self.out_d(0, c.period)
        elif cmd == Command.GET_ACTUAL_JOINT_POSITIONS_HISTORY:
            steps = max(0, self.in_int(1))
            hist = c.history
            q = hist[max(0, len(hist) - 1 - steps)] if hist else self._q_now()
            self.out_vec(q)
        elif cmd == Command.GET_JOINT_TORQUES:
            self.out_vec(c.arm_state().current)
        elif cmd == Command.GET_ACTUAL_TOOL_FLANGE_POSE:
            q = c.arm_state().q
            flange = self.kin.model.with_tool(np.eye(4)).fk(q)
            self.out_vec(ur_vector_from_pose(flange))
        elif cmd == Command.GET_TARGET_JOINT_ACCELERATIONS:
            self.out_vec(c.arm_state().target_qdd)
        elif cmd == Command.GET_JACOBIAN:
            J = self.kin.model.jacobian(c.arm_state().q)
            for col in range(6):
                base = col * 6 if col < 4 else 36 + (col - 4) * 6
                self.out_vec(J[:, col], base)
        # the rest of NOT_EMULATED never gets here (step raises NotEmulatedError)

    def _apply_speedl(self) -> None:
        assert self._speedl is not None
        xd, acc = self._speedl
        c = self.c
        J = self.kin.model.jacobian(self._q_now())
        qd = np.linalg.lstsq(J, xd, rcond=1e-6)[0]
        c.set_speed(qd, acc)

    # ------------------------------------------------------------ blocking commands

    def execute(self, cmd: int) -> Waiter | None:
        """Run one non-real-time command; a waiter while it blocks, else None (done)."""
        c = self.c
        if cmd == Command.MOVEJ:
            q = self.in_vec(0)
            seg = joint_segment(self._q_now(), q, self.in_d(6), self.in_d(7), 0.0, self.kin)
            return self._move(PathMotion(seg.q_start, [seg]), self.in_int(1) != 0)
        if cmd == Command.MOVEJ_IK:
            q0 = self._q_now()
            q = self._ik(self.in_vec(0), q0, "moveJ_IK")
            seg = joint_segment(q0, q, self.in_d(6), self.in_d(7), 0.0, self.kin)
            return self._move(PathMotion(q0, [seg]), self.in_int(1) != 0)
        if cmd in (Command.MOVEL, Command.MOVEL_FK):
            q0 = self._q_now()
            target = self.in_vec(0)
            if cmd == Command.MOVEL_FK:
                target = np.asarray(self.kin.tcp_vector(target))
            seg = linear_segment(q0, target, self.in_d(6), self.in_d(7), 0.0, self.kin)
            return self._move(PathMotion(q0, [seg]), self.in_int(1) != 0)
        if cmd == Command.MOVE_PATH:
            motion = c.build_path(self.program.path)
            return self._move(motion, self.in_int(1) != 0)
        if cmd in (Command.SERVO_STOP, Command.SPEED_STOP, Command.JOG_STOP):
            self._speedl = None
            return self._stop(self.in_d(0) if cmd != Command.JOG_STOP else 2.0, False)
        if cmd in (Command.STOPJ, Command.STOPL):
            return self._stop(self.in_d(0), self.in_int(1) != 0)
        if cmd == Command.GET_INVERSE_KINEMATICS_DEFAULT:
            self.out_vec(self._ik(self.in_vec(0), c.arm_state().q, "get_inverse_kin"))
            return None
        if cmd == Command.GET_INVERSE_KINEMATICS_ARGS:
            self.out_vec(self._ik(self.in_vec(0), self.in_vec(6), "get_inverse_kin"))
            return None
        if cmd in (
            Command.GET_INVERSE_KINEMATICS_HAS_SOLUTION_DEFAULT,
            Command.GET_INVERSE_KINEMATICS_HAS_SOLUTION_ARGS,
        ):
            qnear = self.in_vec(6) if cmd == Command.GET_INVERSE_KINEMATICS_HAS_SOLUTION_ARGS else (
                c.arm_state().q)  # fmt: skip
            self.out_int(1, int(self.kin.ik_nearest(self.in_vec(0), qnear) is not None))
            return None
        if cmd == Command.GET_FORWARD_KINEMATICS_DEFAULT:
            self.out_vec(self.kin.tcp_vector(c.arm_state().q.tolist()))
            return None
        if cmd == Command.GET_FORWARD_KINEMATICS_ARGS:
            q = self.in_vec(0)
            tcp = self.in_vec(6) if self.has_arg(f"input_double_register_{11 + self.off}") else None
            self.out_vec(self.kin.fk_vector(q, tcp))
            return None
        if cmd == Command.SET_TCP:
            self.kin.set_tcp(self.in_vec(0))
            c.log(f"set_tcp(p{np.round(self.in_vec(0), 6).tolist()})")
            return None
        if cmd == Command.GET_TCP_OFFSET:
            self.out_vec(self.kin.tcp_offset)
            return None
        if cmd == Command.POSE_TRANS:
            T = pose_from_ur_vector(self.in_vec(0)) @ pose_from_ur_vector(self.in_vec(6))
            self.out_vec(ur_vector_from_pose(T))
            return None
        if cmd == Command.GET_TARGET_WAYPOINT:
            m = c.motion
            if isinstance(m, PathMotion) and m.segments[-1].linear:
                self.out_vec(m.target)
            elif m is not None:
                self.out_vec(self.kin.tcp_vector(np.asarray(m.q_end).tolist()))
            else:
                self.out_vec(self.kin.tcp_vector(c.arm_state().target_q.tolist()))
            return None
        if cmd == Command.IS_STEADY:
            st = c.arm_state()
            self.out_int(1, int(c.motion is None and float(np.max(np.abs(st.qd))) < 1e-4))
            return None
        if cmd == Command.IS_POSE_WITHIN_SAFETY_LIMITS:
            ok = self.kin.ik_nearest(self.in_vec(0), c.arm_state().q) is not None
            self.out_int(1, int(ok))
            return None
        if cmd == Command.IS_JOINTS_WITHIN_SAFETY_LIMITS:
            self.out_int(1, int(bool(self.kin.model.within_limits(self.in_vec(0)))))
            return None
        if cmd == Command.PROTECTIVE_STOP:
            c.protective_stop("triggerProtectiveStop() from the client")
            return None
        if cmd in (Command.SET_PAYLOAD, Command.SET_TARGET_PAYLOAD):
            c.set_payload(self.in_d(0), self.in_vec(1, 3))
            return None
        if cmd == Command.SET_WATCHDOG:
            c.set_watchdog(f"input_int_register_{self.off}", self.in_d(0), "stop")
            return None
        if cmd == Command.JOG_START:
            self._speedl = (self.in_vec(0), 1.0)
            self._apply_speedl()
            return None
        # ids the script does not know: acknowledged without effect, as the script does
        log.debug("rtde_control: unknown command %d acknowledged", cmd)
        return None
